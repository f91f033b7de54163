"""The ``optimal`` palletizing planner: B passes its clearance heights at speed.

Same clearance rule as Cao et al.'s (2012) ``merged`` plan: the horizontal joints A, C,
D move only while B is above ``Z1`` near the pick (going up) and above ``Z2``
near the place (coming down). ``merged`` moves B rest-to-rest to a top
height ``Zmax`` and back, so B stops at the top. Here B's whole trip is one
jerk-limited motion ``Z0 -> Z3`` that turns at the top without stopping,
and the window between "B passes Z1 going up" and "B passes Z2 coming down"
is exactly what A, C, D need (their common minimum time ``tH``) whenever
that is possible.

Lower bound
-----------
No plan under this rule beats, per trip, ``max(t_up + tH + t_down, t_B)``:

* ``t_up``: B from rest at ``Z0`` to ``Z1`` at full throttle (jerk to the
  accel limit, hold, ease into ``v_max``); ``t_down``: B from ``Z2`` to rest
  at ``Z3``, the time reverse of full throttle under the decel limits.
  A, C, D can start no earlier than ``t_up`` and B cannot get from ``Z2`` to
  rest faster than ``t_down``.
* ``t_B``: B alone from rest at ``Z0`` over ``max(Z1, Z2)`` to rest at
  ``Z3`` (minimum over the acceleration with which it turns at the top).

Candidates
----------
Per trip the planner builds these B motions and keeps the fastest one that
passes every check (limits, position range, the clearance window):

``"window"``
    Full throttle to ``Z1`` (state ``s1``), a state-to-state middle
    ``s1 -> s2`` of duration ``max(tH, its minimum)``, the reversed full
    throttle from ``s2`` down to ``Z3``. When the middle fits into ``tH``
    the trip takes exactly ``t_up + tH + t_down``: the lower bound.
``"turn"``
    B alone: minimum time ``Z0 -> (Zp, 0, ap)`` then ``(Zp, 0, ap) -> Z3``
    with ``Zp = max(Z1, Z2)`` and the turning acceleration ``ap`` that
    minimises the trip; valid when its window already holds ``tH`` (then
    the trip takes ``t_B``: the other lower bound).
``"raised"``
    As ``"turn"`` with the peak ``Zp`` raised (Brent's method) until the
    window equals ``tH``.

Every trip reports its lower bound, so a plan states how far from optimal
it is (:attr:`OptimalTrip.gap_s`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from scipy.optimize import brentq, minimize_scalar

from ..errors import InfeasibleError, InvalidInputError, TrajkitError
from ..limits import AxisLimits
from ..profiles.state import BlockedDurationError, StateProfile, min_state_duration, plan_state_to_state
from ..sync import plan_ptp
from ._crossing import _solve_phase, clearance_crossings, position_peak
from .planners import HORIZONTAL_JOINTS, TripPlan, _assemble, _horizontal_time, register_planner
from .scenario import PalletScenario, TripSpec
from .timeline import Piece

__all__ = [
    "OptimalTrip",
    "full_throttle_phases",
    "trip_lower_bound",
    "trip_bounds",
    "plan_trip_optimal",
    "plan_cycle_optimal",
    "clearance_window",
    "CANDIDATES",
]

_B = 1

#: Candidate B motions, in the order they are tried.
CANDIDATES = ("window", "turn", "raised")

#: Absolute tolerance [m] on the raised peak height (Brent's method).
ZPEAK_XTOL = 1e-9

#: Absolute tolerance [m/s^2] on the turning acceleration at the top.
TURN_XTOL = 1e-7

#: Points of the grid over the turning acceleration scanned before Brent's
#: bounded search (the trip time need not be unimodal in it).
TURN_GRID = 9

#: Relative tolerance on "the window holds tH" (round-off of crossing times).
WINDOW_RTOL = 1e-12


@dataclass(frozen=True)
class OptimalTrip:
    """How the ``optimal`` planner planned one trip.

    Attributes
    ----------
    candidate : str
        Which B motion won (one of :data:`CANDIDATES`).
    duration : float
        Trip duration [s].
    lower_bound : float
        ``max(t_up + tH + t_down, t_B)`` [s] (see the module docstring).
    window_floor : float
        ``t_up + tH + t_down`` [s] alone (B at full throttle up to ``Z1`` and
        down from ``Z2``, ignoring that B must turn around in between).
    t_h : float
        Common minimum time of A, C, D [s].
    window : (float, float)
        Times [s] (from the trip start) when B passes ``Z1`` going up and
        ``Z2`` coming down.
    z_peak : float
        B's highest position [m].
    tried : dict of str to float
        Duration [s] of each candidate that passed its checks.
    """

    candidate: str
    duration: float
    lower_bound: float
    window_floor: float
    t_h: float
    window: tuple
    z_peak: float
    tried: dict

    @property
    def gap_s(self) -> float:
        """How much longer than the lower bound the trip is [s] (>= 0)."""
        return self.duration - self.lower_bound


# ---------------------------------------------------------------- phases
def full_throttle_phases(limits: AxisLimits, leg: str = "accel") -> list:
    """B's fastest departure from rest in the positive direction.

    Jerk up to the acceleration limit, hold it, jerk down so the velocity
    meets ``v_max`` with zero acceleration, then cruise (the last phase
    lasts for ever: ``inf``). Every phase speeds the axis up, so only one
    leg's limits are used.

    Parameters
    ----------
    limits : AxisLimits
    leg : {"accel", "decel"}
        Which leg's acceleration and jerk limits to use (``"decel"``: the
        time reverse is the fastest arrival at rest).

    Returns
    -------
    list of (float, float, float)
        Phases ``(duration [s], jerk, start acceleration)``.
    """
    if leg == "accel":
        A, J = limits.a_max, limits.j_max
    elif leg == "decel":
        A, J = limits.a_max_decel, limits.j_max_decel
    else:
        raise InvalidInputError(f"leg must be 'accel' or 'decel', got {leg!r}")
    V = limits.v_max
    if not math.isfinite(V) and not math.isfinite(A):
        raise InvalidInputError(
            f"axis {limits.name or 'B'} needs a finite v_max or a_max for a full-throttle profile"
        )
    if not math.isfinite(J):
        return [(V / A, 0.0, A), (math.inf, 0.0, 0.0)] if math.isfinite(V) else [(math.inf, 0.0, A)]
    if not math.isfinite(V):
        return [(A / J, J, 0.0), (math.inf, 0.0, A)]
    ap = min(A, math.sqrt(V * J))
    t_ramp = ap / J
    t_hold = max(0.0, (V - ap * ap / J) / ap) if ap == A else 0.0
    return [(t_ramp, J, 0.0), (t_hold, 0.0, ap), (t_ramp, -J, ap), (math.inf, 0.0, 0.0)]


def _cut(phases: list, distance: float) -> tuple[list, float, float, float]:
    """Truncate a rising profile (from position 0 at rest) where it reaches ``distance``.

    Returns the phases up to that point and the state ``(v, a)`` there, and
    the time.
    """
    p = v = 0.0
    out = []
    t = 0.0
    for dt, j, a in phases:
        pe = math.inf if math.isinf(dt) else p + dt * (v + dt * (0.5 * a + dt * j / 6.0))
        if pe >= distance:
            if math.isinf(dt):
                # constant velocity (j = 0, a = 0) or constant acceleration
                if a == 0.0:
                    tc = (distance - p) / v
                else:
                    tc = (-v + math.sqrt(v * v + 2.0 * a * (distance - p))) / a
            else:
                tc = _solve_phase(p, v, a, j, distance, dt, 1.0)
            out.append((tc, j, a))
            v_end = v + tc * (a + 0.5 * tc * j)
            return out, v_end, a + tc * j, t + tc
        if dt > 0.0:
            out.append((dt, j, a))
        p = pe
        v = v + dt * (a + 0.5 * dt * j)
        t += dt
    raise AssertionError("unreachable: the last phase lasts for ever")  # pragma: no cover


def _reverse(phases: list) -> list:
    """Time reverse of constant-jerk phases: order reversed, jerk negated, a from the end."""
    return [(dt, -j, a + j * dt) for dt, j, a in reversed(phases)]


def _end_state(phases: list, p: float, v: float, a: float) -> tuple[float, float, float]:
    for dt, j, a0 in phases:
        p = p + dt * (v + dt * (0.5 * a0 + dt * j / 6.0))
        v = v + dt * (a0 + 0.5 * dt * j)
        a = a0 + j * dt
    return p, v, a


def _phases_of(prof: StateProfile) -> list:
    return list(zip(prof.phase_durations, prof.jerks, prof.phase_accelerations))


def _trip_profile(phases: list, z0: float, z3: float, limits: AxisLimits, family: str) -> StateProfile:
    """One rest-to-rest StateProfile of B's whole trip (phases concatenated)."""
    return StateProfile((z0, 0.0, 0.0), (z3, 0.0, 0.0), phases, sum(p[0] for p in phases), 0,
                        family, limits)


