"""One-axis profiles between arbitrary states (position, velocity, acceleration).

:func:`plan_state_to_state` plans the minimum-time, jerk-limited motion from
a moving start state to a moving goal state (ruckig's problem, with
trajkit's asymmetric limits), or one of exactly a requested duration;
:func:`plan_velocity` reaches a velocity and acceleration with the position
free (jogging, feed override, controlled stop); :func:`feasible_durations`
gives the minimum duration and the blocked intervals (what a
synchronisation of several axes needs). All return or use a
:class:`StateProfile`, a :class:`~trajkit.profiles.motion.JerkMotion`.

Limit semantics (see :class:`~trajkit.limits.AxisLimits`): while ``|v|``
grows (``v*a > 0``, or ``v = 0``) the accel leg's ``a_max`` / ``j_max``
apply, while ``|v|`` shrinks (``v*a < 0``) the decel leg's ``a_max_decel`` /
``j_max_decel``; ``|v| <= v_max`` always. The method (closed-form shapes,
the brake pre-phase, blocked intervals) and the supported numeric range are
described in ``docs/state-profiles.md``.
"""

from __future__ import annotations

import math
import struct
import sys
import threading
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._validate import axis_label
from ..errors import InfeasibleError, InvalidInputError
from ..limits import AxisLimits
from . import _kernel as K
from ._brake import inside
from ._check import check as _check_table
from ._compile import ENABLED as _COMPILED
from ._phase import phase_end
from ._range import (
    DISTANCE_ABS_MIN,
    POSITION_MAX,
    STATE_RATIO_MAX,
    check_distance_range,
    check_duration_range,
    check_limits_range,
    check_position_range,
    check_state_range,
)
from ._shapes import NPH, SHAPE_NAMES
from .motion import JerkMotion

__all__ = [
    "BlockedDurationError",
    "DurationSet",
    "StateProfile",
    "feasible_durations",
    "min_state_duration",
    "plan_state_to_state",
    "plan_velocity",
    "position_extremes",
]

#: Names of the fixed-duration (step 2) shapes, after the step-1 ones.
STEP2_NAMES = ("cruise", "acc0_cruise", "cruise_acc1", "acc0_cruise_acc1", "hold1", "hold3",
               "hold_mid", "acc0_hold_mid", "hold_mid_3", "hold_mid_acc1", "reduced_jerk")
#: Names of the fixed-duration shapes of step 2's last stage (codes 0-3 of the fixed context).
STEP2_HOLD_NAMES = ("hold1_acc1", "acc0_hold3", "cruise_cruise", "cruise_shape")

#: A requested duration within this fraction of the minimum is the minimum.
DURATION_RTOL = K.DURATION_RTOL

_fsum = math.fsum


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
        ``(lower, upper)`` [s]: the blocked interval containing the request;
        both ends are durations of valid profiles (``upper`` is the next
        feasible duration).
    """

    def __init__(self, message: str, minimum: float, interval: tuple[float, float]):
        super().__init__(message, minimum=minimum)
        self.interval = interval


@dataclass(frozen=True)
class DurationSet:
    """The feasible durations of a move: ``[minimum, inf)`` minus ``blocked``.

    Attributes
    ----------
    minimum : float
        Minimum duration [s].
    blocked : tuple of (float, float)
        Open intervals ``(lower, upper)`` [s] of infeasible durations,
        ascending (at most two for symmetric limits).
    """

    minimum: float
    blocked: tuple = ()

    def contains(self, T: float) -> bool:
        """True when the duration ``T`` [s] is feasible."""
        if T < self.minimum * (1.0 - DURATION_RTOL):
            return False
        return not any(lo < T < hi for lo, hi in self.blocked)

    def next_feasible(self, T: float) -> float:
        """The smallest feasible duration >= ``T`` [s]."""
        T = max(T, self.minimum)
        for lo, hi in self.blocked:
            if lo < T < hi:
                T = hi
        return T


class StateProfile(JerkMotion):
    """A piecewise-constant-jerk profile of one axis between two states.

    Built by :func:`plan_state_to_state` or :func:`plan_velocity` (or from a
    phase table: ``StateProfile(start_state, goal_state, phases,
    min_duration, n_brake_phases, family, limits)`` with ``phases`` a list
    of ``(duration, jerk, start acceleration)``).

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
        Length of the brake pre-phase [s] (0 when the start state is inside
        the limits). The first ``n_brake_phases`` phases form it.
    n_brake_phases : int
        Number of phases of the brake pre-phase.
    phase_durations, jerks, phase_accelerations : tuple of float
        The phase table: duration [s], constant jerk [unit/s^3] and the
        acceleration entering each phase [unit/s^2].
    family : str
        The profile's shape: the jerk-sign pattern (``"UDDU"`` or its mirror
        ``"DUUD"``) and the limits reached, ruckig's names in lower case
        (``"none"``, ``"acc0"``, ``"acc1"``, ``"acc0_acc1"``, ``"vel"``,
        ``"acc0_vel"``, ...); ``"fixed ..."`` for a requested duration
        (``cruise``, ``hold1``, ...), ``"velocity ..."`` for
        :func:`plan_velocity`, ``"none"`` when already at the goal.
    limits : AxisLimits
    """

    __slots__ = ("min_duration", "n_brake_phases", "family", "limits")

    def __init__(self, start_state: Any, goal_state: Any, phases: Any, min_duration: float,
                 n_brake_phases: int, family: str, limits: AxisLimits) -> None:
        ph = list(phases)
        super().__init__(start_state, [p[0] for p in ph], [p[1] for p in ph],
                         [p[2] for p in ph], goal_state)
        self.min_duration = float(min_duration)
        self.n_brake_phases = int(n_brake_phases)
        self.family = family
        self.limits = limits

    @property
    def goal_state(self) -> tuple:
        """``(p, v, a)`` at the end [unit, unit/s, unit/s^2]."""
        return self.end_state

    @property
    def start(self) -> float:
        """Start position [unit]."""
        return self.start_state[0]

    @property
    def goal(self) -> float:
        """Goal position [unit]."""
        return self.end_state[0]

    @property
    def brake_duration(self) -> float:
        """Length of the brake pre-phase [s]."""
        return float(math.fsum(self.phase_durations[:self.n_brake_phases]))

    @property
    def shape(self) -> str:
        """Alias of :attr:`family`."""
        return self.family

    def to_dict(self) -> dict:
        """JSON-ready summary (axis units)."""
        d = super().to_dict()
        d.update({
            "goal_state": list(self.goal_state),
            "start": self.start,
            "goal": self.goal,
            "min_duration_s": self.min_duration,
            "brake_duration_s": self.brake_duration,
            "n_brake_phases": self.n_brake_phases,
            "family": self.family,
        })
        return d

    def __repr__(self) -> str:
        return (f"StateProfile(start_state={self.start_state!r}, goal_state={self.goal_state!r}, "
                f"duration={self.duration!r}, family={self.family!r})")


def _from_table(start, goal, flat, n, nb, tmin, family, limits) -> StateProfile:
    """A StateProfile from the kernel's flat phase table (no per-phase Python work)."""
    prof = StateProfile.__new__(StateProfile)
    prof.start_state = start
    # (a tuple ``flat`` is sliced into tuples at once; tuple() of a tuple is itself)
    prof.phase_durations = d = tuple(flat[0:3 * n:3])
    prof.jerks = tuple(flat[1:3 * n:3])
    prof.phase_accelerations = tuple(flat[2:3 * n:3])
    prof.duration = _fsum(d)
    prof._end = goal
    prof._tab = None
    prof.min_duration = tmin
    prof.n_brake_phases = nb
    prof.family = family
    prof.limits = limits
    return prof


