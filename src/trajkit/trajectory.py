"""Multi-axis trajectories: synchronised point-to-point motion (:func:`plan_ptp`)."""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from ._atomicio import atomic_write
from ._csvio import csv_text, unit_suffix
from ._constants import DURATION_RTOL
from ._sampling import MAX_SAMPLES, period_times
from ._validate import check_array
from .errors import InfeasibleError, InvalidInputError
from .limits import AxisLimits
from .profiles.profile import (
    Profile,
    _min_solution,
    _plan_solved,
    _plan_unchecked,
    _rest_profile,
)

__all__ = ["Trajectory", "TrajectorySample", "plan_ptp", "SYNC_MODES"]

#: Accepted values of ``plan_ptp(..., sync=...)``.
SYNC_MODES = ("time", "phase", "none")


@dataclass(frozen=True)
class TrajectorySample:
    """States of all axes at the sampled times.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Times [s].
    position, velocity, acceleration, jerk : ndarray, shape (n, n_axes)
        Per-axis values [unit, unit/s, unit/s^2, unit/s^3].
    """

    t: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray


class Trajectory:
    """A multi-axis trajectory made of one :class:`Profile` per axis.

    Attributes
    ----------
    axes : tuple of Profile
        The per-axis profiles (all start at t = 0).
    duration : float
        The longest axis duration [s].
    sync : str
        How the axes were synchronised ("time", "phase" or "none").
    names : tuple of str
        Axis names (for export headers).
    """

    def __init__(self, axes: Sequence[Profile], sync: str = "none",
                 names: Sequence[str] | None = None) -> None:
        self.axes = tuple(axes)
        self.sync = sync
        self.duration = max((p.duration for p in self.axes), default=0.0)
        if names is None:
            names = [
                str(p.limits.name) if p.limits.name is not None else f"q{i}"
                for i, p in enumerate(self.axes)
            ]
        self.names = tuple(names)

    @property
    def n_axes(self) -> int:
        return len(self.axes)

    @property
    def start(self) -> np.ndarray:
        """Start positions, shape (n_axes,)."""
        return np.array([p.start for p in self.axes])

    @property
    def goal(self) -> np.ndarray:
        """Goal positions, shape (n_axes,)."""
        return np.array([p.goal for p in self.axes])

    def sample(self, t: Any) -> TrajectorySample:
        """Sample every axis at times ``t``.

        Parameters
        ----------
        t : float or array_like, shape (n,)
            Times [s]; outside an axis' duration the axis holds its start or
            goal state.

        Returns
        -------
        TrajectorySample
            Arrays of shape (n, n_axes) (n = 1 for a scalar ``t``).
        """
        tt = np.atleast_1d(np.asarray(t, dtype=np.float64))
        n = tt.shape[0]
        out = np.empty((4, n, self.n_axes))
        for k, prof in enumerate(self.axes):
            s = prof.sample(tt)
            out[0, :, k] = s.position
            out[1, :, k] = s.velocity
            out[2, :, k] = s.acceleration
            out[3, :, k] = s.jerk
        return TrajectorySample(tt, out[0], out[1], out[2], out[3])

    def times(self, period: float, max_samples: int | None = MAX_SAMPLES) -> np.ndarray:
        """Sample times 0, dt, 2 dt, ..., always ending exactly at ``duration``.

        Refuses (:class:`InvalidInputError`) more than ``max_samples`` samples
        (:data:`trajkit._sampling.MAX_SAMPLES` by default; ``None``: no cap).
        """
        return period_times(self.duration, period, end="exact", max_samples=max_samples)

    def to_dict(self) -> dict:
        """JSON-ready description: duration, sync mode and per-axis profiles."""
        return {
            "duration_s": self.duration,
            "sync": self.sync,
            "axes": [dict(name=nm, **p.to_dict()) for nm, p in zip(self.names, self.axes)],
        }

    def to_json(self, path: str | os.PathLike | None = None, indent: int = 2) -> str:
        """Return (and optionally write to ``path``) the JSON description."""
        text = json.dumps(self.to_dict(), indent=indent)
        if path is not None:
            _atomic_write(path, text)
        return text

    def to_csv(self, path: str | os.PathLike | None = None, period: float = 0.001,
               units: str | Sequence[str] = "m") -> str:
        """Samples at a fixed period as CSV text (and optionally to ``path``).

        Columns: ``t_s``, then ``<axis>_position_<u>``, ``<axis>_velocity_<u>_s``,
        ``<axis>_acceleration_<u>_s2``, ``<axis>_jerk_<u>_s3`` for each axis,
        with ``units`` the position unit of all axes or of each (the planner
        itself is unit-agnostic; default ``"m"``).
        """
        us = [units] * self.n_axes if isinstance(units, str) else list(units)
        if len(us) != self.n_axes:
            raise InvalidInputError(f"units has {len(us)} entries but the trajectory has "
                                    f"{self.n_axes} axes")
        t = self.times(period)
        s = self.sample(t)
        header = ["t_s"]
        cols = [t]
        for k, (nm, u) in enumerate(zip(self.names, us)):
            header += [f"{nm}_{q}_{unit_suffix(u, d)}"
                       for d, q in enumerate(("position", "velocity", "acceleration", "jerk"))]
            cols += [s.position[:, k], s.velocity[:, k], s.acceleration[:, k], s.jerk[:, k]]
        text = csv_text(header, cols)
        if path is not None:
            _atomic_write(path, text)
        return text

    def __repr__(self) -> str:
        return f"Trajectory(n_axes={self.n_axes}, duration={self.duration!r}, sync={self.sync!r})"


