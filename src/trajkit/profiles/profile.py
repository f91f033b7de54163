"""One-axis rest-to-rest profiles: :class:`Profile` and :func:`plan_move`."""

from __future__ import annotations

import math
from typing import Any

from .._constants import DURATION_RTOL, PHASE_EPS, REACHED_RTOL
from .._validate import axis_label
from ..errors import InfeasibleError, InvalidInputError
from ..limits import AxisLimits
from . import _scalar as K
from ._range import (
    check_distance_range,
    check_duration_range,
    check_limits_range,
    check_position_range,
    check_rest_cruise,
    check_rest_duration_ratio,
)
from .motion import JerkMotion, ProfileSample

__all__ = ["Profile", "ProfileSample", "plan_move", "PHASE_NAMES"]

#: Names of the seven phases, in order.
PHASE_NAMES = (
    "jerk_up",        # accel leg: jerk +J1 (acceleration builds up)
    "const_accel",    # accel leg: constant acceleration A1
    "jerk_down",      # accel leg: jerk -J1 (acceleration back to zero)
    "cruise",         # constant velocity
    "decel_jerk_in",  # decel leg: jerk -J2
    "const_decel",    # decel leg: constant deceleration A2
    "decel_jerk_out", # decel leg: jerk +J2
)


class Profile(JerkMotion):
    """A rest-to-rest, piecewise-constant-jerk profile of one axis.

    Build it with :func:`plan_move`. Seven phases (some may last zero): jerk
    up, constant acceleration, jerk down, cruise, then the same mirrored for
    the deceleration leg (with its own jerk and acceleration). It is a
    :class:`~trajkit.profiles.motion.JerkMotion` (sampling, extrema, phase
    table) from ``(start, 0, 0)`` to ``(goal, 0, 0)``.

    Attributes
    ----------
    start, goal : float
        Start and goal position [unit].
    duration : float
        Total duration [s].
    min_duration : float
        Minimum duration of this move under its limits [s]; equals
        ``duration`` unless a longer duration was requested.
    phase_durations : tuple of 7 float
        Duration of each phase [s] (see :data:`PHASE_NAMES`).
    jerks : tuple of 7 float
        Constant jerk in each phase [unit/s^3] (signed; zero for a phase of
        zero duration and for the infinite-jerk legs of a trapezoid).
    phase_accelerations : tuple of 7 float
        Acceleration entering each phase [unit/s^2] (it jumps only on a
        trapezoidal leg).
    peak_velocity : float
        Largest speed reached, signed with the direction [unit/s].
    peak_acceleration, peak_deceleration : float
        Largest |acceleration| in the accel leg and the decel leg [unit/s^2].
    limits : AxisLimits
        The limits the profile was planned under.
    """

    __slots__ = (
        "start", "goal", "min_duration", "peak_velocity", "peak_acceleration",
        "peak_deceleration", "limits",
    )

    def __init__(
        self,
        start: float,
        goal: float,
        duration: float,
        min_duration: float,
        phase_durations: tuple[float, ...],
        jerks: tuple[float, ...],
        peak_velocity: float,
        peak_acceleration: float,
        peak_deceleration: float,
        limits: AxisLimits,
    ) -> None:
        s = 1.0 if goal > start else (-1.0 if goal < start else 0.0)
        a1 = s * peak_acceleration
        a2 = -s * peak_deceleration
        self.start_state = (start, 0.0, 0.0)
        self.phase_durations = phase_durations
        self.jerks = jerks
        self.phase_accelerations = (0.0, a1, a1, 0.0, 0.0, a2, a2)
        self.duration = duration
        self._end = (goal, 0.0, 0.0)
        self._tab = None
        self.start = start
        self.goal = goal
        self.min_duration = min_duration
        self.peak_velocity = peak_velocity
        self.peak_acceleration = peak_acceleration
        self.peak_deceleration = peak_deceleration
        self.limits = limits

    # ------------------------------------------------------------------ info
    @property
    def distance(self) -> float:
        """Signed displacement ``goal - start`` [unit]."""
        return self.goal - self.start

    @property
    def direction(self) -> float:
        """+1.0, -1.0, or 0.0 for a zero move."""
        d = self.goal - self.start
        return 1.0 if d > 0 else (-1.0 if d < 0 else 0.0)

    @property
    def reached(self) -> frozenset[str]:
        """Names of the limits that the profile reaches (its shape).

        A subset of ``{"v_max", "a_max", "a_max_decel"}``: ``"v_max"`` when
        it cruises at the velocity limit, ``"a_max"`` / ``"a_max_decel"`` when
        the accel / decel leg has a constant-acceleration phase at its limit.
        """
        out = set()
        lim = self.limits
        tol = 1.0 - REACHED_RTOL
        if self.phase_durations[3] > 0.0 and abs(self.peak_velocity) >= lim.v_max * tol:
            out.add("v_max")
        if self.peak_acceleration >= lim.a_max * tol:
            out.add("a_max")
        if self.peak_deceleration >= lim.a_max_decel * tol:
            out.add("a_max_decel")
        return frozenset(out)

    @property
    def shape(self) -> str:
        """Short name of the profile shape, e.g. ``"7-phase"`` or ``"no-cruise"``.

        One of ``"zero"`` (no motion), ``"7-phase"`` (every phase present),
        or the phases that are absent joined by ``+``:
        ``"no-cruise"``, ``"no-const-accel"``, ``"no-const-decel"``, and
        combinations like ``"no-const-accel+no-const-decel+no-cruise"``.
        A leg without jerk phases (infinite jerk limit: the acceleration
        jumps) is named instead: ``"trapezoid"`` when both legs are
        jerk-free (``"trapezoid+no-cruise"`` for the triangle), else
        ``"jerk-free-accel"`` / ``"jerk-free-decel"`` joined to the rest.
        """
        if self.goal == self.start:
            return "zero"
        eps = PHASE_EPS * self.duration
        t = self.phase_durations
        free1 = t[0] <= eps and t[1] > eps
        free2 = t[4] <= eps and t[5] > eps
        parts = []
        if free1 and free2:
            parts.append("trapezoid")
        else:
            if free1:
                parts.append("jerk-free-accel")
            elif t[1] <= eps:
                parts.append("no-const-accel")
            if free2:
                parts.append("jerk-free-decel")
            elif t[5] <= eps:
                parts.append("no-const-decel")
        if t[3] <= eps:
            parts.append("no-cruise")
        return "+".join(parts) if parts else "7-phase"

    def to_dict(self) -> dict:
        """JSON-ready summary (SI / axis units)."""
        return {
            "start": self.start,
            "goal": self.goal,
            "duration_s": self.duration,
            "min_duration_s": self.min_duration,
            "shape": self.shape,
            "reached": sorted(self.reached),
            "peak_velocity": self.peak_velocity,
            "peak_acceleration": self.peak_acceleration,
            "peak_deceleration": self.peak_deceleration,
            "phases": [
                {"name": n, "duration_s": d, "jerk": j}
                for n, d, j in zip(PHASE_NAMES, self.phase_durations, self.jerks)
            ],
        }

    def __repr__(self) -> str:
        return (
            f"Profile(start={self.start!r}, goal={self.goal!r}, duration={self.duration!r}, "
            f"shape={self.shape!r})"
        )


