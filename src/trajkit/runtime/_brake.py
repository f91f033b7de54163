"""Closed-form minimum-time brake of one axis from a moving state to rest.

The kernel behind the controlled stop: from ``(p0, v0, a0)`` the axis
reaches ``v = a = 0`` as fast as its limits allow. Limit semantics follow
:class:`~trajkit.limits.AxisLimits`: while ``|v|`` grows (``v*a > 0``) the
accel leg (``a_max``, ``j_max``) applies, while it shrinks the decel leg
(``a_max_decel``, ``j_max_decel``). The velocity limit plays no part (a
brake only lowers ``|v|``), so an overspeeding axis can be stopped too.

Cases (``v0 >= 0`` after mirroring):

1. ``a0 > 0``: ramp the acceleration to 0 at ``-j_max`` (accel leg).
2. ``a0 < -a_max_decel`` (a state beyond the limit): ramp up to
   ``-a_max_decel`` at ``+j_max_decel``.
3. From ``a = -a1`` (``0 <= a1 <= a_max_decel``): ramp down to ``-ap`` at
   ``-j_max_decel``, hold ``-ap`` (only when ``ap = a_max_decel``), ramp back
   to 0 at ``+j_max_decel``; ``ap`` from the velocity left,
   ``(2 ap^2 - a1^2) / (2 J) + ap t_hold = v``.
4. Reversal: when even ramping straight back to ``a = 0`` removes more than
   the velocity left (``v < a1^2 / (2 j_max_decel)``), the axis must pass
   through zero velocity: ramp up to ``+ap`` at ``min(j_max, j_max_decel)``
   and back to 0 at ``-j_max_decel``. This case uses the smaller jerk for
   the whole rising ramp, so it is feasible but may be slightly slower than
   the true minimum.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..limits import AxisLimits
from ..profiles._pieces import eval_pieces
from ..profiles.profile import ProfileSample

__all__ = ["BrakeProfile", "brake_phases", "brake_profile"]


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
        Constant-jerk phases; empty when already at rest.
    """
    sgn = -1.0 if (v0 < 0.0 or (v0 == 0.0 and a0 < 0.0)) else 1.0
    v, a = sgn * v0, sgn * a0
    out: list[tuple[float, float]] = []
    if v == 0.0 and a == 0.0:
        return out
    if a > 0.0:  # case 1: still speeding up
        if math.isfinite(j_max):
            t = a / j_max
            out.append((t, -j_max))
            v += 0.5 * a * t
        a = 0.0
    if a < -a_dec:  # case 2: beyond the decel limit
        if math.isfinite(j_dec):
            t = (-a_dec - a) / j_dec
            out.append((t, j_dec))
            v += t * (a + 0.5 * j_dec * t)
        a = -a_dec
    a1 = -a
    if math.isinf(j_dec):  # trapezoidal: the acceleration jumps to -a_dec
        out.append((v / a_dec, 0.0))
        return [(dt, sgn * j) for dt, j in out if dt > 0.0]
    back = a1 * a1 / (2.0 * j_dec)
    if v >= back:  # case 3
        full = (2.0 * a_dec * a_dec - a1 * a1) / (2.0 * j_dec) if math.isfinite(a_dec) else math.inf
        if v >= full:
            ap = a_dec
            th = (v - full) / a_dec
        else:
            ap = math.sqrt(max(j_dec * v + 0.5 * a1 * a1, a1 * a1))
            th = 0.0
        out.append(((ap - a1) / j_dec, -j_dec))
        out.append((th, 0.0))
        out.append((ap / j_dec, j_dec))
    else:  # case 4: reversal through zero velocity
        j1 = min(j_max, j_dec)
        ap = math.sqrt((a1 * a1 / j1 - 2.0 * v) / (1.0 / j1 + 1.0 / j_dec))
        out.append(((ap + a1) / j1, j1))
        out.append((ap / j_dec, -j_dec))
    return [(dt, sgn * j) for dt, j in out if dt > 0.0]


def _integrate(phases, p, v, a):
    for dt, j in phases:
        p = p + dt * (v + dt * (0.5 * a + dt * j / 6.0))
        v = v + dt * (a + 0.5 * dt * j)
        a = a + dt * j
    return p, v, a


class BrakeProfile:
    """Minimum-time brake of one axis to rest (see :func:`brake_profile`).

    Attributes
    ----------
    start_state : tuple of 3 float
        ``(p0 [unit], v0 [unit/s], a0 [unit/s^2])``.
    phase_durations, jerks : tuple of float
        The constant-jerk phases [s], [unit/s^3].
    duration : float
        Time to rest [s].
    stop_position : float
        Where the axis comes to rest [unit].
    """

    __slots__ = (
        "_A",
        "_J",
        "_P",
        "_V",
        "_tb",
        "duration",
        "jerks",
        "phase_durations",
        "start_state",
        "stop_position",
    )

    def __init__(self, start_state, phases):
        p, v, a = (float(x) for x in start_state)
        self.start_state = (p, v, a)
        self.phase_durations = tuple(float(d) for d, _ in phases)
        self.jerks = tuple(float(j) for _, j in phases)
        n = len(phases)
        self._tb = np.zeros(n + 1)
        self._P, self._V, self._A = np.empty(n), np.empty(n), np.empty(n)
        self._J = np.array(self.jerks, dtype=float)
        t = 0.0
        for k, (dt, j) in enumerate(phases):
            self._tb[k] = t
            self._P[k], self._V[k], self._A[k] = p, v, a
            p, v, a = _integrate([(dt, j)], p, v, a)
            t += dt
        self._tb[n] = t
        self.duration = t
        self.stop_position = p

    def sample(self, t: Any) -> ProfileSample:
        """Exact state at times ``t`` [s] (array_like, shape (n,)); rest after the end.

        Before 0 the start state is returned.
        """
        tt = np.asarray(t, dtype=np.float64)
        n = self._J.size
        if n == 0:
            p0, v0, a0 = self.start_state
            z = np.zeros_like(tt)
            return ProfileSample(z + p0, z + v0 * (tt < 0), z + a0 * (tt < 0), z)
        tc = np.clip(tt, 0.0, self.duration)
        pos, vel, acc, j = eval_pieces(tc, self._tb, self._P, self._V, self._A, self._J)
        after = tt >= self.duration
        before = tt < 0.0
        p0, v0, a0 = self.start_state
        pos = np.where(after, self.stop_position, np.where(before, p0, pos))
        vel = np.where(after, 0.0, np.where(before, v0, vel))
        acc = np.where(after, 0.0, np.where(before, a0, acc))
        jer = np.where(after | before, 0.0, j)
        return ProfileSample(pos, vel, acc, jer)

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
    from .._validate import check_finite

    p = check_finite(position, "position", limits.name)
    v = check_finite(velocity, "velocity", limits.name)
    a = check_finite(acceleration, "acceleration", limits.name)
    ph = brake_phases(v, a, limits.a_max, limits.j_max, limits.a_max_decel, limits.j_max_decel)
    return BrakeProfile((p, v, a), ph)


def stop_position(position: float, velocity: float, acceleration: float,
                  limits: AxisLimits) -> float:
    """Where the minimum-time brake from this state ends [unit] (no validation)."""
    ph = brake_phases(velocity, acceleration, limits.a_max, limits.j_max,
                      limits.a_max_decel, limits.j_max_decel)
    return _integrate(ph, position, velocity, acceleration)[0]
