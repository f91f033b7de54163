"""Many axes at rest at both ends: time-, phase- or un-synchronised moves.

Step 1 (ruckig's scheme): every axis' minimum duration (closed form of
:mod:`trajkit.profiles`); the common duration is the largest; step 2: every
axis planned for exactly that duration (a lower cruise velocity). With
``sync="phase"`` one normalised profile moves every axis along the
joint-space straight line.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from .._constants import DURATION_RTOL
from ..errors import InfeasibleError, InvalidInputError
from ..limits import AxisLimits
from ..profiles._range import check_limits_range
from ..profiles.profile import (
    Profile,
    _min_solution,
    _plan_solved,
    _plan_unchecked,
    _rest_profile,
)
from ..trajectory import SYNC_MODES, Trajectory
from ._inputs import (
    check_distances,
    check_duration,
    check_positions,
    coerce_limits,
    float_list,
)

__all__ = ["plan_ptp_rest"]


def plan_ptp_rest(
    start: Any,
    goal: Any,
    limits: AxisLimits | Sequence[AxisLimits],
    sync: str = "time",
    duration: float | None = None,
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
        axis' minimum time (Jiang, 1987's synchronisation, with S-curves), each
        keeping its own limits. ``"phase"``: every axis follows the same
        normalised profile, so the motion is a straight line in joint space,
        within every axis' limits. ``"none"``: each axis at its own minimum
        time.
    duration : float, optional
        With ``"time"`` or ``"phase"``: stretch the motion to exactly this
        duration [s] (must be >= the synchronised minimum).

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
    # entries are checked per axis below (the messages name the axis)
    sl = float_list(start, "start")
    gl = float_list(goal, "goal")
    if len(sl) != len(gl):
        raise InvalidInputError(
            f"start has {len(sl)} axes but goal has {len(gl)}"
        )
    n = len(sl)
    if n == 0:
        raise InvalidInputError("start and goal must have at least one axis")
    lims = coerce_limits(limits, n)
    for lim in lims:
        check_limits_range(lim)
    check_positions(sl, lims, "start")
    check_positions(gl, lims, "goal")
    check_distances(sl, gl, lims)
    duration = check_duration(duration, sync)

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
