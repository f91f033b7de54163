"""The ``optimal`` palletizing planner: seed numbers, bounds, oracles, verification, sweeps."""

from __future__ import annotations

import dataclasses
import math
import os

import numpy as np
import pytest
from scipy.optimize import linprog, minimize
from test_pallet_planners import _random_scenario

from trajkit import AxisLimits
from trajkit.errors import InfeasibleError, InvalidInputError, UnreachableError
from trajkit.kinematics import CylindricalPalletizer
from trajkit.kinematics.palletizer import DEFAULT_JOINT_TABLE
from trajkit.palletizing import (
    PLANNERS,
    Piece,
    Timeline,
    plan_cycle,
    seed_scenario,
    verify_plan,
)
from trajkit.palletizing._crossing import clearance_crossings, level_crossings, position_peak
from trajkit.palletizing.optimal import (
    _cut,
    _reverse,
    _throttle,
    full_throttle_phases,
    plan_trip_optimal,
    trip_bounds,
)
from trajkit.palletizing.planners import HORIZONTAL_JOINTS, CyclePlan, _horizontal_time
from trajkit.palletizing.report import bound_lines, summarize
from trajkit.profiles.state import StateProfile, min_state_duration, plan_state_to_state
from trajkit.verify import verify_state_profile

SWEEP = bool(os.environ.get("TRAJKIT_SWEEP"))
N_SCEN = 30 if SWEEP else 3
N_PROF = 3000 if SWEEP else 300
B = 1


@pytest.fixture(scope="module")
def seed():
    return seed_scenario()


@pytest.fixture(scope="module")
def plans(seed):
    return {n: plan_cycle(seed, n) for n in ("merged", "optimal")}


def _b_profile(plan, i):
    (pc,) = plan.trips[i].pieces[B]
    return pc.profile


# ----------------------------------------------------------- seed numbers
def test_optimal_is_registered_and_verifies(plans):
    assert "optimal" in PLANNERS
    rep = verify_plan(plans["optimal"])
    assert rep.ok, rep.violations[:3]
    assert rep.checks["crossings"] == 100
    # B uses its full limits somewhere (the plan is not a slow one)
    assert rep.checks["worst_ratio"]["B"]["velocity"] == pytest.approx(1.0, abs=1e-9)


def test_seed_numbers_against_the_issue(plans):
    opt, mer = plans["optimal"], plans["merged"]
    floor, bound = opt.info["window_floor_s"], opt.info["lower_bound_s"]
    # no plan under this rule can go below about 88.1 s; merged ~89.4 s
    assert floor == pytest.approx(88.1, abs=0.05)
    assert mer.total_s == pytest.approx(89.4, abs=0.05)
    assert floor <= bound <= opt.total_s < mer.total_s
    # within 0.5 % of the tighter bound (max of B alone and the window floor)
    assert opt.total_s <= 1.005 * bound
    # per trip: never slower than merged, never below its bound
    for tp, info, tm in zip(opt.trips, opt.info["trips"], mer.trip_times()):
        assert info.duration == tp.duration
        assert info.lower_bound - 1e-12 <= tp.duration <= tm + 1e-12
        assert info.window[1] - info.window[0] >= info.t_h * (1 - 1e-12)


def test_window_trips_hit_the_floor_exactly(seed, plans):
    n = 0
    for tp, info in zip(plans["optimal"].trips, plans["optimal"].info["trips"]):
        if info.candidate != "window":
            continue
        n += 1
        assert tp.duration == pytest.approx(info.window_floor, rel=1e-12)
        # the window is exactly tH: A, C, D fill it
        assert info.window[1] - info.window[0] == pytest.approx(info.t_h, rel=1e-12)
    assert n >= 10


def test_b_turns_at_the_top_without_stopping(plans):
    for i, tp in enumerate(plans["optimal"].trips):
        prof = _b_profile(plans["optimal"], i)
        zp, t0, t1 = position_peak(prof)
        assert t1 == t0  # one instant at the top, no dwell
        s = prof.sample(np.array([t0]))
        assert s.acceleration[0] < -0.1  # still decelerating: it turns, it does not stop
        # between the crossings B is never at rest
        a, b = tp.window
        ts = np.linspace(a, b, 4001)
        sm = prof.sample(ts)
        assert not np.any((np.abs(sm.velocity) < 1e-6) & (np.abs(sm.acceleration) < 1e-6))