def _build(start, goal, limits, d, vc, duration, min_duration, sign):
    a1, j1 = limits.a_max, limits.j_max
    a2, j2 = limits.a_max_decel, limits.j_max_decel
    thr1, thr2 = limits._thresholds
    tj1, ta1, ap1 = K.leg_phases(vc, a1, j1, thr1)
    tj2, ta2, ap2 = K.leg_phases(vc, a2, j2, thr2)
    ramps = 2.0 * tj1 + ta1 + 2.0 * tj2 + ta2
    if duration is None:
        tv = (d - 0.5 * vc * (2.0 * tj1 + ta1 + 2.0 * tj2 + ta2)) / vc if vc > 0.0 else 0.0
        if tv < 0.0:
            tv = 0.0
        duration = ramps + tv
    else:
        tv = duration - ramps
        if tv < 0.0:
            tv = 0.0
    jj1 = sign * j1 if tj1 > 0.0 else 0.0
    jj2 = sign * j2 if tj2 > 0.0 else 0.0
    return Profile(
        start, goal, duration, min_duration if min_duration is not None else duration,
        (tj1, ta1, tj1, tv, tj2, ta2, tj2),
        (jj1, 0.0, -jj1, 0.0, -jj2, 0.0, jj2),
        sign * vc, ap1, ap2, limits,
    )


def min_duration(distance: float, limits: AxisLimits) -> float:
    """Minimum duration [s] of a rest-to-rest move over ``distance`` [unit].

    The same value as ``plan_move(0.0, distance, limits).duration``; inputs
    outside the supported range (:mod:`trajkit.profiles._range`) raise
    :class:`~trajkit.errors.InvalidInputError`.
    """
    _check_rest_limits(limits)
    try:
        d = float(distance)
    except (TypeError, ValueError):
        raise InvalidInputError(
            f"distance{axis_label(limits.name)} must be a number, got {distance!r}") from None
    if not math.isfinite(d):
        raise InvalidInputError(f"distance{axis_label(limits.name)} must be finite, got {d!r}")
    check_position_range(0.5 * d, "distance / 2", limits.name, states=False)
    check_distance_range(0.0, d, limits.name)
    d = abs(d)
    if d == 0.0:
        return 0.0
    return _min_solution(d, limits)[1]


def _check_rest_limits(limits: Any) -> None:
    if not isinstance(limits, AxisLimits):
        raise InvalidInputError(
            f"limits must be an AxisLimits, got {type(limits).__name__}"
        )
    check_limits_range(limits)