def _profile(start, goal, flat: tuple, tmin: float, nb: int, code: int,
             limits: AxisLimits) -> StateProfile:
    """A StateProfile from a phase table read as one tuple ``flat`` (rows of
    ``(duration, jerk, start acceleration)``, see :data:`_TABLES`)."""
    prof = _new_profile(StateProfile)
    prof.start_state = start
    prof.phase_durations = d = flat[0::3]
    prof.jerks = flat[1::3]
    prof.phase_accelerations = flat[2::3]
    prof.duration = _fsum(d)
    prof._end = goal
    prof._tab = None
    prof.min_duration = tmin
    prof.n_brake_phases = nb
    prof.family = _FAMILIES.get(code) or _family(code)
    prof.limits = limits
    return prof


# ------------------------------------------------------------ validation
_local = threading.local()


def _ws():
    ws = getattr(_local, "ws", None)
    if ws is None:
        ws = _local.ws = K.workspace()
        _local.mv = memoryview(ws)
    return ws


def _wsmv():
    """The thread's workspace as a memoryview (item access on Python floats is
    several times cheaper than on the numpy array)."""
    mv = getattr(_local, "mv", None)
    if mv is None:
        _ws()
        mv = _local.mv
    return mv


_NAMES3 = ("position", "velocity", "acceleration")
_PMAX = POSITION_MAX
_SMAX = STATE_RATIO_MAX
_FMAX = sys.float_info.max
_INF = math.inf


def _check_limits(limits: Any) -> AxisLimits:
    if type(limits) is AxisLimits and "_sfast" in limits.__dict__:
        return limits
    if not isinstance(limits, AxisLimits):
        raise InvalidInputError(f"limits must be an AxisLimits, got {type(limits).__name__}")
    if limits.v_max == math.inf and limits.a_max == math.inf and limits.a_max_decel == math.inf:
        raise InvalidInputError(
            f"limits{axis_label(limits.name)}: v_max and a_max cannot both be infinite for a "
            "profile between moving states")
    check_limits_range(limits, states=True)
    _cache_fast(limits)
    return limits


def _cache_fast(limits: AxisLimits) -> None:
    """Cache on validated limits what the fast checks of a state need (``_sfast``):
    the position bounds (axis range within the supported one), the velocity and
    acceleration bounds of a state (capped at the largest float: a bound passed
    implies a finite value), ``1/(2 min j)``, the uncapped velocity bound of the
    forced speed, whether the position range is unbounded, the kernel's five
    limits and ``v_max``; and the same limits and bounds as one row tail of the
    compiled synchronisation (``_srow``)."""
    vb = _SMAX * limits.v_max
    tol = 1.0 + 1e-12  # (as in _goal_violation)
    object.__setattr__(limits, "_sgoal", (
        limits.v_max * tol, limits.a_max * tol, limits.a_max_decel * tol, limits.v_max,
        limits.a_max_decel, 0.0 if limits.j_max_decel == math.inf else 1.0 / limits.j_max_decel,
        limits.a_max, 0.0 if limits.j_max == math.inf else 1.0 / limits.j_max))
    object.__setattr__(limits, "_sfast", (
        max(-_PMAX, limits.position_min), min(_PMAX, limits.position_max),
        min(vb, _FMAX), min(_SMAX * limits._amax, _FMAX), limits._kmin2, vb,
        limits.position_min == -math.inf and limits.position_max == math.inf,
        (limits.v_max, limits.a_max, limits.j_max, limits.a_max_decel, limits.j_max_decel),
        limits.v_max))
    sf = limits.__dict__["_sfast"]
    # the compiled synchronisation's row tail: the kernel's limits, then the bounds
    # of :func:`_fast_pair` (checked in the compiled code)
    object.__setattr__(limits, "_srow", sf[7] + tuple(float(x) for x in sf[:6]))


def _num(x, field, name):
    try:
        f = float(x)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{field}{axis_label(name)} must be a number, got {x!r}") from None
    if not math.isfinite(f):
        raise InvalidInputError(f"{field}{axis_label(name)} must be finite, got {f!r}")
    return f


