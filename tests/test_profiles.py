"""One-axis profiles: the cases named in issue 2, seed closed forms, exact states.

Each named case asserts its ``shape`` and ``reached`` set, exact states at the
phase boundaries (hand-derived numbers), the limits via ``verify_profile``,
and the duration against the independent reference.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import reference as R
from hypothesis import given, settings
from hypothesis import strategies as st

from trajkit import AxisLimits, InfeasibleError, min_duration, plan_move
from trajkit._constants import DURATION_RTOL
from trajkit.profiles import PHASE_NAMES
from trajkit.verify import verify_profile

EXACT = 1e-12  # relative tolerance for hand-derived values (a few ulp of work)

SYM = AxisLimits(v_max=1.0, a_max=2.0, j_max=10.0)  # a^2/j = 0.4, ramp to v: 0.7 s
# accel leg never reaches a_max below v = 2; decel leg reaches it above 0.1
SLOW_JERK_UP = AxisLimits(v_max=1.0, a_max=2.0, j_max=2.0, a_max_decel=1.0, j_max_decel=10.0)
SLOW_JERK_DOWN = AxisLimits(v_max=1.0, a_max=1.0, j_max=10.0, a_max_decel=2.0, j_max_decel=2.0)
BOTH_SLOW = AxisLimits(v_max=1.0, a_max=2.0, j_max=1.0)


def _ref(p):
    lim = p.limits
    return R.min_duration(p.goal - p.start, lim.v_max, lim.a_max, lim.j_max,
                          lim.a_max_decel, lim.j_max_decel)


def _checked(start, goal, limits, **kw):
    p = plan_move(start, goal, limits, **kw)
    verify_profile(p).raise_if_failed()
    if "duration" not in kw and goal != start:
        assert p.duration == pytest.approx(_ref(p), rel=1e-9)
    return p


# ------------------------------------------------------------ named cases
NAMED = [
    # (id, start, goal, limits, shape, reached)
    ("7-phase", 0.0, 5.0, SYM, "7-phase", {"v_max", "a_max", "a_max_decel"}),
    ("no-cruise", 0.0, 0.5, SYM, "no-cruise", {"a_max", "a_max_decel"}),
    ("no-const-at-all", 0.0, 0.1, SYM, "no-const-accel+no-const-decel+no-cruise", set()),
    ("accel-leg-only", 0.0, 10.0, SLOW_JERK_UP, "no-const-accel", {"v_max", "a_max_decel"}),
    ("accel-leg-only-no-cruise", 0.0, 1.0, SLOW_JERK_UP, "no-const-accel+no-cruise",
     {"a_max_decel"}),
    ("decel-leg-only", 0.0, 10.0, SLOW_JERK_DOWN, "no-const-decel", {"v_max", "a_max"}),
    ("decel-leg-only-no-cruise", 0.0, 1.0, SLOW_JERK_DOWN, "no-const-decel+no-cruise",
     {"a_max"}),
    ("both-legs", 0.0, 10.0, BOTH_SLOW, "no-const-accel+no-const-decel", {"v_max"}),
    ("zero", 3.0, 3.0, SYM, "zero", set()),
    ("negative", 2.0, -3.0, SYM, "7-phase", {"v_max", "a_max", "a_max_decel"}),
    ("trapezoid", 0.0, 5.0, AxisLimits(1.0, 2.0, math.inf), "trapezoid",
     {"v_max", "a_max", "a_max_decel"}),
    ("triangle", 0.0, 0.2, AxisLimits(1.0, 2.0, math.inf), "trapezoid+no-cruise",
     {"a_max", "a_max_decel"}),
    ("no-a-limit", 0.0, 5.0, AxisLimits(1.0, math.inf, 10.0), "no-const-accel+no-const-decel",
     {"v_max"}),
]


@pytest.mark.parametrize("start,goal,limits,shape,reached",
                         [c[1:] for c in NAMED], ids=[c[0] for c in NAMED])
def test_named_case_shape_and_limits(start, goal, limits, shape, reached):
    p = _checked(start, goal, limits)
    assert p.shape == shape
    assert p.reached == frozenset(reached)
    assert len(p.phase_durations) == len(p.jerks) == len(PHASE_NAMES) == 7
    # sample the move densely and independently: ends at rest at the goal
    s = p.sample(np.linspace(0.0, p.duration, 2001))
    assert s.position[-1] == goal
    assert s.velocity[-1] == 0.0
    if goal != start:
        assert np.all(np.sign(s.velocity[1:-1]) * np.sign(goal - start) >= 0.0)


def test_cao2012_full_profile_closed_form():
    """Cao et al. (2012): full profile accel time t1 = a/J + V/a, T = D/V + V/a + a/J (symmetric)."""
    V, A, J, D = 1.0, 2.0, 10.0, 5.0
    p = _checked(0.0, D, SYM)
    t = p.phase_durations
    assert t[0] + t[1] + t[2] == pytest.approx(A / J + V / A, rel=EXACT)
    assert p.duration == pytest.approx(D / V + V / A + A / J, rel=EXACT)
    assert t == pytest.approx((0.2, 0.3, 0.2, 4.3, 0.2, 0.3, 0.2), rel=EXACT)


def test_cao2012_no_const_accel_no_cruise_closed_form():
    """Cao et al. (2012): t2 = 2 (S / (2J))^(1/3) per half when neither a nor v is reached."""
    S, J = 0.1, 10.0
    p = _checked(0.0, S, SYM)
    half = 2.0 * (S / (2.0 * J)) ** (1.0 / 3.0)
    assert p.duration == pytest.approx(2.0 * half, rel=EXACT)
    assert p.peak_acceleration == pytest.approx(J * half / 2.0, rel=EXACT)
    assert p.peak_acceleration < SYM.a_max


def test_docstring_example():
    p = plan_move(0.0, 1.0, AxisLimits(v_max=1.0, a_max=2.0, j_max=10.0))
    assert p.duration == pytest.approx(1.7, rel=EXACT)


def test_boundary_states_exact():
    """Hand-integrated states at every boundary of the 7-phase case."""
    p = plan_move(0.0, 5.0, SYM)
    bs = p.boundary_states()
    assert bs.shape == (8, 3)
    # end of jerk-up: p = J t^3/6, v = J t^2/2, a = J t
    expected = np.array([
        [0.0, 0.0, 0.0],
        [10 * 0.2 ** 3 / 6, 0.2, 2.0],
        [10 * 0.2 ** 3 / 6 + 0.2 * 0.3 + 0.3 ** 2, 0.8, 2.0],
        [0.35, 1.0, 0.0],          # a ramp covers v * T_ramp / 2
        [0.35 + 4.3, 1.0, 0.0],
        [4.65 + 0.2 - 10 * 0.2 ** 3 / 6, 0.8, -2.0],
        [5.0 - 10 * 0.2 ** 3 / 6, 0.2, -2.0],    # mirror of the first jerk phase
        [5.0, 0.0, 0.0],
    ])
    np.testing.assert_allclose(bs, expected, rtol=EXACT, atol=EXACT)
    np.testing.assert_allclose(p.phase_times, [0, 0.2, 0.5, 0.7, 5.0, 5.2, 5.5, 5.7],
                               rtol=EXACT)
    # sample() agrees with the boundary table on both sides of each boundary
    s = p.sample(p.phase_times)
    np.testing.assert_allclose(s.position, bs[:, 0], rtol=EXACT, atol=EXACT)
    np.testing.assert_allclose(s.velocity, bs[:, 1], rtol=EXACT, atol=EXACT)
    assert p.jerks == (10.0, 0.0, -10.0, 0.0, -10.0, 0.0, 10.0)


def test_negative_move_mirrors_positive():
    pos = plan_move(0.0, 5.0, SLOW_JERK_UP)
    neg = plan_move(5.0, 0.0, SLOW_JERK_UP)
    assert neg.duration == pos.duration
    assert neg.phase_durations == pos.phase_durations
    assert neg.jerks == tuple(-j for j in pos.jerks)
    assert neg.peak_velocity == -pos.peak_velocity
    t = np.linspace(0.0, pos.duration, 501)
    a, b = pos.sample(t), neg.sample(t)
    np.testing.assert_allclose(b.position, 5.0 - a.position, atol=1e-12)
    np.testing.assert_allclose(b.velocity, -a.velocity, atol=1e-12)
    np.testing.assert_allclose(b.acceleration, -a.acceleration, atol=1e-12)
    # asymmetric semantics: slowing down uses the decel leg in both directions
    assert pos.peak_deceleration == neg.peak_deceleration == SLOW_JERK_UP.a_max_decel


def test_trapezoid_acceleration_jumps():
    """j_max = inf: the entering acceleration of the plateau is a_max (a jump)."""
    lim = AxisLimits(1.0, 2.0, math.inf, 4.0, math.inf)
    p = _checked(0.0, 5.0, lim)
    assert p.phase_durations[0] == p.phase_durations[2] == 0.0
    assert p.jerks == (0.0,) * 7
    bs = p.boundary_states()
    assert bs[1, 2] == 2.0 and bs[5, 2] == -4.0
    assert p.duration == pytest.approx(5.0 / 1.0 + 1.0 / (2 * 2.0) + 1.0 / (2 * 4.0), rel=EXACT)
    s = p.sample([0.1, 2.0, p.duration - 0.1])
    np.testing.assert_allclose(s.acceleration, [2.0, 0.0, -4.0], rtol=EXACT)


def test_zero_move_and_zero_move_with_duration():
    p = _checked(1.5, 1.5, SYM)
    assert p.duration == 0.0 and p.peak_velocity == 0.0
    q = _checked(1.5, 1.5, SYM, duration=2.0)
    assert q.duration == 2.0
    s = q.sample([0.0, 1.0, 2.0, 3.0])
    assert np.all(s.position == 1.5) and np.all(s.velocity == 0.0)


# ------------------------------------------------------------ sampling
def test_sample_shapes_and_holding():
    p = plan_move(1.0, 4.0, SYM)
    s = p.sample(0.3)
    assert s.position.shape == () and s.jerk.shape == ()
    t = np.linspace(-1.0, p.duration + 1.0, 37)
    s = p.sample(t)
    for arr in (s.position, s.velocity, s.acceleration, s.jerk):
        assert arr.shape == t.shape
    before, after = t < 0, t > p.duration
    assert np.all(s.position[before] == 1.0) and np.all(s.position[after] == 4.0)
    for arr in (s.velocity, s.acceleration, s.jerk):
        assert np.all(arr[before | after] == 0.0)


def test_sample_derivatives_consistent():
    """Finite differences of the sampled position match the sampled velocity."""
    p = plan_move(0.0, 0.9, SLOW_JERK_DOWN)
    t = np.linspace(0.0, p.duration, 20001)
    s = p.sample(t)
    h = t[1] - t[0]
    v_fd = np.gradient(s.position, h)
    a_fd = np.gradient(s.velocity, h)
    assert np.max(np.abs(v_fd - s.velocity)[1:-1]) < 1e-6
    # the acceleration is continuous (jerk finite), so central differences match too
    assert np.max(np.abs(a_fd - s.acceleration)[1:-1]) < 1e-3


# ------------------------------------------------------------ fixed duration
@pytest.mark.parametrize("factor", [1.0, 1.0 + 1e-13, 1.0 + 1e-9, 1.001, 1.5, 3.0, 100.0])
@pytest.mark.parametrize("limits", [SYM, SLOW_JERK_UP, SLOW_JERK_DOWN,
                                    AxisLimits(1.0, 2.0, math.inf, 0.5, math.inf)])
@pytest.mark.parametrize("goal", [5.0, 0.3, -0.05])
def test_fixed_duration(limits, goal, factor):
    tmin = min_duration(goal, limits)
    T = tmin * factor
    p = plan_move(0.0, goal, limits, duration=T)
    verify_profile(p, expected_duration=T).raise_if_failed()
    assert p.duration == T
    assert p.min_duration == tmin
    d = abs(goal)
    vc, phases = R.fixed_duration(d, T, limits.v_max, limits.a_max, limits.j_max,
                                  limits.a_max_decel, limits.j_max_decel)
    vq = abs(p.peak_velocity)
    # backward error in the reference's own time equation
    a1, j1, a2, j2 = limits.a_max, limits.j_max, limits.a_max_decel, limits.j_max_decel
    res = R.time_at(vq, a1, j1, a2, j2) + (d - R.dist_at(vq, a1, j1, a2, j2)) / vq - T
    assert abs(res) <= 1e-12 * T
    if factor > 1.001:
        assert vq == pytest.approx(vc, rel=1e-9)
        ref_d = [ph[0] for ph in phases]
        ours = [x for x in p.phase_durations if x > 0.0]
        assert ours == pytest.approx([x for x in ref_d if x > 0.0], rel=1e-9)


def test_duration_below_minimum_raises_with_minimum():
    tmin = min_duration(5.0, SYM)
    with pytest.raises(InfeasibleError, match=r"below the minimum duration 5\.7") as ei:
        plan_move(0.0, 5.0, SYM, duration=5.0)
    assert ei.value.minimum == pytest.approx(tmin, rel=EXACT)
    # within round-off of the minimum: accepted as the minimum
    p = plan_move(0.0, 5.0, SYM, duration=tmin * (1.0 - DURATION_RTOL / 2))
    assert p.duration == tmin


def test_min_duration_matches_plan_move():
    for d in (0.0, 1e-7, 0.1, 0.5, 5.0, -7.0, 1e6):
        for lim in (SYM, SLOW_JERK_UP, SLOW_JERK_DOWN, BOTH_SLOW):
            assert min_duration(d, lim) == plan_move(0.0, d, lim).duration


def test_to_dict_is_json():
    p = plan_move(0.0, 0.5, SLOW_JERK_UP)
    d = json.loads(json.dumps(p.to_dict()))
    assert d["shape"] == p.shape == "no-const-accel+no-cruise"
    assert d["reached"] == ["a_max_decel"]
    assert [ph["name"] for ph in d["phases"]] == list(PHASE_NAMES)
    assert sum(ph["duration_s"] for ph in d["phases"]) == pytest.approx(p.duration, rel=EXACT)


# ------------------------------------------------------------ hypothesis
_lim = st.floats(1e-2, 1e2)
_ratio = st.floats(0.05, 20.0)


@settings(max_examples=300, deadline=None)
@given(v=_lim, a=_lim, j=_lim, ra=_ratio, rj=_ratio,
       d=st.floats(1e-4, 1e4) | st.floats(-1e4, -1e-4), start=st.floats(-100.0, 100.0))
def test_hypothesis_against_reference(v, a, j, ra, rj, d, start):
    lim = AxisLimits(v, a, j, a * ra, j * rj)
    p = plan_move(start, start + d, lim)
    verify_profile(p, n_samples=0).raise_if_failed()
    assert p.duration == pytest.approx(_ref(p), rel=1e-9)


# ------------------------------------------------------------ regressions
def test_trapezoid_fixed_duration():
    """Was ZeroDivisionError: both legs jerk-free and a stretched duration."""
    lim = AxisLimits(1.0, 2.0, math.inf, 0.5, math.inf)
    tmin = min_duration(1.0, lim)
    for T in (tmin * (1 + 1e-14), tmin * 1.5, 5.0):
        p = plan_move(0.0, 1.0, lim, duration=T)
        verify_profile(p, expected_duration=T).raise_if_failed()
        assert p.shape in ("trapezoid", "trapezoid+no-cruise")


def test_fixed_duration_without_overflow():
    """Was a zero cruise velocity: (t - q)^2 overflowed for a 1e159 s move."""
    lim = AxisLimits(1e-150, 1e-150, 1.0, 3e-150, 0.5)
    tmin = min_duration(1e9, lim)
    p = plan_move(0.0, 1e9, lim, duration=2.0 * tmin)
    verify_profile(p, expected_duration=2.0 * tmin).raise_if_failed()
    assert abs(p.peak_velocity) == pytest.approx(1e9 / (2.0 * tmin), rel=1e-6)


@pytest.mark.parametrize("lim", [AxisLimits(1.0, 2.0, 10.0, 1.0, 4.0), AxisLimits(1.0, 2.0, math.inf)])
def test_sorted_fast_path_equals_lookup_path_bit_for_bit(lim):
    """Sorted time arrays are sampled phase by phase; the results must be identical
    to the per-sample lookup used for unsorted times, at the boundaries too."""
    p = plan_move(0.3, 1.8, lim)
    t = np.concatenate([np.linspace(-0.1, p.duration + 0.1, 5001), p.phase_times])
    t.sort()
    perm = np.random.default_rng(3).permutation(t.size)
    fast, slow = p.sample(t), p.sample(t[perm])
    for field in ("position", "velocity", "acceleration", "jerk"):
        np.testing.assert_array_equal(getattr(fast, field)[perm], getattr(slow, field))
    assert fast.position[-1] == 1.8 and fast.position[0] == 0.3
