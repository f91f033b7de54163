"""Minimum-time brake of one axis from a moving state to rest (the controlled stop).

The runtime's stop uses the one state-to-state kernel of
:mod:`trajkit.profiles` (velocity interface, goal ``v = a = 0``, position
free) with the velocity limit left out: a brake only lowers ``|v|``, so an
overspeeding axis is stopped straight away. Limit semantics follow
:class:`~trajkit.limits.AxisLimits`: while ``|v|`` grows (``v*a > 0``) the
accel leg (``a_max``, ``j_max``) applies, while it shrinks the decel leg
(``a_max_decel``, ``j_max_decel``), including the exact leg change when the
velocity passes through zero (a reversal). An acceleration beyond its limit
is first brought back within it (the brake pre-phase of the kernel).
"""

from __future__ import annotations

import math
import threading
from typing import Any

from .._validate import check_finite
from ..limits import AxisLimits
from ..profiles import _kernel as K
from ..profiles._compile import ENABLED as _COMPILED
from ..profiles._phase import phase_end
from ..profiles.motion import JerkMotion

__all__ = ["BrakeProfile", "brake_phases", "brake_profile", "stop_position"]

_local = threading.local()


def _stop_table(v0: float, a0: float, a_max: float, j_max: float, a_dec: float,
                j_dec: float, with_nb: bool = False):
    """Phases ``[(dt, j, a_start), ...]`` of the minimum-time stop (kernel);
    with ``with_nb`` also the number of its brake pre-phases (an acceleration
    beyond its limit brought back first)."""
    if v0 == 0.0 and a0 == 0.0:
        return ([], 0) if with_nb else []
    ws = getattr(_local, "ws", None)
    if ws is None:
        ws = _local.ws = K.workspace()
    ws[0] = 0.0
    ws[1] = v0
    ws[2] = a0
    ws[3] = math.nan
    ws[4] = 0.0
    ws[5] = 0.0
    ws[6] = math.inf
    ws[7] = a_max
    ws[8] = j_max
    ws[9] = a_dec
    ws[10] = j_dec
    ws[K.IN_TASK] = K.TASK_VELOCITY
    if _COMPILED:
        K.solve(ws)
    else:
        import numpy as np

        with np.errstate(all="ignore"):
            K.solve(ws)
    if int(ws[K.OUT_STATUS]) != K.ST_OK:  # pragma: no cover - the stop always exists
        raise ArithmeticError(f"internal: no stop from velocity {v0!r}, acceleration {a0!r}")
    n = int(ws[K.OUT_N])
    flat = ws[K.OUT_PH:K.OUT_PH + 3 * n].tolist()
    out = list(zip(flat[0::3], flat[1::3], flat[2::3]))
    return (out, int(ws[K.OUT_NB])) if with_nb else out


def brake_phases(v0: float, a0: float, a_max: float, j_max: float,
                 a_dec: float, j_dec: float) -> list[tuple[float, float]]:
    """Phases ``[(duration [s], jerk [unit/s^3]), ...]`` of the minimum-time brake.

    Parameters
    ----------
    v0, a0 : float
        Start velocity [unit/s] and acceleration [unit/s^2].
    a_max, j_max : float
        Accel-leg limits (``|v|`` growing); ``inf`` allowed for one of them.
    a_dec, j_dec : float
        Decel-leg limits (``|v|`` shrinking).

    Returns
    -------
    list of (float, float)
        Constant-jerk phases; empty when already at rest. (With an infinite
        jerk limit the acceleration jumps between phases: use
        :func:`brake_profile`, whose table carries the start accelerations.)
    """
    return [(dt, j) for dt, j, _ in _stop_table(v0, a0, a_max, j_max, a_dec, j_dec)]


class BrakeProfile(JerkMotion):
    """Minimum-time brake of one axis to rest (see :func:`brake_profile`).

    A :class:`~trajkit.profiles.motion.JerkMotion` from the start state to
    ``(stop_position, 0, 0)``; after the end it rests there.

    Attributes
    ----------
    start_state : tuple of 3 float
        ``(p0 [unit], v0 [unit/s], a0 [unit/s^2])``.
    phase_durations, jerks, phase_accelerations : tuple of float
        The constant-jerk phases [s], [unit/s^3], [unit/s^2].
    duration : float
        Time to rest [s].
    stop_position : float
        Where the axis comes to rest [unit].
    limits : AxisLimits or None
        The limits it was planned for (checked by :func:`trajkit.verify.verify_motion`).
    n_brake_phases : int
        Leading phases that bring an acceleration beyond its limit back
        within it (exempt from the limits, as in a StateProfile).
    """

    __slots__ = ("stop_position", "limits", "n_brake_phases")

    def __init__(self, start_state: Any, phases: Any, limits: AxisLimits | None = None,
                 n_brake_phases: int = 0) -> None:
        ph = [tuple(p) for p in phases]
        acc = [p[2] for p in ph] if ph and len(ph[0]) > 2 else None
        m = JerkMotion(start_state, [p[0] for p in ph], [p[1] for p in ph], acc)
        super().__init__(start_state, m.phase_durations, m.jerks, m.phase_accelerations,
                         (m.end_state[0], 0.0, 0.0))
        self.stop_position = self.end_state[0]
        self.limits = limits
        self.n_brake_phases = int(n_brake_phases)

    def __repr__(self) -> str:
        return (f"BrakeProfile(start_state={self.start_state!r}, duration={self.duration!r}, "
                f"stop_position={self.stop_position!r})")


def brake_profile(position: float, velocity: float, acceleration: float,
                  limits: AxisLimits) -> BrakeProfile:
    """Plan the minimum-time brake of one axis from a moving state to rest.

    Parameters
    ----------
    position : float
        Current position [unit].
    velocity : float
        Current velocity [unit/s] (may exceed ``v_max``: overspeed stop).
    acceleration : float
        Current acceleration [unit/s^2] (may exceed the limits: it is first
        brought back within them).
    limits : AxisLimits
        Accel/decel acceleration and jerk limits of the axis.

    Returns
    -------
    BrakeProfile

    Raises
    ------
    InvalidInputError
        A non-finite state value (the message names the field and the axis).
    """
    p = check_finite(position, "position", limits.name)
    v = check_finite(velocity, "velocity", limits.name)
    a = check_finite(acceleration, "acceleration", limits.name)
    ph, nb = _stop_table(v, a, limits.a_max, limits.j_max, limits.a_max_decel, limits.j_max_decel,
                         with_nb=True)
    return BrakeProfile((p, v, a), ph, limits, nb)


def stop_position(position: float, velocity: float, acceleration: float,
                  limits: AxisLimits) -> float:
    """Where the minimum-time brake from this state ends [unit] (no validation)."""
    ph = _stop_table(velocity, acceleration, limits.a_max, limits.j_max,
                     limits.a_max_decel, limits.j_max_decel)
    p, v = position, velocity
    for dt, j, a in ph:
        p, v, _ = phase_end(p, v, a, j, dt)
    return p
