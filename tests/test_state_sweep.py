"""Seeded property sweeps of the state-to-state planner (>= 10,000 cases).

Default sizes keep this file well under a minute; ``TRAJKIT_SWEEP=1``
multiplies them by 10.

* symmetric limits: minimum durations equal ruckig's (``Ruckig(1).calculate``)
  to 1e-6 relative, over random non-zero states and the hard corners;
* asymmetric limits: bracketed by ruckig with the loosest and the tightest
  symmetric limits, and equal to an independent double-S formula where it
  applies (test_state_profiles.py);
* every profile: goal state reached to 1e-9, every limit kept (independent
  exact check at phase boundaries, extrema and v = 0 crossings, plus dense
  samples);
* fixed durations (6,000 requests): exactly the requested duration,
  or a blocked interval that ruckig confirms (no false "blocked");
* velocity interface and brake pre-phases.
"""

from __future__ import annotations

import os

import numpy as np
import pytest
from state_reference import (
    dense_check,
    exact_check,
    goal_error,
    random_case,
    ruckig_duration,
    ruckig_fixed,
    ruckig_velocity_duration,
)

from trajkit import AxisLimits
from trajkit.errors import InfeasibleError
from trajkit.profiles.state import (
    BlockedDurationError,
    plan_state_to_state,
    plan_velocity,
)

SCALE = 10 if os.environ.get("TRAJKIT_SWEEP") == "1" else 1

N_SYMMETRIC = 1500 * SCALE
N_ASYMMETRIC = 700 * SCALE
N_FIXED = 1500 * SCALE  # 4 durations each: 6,000 requests (60,000 with TRAJKIT_SWEEP=1)
N_VELOCITY = 6000 * SCALE
N_BRAKE = 2000 * SCALE


def _check(prof, lim, dense=True):
    why = exact_check(prof, lim)
    assert why is None, why
    err = goal_error(prof)
    assert err < 1e-9, err
    if dense:
        why = dense_check(prof, lim, n=1001)
        assert why is None, why


def test_symmetric_matches_ruckig():
    rng = np.random.default_rng(2024)
    n = 0
    for i in range(N_SYMMETRIC):
        s, g, L = random_case(rng, symmetric=True)
        lim = AxisLimits(*L)
        p = plan_state_to_state(s, g, lim)
        _check(p, lim, dense=i % 10 == 0)
        if s == g:
            # already there: duration 0 (ruckig plans a detour instead)
            assert p.duration == 0.0
            continue
        ref = ruckig_duration(s, g, L[0], L[1], L[2])
        assert ref is not None
        assert p.duration == pytest.approx(ref, rel=1e-6, abs=1e-12), (i, s, g, L)
        n += 1
    assert n >= 0.9 * N_SYMMETRIC


def test_asymmetric_bracketed_by_ruckig():
    rng = np.random.default_rng(77)
    for i in range(N_ASYMMETRIC):
        s, g, L = random_case(rng, symmetric=False)
        lim = AxisLimits(*L)
        p = plan_state_to_state(s, g, lim)
        _check(p, lim, dense=i % 10 == 0)
        if s[:2] == g[:2]:
            continue
        V, A1, J1, A2, J2 = L
        loose = ruckig_duration(s, g, V, max(A1, A2), max(J1, J2))
        tight = ruckig_duration(s, g, V, min(A1, A2), min(J1, J2))
        # never faster than allowed by the loosest limits, never slower than
        # the tightest symmetric solution (valid under ours)
        assert p.duration >= loose * (1 - 1e-6), (i, s, g, L)
        # the tight problem is only comparable when its own start/goal are valid
        Jm, Am = min(J1, J2), min(A1, A2)
        ok_tight = all(
            abs(st[2]) <= Am and abs(st[1] + sg * st[2] * abs(st[2]) / (2 * Jm)) <= V
            for st, sg in ((s, 1.0), (g, -1.0))
        )
        if ok_tight and tight is not None:
            assert p.duration <= tight * (1 + 1e-6), (i, s, g, L)


def test_fixed_duration_against_ruckig():
    """Fixed durations: every one ruckig can fill, we fill (no false
    "blocked"); every blocked interval is confirmed by ruckig at its upper
    end, and both of its ends are feasible durations."""
    rng = np.random.default_rng(9)
    n_false_block = 0
    n_total = 0
    n_blocked = 0
    n_no_oracle = 0
    for i in range(N_FIXED):
        s, g, L = random_case(rng, symmetric=True)
        if s == g:
            continue
        lim = AxisLimits(*L)
        p = plan_state_to_state(s, g, lim)
        for f in (1e-6, 0.01, 0.1, 0.5):
            T = p.duration * (1.0 + f)
            ref = ruckig_fixed(s, g, L[0], L[1], L[2], T)
            n_total += 1
            if ref is None:
                # ruckig failed (rare): ours must still be valid or blocked
                n_no_oracle += 1
                try:
                    q = plan_state_to_state(s, g, lim, duration=T)
                except BlockedDurationError:
                    continue
                assert q.duration == pytest.approx(T, rel=1e-12)
                _check(q, lim, dense=False)
                continue
            try:
                q = plan_state_to_state(s, g, lim, duration=T)
            except BlockedDurationError as err:
                lo, hi = err.interval
                assert lo <= T <= hi
                if ref <= T * (1 + 1e-9):
                    n_false_block += 1  # a feasible T we could not fill
                    continue
                n_blocked += 1
                # ruckig agrees the interval is blocked and where it ends
                assert hi == pytest.approx(ref, rel=1e-6)
                # both ends are feasible durations (the lower one: ours, the
                # upper one: ours and ruckig's)
                for t_end in (lo, hi):
                    _check(plan_state_to_state(s, g, lim, duration=t_end), lim, dense=False)
                continue
            # a profile we return must be feasible: ruckig must agree
            assert ref == pytest.approx(T, rel=1e-9), (i, s, g, L, T)
            assert q.duration == pytest.approx(T, rel=1e-12)
            _check(q, lim, dense=(i % 25 == 0))
    assert n_total >= 0.99 * 4 * N_FIXED
    assert n_no_oracle <= 1e-3 * n_total
    assert n_blocked > 0
    # measured: 0 false blocks in 6 x 10,000 requests (docs/state-profiles.md)
    assert n_false_block == 0


