"""Multi-axis trajectories: :class:`Trajectory` (samples and export of several axes).

A trajectory holds one one-axis motion per axis (a
:class:`~trajkit.profiles.Profile`, a :class:`~trajkit.profiles.StateProfile`
or any :class:`~trajkit.profiles.motion.JerkMotion` with ``limits``); the
planners that build them live in :mod:`trajkit.sync`. ``trajkit.trajectory.plan_ptp``
is kept as an alias of :func:`trajkit.sync.plan_ptp` for existing callers.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from ._atomicio import atomic_write
from ._csvio import csv_text, unit_suffix
from ._sampling import MAX_SAMPLES, period_times
from .errors import InvalidInputError

__all__ = ["Trajectory", "TrajectorySample", "SYNC_MODES"]

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
    """A multi-axis trajectory made of one motion per axis.

    Attributes
    ----------
    axes : tuple of Profile or StateProfile
        The per-axis motions (all start at t = 0).
    duration : float
        The longest axis duration [s].
    sync : str
        How the axes were synchronised ("time", "phase" or "none").
    names : tuple of str
        Axis names (for export headers).
    """

    def __init__(self, axes: Sequence[Any], sync: str = "none",
                 names: Sequence[str] | None = None) -> None:
        self.__dict__["axes"] = tuple(axes)
        self.sync = sync
        self.duration = max((p.duration for p in self.axes), default=0.0)
        self._names = None if names is None else tuple(names)
        self._build: Callable[[], Sequence[Any]] | None = None

    @classmethod
    def _deferred(cls, build: Callable[[], Sequence[Any]], duration: float,
                  sync: str) -> Trajectory:
        """A trajectory whose axis motions ``build()`` makes on the first access of
        :attr:`axes` (a planner that has every axis' phase table already, and its
        ``duration``, the longest axis duration, leaves the objects for when they
        are used)."""
        traj = cls.__new__(cls)
        traj.sync = sync
        traj.duration = duration
        traj._names = None
        traj._build = build
        return traj

    @cached_property
    def axes(self) -> tuple[Any, ...]:
        """The per-axis motions (all start at t = 0)."""
        build = self._build
        assert build is not None  # (set by _deferred; __init__ stores the axes)
        self._build = None
        return tuple(build())

    @property
    def names(self) -> tuple[str, ...]:
        """Axis names (for export headers): the limits' names, or ``q<i>``."""
        if self._names is None:
            self._names = tuple(_axis_name(p.limits.name, i) for i, p in enumerate(self.axes))
        return self._names

    @property
    def n_axes(self) -> int:
        return len(self.axes)

    @property
    def start_states(self) -> np.ndarray:
        """Start states ``(p, v, a)`` per axis, shape (n_axes, 3)."""
        return np.array([p.start_state for p in self.axes], dtype=float).reshape(-1, 3)

    @property
    def goal_states(self) -> np.ndarray:
        """Goal states ``(p, v, a)`` per axis, shape (n_axes, 3)."""
        return np.array([p.end_state for p in self.axes], dtype=float).reshape(-1, 3)

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

    def state_at(self, t: float) -> np.ndarray:
        """Every axis' state at one time ``t`` [s] (what :meth:`sample` gives
        there, without its arrays per axis: one setpoint per control period).

        Returns
        -------
        ndarray, shape (4, n_axes)
            Rows: position, velocity, acceleration, jerk [unit, unit/s,
            unit/s^2, unit/s^3].
        """
        t = float(t)
        return np.array([p.state_at(t) for p in self.axes]).T.reshape(4, -1)

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


def _axis_name(name: Any, i: int) -> str:
    """Column name of an axis: its name, or ``q<i>`` (also for an integer index)."""
    if name is None or (isinstance(name, int) and not isinstance(name, bool)):
        return f"q{i if name is None else name}"
    return str(name)


def __getattr__(attr: str):
    """``trajkit.trajectory.plan_ptp``: the planner moved to :mod:`trajkit.sync`."""
    if attr == "plan_ptp":
        from .sync import (
            plan_ptp,  # deferred: trajectory never imports sync at load time
        )

        return plan_ptp
    raise AttributeError(f"module {__name__!r} has no attribute {attr!r}")