# ---------------------------------------------------------------- window
def clearance_window(profile, z1: float, z2: float) -> tuple[float, float, float]:
    """When B passes ``z1`` going up and ``z2`` coming down, and its peak.

    Parameters
    ----------
    profile : Profile or StateProfile
        B's motion over one trip (rest to rest, up then down).
    z1, z2 : float
        Clearance heights at the start and at the goal [m].

    Returns
    -------
    (float, float, float)
        ``(t_up, t_down, z_peak)``: the last time B rises through ``z1``
        before its peak (0 if it starts at or above ``z1``), the first time
        it falls through ``z2`` after its peak (the end if it ends at or
        above ``z2``), and the peak height [s, s, m].

    Raises
    ------
    InfeasibleError
        B never gets above ``z1`` or ``z2``.
    """
    r = clearance_crossings([(0.0, profile)], z1, z2, 0.0, float(profile.duration),
                            float(profile.start))
    if r is None:
        raise InfeasibleError(f"B never gets above the clearance {max(z1, z2)!r} m")
    return r


# ----------------------------------------------------------- lower bound
def _throttle(spec: TripSpec, lb: AxisLimits):
    z0, z1, z2, z3 = spec.z_levels
    up, v1, a1, tu = _cut(full_throttle_phases(lb, "accel"), z1 - z0)
    dn, v2, a2, td = _cut(full_throttle_phases(lb, "decel"), z2 - z3)
    return up, (z1, v1, a1), tu, _reverse(dn), (z2, -v2, a2), td