N_FIXED_ASYMMETRIC = 300 * SCALE


def test_fixed_duration_asymmetric_hole_is_filled():
    """Asymmetric limits, a reversal between a start that speeds up and a goal at
    v_max: every step-2 family missed the durations 2.05..3.44 s (the leg
    changes within a hold). The fallback (fastest velocity change to a cruise,
    the cruise, fastest velocity change to the goal's velocity and acceleration)
    fills them exactly."""
    s, g = (-0.5963202627477577, -0.5533282370375284, -0.511925761104837), (-0.9521145791756845, 0.7512112489670693, 0.41543330300172043)
    lim = AxisLimits(0.7512112489670693, 1.6030418409186065, 21.826154752548653, 0.511925761104837,
                     43.27977313259438)
    t_min = plan_state_to_state(s, g, lim).duration
    assert t_min == pytest.approx(1.98463, abs=1e-5)
    for T in np.linspace(2.05, 3.44, 15):
        q = plan_state_to_state(s, g, lim, duration=T)
        assert q.duration == pytest.approx(T, rel=1e-12)
        _check(q, lim)


def test_fixed_duration_asymmetric_sweep(capsys):
    """Asymmetric fixed durations ``T = T_min (1 + f)``, ``f`` in 0.01..3: every
    returned profile has exactly ``T`` and keeps every limit; the requests no
    family or fallback fills are counted (a known gap, docs/state-profiles.md)."""
    rng = np.random.default_rng(7)
    n_req = n_none = n_blocked = 0
    for _ in range(N_FIXED_ASYMMETRIC):
        s, g, L = random_case(rng, symmetric=False)
        lim = AxisLimits(*L)
        p = plan_state_to_state(s, g, lim)
        for f in rng.uniform(0.01, 3.0, size=5):
            T = p.duration * (1.0 + f)
            try:
                q = plan_state_to_state(s, g, lim, duration=T)
            except BlockedDurationError as err:
                lo, hi = err.interval
                assert lo <= T <= hi
                n_blocked += 1
                continue
            except InfeasibleError as err:
                assert "no profile found" in str(err)
                assert "a longer duration may be feasible" in str(err)
                n_req += 1
                n_none += 1
                continue
            n_req += 1
            assert q.duration == pytest.approx(T, rel=1e-12)
            _check(q, lim, dense=False)
    with capsys.disabled():
        print(f"\nasymmetric fixed durations: {n_req} requests, {n_none} without a profile, "
              f"{n_blocked} blocked")
    # measured: 0 of 1,490 (this seed, 300 cases); with benchmarks/state_step2_study.py
    # (T = T_min f, f in [1, 3]) 0 of 11,992 (seed 2), 0 of 8,000 (seed 11) and 13 of
    # 479,708 (seeds 20-59) for the families alone, 2 with the split into two halves
    assert n_none <= 0.001 * n_req


def test_velocity_interface_sweep():
    rng = np.random.default_rng(31)
    for i in range(N_VELOCITY):
        s, g, L = random_case(rng, symmetric=bool(i % 2))
        lim = AxisLimits(*L)
        p = plan_velocity(s, g[1], g[2], limits=lim)
        _check(p, lim, dense=i % 20 == 0)
        assert p.goal_state[1:] == (g[1], g[2])
        if L[1] == L[3] and L[2] == L[4]:
            # symmetric limits: ruckig's velocity interface gives the same time
            ref = ruckig_velocity_duration(s, g[1], g[2], L[0], L[1], L[2])
            assert p.duration == pytest.approx(ref, rel=1e-6, abs=1e-12), (i, s, g, L)


def test_controlled_stop_sweep_with_brake():
    """Start states anywhere (also beyond the limits): brake, then a valid stop."""
    rng = np.random.default_rng(5)
    n_brake = 0
    for i in range(N_BRAKE):
        V = 10 ** rng.uniform(-1, 1)
        A1, A2 = 10 ** rng.uniform(-1, 1, 2)
        J1, J2 = 10 ** rng.uniform(-1, 1.5, 2)
        lim = AxisLimits(V, A1, J1, A2, J2)
        v0 = rng.uniform(-2, 2) * V
        a0 = rng.uniform(-2, 2) * min(A1, A2)
        p = plan_velocity((0.0, v0, a0), 0.0, limits=lim)
        n_brake += p.brake_duration > 0
        _check(p, lim, dense=i % 20 == 0)
        # the brake never makes |v| larger than the start state forces:
        # peak |v| <= the velocity reached by ramping a0 to zero at the
        # smaller jerk limit, |v0 + a0 |a0| / (2 min(J1, J2))|, or |v0|
        b = p.boundary_states()
        natural = abs(v0 + a0 * abs(a0) / (2 * min(J1, J2)))
        bound = max(V, abs(v0), natural)
        assert np.abs(b[:, 1]).max() <= bound * (1 + 1e-9) + 1e-12
    assert n_brake > N_BRAKE // 4