def _check_state(state: Any, field: str, limits: AxisLimits) -> tuple:
    # fast path: three finite floats inside the ranges (the common call)
    if type(state) is tuple and len(state) == 3:
        p, v, a = state
        plo, phi, vb, ab, k2, vb2 = limits.__dict__["_sfast"][:6]
        if (type(p) is float and type(v) is float and type(a) is float
                and plo <= p <= phi and abs(v) <= vb and abs(a) <= ab
                and abs(v) + a * a * k2 <= vb2):
            return state
    return _check_state_slow(state, field, limits)


def _fast_pair(start: Any, goal: Any, limits: Any) -> tuple | None:
    """The validated ``_sfast`` of ``limits`` when the common call passes every check
    of :func:`_prepare` at once (two tuples of finite floats inside the ranges, a
    resolvable distance, a goal reached within the limits), else None (then
    :func:`_prepare` decides, with its messages)."""
    if type(limits) is not AxisLimits or type(start) is not tuple or type(goal) is not tuple:
        return None
    sf = limits.__dict__.get("_sfast")
    if sf is None or len(start) != 3 or len(goal) != 3:
        return None
    p0, v0, a0 = start
    pf, vf, af = goal
    plo, phi, vb, ab, k2, vb2 = sf[:6]
    if (type(p0) is float and type(v0) is float and type(a0) is float
            and type(pf) is float and type(vf) is float and type(af) is float
            and plo <= p0 <= phi and abs(v0) <= vb and abs(a0) <= ab
            and abs(v0) + a0 * a0 * k2 <= vb2
            and plo <= pf <= phi and abs(vf) <= vb and abs(af) <= ab
            and abs(vf) + af * af * k2 <= vb2
            and (af == 0.0 and abs(vf) <= limits.v_max or _goal_ok(vf, af, limits))):
        d = abs(pf - p0)
        if d == 0.0 or d >= DISTANCE_ABS_MIN:
            return sf
    return None


def _check_state_slow(state: Any, field: str, limits: AxisLimits) -> tuple:
    name = limits.name
    try:
        vals = tuple(state)
    except TypeError:
        raise InvalidInputError(
            f"{field}{axis_label(name)} must be a sequence of 3 numbers "
            f"(position, velocity, acceleration), got {state!r}"
        ) from None
    if len(vals) != 3:
        raise InvalidInputError(
            f"{field}{axis_label(name)} must have 3 entries "
            f"(position, velocity, acceleration), got {len(vals)}"
        )
    p = _num(vals[0], f"{field} position", name)
    v = _num(vals[1], f"{field} velocity", name)
    a = _num(vals[2], f"{field} acceleration", name)
    check_position_range(p, f"{field} position", name)
    limits.check_position(p, f"{field} position")
    check_state_range(v, a, field, limits)
    return (p, v, a)


def _goal_ok(v: float, a: float, limits: AxisLimits) -> bool:
    """``_goal_violation(v, a, limits) is None`` on validated limits, without the
    messages (the same comparisons on the bounds cached in ``_sgoal``)."""
    if a == 0.0 and abs(v) <= limits.v_max:
        return True
    vt, a1t, a2t, V, A2, k2, A1, k1 = limits.__dict__["_sgoal"]
    if abs(v) > vt or abs(a) > (a1t if v * a > 0.0 else a2t):
        return False
    return _inside(v, -a, V, A2, k2, A1, k1)


#: :func:`._brake.inside` as plain Python (the same comparisons; no dispatch).
_inside = getattr(inside, "py_func", inside)


def _goal_violation(v: float, a: float, limits: AxisLimits) -> str | None:
    """Why the goal (v, a) cannot be reached within the limits, or None.

    Arriving at ``(v, a)`` is leaving ``(v, -a)`` backwards in time with the
    legs swapped: the goal is reachable when that state is inside the limits.
    """
    if a == 0.0 and abs(v) <= limits.v_max:
        return None
    V = limits.v_max
    tol = 1.0 + 1e-12
    if abs(v) > V * tol:
        return f"|velocity| {abs(v)!r} is above v_max {V!r}"
    speeding = v * a > 0.0
    A = limits.a_max if speeding else limits.a_max_decel
    if abs(a) > A * tol:
        return (f"|acceleration| {abs(a)!r} is above "
                f"{'a_max' if speeding else 'a_max_decel'} {A!r}")
    k1 = 0.0 if limits.j_max == math.inf else 1.0 / limits.j_max
    k2 = 0.0 if limits.j_max_decel == math.inf else 1.0 / limits.j_max_decel
    if not inside(v, -a, V, limits.a_max_decel, k2, limits.a_max, k1):
        vn = v - a * abs(a) * (k2 if speeding else k1) / 2.0
        return (f"arriving with acceleration {a!r} needs the velocity about {vn!r} just "
                f"before, past v_max {V!r} (or a reversal past a limit)")
    return None


def _duration_arg(duration: Any, name) -> float | None:
    if duration is None:
        return None
    try:
        T = float(duration)
    except (TypeError, ValueError):
        raise InvalidInputError(f"duration must be a number of seconds, got {duration!r}") from None
    if not math.isfinite(T) or T < 0.0:
        raise InvalidInputError(f"duration{axis_label(name)} must be finite and >= 0 s, got {T!r}")
    check_duration_range(T, name)
    return T


def _prepare(start, goal, limits, velocity_only=False):
    limits = _check_limits(limits)
    s = _check_state(start, "start", limits)
    if velocity_only:
        g = goal
    else:
        g = _check_state(goal, "goal", limits)
        check_distance_range(s[0], g[0], limits.name)
    gv = _goal_violation(g[1], g[2], limits)
    if gv is not None:
        what = "goal velocity/acceleration" if velocity_only else "goal state"
        raise InvalidInputError(
            f"{what}{axis_label(limits.name)} cannot be reached within the limits: {gv}")
    return limits, s, g


def _run(s, g, limits, task, T=0.0):
    ws = _ws()
    _load(_local.mv, s, g, limits, task, T)
    if _COMPILED:
        _solve(ws)
    else:
        with np.errstate(all="ignore"):
            K.solve(ws)
    return ws


