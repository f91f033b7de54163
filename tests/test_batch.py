"""``plan_moves`` (vectorised) against ``plan_move`` (scalar), move by move."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import random_cases, sweep_size
from floatcmp import assert_ulp_close

from trajkit import AxisLimits, InfeasibleError, InvalidInputError, plan_move, plan_moves
from trajkit.verify import verify_profile

#: Compares two code paths (see floatcmp); CI runs it again with numpy SIMD off.
pytestmark = pytest.mark.codepaths

#: Batch and scalar agree to 1e-12 relative (two code paths: never bit for bit).
BATCH_RTOL = 1e-12

N = sweep_size(4000)


def _arrays(cases):
    cols = np.array([c.as_tuple() for c in cases], dtype=float)
    return [cols[:, k] for k in range(7)]


def _rel(a, b, scale):
    return np.abs(a - b) / np.where(scale > 0, scale, 1.0)


def _compare(batch, profiles):
    dur = np.array([p.duration for p in profiles])
    ph = np.array([p.phase_durations for p in profiles])
    jk = np.array([p.jerks for p in profiles])
    vp = np.array([p.peak_velocity for p in profiles])
    ap = np.array([p.peak_acceleration for p in profiles])
    ad = np.array([p.peak_deceleration for p in profiles])
    assert np.max(_rel(batch.duration, dur, dur)) <= BATCH_RTOL
    assert np.max(_rel(batch.phase_durations, ph, dur[:, None])) <= BATCH_RTOL
    assert np.max(_rel(batch.jerks, jk, np.abs(jk))) <= BATCH_RTOL
    assert np.max(_rel(batch.peak_velocity, vp, np.abs(vp))) <= BATCH_RTOL
    assert np.max(_rel(batch.peak_acceleration, ap, ap)) <= BATCH_RTOL
    assert np.max(_rel(batch.peak_deceleration, ad, ad)) <= BATCH_RTOL
    # phase times (cumulative sums) too
    assert np.max(_rel(np.cumsum(batch.phase_durations, axis=1), np.cumsum(ph, axis=1),
                       dur[:, None])) <= BATCH_RTOL


def test_batch_matches_scalar_min_time():
    cases = random_cases(31, N)
    s, g, v, a, j, a2, j2 = _arrays(cases)
    batch = plan_moves(s, g, v, a, j, a2, j2)
    assert len(batch) == N
    profiles = [plan_move(c.start, c.goal, c.limits()) for c in cases]
    _compare(batch, profiles)
    np.testing.assert_array_equal(batch.min_duration, batch.duration)


def test_batch_matches_scalar_fixed_durations():
    rng = np.random.default_rng(32)
    cases = random_cases(33, N)
    s, g, v, a, j, a2, j2 = _arrays(cases)
    tmin = plan_moves(s, g, v, a, j, a2, j2).duration
    r = rng.random(N)
    factor = np.where(r < 0.3, 1.0 + np.exp(rng.uniform(np.log(1e-15), np.log(1e-5), N)),
                      np.exp(rng.uniform(0.0, np.log(100.0), N)))
    factor[r > 0.95] = 1.0
    T = np.where(tmin > 0, tmin * factor, factor)
    batch = plan_moves(s, g, v, a, j, a2, j2, durations=T)
    np.testing.assert_array_equal(batch.duration, T)
    profiles = [plan_move(c.start, c.goal, c.limits(), duration=t) for c, t in zip(cases, T)]
    _compare(batch, profiles)
    np.testing.assert_array_equal(batch.min_duration, tmin)


def test_batch_profile_is_verified():
    cases = random_cases(34, 300)
    s, g, v, a, j, a2, j2 = _arrays(cases)
    batch = plan_moves(s, g, v, a, j, a2, j2)
    for i in range(len(batch)):
        verify_profile(batch.profile(i), n_samples=33).raise_if_failed()


def test_scalar_limits_broadcast_and_symmetric_default():
    s = np.zeros(5)
    g = np.array([0.1, -0.5, 2.0, 0.0, 7.0])
    batch = plan_moves(s, g, 1.0, 2.0, 10.0)
    for i in range(5):
        p = plan_move(0.0, g[i], AxisLimits(1.0, 2.0, 10.0))
        assert_ulp_close(batch.duration[i], p.duration, err_msg="duration")
        assert_ulp_close(batch.phase_durations[i], p.phase_durations, scale=p.duration,
                         err_msg="phases")
    assert batch.duration[3] == 0.0 and batch.peak_velocity[3] == 0.0
    assert batch.peak_velocity[1] < 0.0


def test_scalar_duration_broadcasts():
    batch = plan_moves([0.0, 0.0], [1.0, -2.0], 1.0, 2.0, 10.0, durations=10.0)
    np.testing.assert_array_equal(batch.duration, [10.0, 10.0])


def test_infeasible_duration_names_move_and_minimum():
    with pytest.raises(InfeasibleError, match=r"durations\[1\] = 1\.0 s is below the minimum "
                                              r"duration 2\.7 s") as ei:
        plan_moves([0.0, 0.0], [1.0, 2.0], 1.0, 2.0, 10.0, durations=[5.0, 1.0])
    assert ei.value.minimum == pytest.approx(2.7)


@pytest.mark.parametrize("kwargs,match", [
    (dict(starts=[[0.0]], goals=[[1.0]]), r"starts must have 1 dimension\(s\), got shape \(1, 1\)"),
    (dict(starts=[0.0, 1.0], goals=[1.0]),
     r"starts and goals must have the same shape, got \(2,\) and \(1,\)"),
    (dict(starts=[0.0, math.nan], goals=[1.0, 1.0]), r"starts\[1\] must be finite, got nan"),
    (dict(goals=[1.0, math.inf]), r"goals\[1\] must be finite, got inf"),
    (dict(v_max=[1.0, 2.0, 3.0]), r"v_max must be a scalar or have 2 entries, got shape \(3,\)"),
    (dict(a_max=[1.0, -2.0]), r"a_max\[1\] should be larger than zero, got -2\.0"),
    (dict(j_max=math.nan), r"j_max\[0\] should be larger than zero, got nan"),
    (dict(a_max=math.inf, j_max=math.inf), r"a_max\[0\] and j_max\[0\] cannot both be infinite"),
    (dict(a_max_decel=[1.0, math.inf], j_max_decel=math.inf),
     r"a_max_decel\[1\] and j_max_decel\[1\] cannot both be infinite"),
    (dict(durations=[1.0, 2.0, 3.0]), r"durations must be a scalar or have 2 entries"),
    (dict(durations=[1.0, -2.0]), r"durations\[1\] must be finite and >= 0 s, got -2\.0"),
    (dict(durations=[math.nan, 1.0]), r"durations\[0\] must be finite and >= 0 s, got nan"),
])
def test_bad_batch_input(kwargs, match):
    args = dict(starts=[0.0, 0.0], goals=[1.0, 2.0], v_max=1.0, a_max=2.0, j_max=10.0)
    args.update(kwargs)
    with pytest.raises(InvalidInputError, match=match):
        plan_moves(**args)