def _turn_profile(z0, zp, z3, ap, lb):
    u = plan_state_to_state((z0, 0.0, 0.0), (zp, 0.0, ap), lb)
    d = plan_state_to_state((zp, 0.0, ap), (z3, 0.0, 0.0), lb)
    return _trip_profile(_phases_of(u) + _phases_of(d), z0, z3, lb, "optimal:turn")


def _turn_bounds(lb: AxisLimits) -> tuple[float, float]:
    # at the top |v| shrinks just before (decel leg) and grows just after
    # (accel leg, downwards): the turning acceleration obeys both
    return -min(lb.a_max, lb.a_max_decel), 0.0


def _best_turn(z0, zp, z3, lb, cache):
    key = (z0, zp, z3)
    if key not in cache:
        lo, hi = _turn_bounds(lb)

        def f(ap):
            try:
                return (min_state_duration((z0, 0.0, 0.0), (zp, 0.0, ap), lb)
                        + min_state_duration((zp, 0.0, ap), (z3, 0.0, 0.0), lb))
            except TrajkitError:  # out of B's range (a peak at the very top)
                return math.inf

        if math.isfinite(lo):
            # a grid first (the trip time need not be unimodal in ap), then
            # Brent's bounded search between the best grid point's neighbours
            grid = [lo + (hi - lo) * i / (TURN_GRID - 1) for i in range(TURN_GRID)]
            cands = [(f(x), x) for x in grid]
            i = min(range(TURN_GRID), key=lambda k: cands[k][0])
            a, b = grid[max(i - 1, 0)], grid[min(i + 1, TURN_GRID - 1)]
            r = minimize_scalar(f, bounds=(a, b), method="bounded", options={"xatol": TURN_XTOL})
            cands.append((float(r.fun), float(r.x)))
        else:  # pragma: no cover - B always has a finite acceleration limit here
            cands = [(f(hi), hi)]
        # durations within round-off of the best are ties: the first (a grid
        # point, e.g. the bound itself) wins over Brent's point a hair from it
        fb = min(c[0] for c in cands)
        cache[key] = next(c for c in cands if c[0] <= fb + 8.0 * math.ulp(fb))
    return cache[key]