def _load(mv, s, g, limits, task, T):
    """Write the problem into the workspace (through its memoryview)."""
    mv[0], mv[1], mv[2] = s
    mv[3], mv[4], mv[5] = g
    sf = limits.__dict__.get("_sfast")
    if sf is None:
        lim = (limits.v_max, limits.a_max, limits.j_max, limits.a_max_decel, limits.j_max_decel)
    else:
        lim = sf[7]
    mv[6], mv[7], mv[8], mv[9], mv[10] = lim
    mv[_IN_TASK] = task
    mv[_IN_T] = T


_solve = K.solve
_OUT_PH_BYTES = 8 * K.OUT_PH

#: ``_TABLES[n]`` reads a phase table of ``n`` rows from the workspace as one tuple.
_TABLES = tuple(struct.Struct(f"={3 * n}d") for n in range(NPH + 1))

_new_profile = object.__new__


_IN_TASK = K.IN_TASK
_IN_T = K.IN_T
_OUT_STATUS = K.OUT_STATUS
_OUT_TMIN = K.OUT_TMIN
_OUT_N = K.OUT_N
_OUT_NB = K.OUT_NB
_OUT_SHAPE = K.OUT_SHAPE
_OUT_PH = K.OUT_PH


_FAMILIES: dict[int, str] = {}

#: Shape codes of a fixed-duration profile made of two halves through a velocity
#: reversal or a velocity extremum (:func:`_split_fixed`; above every code of
#: the kernel).
SHAPE_SPLIT = 1024
SHAPE_SPLIT_EXTREMUM = 1025
#: ... or through a state of the minimum-time profile (:func:`_split_along`).
SHAPE_SPLIT_ALONG = 1026


def _family(code: float) -> str:
    """The shape name of a kernel shape code (see :attr:`StateProfile.family`)."""
    c = int(code)
    name = _FAMILIES.get(c)
    if name is None:
        name = _FAMILIES[c] = _family_name(c)
    return name


def _family_name(c: int) -> str:
    if c == SHAPE_SPLIT:
        return "fixed split_at_reversal"
    if c == SHAPE_SPLIT_EXTREMUM:
        return "fixed split_at_velocity_extremum"
    if c == SHAPE_SPLIT_ALONG:
        return "fixed split_along_minimum"
    if c >= K.SHAPE_REVERSED:
        return _family_name(c - K.SHAPE_REVERSED).replace("fixed ", "fixed reversed ", 1)
    fixed = c >= 32
    direction = "DUUD" if c & 16 else "UDDU"
    c &= 15
    if fixed:
        if c == K.SHAPE_CRUISE_FALLBACK:
            return f"fixed {direction} velocity_change_cruise_velocity_change"
        if c < len(STEP2_HOLD_NAMES):
            return f"fixed {direction} {STEP2_HOLD_NAMES[c]}"
        return f"fixed {direction} {STEP2_NAMES[c - 4] if 4 <= c < 15 else '?'}"
    if c == 15:  # NONE with equal jerks (solved in w = c1 - c3)
        return f"{direction} none"
    if c >= 8:
        return f"velocity {direction}" + (" acc0" if c == 9 else "")
    return f"{direction} {SHAPE_NAMES[c]}"


def _blocked(ws) -> list[tuple[float, float]]:
    """The blocked intervals [s] the kernel wrote into ``ws``."""
    return [(float(ws[K.OUT_BLK + 2 * i]), float(ws[K.OUT_BLK + 2 * i + 1]))
            for i in range(int(ws[K.OUT_NBLK]))]


def _fail(st, s, g, limits, what):
    """Raise the error of the kernel's status ``st`` (not OK)."""
    name = axis_label(limits.name)
    if st == K.ST_BRAKE:
        raise InfeasibleError(
            f"start state {s!r}{name} cannot be brought back within the limits")
    if what.startswith("of duration") and not limits.symmetric:
        # the fixed-duration gap of asymmetric limits (docs/state-profiles.md)
        raise InfeasibleError(
            f"no profile found {what}{name} from state {s!r} to {g!r} within the limits: with "
            "separate accel/decel limits the fixed-duration search (the shape families, then "
            "two halves through a velocity reversal, a velocity extremum or a state of the "
            "minimum-time profile) may miss a duration of a profile that reverses; a longer "
            "duration may be feasible")
    raise InfeasibleError(
        f"no profile found {what}{name} from state {s!r} to {g!r} within the limits "
        "(please report this input)")


# ------------------------------------------- fixed duration: split at a reversal
#: The search for the state ``M`` between two halves (:func:`_split_at`): positions
#: and values of the free coordinate on its first grid, and positions closer to both ends (``SPLIT_NEAR`` halvings
#: of the range); finer grids around its best ``SPLIT_STARTS`` points
#: (``SPLIT_ZOOM`` times); a Nelder-Mead search of at most ``SPLIT_EVALS``
#: evaluations from each of them; ``SPLIT_BISECT`` bisection steps; at most
#: ``SPLIT_TRIES`` durations tried per reversal; and ``SPLIT_BUDGET`` minimum-time
#: plans in all (about 0.3 s: the search runs only where every shape family has
#: missed the duration).
SPLIT_POSITIONS = 41
SPLIT_VALUES = 17
SPLIT_NEAR = 12
SPLIT_STARTS = 4
SPLIT_ZOOM = 3
SPLIT_EVALS = 300
SPLIT_BISECT = 60
SPLIT_TRIES = 3
SPLIT_BUDGET = 6000

#: ``M``'s free coordinate stays this fraction inside its bound: the smaller of
#: the two legs' acceleration limits at a reversal (both legs meet at ``v = 0``),
#: ``v_max`` at an extremum.
SPLIT_MARGIN = 1e-3


def _min_or_inf(s, g, limits: AxisLimits) -> float:
    """Minimum duration [s] of a move from ``s`` to ``g`` (inf where there is none)."""
    ws = _run(s, g, limits, K.TASK_MIN)
    return float(ws[K.OUT_TMIN]) if int(ws[K.OUT_STATUS]) == K.ST_OK else math.inf


