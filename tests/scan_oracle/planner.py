"""The retired scan planner (oracle of the tests; see ``kernel.py``).

Original text: one-axis profiles between arbitrary states (position, velocity, acceleration).

:func:`plan_state_to_state` plans the minimum-time, jerk-limited motion from
a moving start state to a moving goal state (ruckig's problem, with
trajkit's asymmetric limits), or one of exactly a requested duration;
:func:`plan_velocity` reaches a velocity and acceleration with the position
free (jogging, feed override, controlled stop). Both return a
:class:`StateProfile`, which samples like :class:`~trajkit.profiles.Profile`.

Limit semantics (see :class:`~trajkit.limits.AxisLimits`): while ``|v|``
grows (``v*a > 0``, or ``v = 0``) the accel leg's ``a_max`` / ``j_max``
apply, while ``|v|`` shrinks (``v*a < 0``) the decel leg's ``a_max_decel`` /
``j_max_decel``; ``|v| <= v_max`` always. The method and its limits are
described in ``docs/state-profiles.md``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from trajkit._constants import DURATION_RTOL
from trajkit._validate import axis_label, check_finite
from trajkit.errors import InfeasibleError, InvalidInputError
from trajkit.limits import AxisLimits
from trajkit.profiles._phase import phase_eval
from trajkit.profiles.motion import ProfileSample

from . import kernel as K


def eval_pieces(tc, tb, P, V, A, J):
    n = J.size
    idx = np.searchsorted(tb[1:n], tc, side="right")
    dt = tc - tb[idx]
    pos, vel, acc = phase_eval(P[idx], V[idx], A[idx], J[idx], dt)
    return pos, vel, acc, J[idx]

__all__ = [
    "BlockedDurationError",
    "StateProfile",
    "min_state_duration",
    "plan_state_to_state",
    "plan_velocity",
]

#: Relative precision of the upper end of a blocked duration interval (the
#: next feasible duration; the value returned is itself feasible).
BLOCKED_SEARCH_RTOL = 1e-9

#: Relative precision of the upper end where only the slow F2-with-hold
#: family reaches the feasible durations next to it.
BLOCKED_HOLD_RTOL = 1e-4

#: Relative precision of the lower end of a blocked interval (informative).
BLOCKED_LOWER_RTOL = 1e-6

#: Maximum rounds of the brake pre-phase (each removes one kind of excess).
BRAKE_MAX_ROUNDS = 6

#: Maximum doublings when searching for the end of a blocked interval.
BLOCKED_SEARCH_MAX = 80


class BlockedDurationError(InfeasibleError):
    """A requested duration lies in a blocked interval of a state-to-state move.

    Between moving states the set of feasible durations is not always
    ``[T_min, inf)``: e.g. an axis moving fast away from its goal can arrive
    at ``T_min`` by turning back at once, but cannot arrive a little later
    without violating a limit, yet can again with a longer detour.

    Attributes
    ----------
    minimum : float
        The minimum duration [s].
    interval : tuple of float
        ``(lower, upper)`` [s]: the blocked interval containing the request,
        with ``upper`` the next feasible duration (to ``BLOCKED_SEARCH_RTOL``).
    """

    def __init__(self, message: str, minimum: float, interval: tuple[float, float]):
        super().__init__(message, minimum=minimum)
        self.interval = interval


class StateProfile:
    """A piecewise-constant-jerk profile of one axis between two states.

    Built by :func:`plan_state_to_state` or :func:`plan_velocity`.

    Attributes
    ----------
    start_state, goal_state : tuple of 3 float
        ``(position [unit], velocity [unit/s], acceleration [unit/s^2])`` at
        ``t = 0`` and ``t = duration``. For :func:`plan_velocity` the goal
        position is where the profile ends.
    start, goal : float
        Start and goal positions [unit] (as on :class:`Profile`).
    duration : float
        Total duration [s], including any brake pre-phase.
    min_duration : float
        Minimum duration of this motion [s] (``duration`` unless a longer one
        was requested).
    brake_duration : float
        Length of the brake pre-phase [s] (0 when the start state is within
        the limits). The first ``n_brake_phases`` phases form it.
    n_brake_phases : int
        Number of phases of the brake pre-phase.
    phase_durations : tuple of float
        Duration of each phase [s] (their number varies with the shape).
    jerks : tuple of float
        Constant jerk of each phase [unit/s^3].
    phase_accelerations : tuple of float
        Acceleration at the start of each phase [unit/s^2] (continuous unless
        a jerk limit is infinite).
    family : str
        Which profile family won: ``"F1"`` (two acceleration bumps through a
        velocity extremum), ``"F1-cruise"`` (with a cruise at ``+-v_max``),
        ``"F2"`` (a bump and a ramp through an acceleration extremum),
        ``"fixed"`` / ``"fixed-blend"`` (fixed duration), ``"velocity"``
        (:func:`plan_velocity`), ``"none"`` (already at the goal).
    limits : AxisLimits
    """

    __slots__ = (
        "_A",
        "_J",
        "_P",
        "_V",
        "_tb",
        "brake_duration",
        "duration",
        "family",
        "goal_state",
        "jerks",
        "limits",
        "min_duration",
        "n_brake_phases",
        "phase_accelerations",
        "phase_durations",
        "start_state",
    )

    def __init__(self, start_state, goal_state, phases, min_duration, n_brake_phases,
                 family, limits):
        self.start_state = tuple(float(x) for x in start_state)
        self.goal_state = tuple(float(x) for x in goal_state)
        self.phase_durations = tuple(float(p[0]) for p in phases)
        self.jerks = tuple(float(p[1]) for p in phases)
        self.phase_accelerations = tuple(float(p[2]) for p in phases)
        self.n_brake_phases = int(n_brake_phases)
        self.brake_duration = float(sum(self.phase_durations[:n_brake_phases]))
        self.duration = float(sum(self.phase_durations))
        self.min_duration = float(min_duration)
        self.family = family
        self.limits = limits
        n = len(phases)
        tb = np.empty(n + 1)
        P = np.empty(n)
        Vv = np.empty(n)
        p, v, _ = self.start_state
        t = 0.0
        for k, (dt, j, a) in enumerate(phases):
            tb[k] = t
            P[k], Vv[k] = p, v
            p = p + dt * (v + dt * (0.5 * a + dt * j / 6.0))
            v = v + dt * (a + 0.5 * dt * j)
            t += dt
        tb[n] = self.duration
        self._tb = tb
        self._P = P
        self._V = Vv
        self._A = np.array(self.phase_accelerations, dtype=float)
        self._J = np.array(self.jerks, dtype=float)

    # ------------------------------------------------------------------ info
    @property
    def start(self) -> float:
        """Start position [unit]."""
        return self.start_state[0]

    @property
    def goal(self) -> float:
        """Goal position [unit]."""
        return self.goal_state[0]

    @property
    def n_phases(self) -> int:
        return len(self.phase_durations)

    @property
    def phase_times(self) -> np.ndarray:
        """Phase boundary times, shape (n_phases + 1,) [s]."""
        return self._tb.copy()

    def boundary_states(self) -> np.ndarray:
        """Exact state at every phase boundary.

        Returns
        -------
        ndarray, shape (n_phases + 1, 3)
            Position, velocity, acceleration at each boundary time (the
            acceleration is the value entering the next phase); the last row
            is the goal state.
        """
        n = self.n_phases
        out = np.empty((n + 1, 3))
        out[:n, 0] = self._P
        out[:n, 1] = self._V
        out[:n, 2] = self._A
        out[n] = self.goal_state
        return out

    # -------------------------------------------------------------- sampling
    def sample(self, t: Any) -> ProfileSample:
        """Evaluate the profile at time(s) ``t`` [s] by exact integration.

        Parameters
        ----------
        t : float or array_like, shape (n,)
            Times [s]. Before 0 the start state is held (its position,
            velocity and acceleration, jerk 0); after ``duration`` the goal
            state is continued at constant goal acceleration
            (``p = pf + vf dt + af dt^2/2``, ``v = vf + af dt``, ``a = af``,
            jerk 0), which is what an axis does when the next segment is late.

        Returns
        -------
        ProfileSample
            Arrays shaped like ``t``.
        """
        tt = np.asarray(t, dtype=np.float64)
        n = self.n_phases
        pf, vf, af = self.goal_state
        if n == 0:
            dt = np.maximum(tt, 0.0)
            p0, v0, a0 = self.start_state
            return ProfileSample(
                np.where(tt < 0, p0, pf + dt * (vf + 0.5 * af * dt)),
                np.where(tt < 0, v0, vf + af * dt),
                np.where(tt < 0, a0, af + 0 * dt),
                np.zeros_like(dt),
            )
        tc = np.clip(tt, 0.0, self.duration)
        pos, vel, acc, j = eval_pieces(tc, self._tb, self._P, self._V, self._A, self._J)
        after = tt >= self.duration
        before = tt < 0.0
        if np.any(after) or np.any(before):
            p0, v0, a0 = self.start_state
            da = np.where(after, tt - self.duration, 0.0)
            pos = np.where(after, pf + da * (vf + 0.5 * af * da), np.where(before, p0, pos))
            vel = np.where(after, vf + af * da, np.where(before, v0, vel))
            acc = np.where(after, af, np.where(before, a0, acc))
            j = np.where(after | before, 0.0, j)
        return ProfileSample(pos, vel, acc, j)

    def to_dict(self) -> dict:
        """JSON-ready summary (axis units)."""
        return {
            "start_state": list(self.start_state),
            "goal_state": list(self.goal_state),
            "start": self.start,
            "goal": self.goal,
            "duration_s": self.duration,
            "min_duration_s": self.min_duration,
            "brake_duration_s": self.brake_duration,
            "family": self.family,
            "phases": [
                {"duration_s": d, "jerk": j, "start_acceleration": a}
                for d, j, a in zip(self.phase_durations, self.jerks, self.phase_accelerations)
            ],
        }

    def __repr__(self) -> str:
        return (
            f"StateProfile(start_state={self.start_state!r}, goal_state={self.goal_state!r}, "
            f"duration={self.duration!r}, family={self.family!r})"
        )


# ------------------------------------------------------------ validation
def _limits_tuple(limits: AxisLimits):
    return (limits.v_max, limits.a_max, limits.j_max, limits.a_max_decel, limits.j_max_decel)


def _check_limits(limits: Any) -> AxisLimits:
    if not isinstance(limits, AxisLimits):
        raise InvalidInputError(f"limits must be an AxisLimits, got {type(limits).__name__}")
    return limits


def _check_state(state: Any, field: str, limits: AxisLimits, with_position: bool = True):
    n = 3 if with_position else 2
    try:
        vals = [x for x in state]
    except TypeError:
        raise InvalidInputError(
            f"{field}{axis_label(limits.name)} must be a sequence of {n} numbers "
            f"(position, velocity, acceleration), got {state!r}"
        ) from None
    if len(vals) != n:
        raise InvalidInputError(
            f"{field}{axis_label(limits.name)} must have {n} entries "
            f"(position, velocity, acceleration), got {len(vals)}"
        )
    names = ("position", "velocity", "acceleration")[3 - n:]
    out = [check_finite(x, f"{field} {nm}", limits.name) for x, nm in zip(vals, names)]
    if with_position:
        limits.check_position(out[0], f"{field} position")
    return tuple(out)


def _natural_velocity(v, a, L):
    """Velocity reached by ramping ``a`` to zero at once (regime jerks)."""
    s = 1.0 if v > 0.0 or (v == 0.0 and a > 0.0) else -1.0
    out: list = []
    dv, _ = K.ramp(s * a, 0.0, L[2], L[4], out)
    vn = v + s * dv
    if vn * s < 0.0:  # the ramp crosses v = 0: conservative jerk
        Jm = min(L[2], L[4])
        out = []
        dv, _ = K.ramp(s * a, 0.0, Jm, Jm, out)
        vn = v + s * dv
    return vn


def _start_violation(v, a, L) -> str | None:
    """Why the start state cannot be kept within the limits, or None."""
    V, A1, J1, A2, J2 = L
    tol = K.LIMIT_RTOL
    if abs(v) > V * (1.0 + tol):
        return f"|velocity| {abs(v)!r} is above v_max {V!r}"
    speeding = v * a > 0.0 or (v == 0.0 and a != 0.0)
    A = A1 if speeding else A2
    if abs(a) > A * (1.0 + tol):
        return (f"|acceleration| {abs(a)!r} is above "
                f"{'a_max' if speeding else 'a_max_decel'} {A!r}")
    vn = _natural_velocity(v, a, L)
    if abs(vn) > V * (1.0 + tol):
        return (f"the acceleration {a!r} carries the velocity to {vn!r}, past v_max {V!r}")
    if _reverses_too_hard(v, a, L):
        return (f"slowing down with |acceleration| {abs(a)!r}, the velocity {v!r} reverses "
                f"before the acceleration can drop to a_max {A1!r}")
    return None


def _reverses_too_hard(v, a, L):
    """Slowing down with |a| > a_max: does v reach 0 before |a| drops to a_max?"""
    V, A1, J1, A2, J2 = L
    if not (v * a < 0.0 and abs(a) > A1 * (1.0 + K.LIMIT_RTOL)):
        return False
    if J2 == math.inf:
        return False
    dv = (a * a - A1 * A1) / (2.0 * J2)  # |v| lost while |a| ramps down to A1
    return abs(v) < dv


def _goal_violation(v, a, L) -> str | None:
    """Why the goal state cannot be reached within the limits, or None."""
    V, A1, J1, A2, J2 = L
    tol = K.LIMIT_RTOL
    if abs(v) > V * (1.0 + tol):
        return f"|velocity| {abs(v)!r} is above v_max {V!r}"
    speeding = v * a > 0.0
    A = A1 if speeding else A2
    if abs(a) > A * (1.0 + tol):
        return (f"|acceleration| {abs(a)!r} is above "
                f"{'a_max' if speeding else 'a_max_decel'} {A!r}")
    # time-reversed: the arrival state mirrored, decel/accel legs swapped
    Lr = (V, A2, J2, A1, J1)
    vn = _natural_velocity(v, -a, Lr)
    if abs(vn) > V * (1.0 + tol):
        return (f"arriving with acceleration {a!r} needs the velocity {vn!r} just "
                f"before, past v_max {V!r}")
    return None


def brake_phases(v0: float, a0: float, L) -> list:
    """Brake pre-phase bringing ``(v0, a0)`` back into the limits.

    Empty when the start state is within the limits. Otherwise, in rounds
    (each at the largest jerk) until the state is valid:

    1. an acceleration above its leg's limit is ramped back to the limit;
       slowing down with ``|a| > a_max`` so hard that the velocity reverses
       first, ``|a|`` is ramped down to ``a_max`` (through the reversal);
    2. above ``v_max`` while already slowing down (and the slowdown alone
       brings the velocity back within the limits): the acceleration is held
       until ``|v| = v_max``; otherwise the fastest velocity change to
       ``(+-v_max, 0)`` (decelerating at up to ``a_max_decel``);
    3. a slowdown so hard that the velocity reverses past ``-v_max``: the
       acceleration is ramped to zero, then the velocity brought back to
       ``v_max`` in the new direction.

    During the pre-phase the velocity may exceed ``v_max`` and the
    acceleration its limit (the start state forces it); each round only
    reduces the excess.
    """
    V, A1, J1, A2, J2 = L
    out: list = []
    v, a = v0, a0
    for _ in range(BRAKE_MAX_ROUNDS):
        if _start_violation(v, a, L) is None:
            break
        s = 1.0 if v > 0.0 or (v == 0.0 and a > 0.0) else -1.0
        fv, fa = s * v, s * a  # frame: velocity >= 0
        r: list = []
        if fa > A1 * (1.0 + K.LIMIT_RTOL):
            K.ramp(fa, A1, J1, J2, r)
        elif fa < -A2 * (1.0 + K.LIMIT_RTOL):
            K.ramp(fa, -A2, J1, J2, r)
        elif _reverses_too_hard(fv, fa, L):
            K.ramp(fa, -A1, J1, J2, r)
        else:
            vn = _natural_velocity(fv, fa, L)
            if fv > V * (1.0 + K.LIMIT_RTOL) and fa < 0.0 and abs(vn) <= V:
                r.append(((fv - V) / -fa, 0.0, fa))
            elif fv > V * (1.0 + K.LIMIT_RTOL) or vn > V:
                b = K.bump(fv, fa, V, 0.0, L)
                if b is None:
                    break
                r += b
            elif vn < -V:
                K.ramp(fa, 0.0, J1, J2, r)
            else:  # pragma: no cover - _start_violation has no other case
                break
        ph = r if s > 0 else K.negate(r)
        v, a = K.integrate_va(ph, v, a)
        out += ph
    return out


def _duration_arg(duration: Any, limits: AxisLimits) -> float | None:
    if duration is None:
        return None
    try:
        T = float(duration)
    except (TypeError, ValueError):
        raise InvalidInputError(f"duration must be a number of seconds, got {duration!r}") from None
    if not math.isfinite(T) or T < 0.0:
        raise InvalidInputError(
            f"duration{axis_label(limits.name)} must be finite and >= 0 s, got {T!r}"
        )
    return T


# -------------------------------------------------------------- planners
def _pre_ramp(v, a, L):
    """Ramp ``|a|`` down to ``a_max`` at the decel jerk while slowing down.

    Used when no family member verifies from a slowing-down state with
    ``|a| > a_max``: the families use the tighter jerk of both legs in a
    bump that reverses the velocity, which can be too slow to bring ``|a|``
    within ``a_max`` before the reversal; the decel jerk is not.
    Returns the phases (empty when it does not apply).
    """
    V, A1, J1, A2, J2 = L
    if not (v * a < 0.0 and abs(a) > A1):
        return []
    sgn = 1.0 if v > 0.0 else -1.0
    r: list = []
    K.ramp(sgn * a, -A1, J1, J2, r)
    return r if sgn > 0 else K.negate(r)


def _min_time(start, goal, L, name):
    """Fastest verified candidate; (phases, family, seeds).

    ``seeds`` iterates the phases of every verified candidate (checked
    lazily, see :class:`~trajkit.profiles._state_kernel.VerifiedSeeds`):
    the minimum time only needs the candidates up to the fastest one that
    verifies, the fixed-duration search the others only when it gets there.
    """
    if start == goal and start[2] == 0.0:
        return [], "none", [[]]
    seeds = K.VerifiedSeeds(K.candidates_min_time(start, goal, L, verified=False), start, goal, L)
    best = seeds.fastest()
    if best is None:
        pre = _pre_ramp(start[1], start[2], L)
        if pre:
            mid = K.integrate(pre, *start)
            cands = [(t + K.total_time(pre), fam + "+pre", pre + ph)
                     for t, fam, ph in K.candidates_min_time(mid, goal, L)]
            seeds = K.VerifiedSeeds(cands, start, goal, L)
            best = seeds.fastest()
    if best is None:
        raise InfeasibleError(
            f"no profile found from state {start!r} to {goal!r}{axis_label(name)} "
            "within the limits (please report this input)"
        )
    return best[2], best[1], seeds


def _prepare(start, goal, limits):
    L = _limits_tuple(limits)
    gv = _goal_violation(goal[1], goal[2], L)
    if gv is not None:
        raise InvalidInputError(f"goal state{axis_label(limits.name)} cannot be reached within the limits: {gv}")
    brake = brake_phases(start[1], start[2], L)
    p1, v1, a1 = K.integrate(brake, *start) if brake else start
    if brake:
        sv = _start_violation(v1, a1, L)
        if sv is not None:
            raise InfeasibleError(
                f"start state{axis_label(limits.name)} cannot be brought back within the limits: {sv}"
            )
    return L, brake, (p1, v1, a1)


def min_state_duration(start: Sequence[float], goal: Sequence[float], limits: AxisLimits) -> float:
    """Minimum duration [s] of :func:`plan_state_to_state` (brake included).

    The same plan, value and errors as ``plan_state_to_state(start, goal,
    limits).duration``, without building the :class:`StateProfile`.
    """
    limits = _check_limits(limits)
    s = _check_state(start, "start", limits)
    g = _check_state(goal, "goal", limits)
    L, brake, s1 = _prepare(s, g, limits)
    main, _, _ = _min_time(s1, g, L, limits.name)
    _final_check(s, g, brake, main, limits)
    phases = list(brake) + list(main)
    _check_range_phases(s, g, phases, limits)
    return float(sum(ph[0] for ph in phases))


def plan_state_to_state(
    start: Sequence[float],
    goal: Sequence[float],
    limits: AxisLimits,
    duration: float | None = None,
) -> StateProfile:
    """Plan a jerk-limited move of one axis between two moving states.

    Parameters
    ----------
    start, goal : sequence of 3 float
        ``(position [unit], velocity [unit/s], acceleration [unit/s^2])``.
        The goal must be reachable within the limits: ``|vf| <= v_max``,
        ``|af|`` within its leg's limit and the velocity just before arrival
        within ``v_max``. A start state outside the limits gets a brake
        pre-phase (see :func:`brake_phases`).
    limits : AxisLimits
        Velocity, acceleration and jerk limits (asymmetric accel/decel legs:
        accel limits while ``|v|`` grows, decel limits while it shrinks).
    duration : float, optional
        Requested duration [s], brake pre-phase included. ``None`` gives the
        minimum-time profile.

    Returns
    -------
    StateProfile
        Exact (piecewise-constant jerk), hitting the goal state to 1e-9
        relative, every limit kept (checked exactly at phase boundaries,
        in-phase extrema and ``v = 0`` crossings) after the brake pre-phase.

    Raises
    ------
    InvalidInputError
        Malformed or non-finite states, positions outside the range, an
        unreachable goal state, a bad duration.
    InfeasibleError
        ``duration`` below the minimum (``error.minimum``); a
        :class:`BlockedDurationError` when it lies in a blocked interval
        (``error.interval``).

    Examples
    --------
    >>> from trajkit import AxisLimits
    >>> from trajkit.profiles.state import plan_state_to_state
    >>> lim = AxisLimits(v_max=1.0, a_max=2.0, j_max=10.0)
    >>> p = plan_state_to_state((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), lim)
    >>> round(p.duration, 6)
    1.7
    """
    limits = _check_limits(limits)
    s = _check_state(start, "start", limits)
    g = _check_state(goal, "goal", limits)
    T = _duration_arg(duration, limits)
    L, brake, s1 = _prepare(s, g, limits)
    tb = K.total_time(brake)
    main, fam, seeds = _min_time(s1, g, L, limits.name)
    tmin = tb + K.total_time(main)
    if T is None or abs(T - tmin) <= DURATION_RTOL * max(tmin, K.TINY):
        return _finish(s, g, brake, main, tmin, fam, limits)
    if T < tmin:
        raise InfeasibleError(
            f"duration {T!r} s{axis_label(limits.name)} is below the minimum duration "
            f"{tmin!r} s from state {s!r} to {g!r}",
            minimum=tmin,
        )
    ph = K.fixed_time_profile(s1, g, L, T - tb, seeds)
    if ph is None:
        lo, hi = _blocked_interval(s1, g, L, T - tb, tmin - tb, seeds)
        raise BlockedDurationError(
            f"duration {T!r} s{axis_label(limits.name)} lies in a blocked interval "
            f"({lo + tb!r}, {hi + tb!r}) s of the move from state {s!r} to {g!r}: no profile of "
            f"that duration keeps the limits; the minimum is {tmin!r} s",
            minimum=tmin, interval=(lo + tb, hi + tb),
        )
    return _finish(s, g, brake, ph, tmin, "fixed", limits)


def _blocked_interval(s1, g, L, T, tmin, seeds):
    """``(lower, upper)`` feasible-duration gap containing the infeasible ``T``."""
    def ok(t):
        # the fast families only: a "yes" is a verified profile; a rare
        # "no" that only the slow F2-with-hold family could turn into a yes
        # makes the interval slightly wider than the truth, never wrong
        # the other way (the upper end returned is feasible)
        return K.fixed_time_profile(s1, g, L, t, seeds, hold=False) is not None

    step = max(T - tmin, BLOCKED_SEARCH_RTOL * max(T, K.TINY))
    hi = T + step
    n = 0
    while not ok(hi):
        step *= 2.0
        hi = T + step
        n += 1
        if n > BLOCKED_SEARCH_MAX:
            return T, math.inf
    lo_in = T
    while hi - lo_in > BLOCKED_SEARCH_RTOL * hi:
        mid = 0.5 * (lo_in + hi)
        if ok(mid):
            hi = mid
        else:
            lo_in = mid

    def ok_full(t):
        return K.fixed_time_profile(s1, g, L, t, seeds) is not None

    # the slow F2-with-hold family may reach durations the fast ones miss:
    # if it does just below the end found, refine the end with it
    if ok_full(hi * (1.0 - BLOCKED_HOLD_RTOL)):
        lo_in = T
        while hi - lo_in > BLOCKED_HOLD_RTOL * hi:
            mid = 0.5 * (lo_in + hi)
            if ok_full(mid):
                hi = mid
            else:
                lo_in = mid
    # lower end: between tmin (feasible) and T (infeasible)
    lo_ok, lo_in = tmin, T
    while lo_in - lo_ok > BLOCKED_LOWER_RTOL * lo_in:
        mid = 0.5 * (lo_ok + lo_in)
        if ok(mid):
            lo_ok = mid
        else:
            lo_in = mid
    return lo_ok, hi


def _final_check(s, g, brake, main, limits):
    """Exact check of the planned motion after the brake (every candidate is
    verified before it is used; this guards the assembly)."""
    L = _limits_tuple(limits)
    start_main = K.integrate(brake, *s) if brake else s
    why = K.verify(main, *start_main, L, g)
    if why is not None:  # pragma: no cover - every candidate is verified before
        raise InfeasibleError(f"internal: profile{axis_label(limits.name)} failed verification: {why}")


def _finish(s, g, brake, main, tmin, fam, limits):
    _final_check(s, g, brake, main, limits)
    phases = list(brake) + list(main)
    prof = StateProfile(s, g, phases, tmin, len(brake), fam, limits)
    _check_range(prof, limits)
    return prof


def _check_range(prof: StateProfile, limits: AxisLimits) -> None:
    _check_range_phases(prof.start_state, prof.goal_state, list(zip(
        prof.phase_durations, prof.jerks, prof.phase_accelerations)), limits)


def _check_range_phases(start, goal, phases, limits: AxisLimits) -> None:
    if limits.position_min == -math.inf and limits.position_max == math.inf:
        return
    lo, hi = _phase_extremes(start, goal, phases)
    if lo < limits.position_min or hi > limits.position_max:
        raise InfeasibleError(
            f"the profile{axis_label(limits.name)} would leave the position range "
            f"[{limits.position_min}, {limits.position_max}] (reaches [{lo}, {hi}])"
        )


def position_extremes(prof: StateProfile) -> tuple[float, float]:
    """Exact smallest and largest position of a profile over ``[0, duration]``."""
    return _phase_extremes(prof.start_state, prof.goal_state, list(zip(
        prof.phase_durations, prof.jerks, prof.phase_accelerations)))


def _phase_extremes(start, goal, phases) -> tuple[float, float]:
    """Smallest and largest position along ``phases`` (``(dt, j, a)``) from
    ``start``: at every phase end and every in-phase ``v = 0`` (the phase
    boundary states integrated as :class:`StateProfile` does)."""
    if not phases:
        return float(goal[0]), float(goal[0])
    p, v = float(start[0]), float(start[1])
    lo = hi = p
    for dt, j, a in phases:
        for t in (dt,) + tuple(x for x in K._quad_roots(0.5 * j, a, v) if 0.0 < x < dt):
            x = p + t * (v + t * (0.5 * a + t * j / 6.0))
            lo, hi = min(lo, x), max(hi, x)
        p = p + dt * (v + dt * (0.5 * a + dt * j / 6.0))
        v = v + dt * (a + 0.5 * dt * j)
    return lo, hi


def plan_velocity(
    start: Sequence[float],
    goal_velocity: float,
    goal_acceleration: float = 0.0,
    *,
    limits: AxisLimits,
    duration: float | None = None,
) -> StateProfile:
    """Reach a velocity and acceleration with the position free.

    Jogging, feed override and the controlled stop (``goal_velocity=0``:
    the minimum-time brake) all use this.

    Parameters
    ----------
    start : sequence of 3 float
        ``(position [unit], velocity [unit/s], acceleration [unit/s^2])``.
    goal_velocity : float
        Target velocity [unit/s], ``|goal_velocity| <= v_max``.
    goal_acceleration : float, optional
        Target acceleration [unit/s^2] (default 0).
    limits : AxisLimits
        Keyword-only.
    duration : float, optional
        Requested duration [s]: the velocity first changes to a cruise
        velocity ``vc`` (the goal velocity when the goal acceleration is 0),
        holds it, then ramps into the goal acceleration, ending exactly at
        ``duration``.

    Returns
    -------
    StateProfile
        Its ``goal_state`` position is where the motion ends.

    Raises
    ------
    InvalidInputError
        Malformed input, an unreachable goal velocity/acceleration.
    InfeasibleError
        ``duration`` below the minimum (``error.minimum``) or not reachable.
    """
    limits = _check_limits(limits)
    s = _check_state(start, "start", limits)
    vf = check_finite(goal_velocity, "goal_velocity", limits.name)
    af = check_finite(goal_acceleration, "goal_acceleration", limits.name)
    T = _duration_arg(duration, limits)
    L = _limits_tuple(limits)
    gv = _goal_violation(vf, af, L)
    if gv is not None:
        raise InvalidInputError(
            f"goal velocity/acceleration{axis_label(limits.name)} cannot be reached "
            f"within the limits: {gv}"
        )
    brake = brake_phases(s[1], s[2], L)
    s1 = K.integrate(brake, *s) if brake else s
    if brake and _start_violation(s1[1], s1[2], L) is not None:
        raise InfeasibleError(
            f"start state{axis_label(limits.name)} cannot be brought back within the limits"
        )
    tb = K.total_time(brake)
    main = K.bump(s1[1], s1[2], vf, af, L) if (s1[1], s1[2]) != (vf, af) else []
    ok = main is not None and K.verify(main, *s1, L, (0.0, vf, af), check_goal=False) is None
    if not ok:
        pre = _pre_ramp(s1[1], s1[2], L)
        if pre:
            vm, am = K.integrate_va(pre, s1[1], s1[2])
            b = K.bump(vm, am, vf, af, L)
            if b is not None:
                main = pre + b
                ok = K.verify(main, *s1, L, (0.0, vf, af), check_goal=False) is None
    if not ok:
        raise InfeasibleError(
            f"no velocity profile found{axis_label(limits.name)} from {s!r} to velocity "
            f"{vf!r}, acceleration {af!r} (please report this input)"
        )
    tmin = tb + K.total_time(main)
    if T is not None and abs(T - tmin) > DURATION_RTOL * max(tmin, K.TINY):
        if T < tmin:
            raise InfeasibleError(
                f"duration {T!r} s{axis_label(limits.name)} is below the minimum duration "
                f"{tmin!r} s to reach velocity {vf!r}",
                minimum=tmin,
            )
        main = _velocity_fixed(s1, vf, af, L, T - tb)
        if main is None:
            raise InfeasibleError(
                f"no velocity profile of duration {T!r} s{axis_label(limits.name)} "
                f"reaches velocity {vf!r}, acceleration {af!r} within the limits",
                minimum=tmin,
            )
        fam = "velocity-fixed"
    else:
        fam = "velocity"
    pe, ve, ae = K.integrate(main, *s1)
    goal = (pe, vf, af)
    why = K.verify(main, *s1, L, goal)
    if why is not None:  # pragma: no cover
        raise InfeasibleError(f"internal: velocity profile failed verification: {why}")
    prof = StateProfile(s, goal, list(brake) + list(main), tmin, len(brake), fam, limits)
    _check_range(prof, limits)
    return prof


def _velocity_fixed(s1, vf, af, L, T):
    """Bump to a cruise velocity, hold, bump to ``(vf, af)``: exactly ``T``."""
    _, v0, a0 = s1
    Am, vn0, vnf = K.natural_scale(s1, (0.0, vf, af), L)
    V = L[0]
    tries = [vnf, vf, vn0, v0]
    w = max(abs(v0), abs(vf), abs(vn0), abs(vnf), K.TINY)
    lo, hi = (-V, V) if V != math.inf else (-2 * w, 2 * w)
    tries += sorted(K._grid(lo, hi, []), key=lambda x: abs(x - vnf))
    for vc in tries:
        if V != math.inf and abs(vc) > V:
            continue
        b1 = K.bump(v0, a0, vc, 0.0, L)
        b2 = K.bump(vc, 0.0, vf, af, L)
        if b1 is None or b2 is None:
            continue
        tc = T - K.total_time(b1) - K.total_time(b2)
        if tc < 0.0:
            continue
        ph = b1 + [(tc, 0.0, 0.0)] + b2
        if K.verify(ph, *s1, L, (0.0, vf, af), check_goal=False) is None:
            return ph
    return None