def trip_bounds(scenario: PalletScenario, spec: TripSpec,
                _cache: dict | None = None) -> tuple[float, float]:
    """``(t_up + tH + t_down, t_B)`` [s] of one trip (module docstring).

    ``t_B`` is 0 when B alone cannot turn at ``max(Z1, Z2)`` inside its range.
    """
    lb = scenario.robot.limits[_B]
    z0, z1, z2, z3 = spec.z_levels
    _, _, tu, _, _, td = _throttle(spec, lb)
    t_h = _horizontal_time(scenario, spec)
    t_b, _ = _best_turn(z0, max(z1, z2), z3, lb, {} if _cache is None else _cache)
    # B alone cannot do it inside its range: only the window floor bounds the trip
    return tu + t_h + td, (t_b if math.isfinite(t_b) else 0.0)


def trip_lower_bound(scenario: PalletScenario, spec: TripSpec, _cache: dict | None = None) -> float:
    """Lower bound [s] on one trip under the clearance rule: ``max(t_up + tH + t_down, t_B)``."""
    return max(trip_bounds(scenario, spec, _cache))


# ---------------------------------------------------------------- planner
def _candidates(scenario: PalletScenario, spec: TripSpec, t_h: float, cache: dict):
    """Yield ``(name, B profile)`` for every candidate that could be built."""
    lb = scenario.robot.limits[_B]
    z0, z1, z2, z3 = spec.z_levels
    up, s1, tu, dn, s2, td = _throttle(spec, lb)
    # window: full throttle, middle of duration max(tH, its minimum), full brake
    try:
        w = max(t_h, min_state_duration(s1, s2, lb))
        try:
            mid = plan_state_to_state(s1, s2, lb, duration=w)
        except BlockedDurationError as e:  # a blocked duration: its upper end is feasible
            mid = plan_state_to_state(s1, s2, lb, duration=e.interval[1])
        yield "window", _trip_profile(up + _phases_of(mid) + dn, z0, z3, lb, "optimal:window")
    except TrajkitError:
        pass
    zp0 = max(z1, z2)
    t_b, ap = _best_turn(z0, zp0, z3, lb, cache)
    if not math.isfinite(t_b):
        return
    try:
        prof = _turn_profile(z0, zp0, z3, ap, lb)
    except TrajkitError:
        return
    yield "turn", prof
    t_up, t_dn, _ = clearance_window(prof, z1, z2)
    if t_dn - t_up >= t_h:
        return
    # raised: lift the peak until the window holds tH
    z_top = lb.position_max

    def gap(zp):
        p = _turn_profile(z0, zp, z3, ap, lb)
        a, b, _ = clearance_window(p, z1, z2)
        return (b - a) - t_h

    try:
        if gap(z_top) < 0.0:
            return
        zr = brentq(gap, zp0, z_top, xtol=ZPEAK_XTOL)
        if gap(zr) < 0.0:
            zr = min(zr + ZPEAK_XTOL, z_top)
        yield "raised", _turn_profile(z0, zr, z3, ap, lb)
    except TrajkitError:
        return


def _symmetric_legs(lim: AxisLimits) -> bool:
    return lim.a_max == lim.a_max_decel and lim.j_max == lim.j_max_decel


def _reversed_profile(prof: StateProfile) -> StateProfile:
    """The time reverse of a rest-to-rest B motion (valid for symmetric legs)."""
    ph = _reverse(_phases_of(prof))
    return _trip_profile(ph, prof.goal, prof.start, prof.limits, prof.family)