def _durations_or_none(s, g, limits: AxisLimits):
    """``(minimum, blocked intervals)`` [s] of a move from ``s`` to ``g``, or None."""
    ws = _run(s, g, limits, K.TASK_BLOCK)
    if int(ws[K.OUT_STATUS]) != K.ST_OK:
        return None
    return float(ws[K.OUT_TMIN]), _blocked(ws)


def _fixed_or_none(s, g, limits: AxisLimits, T: float):
    """The kernel's profile of duration ``T`` from ``s`` to ``g``, or None."""
    ws = _run(s, g, limits, K.TASK_FIXED, T)
    if int(ws[K.OUT_STATUS]) != K.ST_OK:
        return None
    n = int(ws[K.OUT_N])
    return (ws[K.OUT_PH:K.OUT_PH + 3 * n].reshape(n, 3).copy(), int(ws[K.OUT_NB]))


def _stop_reach(v: float, a: float, A: float, J: float) -> float:
    """A bound on the distance [unit] an axis at ``(v, a)`` covers before it can
    be at rest (acceleration ``A``, jerk ``J``: the smaller of both legs)."""
    v_top = abs(v) + 0.5 * a * a / J
    return v_top * (v_top / A + 2.0 * A / J + abs(a) / J)


def _split_fixed(s: tuple, g: tuple, limits: AxisLimits, T: float):
    """A profile of exactly ``T`` [s] as two halves where every shape family
    missed it (:func:`_split_at`, through a velocity reversal, then through a
    velocity extremum; then :func:`_split_along`, through a state of the
    minimum-time profile): ``(table (n, 3), brake phases, shape code)``, or None."""
    for code, extremum in ((SHAPE_SPLIT, False), (SHAPE_SPLIT_EXTREMUM, True)):
        out = _split_at(s, g, limits, T, extremum)
        if out is not None:
            return out[0], out[1], code
    out = _split_along(s, g, limits, T)
    if out is not None:
        return out[0], out[1], SHAPE_SPLIT_ALONG
    return None


def _joined(s: tuple, g: tuple, limits: AxisLimits, T: float, M: tuple):
    """The two halves ``s`` to ``M`` and ``M`` to ``g`` with ``T`` [s] shared
    between their feasible durations (minimum and blocked intervals of each,
    at most ``SPLIT_TRIES`` shares), the joined table checked exactly (after
    any brake pre-phase): ``(table (n, 3), brake phases)``, or None."""
    d1 = _durations_or_none(s, M, limits)
    d2 = _durations_or_none(M, g, limits) if d1 is not None else None
    if d1 is None or d2 is None:
        return None
    (t1, blk1), (t2, blk2) = d1, d2
    lo, hi = t1, T - t2
    if not hi >= lo - K.DURATION_RTOL * T:
        return None
    free = [(lo, max(hi, lo))]
    for a, b in list(blk1) + [(T - b, T - a) for a, b in blk2]:
        free = [piece for c, d in free for piece in ((c, min(d, a)), (max(c, b), d))
                if piece[1] >= piece[0]]
    k1 = 0.0 if limits.j_max == math.inf else 1.0 / limits.j_max
    k2 = 0.0 if limits.j_max_decel == math.inf else 1.0 / limits.j_max_decel
    pf, vf, af = g
    for c, d in sorted(free, key=lambda iv: iv[0] - iv[1])[:SPLIT_TRIES]:
        T1 = 0.5 * (c + d)
        first = _fixed_or_none(s, M, limits, T1)
        if first is None:
            continue
        second = _fixed_or_none(M, g, limits, T - T1)
        if second is None:
            continue
        table = np.concatenate([first[0], second[0]])
        if abs(math.fsum(table[:, 0]) - T) > K.DURATION_RTOL * T:
            continue
        nb = first[1]
        q = s
        for dt, j, a in table[:nb].tolist():  # the state after the brake pre-phase
            q = phase_end(q[0], q[1], a, j, dt)
        if _check_table(np.ascontiguousarray(table[nb:]), table.shape[0] - nb, q[0], q[1],
                        q[2], pf, vf, af, limits.v_max, limits.a_max, k1,
                        limits.a_max_decel, k2):
            return table, nb
    return None


#: States of the minimum-time profile tried by :func:`_split_along`: this many
#: evenly spaced in time, and its phase boundaries.
ALONG_POINTS = 64


def _split_along(s: tuple, g: tuple, limits: AxisLimits, T: float):
    """A phase table of exactly ``T`` [s] made of two profiles of the kernel
    through a state ``M`` of the minimum-time profile (``(table (n, 3), brake
    phases)``, or None).

    Every such ``M`` splits the move into halves whose minima add up to at most
    the minimum duration; ``T`` is shared between their feasible durations
    (:func:`_joined`). This reaches profiles with more free parameters than
    one family or one split through a reversal or an extremum spans: each half
    is a shape of the kernel.
    """
    ws = _run(s, g, limits, K.TASK_MIN)
    if int(ws[K.OUT_STATUS]) != K.ST_OK:
        return None
    n = int(ws[K.OUT_N])
    table = ws[K.OUT_PH:K.OUT_PH + 3 * n].reshape(n, 3).copy()
    ends = np.cumsum(table[:, 0])
    t_min = float(ends[-1])
    times = np.unique(np.concatenate([np.linspace(0.0, t_min, ALONG_POINTS + 2)[1:-1], ends[:-1]]))
    nb = int(ws[K.OUT_NB])
    times = times[times > (ends[nb - 1] if nb else 0.0)]  # (after any brake)
    q = s
    k = 0
    t0 = 0.0
    for t in times.tolist():
        while t > ends[k]:  # the state at the start of the phase that holds t
            q = phase_end(q[0], q[1], table[k, 2], table[k, 1], table[k, 0])
            t0 = float(ends[k])
            k += 1
        M = phase_end(q[0], q[1], table[k, 2], table[k, 1], t - t0)
        if _goal_violation(M[1], M[2], limits) is not None:
            continue
        out = _joined(s, g, limits, T, M)
        if out is not None:
            return out
    return None