def test_load_and_return_trips_mirror(plans):
    t = plans["optimal"].trip_times()
    np.testing.assert_allclose(t[0::2], t[1::2], rtol=1e-13)


def test_json_summary_and_bound_line(plans):
    s = summarize({"merged": plans["merged"], "optimal": plans["optimal"]}, baseline="merged")
    d = s["plans"]["optimal"]
    assert d["total_s"] == plans["optimal"].total_s
    assert 0.0 <= d["vs_lower_bound_pct"] <= 0.5
    assert sum(d["trip_candidates"].values()) == 50
    assert "lower_bound_s" not in s["plans"]["merged"]
    (line,) = bound_lines(s)
    assert line.startswith("optimal: ") and "% above its lower bound" in line
    assert "window floor" in line


# ----------------------------------------------------------- oracles
def _raised_trip(seed, plans, kind="load"):
    opt = plans["optimal"]
    worst = max((i for i, tp in enumerate(opt.trips) if tp.spec.kind == kind),
                key=lambda i: opt.info["trips"][i].gap_s)
    return opt.trips[worst].spec, opt.info["trips"][worst]


def test_no_better_crossing_states_nearby(seed, plans):
    """4-D Nelder-Mead over the crossing states finds nothing faster.

    Trip time = t(Z0 -> s1) + max(tH, t(s1 -> s2)) + t(s2 -> Z3) over the
    states s1 at Z1 and s2 at Z2 (every piece minimum time, independent of
    the planner's candidates), started from the planner's own crossings.
    """
    spec, info = _raised_trip(seed, plans)
    lb = seed.robot.limits[B]
    z0, z1, z2, z3 = spec.z_levels
    prof = next(tp for tp in plans["optimal"].trips if tp.spec is spec).pieces[B][0].profile
    s_up = prof.sample(np.array([info.window[0], info.window[1]]))
    x0 = [s_up.velocity[0], s_up.acceleration[0], s_up.velocity[1], s_up.acceleration[1]]

    def trip(x):
        try:
            s1, s2 = (z1, x[0], x[1]), (z2, x[2], x[3])
            return (min_state_duration((z0, 0.0, 0.0), s1, lb) + min_state_duration(s2, (z3, 0.0, 0.0), lb)
                    + max(info.t_h, min_state_duration(s1, s2, lb)))
        except Exception:
            return math.inf

    assert trip(x0) == pytest.approx(info.duration, abs=1e-9)
    r = minimize(trip, x0, method="Nelder-Mead",
                 options={"xatol": 1e-6, "fatol": 1e-9, "maxfev": 300,
                          "initial_simplex": np.array(x0) + np.vstack([np.zeros(4), 0.05 * np.eye(4)])})
    assert r.fun >= info.duration - 1e-6


def _lp_feasible(T, t_up, t_m, t_h, z, lim, n=200):
    """Is there a B motion of duration T (jerk constant on n steps) under the rule?

    B above Z1 on [t_up, t_m], above Z2 on [t_m, t_up + t_h] (sampled at the
    steps); |v|, |a|, |j| and the range kept; rest to rest.
    """
    z0, z1, z2, z3 = z
    dt = T / n
    k = np.arange(1, n + 1)[:, None]
    i = np.arange(n)[None, :]
    m = i < k
    d = k - i
    Aa = np.where(m, dt, 0.0)
    Av = np.where(m, dt * dt * (d - 0.5), 0.0)
    Ap = np.where(m, dt**3 * (d * d / 2 - d / 2 + 1 / 6), 0.0)
    t = k[:, 0] * dt
    w1 = (t >= t_up) & (t <= t_m)
    w2 = (t >= t_m) & (t <= t_up + t_h)
    if not w2.any():
        return False
    A_ub = np.vstack([Aa, -Aa, Av, -Av, Ap, -Ap[w1], -Ap[w2]])
    b_ub = np.concatenate([np.full(2 * n, lim.a_max), np.full(2 * n, lim.v_max),
                           np.full(n, lim.position_max - z0), np.full(w1.sum(), z0 - z1),
                           np.full(w2.sum(), z0 - z2)])
    A_eq = np.vstack([Aa[-1], Av[-1], Ap[-1]])
    r = linprog(np.zeros(n), A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=[0.0, 0.0, z3 - z0],
                bounds=[(-lim.j_max, lim.j_max)] * n, method="highs")
    return r.status == 0