def _best_candidate(scenario: PalletScenario, spec: TripSpec, t_h: float, cache: dict):
    """Fastest candidate that keeps the range and leaves A, C, D their ``t_h``."""
    z0, z1, z2, z3 = spec.z_levels
    best = None
    tried = {}
    for name, prof in _candidates(scenario, spec, t_h, cache):
        lo, hi = prof.limits.position_min, prof.limits.position_max
        zp, _, _ = position_peak(prof)
        if zp > hi or min(prof.boundary_states()[:, 0]) < lo - 1e-12:
            continue
        t_up, t_dn, zp = clearance_window(prof, z1, z2)
        if t_dn - t_up < t_h * (1.0 - WINDOW_RTOL):
            continue
        tried[name] = prof.duration
        if best is None or prof.duration < best[1].duration:
            best = (name, prof, t_up, t_dn, zp)
    if best is None:
        raise InfeasibleError(
            f"{spec.kind} trip of box {spec.box}: no B motion keeps the limits and leaves "
            f"A, C, D their {t_h:.6g} s between Z1 and Z2"
        )
    return best, tried


def plan_trip_optimal(scenario: PalletScenario, spec: TripSpec,
                      _cache: dict | None = None) -> tuple[TripPlan, OptimalTrip]:
    """Plan one trip with B passing its clearance heights at speed.

    Parameters
    ----------
    scenario : PalletScenario
    spec : TripSpec

    Returns
    -------
    (TripPlan, OptimalTrip)
        The trip (B as one rest-to-rest state profile; A, C, D
        time-synchronised over ``tH`` starting when B passes ``Z1``) and how
        it was chosen.

    Raises
    ------
    InfeasibleError
        No candidate keeps the limits and the clearance rule (B's range too
        short for the window, say).
    """
    cache = {} if _cache is None else _cache
    lims = scenario.robot.limits
    z0, z1, z2, z3 = spec.z_levels
    t_h = _horizontal_time(scenario, spec)
    key = ("trip", z0, z1, z2, z3, t_h)
    if key in cache:
        name, prof, tried = cache[key]
        best = (name, prof) + clearance_window(prof, z1, z2)
    else:
        best, tried = _best_candidate(scenario, spec, t_h, cache)
        cache[key] = (best[0], best[1], tried)
        if _symmetric_legs(lims[_B]):
            # the time reverse of this B motion is the best one of the mirrored
            # trip (the return trip of the same box): same window, same time
            cache[("trip", z3, z2, z1, z0, t_h)] = (best[0], _reversed_profile(best[1]), tried)
    name, prof, t_up, t_dn, zp = best
    h = list(HORIZONTAL_JOINTS)
    hz = plan_ptp(spec.q_start[h], spec.q_goal[h], [lims[k] for k in HORIZONTAL_JOINTS], sync="time")
    pieces: list[list[Piece]] = [[] for _ in range(4)]
    pieces[_B] = [Piece(0.0, prof)]
    for i, k in enumerate(HORIZONTAL_JOINTS):
        pieces[k] = [Piece(t_up, hz.axes[i])]
    trip = TripPlan(spec, prof.duration, tuple(tuple(p) for p in pieces), (t_up, t_dn), zp)
    floor, t_b = trip_bounds(scenario, spec, cache)
    return trip, OptimalTrip(name, prof.duration, max(floor, t_b), floor, t_h, (t_up, t_dn), zp,
                             tried)


def plan_cycle_optimal(scenario: PalletScenario):
    """The ``optimal`` plan of the whole job (see :func:`plan_trip_optimal`).

    ``plan.info`` holds ``"trips"`` (one :class:`OptimalTrip` per trip),
    ``"lower_bound_s"`` (the job's lower bound under the clearance rule) and
    ``"window_floor_s"`` (the sum of ``t_up + tH + t_down``, a weaker bound);
    both include the grip and release dwells.
    """
    cache: dict = {}
    trips, infos = [], []
    for spec in scenario.trips():
        tp, info = plan_trip_optimal(scenario, spec, cache)
        trips.append(tp)
        infos.append(info)
    plan = _assemble("optimal", scenario, trips)
    dwell = plan.total_s - sum(t.duration for t in trips)
    plan.info["trips"] = infos
    plan.info["lower_bound_s"] = float(dwell + sum(i.lower_bound for i in infos))
    plan.info["window_floor_s"] = float(dwell + sum(i.window_floor for i in infos))
    return plan


register_planner("optimal", plan_cycle_optimal)