def _split_at(s: tuple, g: tuple, limits: AxisLimits, T: float, extremum: bool):
    """A phase table of exactly ``T`` [s] from ``s`` to ``g`` made of two profiles
    of the kernel (``s`` to ``M`` and ``M`` to ``g``, each of a fixed duration)
    through a velocity reversal ``M = (p_m, 0, a_m)``, or with ``extremum``
    through a velocity extremum ``M = (p_m, v_m, 0)``: ``(table (n, 3), brake
    phases)``, or None.

    Any profile that passes such a state is two such halves, each at least as
    long as its own minimum: ``M`` is searched for where the two minima add up
    to at most ``T`` (a grid of positions and of the free coordinate, finer
    grids around its best points, a Nelder-Mead search from them on the sum,
    and a bisection towards where the sum is ``T``), and ``T`` is shared
    between the halves' feasible durations (minimum and blocked intervals of
    each). The table found is checked exactly (after any brake pre-phase)
    before it is returned.
    """
    from scipy.optimize import minimize

    p0, v0, a0 = s
    pf, vf, af = g
    A = min(limits.a_max, limits.a_max_decel)
    J = min(limits.j_max, limits.j_max_decel)
    # the free coordinate of M: its acceleration (at v = 0), or with ``extremum``
    # its velocity (at a = 0)
    c_top = (limits.v_max if extremum else A) * (1.0 - SPLIT_MARGIN)
    if not math.isfinite(c_top):
        return None
    # M lies within reach of both ends: no farther out than the stops, and no
    # farther from either end than the axis can travel in T
    reach = abs(pf - p0) + _stop_reach(v0, a0, A, J) + _stop_reach(vf, af, A, J)
    travel = T * max(limits.v_max, abs(v0) + 0.5 * a0 * a0 / J)
    lo = max(min(p0, pf) - reach, max(p0, pf) - travel)
    hi = min(max(p0, pf) + reach, min(p0, pf) + travel)
    if not (math.isfinite(lo) and math.isfinite(hi) and hi > lo):
        return None

    def state(z) -> tuple | None:
        c = float(min(max(z[1], -c_top), c_top))
        M = (float(min(max(z[0], lo), hi)), c, 0.0) if extremum else (float(min(max(z[0], lo), hi)), 0.0, c)
        return M if _goal_violation(M[1], M[2], limits) is None else None

    spent = [0]

    def total(z) -> float:
        M = state(z)
        if M is None or spent[0] >= SPLIT_BUDGET:
            return math.inf
        spent[0] += 1
        t1 = _min_or_inf(s, M, limits)
        if not t1 < T:
            return math.inf
        spent[0] += 1
        return t1 + _min_or_inf(M, g, limits)

    dp = (hi - lo) / (SPLIT_POSITIONS - 1)
    dc = 2.0 * c_top / (SPLIT_VALUES - 1)
    # a grid over the range, denser towards both ends (a reversal right after
    # the start or just before the goal)
    near = (hi - lo) * 0.5 ** np.arange(1, SPLIT_NEAR + 1)
    pos = np.concatenate([np.linspace(lo, hi, SPLIT_POSITIONS), p0 - near, p0 + near, pf - near,
                          pf + near])
    pos = pos[(pos >= lo) & (pos <= hi)]
    grid = sorted((total((pm, cm)), pm, cm) for pm in pos
                  for cm in np.linspace(-c_top, c_top, SPLIT_VALUES))
    for _ in range(SPLIT_ZOOM):  # finer grids around the best points
        if not (math.isfinite(grid[0][0]) and grid[0][0] > T):
            break
        dp, dc = dp / 5.0, dc / 5.0
        grid = sorted(grid[:SPLIT_STARTS] + [
            (total((pm + i * dp, cm + k * dc)), pm + i * dp, cm + k * dc)
            for _f, pm, cm in grid[:SPLIT_STARTS] for i in range(-5, 6) for k in range(-5, 6)
            if i or k])
    for f, pm, cm in grid[:SPLIT_STARTS]:
        if not math.isfinite(f):
            break
        z = (pm, cm)
        if f > T:
            with np.errstate(invalid="ignore"):  # (inf - inf between infeasible points)
                res = minimize(total, z, method="Nelder-Mead",
                               options={"maxfev": SPLIT_EVALS, "xatol": 1e-12 * (hi - lo + c_top),
                                        "fatol": 1e-12 * T})
            if not res.fun <= T:
                continue
            z = (float(res.x[0]), float(res.x[1]))
        M = state(z)
        if M is None:
            continue
        out = _joined(s, g, limits, T, M)
        if out is None:
            # a half may have no profile longer than its minimum: move M
            # (bisection in position, then in the free coordinate) to where the
            # two minima add up to T
            for side in ((hi, z[1]), (lo, z[1]), (z[0], c_top), (z[0], -c_top)):
                if not total(side) > T:
                    continue
                w_in, w_out = 0.0, 1.0
                for _ in range(SPLIT_BISECT):
                    w = 0.5 * (w_in + w_out)
                    if total((z[0] + w * (side[0] - z[0]), z[1] + w * (side[1] - z[1]))) <= T:
                        w_in = w
                    else:
                        w_out = w
                M2 = state((z[0] + w_in * (side[0] - z[0]), z[1] + w_in * (side[1] - z[1])))
                out = None if M2 is None else _joined(s, g, limits, T, M2)
                if out is not None:
                    break
        if out is not None:
            return out
    return None