def test_linear_programme_oracle_agrees_on_the_hardest_trip(seed, plans):
    """An independent direct transcription (LP, HiGHS) brackets the planner's time.

    On the trip farthest above its analytic bound: the LP finds a motion a
    hair slower than the planner's, and none 0.5 % faster over a scan of the
    window placement.
    """
    spec, info = _raised_trip(seed, plans)
    lim = seed.robot.limits[B]
    assert lim.a_max == lim.a_max_decel and lim.j_max == lim.j_max_decel  # LP has one leg
    z = spec.z_levels
    _, _, tu, _, _, _ = _throttle(spec, lim)
    T = info.duration
    t_up, t_dn = info.window
    assert _lp_feasible(T * 1.003, t_up, t_dn - 0.02, info.t_h, z, lim)
    for tu_try in (tu, tu + 0.01):
        for t_m in np.linspace(tu_try + 0.3 * info.t_h, tu_try + info.t_h - 0.01, 4):
            assert not _lp_feasible(T * 0.995, tu_try, t_m, info.t_h, z, lim)


# ----------------------------------------------------------- pieces
def test_full_throttle_reaches_v_max_and_cut_is_exact(seed):
    lb = seed.robot.limits[B]
    ph = full_throttle_phases(lb)
    p, v, a = 0.0, 0.0, 0.0
    for dt, j, a0 in ph[:-1]:
        assert abs(j) <= lb.j_max and abs(a0) <= lb.a_max
        p, v, a = p + dt * (v + dt * (a0 / 2 + dt * j / 6)), v + dt * (a0 + dt * j / 2), a0 + j * dt
    assert v == pytest.approx(lb.v_max, rel=1e-14) and abs(a) < 1e-12
    for d in (1e-6, 0.01, 0.2, 0.4, 1.0):
        cut, vc, ac, tc = _cut(ph, d)
        pe, ve = 0.0, 0.0
        for dt, j, a0 in cut:
            pe, ve = pe + dt * (ve + dt * (a0 / 2 + dt * j / 6)), ve + dt * (a0 + dt * j / 2)
        assert pe == pytest.approx(d, rel=1e-12) and ve == pytest.approx(vc, rel=1e-12)
        assert tc == pytest.approx(sum(c[0] for c in cut), rel=1e-14)
    # time reverse: ends at rest, starts at the cut state with v negated
    cut, vc, ac, _ = _cut(ph, 0.3)
    rev = _reverse(cut)
    p, v, a = 0.3, -vc, rev[0][2]
    assert a == pytest.approx(ac, rel=1e-14)
    for dt, j, a0 in rev:
        p, v = p + dt * (v + dt * (a0 / 2 + dt * j / 6)), v + dt * (a0 + dt * j / 2)
    assert abs(p) < 1e-12 and abs(v) < 1e-12


def test_full_throttle_rejects_no_finite_limit():
    lim = AxisLimits(math.inf, math.inf, 10.0)
    with pytest.raises(InvalidInputError, match="finite v_max or a_max"):
        full_throttle_phases(lim)
    with pytest.raises(InvalidInputError, match="leg must be"):
        full_throttle_phases(AxisLimits(1, 1, 1), "sideways")


