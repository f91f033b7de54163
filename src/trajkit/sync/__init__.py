"""Many axes: synchronised point-to-point moves, at rest or between moving states.

:func:`plan_ptp` is the one entry point. The form of ``start`` / ``goal``
says which problem it is -- nothing switches silently on the values:

* shape ``(n_axes,)``: positions at rest; the axes are rest-to-rest
  :class:`~trajkit.profiles.Profile` objects (closed form, :mod:`.rest`);
* shape ``(n_axes, 3)``: states ``(position, velocity, acceleration)``; the
  axes are :class:`~trajkit.profiles.StateProfile` objects
  (:func:`plan_ptp_states`, :mod:`.states`), also when every velocity is 0.

The keywords ``start_velocity`` ... ``goal_acceleration`` of earlier
versions still work: given (even as zeros) they build the states and select
the state planner.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .._validate import check_array
from ..errors import InvalidInputError
from ..limits import AxisLimits
from ..trajectory import SYNC_MODES, Trajectory
from .rest import plan_ptp_rest
from .states import STATE_SYNC_MODES, plan_ptp_states

__all__ = ["plan_ptp", "plan_ptp_rest", "plan_ptp_states", "SYNC_MODES", "STATE_SYNC_MODES"]


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
    start, goal : array_like, shape (n_axes,) or (n_axes, 3)
        Positions at rest [axis unit], or states ``(position [unit], velocity
        [unit/s], acceleration [unit/s^2])`` per axis (see the module text).
    limits : AxisLimits or sequence of n_axes AxisLimits
        One set of limits for every axis, or one per axis.
    sync : {"time", "phase", "none"}
        ``"time"``: every axis starts and arrives together at the slowest
        axis' minimum time (between states: moved past blocked intervals),
        each keeping its own limits. ``"phase"``: one normalised profile for
        every axis, a straight line in joint space (between states only when
        they are collinear with the displacement, else ``"time"``).
        ``"none"``: each axis at its own minimum time.
    duration : float, optional
        With ``"time"`` or ``"phase"``: exactly this duration [s].
    start_velocity, start_acceleration, goal_velocity, goal_acceleration : array_like, shape (n_axes,), optional
        Compatibility keywords: when any is given, ``start`` / ``goal`` are
        positions and these complete the states (missing ones are zero);
        the state planner is used.

    Returns
    -------
    Trajectory

    Raises
    ------
    InvalidInputError
        NaN/inf, mismatched axis counts, values outside the supported range
        or an axis' position range, an unknown ``sync``.
    InfeasibleError
        ``duration`` below the minimum (or in a blocked interval).
    """
    rates = (start_velocity, start_acceleration, goal_velocity, goal_acceleration)
    if any(x is not None for x in rates):
        s = check_array(start, "start", ndim=1, finite=False)
        g = check_array(goal, "goal", ndim=1, finite=False)
        if g.size != s.size:
            raise InvalidInputError(f"start has {s.size} axes but goal has {g.size}")
        cols = []
        for value, field in zip(rates, ("start_velocity", "start_acceleration",
                                        "goal_velocity", "goal_acceleration")):
            cols.append(np.zeros(s.size) if value is None else
                        check_array(value, field, ndim=1, size=s.size))
        return plan_ptp_states(np.column_stack([s, cols[0], cols[1]]),
                               np.column_stack([g, cols[2], cols[3]]), limits, sync, duration)
    if np.ndim(start) == 2 or np.ndim(goal) == 2:
        return plan_ptp_states(start, goal, limits, sync, duration)
    return plan_ptp_rest(start, goal, limits, sync, duration)