def _check_range(prof: StateProfile, limits: AxisLimits) -> StateProfile:
    if limits.position_min == -math.inf and limits.position_max == math.inf:
        return prof
    lo, hi = prof.extrema().position
    # the integrated positions carry a few ulp of round-off (a goal at the range
    # end is reached exactly: sample() returns the declared goal there)
    tol = 8.0 * math.ulp(max(abs(lo), abs(hi), abs(prof.start), abs(prof.goal)))
    if lo < limits.position_min - tol or hi > limits.position_max + tol:
        raise InfeasibleError(
            f"the profile{axis_label(limits.name)} would leave the position range "
            f"[{limits.position_min}, {limits.position_max}] (reaches [{lo}, {hi}])"
        )
    return prof


def position_extremes(prof: JerkMotion) -> tuple[float, float]:
    """Exact smallest and largest position of a motion over ``[0, duration]``."""
    return prof.extrema().position


# ------------------------------------------------------------ planners
def min_state_duration(start: Sequence[float], goal: Sequence[float], limits: AxisLimits) -> float:
    """Minimum duration [s] of :func:`plan_state_to_state` (brake included).

    The same plan, value and errors as ``plan_state_to_state(start, goal,
    limits).duration``, without building the :class:`StateProfile`.
    """
    return plan_state_to_state(start, goal, limits).duration