def _random_updown(rng, lim):
    z0 = rng.uniform(0.2, 0.8)
    zp = rng.uniform(z0 + 0.05, 1.9)
    z3 = rng.uniform(0.2, zp - 0.02)
    ap = rng.uniform(-min(lim.a_max, lim.a_max_decel), 0.0)
    u = plan_state_to_state((z0, 0.0, 0.0), (zp, 0.0, ap), lim)
    d = plan_state_to_state((zp, 0.0, ap), (z3, 0.0, 0.0), lim)
    ph = list(zip(u.phase_durations, u.jerks, u.phase_accelerations)) + \
        list(zip(d.phase_durations, d.jerks, d.phase_accelerations))
    return StateProfile((z0, 0, 0), (z3, 0, 0), ph, u.duration + d.duration, 0, "test", lim), zp


@pytest.mark.parametrize("legs", ["symmetric", "asymmetric"])
def test_level_crossings_and_peak_against_dense_samples(legs):
    lim = AxisLimits(1.3, 5.2, 45.0, position_min=0.0, position_max=2.0) if legs == "symmetric" \
        else AxisLimits(1.3, 5.2, 45.0, 3.1, 20.0, position_min=0.0, position_max=2.0)
    rng = np.random.default_rng(7)
    for _ in range(N_PROF // 10):
        prof, zp_true = _random_updown(rng, lim)
        zp, t0, t1 = position_peak(prof)
        assert zp == pytest.approx(zp_true, abs=1e-12)
        ts = np.linspace(0, prof.duration, 20001)
        zs = prof.sample(ts).position
        assert zs.max() <= zp + 1e-12
        for x in rng.uniform(max(prof.start, prof.goal) + 1e-3, zp - 1e-3, 3):
            cr = level_crossings(prof, x)
            assert [d for _, d in cr] == [1, -1]
            for t, _ in cr:
                assert prof.sample(np.array([t])).position[0] == pytest.approx(x, abs=1e-12)
            # the dense samples change side of x exactly once around each crossing
            above = zs > x
            flips = ts[1:][above[1:] != above[:-1]]
            assert len(flips) == 2
            assert np.all(np.abs(flips - np.array([t for t, _ in cr])) <= ts[1] + 1e-12)
        rep = verify_state_profile(prof, n_samples=201)
        assert rep.ok, rep.violations


def test_clearance_crossings_cases():
    lim = AxisLimits(1.0, 2.0, 10.0)
    up = plan_state_to_state((0.0, 0, 0), (1.0, 0, 0), lim)
    dn = plan_state_to_state((1.0, 0, 0), (0.2, 0, 0), lim)
    pcs = [(0.0, up), (5.0, dn)]
    t_up, t_dn, zp = clearance_crossings(pcs, 0.5, 0.6, 0.0, 9.0, 0.0)
    assert zp == 1.0 and t_up < up.duration and 5.0 < t_dn < 5.0 + dn.duration
    assert up.sample(np.array([t_up])).position[0] == pytest.approx(0.5, abs=1e-12)
    # a peak that only touches the clearance closes the window at the peak
    t_up, t_dn, _ = clearance_crossings(pcs, 1.0, 1.0, 0.0, 9.0, 0.0)
    assert t_up == pytest.approx(up.duration) and t_dn == pytest.approx(5.0)
    # never high enough
    assert clearance_crossings(pcs, 1.2, 0.5, 0.0, 9.0, 0.0) is None
    # starts above Z1: the window opens at the trip start
    t_up, _, _ = clearance_crossings([(1.0, dn)], 0.1, 0.5, 0.0, 9.0, 1.0)
    assert t_up == 0.0


# ----------------------------------------------------------- verification
def test_verify_catches_horizontals_starting_early(seed, plans):
    opt = plans["optimal"]
    tl = opt.timeline
    shift = 0.02
    pieces = [list(p) for p in tl.pieces]
    for k in HORIZONTAL_JOINTS:
        pieces[k] = [Piece(pc.t0 - shift, pc.profile) for pc in pieces[k]]
    bad = CyclePlan("optimal", seed, opt.trips, opt.trip_starts,
                    Timeline(pieces, tl.start, tl.duration, names=tl.names))
    rep = verify_plan(bad, samples_per_s=100)
    assert not rep.ok
    assert any("outside the clearance window" in v or "while B is below" in v for v in rep.violations)


def test_verify_catches_a_b_profile_over_its_jerk(seed, plans):
    opt = plans["optimal"]
    tl = opt.timeline
    pieces = [list(p) for p in tl.pieces]
    pc = pieces[B][3]
    p = pc.profile
    # the same phases against tighter limits: now above the jerk limit
    tight = dataclasses.replace(p.limits, j_max=0.9 * p.limits.j_max, j_max_decel=0.9 * p.limits.j_max)
    ph = list(zip(p.phase_durations, p.jerks, p.phase_accelerations))
    pieces[B][3] = Piece(pc.t0, StateProfile(p.start_state, p.goal_state, ph, p.min_duration, 0,
                                             p.family, tight))
    bad = CyclePlan("optimal", seed, opt.trips, opt.trip_starts,
                    Timeline(pieces, tl.start, tl.duration, names=tl.names))
    rep = verify_plan(bad, samples_per_s=50)
    assert any("jerk" in v for v in rep.violations), rep.violations[:3]


def test_verify_state_profile_catches_a_wrong_goal_and_overspeed():
    lim = AxisLimits(1.0, 2.0, 10.0)
    p = plan_state_to_state((0.0, 0.5, 0.0), (2.0, 0.0, 0.0), lim)
    assert verify_state_profile(p).ok
    ph = list(zip(p.phase_durations, p.jerks, p.phase_accelerations))
    wrong = StateProfile(p.start_state, (2.001, 0.0, 0.0), ph, p.min_duration, 0, "x", lim)
    assert any(v.quantity == "goal" for v in verify_state_profile(wrong).violations)
    slow = dataclasses.replace(lim, v_max=0.9 * lim.v_max)
    bad = StateProfile(p.start_state, p.goal_state, ph, p.min_duration, 0, "x", slow)
    assert any(v.quantity == "velocity" for v in verify_state_profile(bad, n_samples=0).violations)


# ----------------------------------------------------------- sweeps
def test_random_scenarios_optimal_verifies_and_beats_merged():
    rng = np.random.default_rng(99)
    done = 0
    while done < N_SCEN:
        try:
            sc = _random_scenario(rng)
        except (InvalidInputError, UnreachableError):
            continue
        mer, opt = plan_cycle(sc, "merged"), plan_cycle(sc, "optimal")
        rep = verify_plan(opt, samples_per_s=100)
        assert rep.ok, rep.violations[:3]
        assert np.all(opt.trip_times() <= mer.trip_times() + 1e-9)
        for info in opt.info["trips"]:
            assert info.duration >= info.lower_bound - 1e-9
        done += 1


def test_asymmetric_b_limits_plan_and_verify():
    # B brakes harder than it accelerates (decel limits 1.5x)
    rob = CylindricalPalletizer.from_table(DEFAULT_JOINT_TABLE, decel={"B": (7800.0, 67500.0)})
    sc = seed_scenario(robot=rob)
    lb = sc.robot.limits[B]
    assert lb.a_max_decel > lb.a_max
    mer, opt = plan_cycle(sc, "merged"), plan_cycle(sc, "optimal")
    rep = verify_plan(opt)
    assert rep.ok, rep.violations[:3]
    assert opt.total_s < mer.total_s
    assert np.all(opt.trip_times() <= mer.trip_times() + 1e-9)
    for tp, info in zip(opt.trips, opt.info["trips"]):
        assert info.duration >= info.lower_bound - 1e-9
        floor, t_b = trip_bounds(sc, tp.spec)
        assert info.lower_bound == max(floor, t_b)


def test_trip_too_short_for_the_range_is_a_clear_error(seed):
    # B's range capped right at the clearance heights: no room to turn above Z2
    tab = dict(DEFAULT_JOINT_TABLE)
    spec = seed.trips()[48]
    z2 = max(spec.z_levels[1:3])
    row = list(tab["B"])
    row[4] = z2 * 1000.0
    tab["B"] = tuple(row)
    rob = CylindricalPalletizer.from_table(tab)
    sc = seed_scenario(robot=rob)
    spec = sc.trips()[48]
    assert _horizontal_time(sc, spec) > 0.3  # A, C, D need a real window
    with pytest.raises(InfeasibleError, match="no B motion keeps the limits"):
        plan_trip_optimal(sc, spec)