def _atomic_write(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` to ``path`` atomically (see :func:`trajkit._atomicio.atomic_write`)."""
    atomic_write(path, text)


def _coerce_limits(
    limits: AxisLimits | Sequence[AxisLimits], n: int, named: bool = False
) -> list[AxisLimits]:
    """One AxisLimits per axis: the same objects, or with ``named=True`` copies of
    the unnamed ones carrying their axis index (for messages)."""
    if isinstance(limits, AxisLimits):
        if named and limits.name is None:
            return [limits.with_name(i) for i in range(n)]
        return [limits] * n
    try:
        lims = list(limits)
    except TypeError:
        raise InvalidInputError(
            f"limits must be an AxisLimits or a sequence of them, got {type(limits).__name__}"
        ) from None
    if len(lims) != n:
        raise InvalidInputError(
            f"limits has {len(lims)} entries but start/goal have {n} axes"
        )
    for i, lim in enumerate(lims):
        if not isinstance(lim, AxisLimits):
            raise InvalidInputError(
                f"limits[{i}] must be an AxisLimits, got {type(lim).__name__}"
            )
        if named and lim.name is None:
            lims[i] = lim.with_name(i)
    return lims


def _float_list(value: Any, field: str) -> list[float]:
    """A 1-D sequence of numbers as a list of floats (fast path for lists and
    1-D arrays; everything else goes through :func:`check_array`)."""
    if isinstance(value, np.ndarray) and value.ndim == 1 and value.dtype.kind in "fiu":
        return value.astype(np.float64, copy=False).tolist()
    if isinstance(value, (list, tuple)) and all(type(x) in (float, int) for x in value):
        return [float(x) for x in value]
    return check_array(value, field, ndim=1, finite=False).tolist()


def _check_positions(values: list[float], lims: list[AxisLimits], field: str) -> list[float]:
    """Finite and inside each axis' range; messages name the axis (its name or index)."""
    for i, (x, lim) in enumerate(zip(values, lims)):
        if not (lim.position_min <= x <= lim.position_max) or not math.isfinite(x):
            (lim if lim.name is not None else lim.with_name(i)).check_position(x, field)
    return values


def _boundary_states(start, goal, v0, a0, v1, a1):
    """(n, 3) start and goal states, or None when every given rate is zero."""
    s = check_array(start, "start", ndim=1, finite=False)
    g = check_array(goal, "goal", ndim=1, finite=False)
    n = s.size
    rates = []
    for value, field in ((v0, "start_velocity"), (a0, "start_acceleration"),
                         (v1, "goal_velocity"), (a1, "goal_acceleration")):
        if value is None:
            rates.append(np.zeros(n))
        else:
            rates.append(check_array(value, field, ndim=1, size=n))
    if not any(np.any(r != 0.0) for r in rates):
        return None
    if g.size != n:
        raise InvalidInputError(f"start has {n} axes but goal has {g.size}")
    return (np.column_stack([s, rates[0], rates[1]]), np.column_stack([g, rates[2], rates[3]]))


def plan_ptp(
    start: Any,
    goal: Any,
    limits: AxisLimits | Sequence[AxisLimits],
    sync: str = "time",
    duration: float | None = None,
    *,
    start_velocity: Any = None,
    start_acceleration: Any = None,
    goal_velocity: Any = None,
    goal_acceleration: Any = None,
) -> Trajectory:
    """Plan a synchronised, jerk-limited point-to-point move of several axes.

    Parameters
    ----------
    start, goal : array_like, shape (n_axes,)
        Positions per axis [axis unit].
    limits : AxisLimits or sequence of n_axes AxisLimits
        One set of limits for every axis, or one per axis.
    sync : {"time", "phase", "none"}
        ``"time"``: every axis starts and arrives together at the slowest
        axis' minimum time (seed 002's synchronisation, with S-curves), each
        keeping its own limits. ``"phase"``: every axis follows the same
        normalised profile, so the motion is a straight line in joint space,
        within every axis' limits. ``"none"``: each axis at its own minimum
        time.
    duration : float, optional
        With ``"time"`` or ``"phase"``: stretch the motion to exactly this
        duration [s] (must be >= the synchronised minimum).
    start_velocity, start_acceleration, goal_velocity, goal_acceleration : array_like, shape (n_axes,), optional
        Moving boundary states [unit/s, unit/s^2]; when any is non-zero the
        move is planned between states by :func:`trajkit.sync_states.plan_ptp_states`
        (axes are then :class:`~trajkit.profiles.state.StateProfile` objects).

    Returns
    -------
    Trajectory

    Raises
    ------
    InvalidInputError
        NaN/inf positions, mismatched axis counts, positions outside an
        axis' range, an unknown ``sync``.
    InfeasibleError
        ``duration`` below the minimum.
    """
    if sync not in SYNC_MODES:
        raise InvalidInputError(f"sync must be one of {SYNC_MODES}, got {sync!r}")
    moving = (start_velocity, start_acceleration, goal_velocity, goal_acceleration)
    if any(x is not None for x in moving):
        states = _boundary_states(start, goal, *moving)
        if states is not None:
            from .sync_states import plan_ptp_states

            return plan_ptp_states(states[0], states[1], limits, sync=sync, duration=duration)
    # entries are checked per axis below (the messages name the axis)
    sl = _float_list(start, "start")
    gl = _float_list(goal, "goal")
    if len(sl) != len(gl):
        raise InvalidInputError(
            f"start has {len(sl)} axes but goal has {len(gl)}"
        )
    n = len(sl)
    if n == 0:
        raise InvalidInputError("start and goal must have at least one axis")
    lims = _coerce_limits(limits, n)
    _check_positions(sl, lims, "start")
    _check_positions(gl, lims, "goal")
    if duration is not None:
        try:
            duration = float(duration)
        except (TypeError, ValueError):
            raise InvalidInputError(
                f"duration must be a number of seconds, got {duration!r}"
            ) from None
        if not math.isfinite(duration) or duration < 0:
            raise InvalidInputError(f"duration must be finite and >= 0 s, got {duration!r}")
        if sync == "none":
            raise InvalidInputError('duration cannot be given with sync="none"')

    if sync == "none":
        return Trajectory([_plan_unchecked(a, b, lim, None) for a, b, lim in zip(sl, gl, lims)], "none")

    if sync == "time":
        # step 1: each axis' fastest profile; the slowest sets the common duration
        sols = [None if b == a else _min_solution(abs(b - a), lim)
                for a, b, lim in zip(sl, gl, lims)]
        tmin = max((sol[1] for sol in sols if sol is not None), default=0.0)
        T = tmin if duration is None else duration
        if duration is not None and duration < tmin * (1.0 - DURATION_RTOL):
            raise InfeasibleError(
                f"duration {duration!r} s is below the minimum synchronised duration {tmin:.15g} s",
                minimum=tmin,
            )
        # step 2: every axis for exactly that duration
        axes = [
            _rest_profile(a, lim, T) if sol is None else _plan_solved(a, b, lim, sol[0], sol[1], T)
            for a, b, lim, sol in zip(sl, gl, lims, sols)
        ]
        return Trajectory(axes, "time")

    # phase: one normalised profile u(t) in [0, 1]; axis k = s_k + D_k u(t).
    dist = [abs(b - a) for a, b in zip(sl, gl)]
    moving = [k for k in range(n) if dist[k] > 0.0]
    if not moving:
        T = 0.0 if duration is None else duration
        return Trajectory([_plan_unchecked(a, b, lim, T) for a, b, lim in zip(sl, gl, lims)], "phase")
    vn = min(lims[k].v_max / dist[k] for k in moving)
    an = min(lims[k].a_max / dist[k] for k in moving)
    jn = min(lims[k].j_max / dist[k] for k in moving)
    adn = min(lims[k].a_max_decel / dist[k] for k in moving)
    jdn = min(lims[k].j_max_decel / dist[k] for k in moving)
    unit = AxisLimits(vn, an, jn, adn, jdn, name="path")
    u = _plan_unchecked(0.0, 1.0, unit, duration)
    axes = []
    for a, b, lim in zip(sl, gl, lims):
        d = b - a
        sgn = 1.0 if d > 0 else -1.0
        ad = abs(d)
        axes.append(Profile(
            a, b, u.duration, u.min_duration if ad > 0 else 0.0,
            u.phase_durations if ad > 0 else (0.0, 0.0, 0.0, u.duration, 0.0, 0.0, 0.0),
            tuple(sgn * ad * jj for jj in u.jerks),
            d * u.peak_velocity, ad * u.peak_acceleration, ad * u.peak_deceleration, lim,
        ))
    return Trajectory(axes, "phase")