def feasible_durations(start: Sequence[float], goal: Sequence[float],
                       limits: AxisLimits) -> DurationSet:
    """The feasible durations of a move between states: minimum and blocked intervals.

    Parameters
    ----------
    start, goal : sequence of 3 float
        As in :func:`plan_state_to_state`.
    limits : AxisLimits

    Returns
    -------
    DurationSet
        Step 1 of the planner: the durations of every valid profile of the
        shape enumeration bound the feasible set (ruckig's *block*). With
        separate accel/decel limits each gap between two consecutive valid
        durations is tried by the fixed-duration search (at five points) and
        reported blocked where it finds no profile (docs/state-profiles.md).
    """
    limits, s, g = _prepare(start, goal, limits)
    ws = _run(s, g, limits, K.TASK_BLOCK)
    if int(ws[K.OUT_STATUS]) != K.ST_OK:
        _fail(int(ws[K.OUT_STATUS]), s, g, limits, "")
    return DurationSet(float(ws[K.OUT_TMIN]), tuple(_blocked(ws)))


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
        pre-phase (the fastest return into them, chosen together with the
        rest for the shortest total).
    limits : AxisLimits
        Velocity, acceleration and jerk limits (asymmetric accel/decel legs:
        accel limits while ``|v|`` grows, decel limits while it shrinks).
    duration : float, optional
        Requested duration [s], brake pre-phase included. ``None`` gives the
        minimum-time profile.

    Returns
    -------
    StateProfile
        Exact (piecewise-constant jerk), ending at the goal state (to 1e-10
        relative; ``sample`` returns it exactly at the end), every limit kept
        after the brake pre-phase (checked exactly at phase boundaries,
        in-phase extrema and ``v = 0`` crossings).

    Raises
    ------
    InvalidInputError
        Malformed or non-finite states, values outside the supported range
        (``trajkit.profiles._range``), positions outside the axis range, an
        unreachable goal state, a bad duration.
    InfeasibleError
        ``duration`` below the minimum (``error.minimum``); a
        :class:`BlockedDurationError` when it lies in a blocked interval
        (``error.interval``); a profile that would leave the position range.

    Examples
    --------
    >>> from trajkit import AxisLimits
    >>> from trajkit.profiles.state import plan_state_to_state
    >>> lim = AxisLimits(v_max=1.0, a_max=2.0, j_max=10.0)
    >>> p = plan_state_to_state((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), lim)
    >>> round(p.duration, 6)
    1.7
    """
    if (duration is None and type(limits) is AxisLimits and type(start) is tuple
            and type(goal) is tuple and len(start) == 3 and len(goal) == 3 and start != goal):
        # the common call: every check of _prepare at once on the bounds cached on
        # the validated limits (anything else goes the long way, with its messages),
        # then planned and built from the workspace without numpy scalars
        sf = limits.__dict__.get("_sfast")
        if sf is not None:
            p0, v0, a0 = start
            pf, vf, af = goal
            plo, phi, vb, ab, k2, vb2, free, lim5, vmax = sf
            if (float is type(p0) is type(v0) is type(a0) is type(pf) is type(vf) is type(af)
                    and plo <= p0 <= phi and plo <= pf <= phi
                    and abs(v0) <= vb and abs(a0) <= ab and abs(vf) <= vb and abs(af) <= ab
                    and abs(v0) + a0 * a0 * k2 <= vb2 and abs(vf) + af * af * k2 <= vb2
                    and (af == 0.0 and abs(vf) <= vmax or _goal_ok(vf, af, limits))
                    and (abs(pf - p0) >= DISTANCE_ABS_MIN or pf == p0)):
                try:
                    mv = _local.mv
                except AttributeError:
                    _ws()
                    mv = _local.mv
                mv[0] = p0
                mv[1] = v0
                mv[2] = a0
                mv[3] = pf
                mv[4] = vf
                mv[5] = af
                mv[6], mv[7], mv[8], mv[9], mv[10] = lim5
                mv[_IN_TASK] = 0.0  # K.TASK_MIN
                if _COMPILED:
                    _solve(_local.ws)
                else:
                    with np.errstate(all="ignore"):
                        K.solve(_local.ws)
                if mv[_OUT_STATUS] == 0.0:  # K.ST_OK
                    flat = _TABLES[int(mv[_OUT_N])].unpack_from(mv, _OUT_PH_BYTES)
                    prof = _profile(start, goal, flat, mv[_OUT_TMIN], int(mv[_OUT_NB]),
                                    int(mv[_OUT_SHAPE]), limits)
                    return prof if free else _check_range(prof, limits)
    limits, s, g = _prepare(start, goal, limits)
    T = _duration_arg(duration, limits.name)
    if s == g and (T is None or T == 0.0):
        return StateProfile(s, g, [], 0.0, 0, "none", limits)
    ws = _run(s, g, limits, K.TASK_MIN if T is None else K.TASK_FIXED, 0.0 if T is None else T)
    st = int(ws[K.OUT_STATUS])
    if st != K.ST_OK:
        tmin = float(ws[K.OUT_TMIN])
        name = axis_label(limits.name)
        if st == K.ST_SHORT:
            raise InfeasibleError(
                f"duration {T!r} s{name} is below the minimum duration {tmin!r} s from state "
                f"{s!r} to {g!r}", minimum=tmin)
        if st == K.ST_BLOCKED:
            assert T is not None  # a duration is blocked only when one is requested
            lo, hi = next(iv for iv in _blocked(ws) if iv[0] < T < iv[1])
            raise BlockedDurationError(
                f"duration {T!r} s{name} lies in a blocked interval ({lo!r}, {hi!r}) s of the "
                f"move from state {s!r} to {g!r}: no profile of that duration keeps the limits; "
                f"the minimum is {tmin!r} s", minimum=tmin, interval=(lo, hi))
        if st == K.ST_NONE and T is not None:
            # a profile the shape families miss: two halves
            split = _split_fixed(s, g, limits, T)
            if split is not None:
                table, nb, code = split
                return _check_range(_from_table(s, g, table.ravel().tolist(), table.shape[0], nb,
                                                tmin, _family(code), limits), limits)
        _fail(st, s, g, limits, "" if T is None else f"of duration {T!r} s")
    n = int(ws[K.OUT_N])
    flat = ws[K.OUT_PH:K.OUT_PH + 3 * n].tolist()
    prof = _from_table(s, g, flat, n, int(ws[K.OUT_NB]), float(ws[K.OUT_TMIN]),
                       _family(ws[K.OUT_SHAPE]), limits)
    return _check_range(prof, limits)


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
        ``(position [unit], velocity [unit/s], acceleration [unit/s^2])``;
        a state outside the limits is braked first.
    goal_velocity : float
        Target velocity [unit/s], ``|goal_velocity| <= v_max``.
    goal_acceleration : float, optional
        Target acceleration [unit/s^2] (default 0).
    limits : AxisLimits
        Keyword-only.
    duration : float, optional
        Requested duration [s]: the velocity first changes to a cruise
        velocity (the goal velocity when the goal acceleration is 0, else the
        velocity from which one ramp of the acceleration reaches the goal),
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
        ``duration`` below the minimum (``error.minimum``).
    """
    limits = _check_limits(limits)
    vf = _num(goal_velocity, "goal_velocity", limits.name)
    af = _num(goal_acceleration, "goal_acceleration", limits.name)
    limits, s, g = _prepare(start, (math.nan, vf, af), limits, velocity_only=True)
    T = _duration_arg(duration, limits.name)
    if T is None or (s[1] == vf and s[2] == af and T == 0.0):
        return _velocity(s, vf, af, limits)
    if af == 0.0:
        first = _velocity(s, vf, 0.0, limits)
        tmin = first.duration
        if T < tmin * (1.0 - DURATION_RTOL):
            raise InfeasibleError(
                f"duration {T!r} s{axis_label(limits.name)} is below the minimum duration "
                f"{tmin!r} s to reach velocity {vf!r}", minimum=tmin)
        ph = first.phases() + [(max(T - tmin, 0.0), 0.0, vf * 0.0)]
        return _velocity_profile(s, ph, tmin, first.n_brake_phases, "velocity fixed", limits,
                                 vf, 0.0)
    # cruise at vc, then one ramp of the acceleration into (vf, af), at the smaller
    # jerk limit of both legs (valid whichever leg the ramp lies in)
    jm = min(limits.j_max, limits.j_max_decel)
    k = 0.0 if jm == math.inf else 1.0 / jm
    direct = _velocity(s, vf, af, limits)
    vc = vf - af * abs(af) * k / 2.0
    first = _velocity(s, vc, 0.0, limits)
    ramp = [] if k == 0.0 else [(abs(af) * k, math.copysign(1.0 / k, af), 0.0)]
    t_fixed = first.duration + sum(r[0] for r in ramp)
    if T < direct.duration * (1.0 - DURATION_RTOL):
        raise InfeasibleError(
            f"duration {T!r} s{axis_label(limits.name)} is below the minimum duration "
            f"{direct.duration!r} s to reach velocity {vf!r}, acceleration {af!r}",
            minimum=direct.duration)
    if T < t_fixed:
        raise InfeasibleError(
            f"no velocity profile of duration {T!r} s{axis_label(limits.name)} cruises at "
            f"{vc!r} before ramping into acceleration {af!r} (it needs {t_fixed!r} s)",
            minimum=t_fixed)
    ph = first.phases() + [(T - t_fixed, 0.0, 0.0)] + ramp
    return _velocity_profile(s, ph, direct.duration, first.n_brake_phases, "velocity fixed",
                             limits, vf, af)


def _velocity(s, vf, af, limits) -> StateProfile:
    if s[1] == vf and s[2] == af:
        return StateProfile(s, s, [], 0.0, 0, "none", limits)
    g = (math.nan, vf, af)
    ws = _run(s, g, limits, K.TASK_VELOCITY)
    if int(ws[K.OUT_STATUS]) != K.ST_OK:
        _fail(int(ws[K.OUT_STATUS]), s, (None, vf, af), limits, "to the velocity")
    n = int(ws[K.OUT_N])
    flat = ws[K.OUT_PH:K.OUT_PH + 3 * n].tolist()
    return _velocity_profile(s, list(zip(flat[0::3], flat[1::3], flat[2::3])),
                             float(ws[K.OUT_TMIN]), int(ws[K.OUT_NB]),
                             _family(ws[K.OUT_SHAPE]), limits, vf, af)


def _velocity_profile(s, phases, tmin, nb, family, limits, vf, af) -> StateProfile:
    m = JerkMotion(s, [p[0] for p in phases], [p[1] for p in phases], [p[2] for p in phases])
    prof = StateProfile(s, (m.end_state[0], vf, af), phases, tmin, nb, family, limits)
    return _check_range(prof, limits)