def plan_move(
    start: float, goal: float, limits: AxisLimits, duration: float | None = None
) -> Profile:
    """Plan a rest-to-rest, jerk-limited move of one axis.

    With ``duration=None`` the profile is time-optimal: it reaches the
    velocity limit if the distance allows (7 phases), else the highest peak
    velocity the distance allows, with or without constant-acceleration
    phases in either leg (seeds 000 and 001; asymmetric limits supported).
    With ``duration=T`` the cruise velocity is lowered so that the profile
    lasts exactly ``T`` while keeping every limit.

    Parameters
    ----------
    start, goal : float
        Positions [unit]; must be finite and inside the limits' range.
    limits : AxisLimits
        Velocity, acceleration and jerk limits (accel and decel legs).
    duration : float, optional
        Requested duration [s] (>= the minimum duration). A request below
        the minimum by less than ``DURATION_RTOL`` (relative; float
        round-off, e.g. a minimum printed and typed back) is taken as the
        minimum, and the profile then lasts the minimum duration.

    Returns
    -------
    Profile

    Raises
    ------
    InvalidInputError
        NaN/inf positions, positions outside the range, a bad duration.
    InfeasibleError
        ``duration`` below the minimum duration (the message and
        ``error.minimum`` give the minimum).

    Examples
    --------
    >>> from trajkit import AxisLimits, plan_move
    >>> p = plan_move(0.0, 1.0, AxisLimits(v_max=1.0, a_max=2.0, j_max=10.0))
    >>> round(p.duration, 6)
    1.7
    """
    _check_rest_limits(limits)
    s = limits.check_position(start, "start")
    g = limits.check_position(goal, "goal")
    check_position_range(s, "start", limits.name, states=False)
    check_position_range(g, "goal", limits.name, states=False)
    check_distance_range(s, g, limits.name)
    if duration is not None:
        try:
            T = float(duration)
        except (TypeError, ValueError):
            raise InvalidInputError(f"duration must be a number of seconds, got {duration!r}") from None
        if not math.isfinite(T) or T < 0.0:
            raise InvalidInputError(
                f"duration{axis_label(limits.name)} must be finite and >= 0 s, got {T!r}"
            )
        check_duration_range(T, limits.name, states=False)
    return _plan_unchecked(s, g, limits, duration if duration is None else T)


def _min_solution(d: float, limits: AxisLimits) -> tuple[float, float]:
    """Step 1 for a distance ``d > 0``: ``(peak velocity, minimum duration)``."""
    a1, j1, a2, j2 = limits.a_max, limits.j_max, limits.a_max_decel, limits.j_max_decel
    thr1, thr2 = limits._thresholds
    vp = K.peak_velocity(d, limits.v_max, a1, j1, a2, j2, thr1, thr2)
    tmin = K._lt(vp, a1, j1, thr1) + K._lt(vp, a2, j2, thr2)
    if vp == limits.v_max:
        tmin += max(d - 0.5 * vp * tmin, 0.0) / vp
    return vp, tmin


def _plan_solved(
    s: float, g: float, limits: AxisLimits, vp: float, tmin: float, T: float | None,
    axis: str | int | None = None,
) -> Profile:
    """Step 2: the profile of a move whose step-1 solution ``(vp, tmin)`` is known."""
    d = g - s
    sign = 1.0 if d > 0 else -1.0
    d = abs(d)
    if T is None or T <= tmin:
        if T is not None and T < tmin * (1.0 - DURATION_RTOL):
            raise InfeasibleError(
                f"duration {T!r} s{axis_label(limits.name if axis is None else axis)} is below "
                f"the minimum duration {tmin:.15g} s for a move of distance {d!r}",
                minimum=tmin,
            )
        return _build(s, g, limits, d, vp, tmin, tmin, sign)
    check_rest_duration_ratio(T, tmin, limits.name if axis is None else axis)
    a1, j1, a2, j2 = limits.a_max, limits.j_max, limits.a_max_decel, limits.j_max_decel
    thr1, thr2 = limits._thresholds
    vc = K.cruise_velocity(d, T, vp, a1, j1, a2, j2, thr1, thr2)
    check_rest_cruise(vc, T, limits, limits.name if axis is None else axis)
    return _build(s, g, limits, d, vc, T, tmin, sign)


def _rest_profile(s: float, limits: AxisLimits, T: float | None) -> Profile:
    """A zero move that holds ``s`` for ``T`` seconds (0 when None)."""
    dur = 0.0 if T is None else T
    return Profile(s, s, dur, 0.0, (0.0, 0.0, 0.0, dur, 0.0, 0.0, 0.0),
                   (0.0,) * 7, 0.0, 0.0, 0.0, limits)


def _plan_unchecked(s: float, g: float, limits: AxisLimits, T: float | None) -> Profile:
    if g == s:
        return _rest_profile(s, limits, T)
    vp, tmin = _min_solution(abs(g - s), limits)
    return _plan_solved(s, g, limits, vp, tmin, T)
