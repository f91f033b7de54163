"""Seeded random sweeps of ``plan_move`` against an independent reference and ruckig.

Every case: duration equal to the brentq reference (tests/reference.py) to
1e-9 relative and never above it; goal reached (<= 1e-9 of the distance);
no limit exceeded by more than 1e-9 relative, checked exactly at the phase
boundaries and at in-phase extrema by :func:`trajkit.verify.verify_profile`
(and on dense samples for a share of the cases); continuity of p, v, a.
The same for fixed durations from the minimum to 100x the minimum, including
durations a hair above it.

CI runs 12,000 minimum-time and 12,000 fixed-duration cases; ``TRAJKIT_SWEEP=1``
runs 20x more.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import reference as R
from conftest import random_cases, sweep_size

from trajkit import AxisLimits, plan_move
from trajkit.verify import verify_profile

#: Durations must match the reference to this relative error.
REF_RTOL = 1e-9
#: Residual of the reference's time equation at the planner's cruise velocity.
RESIDUAL_RTOL = 1e-12
#: A planner duration above the reference by more than this is "longer".
NOT_LONGER_RTOL = 1e-12
#: Ruckig agreement on symmetric moves.
RUCKIG_RTOL = 1e-9
#: Every DENSE_EVERY-th case is also checked on dense samples.
DENSE_EVERY = 10
DENSE_SAMPLES = 65

N_CASES = sweep_size(12_000)


def _check_min_time(case):
    lim = case.limits()
    p = plan_move(case.start, case.goal, lim)
    d = abs(p.goal - p.start)  # the distance the planner was asked for
    ref = R.min_duration(d, case.v_max, case.a_max, case.j_max,
                         case.a_max_decel, case.j_max_decel)
    problems = []
    if d == 0.0:
        if p.duration != 0.0 or p.shape != "zero":
            problems.append(f"zero move: duration {p.duration}, shape {p.shape}")
    else:
        rel = (p.duration - ref) / ref
        if abs(rel) > REF_RTOL:
            problems.append(f"duration {p.duration!r} vs reference {ref!r} (rel {rel:.3e})")
        if p.duration > ref * (1.0 + NOT_LONGER_RTOL):
            problems.append(f"duration {p.duration!r} above the reference {ref!r}")
    return p, problems


@pytest.mark.parametrize("chunk", range(4))
def test_min_time_sweep(chunk):
    """Minimum-time moves: reference duration, goal, limits, continuity."""
    cases = random_cases(1000 + chunk, N_CASES // 4)
    failures = []
    worst = 0.0
    for i, case in enumerate(cases):
        p, problems = _check_min_time(case)
        rep = verify_profile(p, n_samples=DENSE_SAMPLES if i % DENSE_EVERY == 0 else 0)
        if not rep.ok:
            problems.append(str(rep.violations))
        worst = max(worst, rep.worst_ratio)
        if problems:
            failures.append((case.as_tuple(), case.kind, problems))
    assert not failures, f"{len(failures)} failures, first: {failures[:3]}"
    # the sweep does reach the limits (the checks are not vacuous)
    assert worst > 0.999


@pytest.mark.parametrize("chunk", range(4))
def test_fixed_duration_sweep(chunk):
    """Fixed durations from the minimum (and a hair above) to 100x the minimum."""
    rng = np.random.default_rng(5000 + chunk)
    cases = random_cases(2000 + chunk, N_CASES // 4)
    failures = []
    for i, case in enumerate(cases):
        lim = case.limits()
        tmin = plan_move(case.start, case.goal, lim).duration
        r = rng.random()
        if r < 0.1:
            factor = 1.0
        elif r < 0.4:
            factor = 1.0 + float(np.exp(rng.uniform(math.log(1e-15), math.log(1e-5))))
        else:
            factor = float(np.exp(rng.uniform(0.0, math.log(100.0))))
        T = tmin * factor if tmin > 0 else factor
        p = plan_move(case.start, case.goal, lim, duration=T)
        rep = verify_profile(p, n_samples=DENSE_SAMPLES if i % DENSE_EVERY == 0 else 0,
                             expected_duration=T)
        problems = [] if rep.ok else [str(rep.violations)]
        if p.duration != T:
            problems.append(f"duration {p.duration!r} != requested {T!r}")
        d = abs(p.goal - p.start)
        if d > 0.0:
            a1, j1, a2, j2 = case.a_max, case.j_max, case.a_max_decel, case.j_max_decel
            vc = abs(p.peak_velocity)
            # backward error: the planner's cruise velocity solves the
            # reference's own time equation
            res = (R.time_at(vc, a1, j1, a2, j2) + (d - R.dist_at(vc, a1, j1, a2, j2)) / vc - T) / T
            if abs(res) > RESIDUAL_RTOL:
                problems.append(f"time residual {res:.3e} at vc {vc!r}")
            # forward error where the problem is well conditioned (away from
            # the minimum, where dT/dv vanishes for trapezoid legs)
            if factor > 1.0 + 1e-4:
                vref, _ = R.fixed_duration(d, T, case.v_max, a1, j1, a2, j2)
                if abs(vc - vref) > REF_RTOL * vref:
                    problems.append(f"cruise velocity {vc!r} vs reference {vref!r}")
        if problems:
            failures.append((case.as_tuple(), case.kind, factor, problems))
    assert not failures, f"{len(failures)} failures, first: {failures[:3]}"


def test_sweep_covers_every_shape():
    """The random cases hit every profile shape (the sweep is not one-sided)."""
    shapes = set()
    kinds = set()
    for case in random_cases(1000, 3000):
        p = plan_move(case.start, case.goal, case.limits())
        shapes.add(p.shape)
        kinds.add(case.kind)
    for s in ("7-phase", "no-cruise", "no-const-accel+no-cruise", "no-const-decel+no-cruise",
              "no-const-accel+no-const-decel+no-cruise", "zero",
              "trapezoid", "trapezoid+no-cruise", "jerk-free-accel+no-cruise"):
        assert s in shapes, (s, shapes)
    assert kinds == {"general", "symmetric", "trapezoid", "trapezoid_accel", "no_a_limit",
                     "no_a_limit_decel", "no_v_limit", "zero"}


# ---------------------------------------------------------------- ruckig
ruckig = pytest.importorskip("ruckig")


def _ruckig_duration(d, v, a, j):
    inp = ruckig.InputParameter(1)
    inp.current_position = [0.0]
    inp.target_position = [d]
    inp.max_velocity = [v]
    inp.max_acceleration = [a]
    inp.max_jerk = [j]
    traj = ruckig.Trajectory(1)
    res = ruckig.Ruckig(1).calculate(inp, traj)
    assert res in (ruckig.Result.Working, ruckig.Result.Finished), res
    return traj.duration


def test_symmetric_matches_ruckig():
    """Symmetric limits, finite v/a/j: same minimum duration as ruckig."""
    rng = np.random.default_rng(77)
    n = sweep_size(3000)
    worst = 0.0
    bad = []
    for _ in range(n):
        v, a, j = (float(x) for x in np.exp(rng.uniform(math.log(1e-3), math.log(1e3), 3)))
        d = float(np.exp(rng.uniform(math.log(1e-4), math.log(1e4)))) * rng.choice([-1.0, 1.0])
        ours = plan_move(0.0, d, AxisLimits(v, a, j)).duration
        theirs = _ruckig_duration(d, v, a, j)
        rel = abs(ours - theirs) / theirs
        worst = max(worst, rel)
        if rel > RUCKIG_RTOL:
            bad.append((d, v, a, j, ours, theirs))
    assert not bad, bad[:5]


def test_reference_matches_ruckig():
    """The test oracle itself agrees with ruckig (it is not wrong the same way)."""
    rng = np.random.default_rng(78)
    for _ in range(200):
        v, a, j = (float(x) for x in np.exp(rng.uniform(math.log(1e-2), math.log(1e2), 3)))
        d = float(np.exp(rng.uniform(math.log(1e-3), math.log(1e3))))
        ref = R.min_duration(d, v, a, j)
        assert ref == pytest.approx(_ruckig_duration(d, v, a, j), rel=RUCKIG_RTOL)


def test_region_thresholds_to_the_ulp():
    """Distances a few ulp either side of every region boundary.

    The boundaries are the distances whose peak velocity is exactly v_max,
    A1^2/J1 or A2^2/J2 (computed by the reference); the planner must switch
    formula there without a jump in duration and without breaking a limit.
    """
    rng = np.random.default_rng(91)
    n = sweep_size(250)
    eps = np.finfo(float).eps
    failures = []
    for _ in range(n):
        v, a, j = (float(x) for x in np.exp(rng.uniform(math.log(1e-3), math.log(1e3), 3)))
        a2 = a * float(np.exp(rng.uniform(math.log(0.05), math.log(20.0))))
        j2 = j * float(np.exp(rng.uniform(math.log(0.05), math.log(20.0))))
        if rng.random() < 0.2:
            j = j2 = math.inf
        lim = AxisLimits(v, a, j, a2, j2)
        for vb in (v, a * a / j, a2 * a2 / j2):
            if not (0.0 < vb <= v):
                continue
            boundary = R.dist_at(vb, a, j, a2, j2)
            for k in (-1e6, -4, -1, 0, 1, 4, 1e6):
                d = boundary * (1.0 + k * eps)
                p = plan_move(0.0, d, lim)
                ref = R.min_duration(d, v, a, j, a2, j2)
                rep = verify_profile(p, n_samples=0)
                T = p.duration * (1.0 + 10.0 ** rng.uniform(-15, -3))
                q = plan_move(0.0, d, lim, duration=T)
                rq = verify_profile(q, n_samples=0, expected_duration=T)
                if abs(p.duration - ref) > REF_RTOL * ref or not rep.ok or not rq.ok:
                    failures.append(((v, a, j, a2, j2, d), p.duration, ref,
                                     rep.violations, rq.violations))
    assert not failures, failures[:3]


@pytest.mark.parametrize("exponent", [30, 150])
def test_extreme_magnitudes_grid(exponent):
    """Limits 10^-E, 1, 10^E, inf in every combination; distances 1e-100..1e100."""
    import itertools

    small, big = 10.0 ** -exponent, 10.0 ** exponent
    values = (small, 1.0, big, math.inf)
    failures = []
    for d in (1e-100, 1e-30, 1e-9, 1.0, 1e9, 1e30, 1e100):
        for v, a, j in itertools.product(values, values, values):
            if math.isinf(a) and math.isinf(j):
                continue
            lim = AxisLimits(v, a, j, a * 3.0, j * 0.5)
            p = plan_move(0.0, d, lim)
            rep = verify_profile(p, n_samples=0)
            T = 2.0 * p.duration
            rq = verify_profile(plan_move(0.0, d, lim, duration=T), n_samples=0,
                                expected_duration=T)
            if not (math.isfinite(p.duration) and rep.ok and rq.ok):
                failures.append((d, v, a, j, rep.violations, rq.violations))
    assert not failures, failures[:3]
