"""Unit tests of trajkit.profiles.state (one axis between moving states)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from state_reference import (
    dense_check,
    double_s_duration,
    exact_check,
    goal_error,
    random_case,
    ruckig_duration,
    ruckig_fixed,
)

from trajkit import AxisLimits
from trajkit.errors import InfeasibleError, InvalidInputError
from trajkit.profiles import plan_move
from trajkit.profiles.state import (
    BlockedDurationError,
    StateProfile,
    plan_state_to_state,
    plan_velocity,
)
from trajkit.verify import verify_state_profile

LIM = AxisLimits(v_max=1.0, a_max=2.0, j_max=10.0)
ASYM = AxisLimits(v_max=1.0, a_max=2.0, j_max=10.0, a_max_decel=1.0, j_max_decel=3.0)


def _lim(L):
    return AxisLimits(L[0], L[1], L[2], L[3], L[4])


def _assert_valid(prof, lim):
    assert exact_check(prof, lim) is None, exact_check(prof, lim)
    assert goal_error(prof) < 1e-9
    assert dense_check(prof, lim, n=401) is None


# ------------------------------------------------------------ rest to rest
@pytest.mark.parametrize("lim", [LIM, ASYM], ids=["symmetric", "asymmetric"])
def test_rest_to_rest_equals_closed_form(lim):
    rng = np.random.default_rng(11)
    for _ in range(60):
        d = float(rng.choice([1e-6, 1e-3, 0.1, 1.0, 7.0])) * rng.uniform(-1, 1)
        # at the origin: the distance is exact, so the durations must agree
        # to round-off (away from it, a tiny d is only known to eps*|p|/|d|)
        p = plan_state_to_state((0.0, 0.0, 0.0), (d, 0.0, 0.0), lim)
        ref = plan_move(0.0, d, lim)
        assert p.duration == pytest.approx(ref.duration, rel=1e-12, abs=1e-15)
        _assert_valid(p, lim)


def test_doc_example():
    p = plan_state_to_state((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), LIM)
    assert p.duration == pytest.approx(1.7, rel=1e-12)


def test_zero_motion_is_zero_duration():
    p = plan_state_to_state((1.0, 0.5, 0.0), (1.0, 0.5, 0.0), LIM)
    assert p.duration == 0.0 and p.family == "none"
    s = p.sample([0.0, 1.0])  # continues at constant velocity after the end
    assert s.position.tolist() == [1.0, 1.5]


# ------------------------------------------------------- sampling interface
def test_sampling_interface_and_continuity():
    p = plan_state_to_state((0.0, 0.4, -1.0), (0.5, -0.3, 0.5), ASYM)
    tb = p.phase_times
    assert tb.shape == (p.n_phases + 1,)
    assert tb[-1] == p.duration
    b = p.boundary_states()
    assert b.shape == (p.n_phases + 1, 3)
    s = p.sample(tb[:-1])
    np.testing.assert_allclose(s.position, b[:-1, 0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(s.velocity, b[:-1, 1], rtol=0, atol=1e-15)
    # continuity of p, v, a across every boundary (left limit == right value)
    eps = 1e-9
    left = p.sample(tb[1:-1] - eps)
    right = p.sample(tb[1:-1])
    np.testing.assert_allclose(left.position, right.position, atol=1e-8)
    np.testing.assert_allclose(left.velocity, right.velocity, atol=1e-7)
    np.testing.assert_allclose(left.acceleration, right.acceleration, atol=1e-7)
    # scalar time gives 0-d arrays
    assert p.sample(0.1).position.shape == ()
    # goal exactly at and after the end; continued with goal v and a
    end = p.sample([p.duration, p.duration + 2.0])
    pf, vf, af = p.goal_state
    assert end.position[0] == pf and end.velocity[0] == vf and end.acceleration[0] == af
    assert end.position[1] == pytest.approx(pf + 2 * vf + 2 * af)
    assert end.velocity[1] == pytest.approx(vf + 2 * af)
    # start state held before 0
    before = p.sample(-1.0)
    assert (float(before.position), float(before.velocity), float(before.acceleration)) == p.start_state
    json.dumps(p.to_dict())


# --------------------------------------------------------- input checking
def test_bad_inputs_are_named():
    with pytest.raises(InvalidInputError, match="start must have 3 entries"):
        plan_state_to_state((0.0, 1.0), (1.0, 0.0, 0.0), LIM)
    with pytest.raises(InvalidInputError, match="goal velocity must be finite, got nan"):
        plan_state_to_state((0.0, 0.0, 0.0), (1.0, math.nan, 0.0), LIM)
    with pytest.raises(InvalidInputError, match=r"goal state of axis B cannot be reached.*velocity.*above v_max 1.0"):
        plan_state_to_state((0.0, 0.0, 0.0), (1.0, 1.5, 0.0), LIM.with_name("B"))
    with pytest.raises(InvalidInputError, match=r"\|acceleration\| 3.0 is above a_max_decel 1.0"):
        plan_state_to_state((0.0, 0.0, 0.0), (1.0, 0.5, -3.0), ASYM)
    with pytest.raises(InvalidInputError, match="arriving with acceleration"):
        plan_state_to_state((0.0, 0.0, 0.0), (1.0, 0.99, -1.9), LIM)
    with pytest.raises(InvalidInputError, match="limits must be an AxisLimits"):
        plan_state_to_state((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), {"v_max": 1})
    with pytest.raises(InvalidInputError, match="duration must be finite and >= 0 s, got -1.0"):
        plan_state_to_state((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), LIM, duration=-1.0)
    lim = AxisLimits(1.0, 2.0, 10.0, position_min=0.0, position_max=1.0)
    with pytest.raises(InvalidInputError, match="goal position 2.0 is outside the position range"):
        plan_state_to_state((0.0, 0.0, 0.0), (2.0, 0.0, 0.0), lim)


def test_leaving_the_position_range_is_reported():
    lim = AxisLimits(1.0, 2.0, 10.0, position_min=-1.0, position_max=0.5)
    # moving fast towards the upper end: the stop overshoots past 0.5
    with pytest.raises(InfeasibleError, match=r"would leave the position range \[-1.0, 0.5\]"):
        plan_state_to_state((0.45, 1.0, 0.0), (0.0, 0.0, 0.0), lim)


def test_duration_below_minimum():
    p = plan_state_to_state((0.0, 0.5, 0.0), (1.0, 0.0, 0.0), LIM)
    with pytest.raises(InfeasibleError, match="below the minimum duration") as err:
        plan_state_to_state((0.0, 0.5, 0.0), (1.0, 0.0, 0.0), LIM, duration=0.9 * p.duration)
    assert err.value.minimum == pytest.approx(p.duration)


# ----------------------------------------------------------- fixed duration
def test_fixed_duration_exact_and_valid():
    rng = np.random.default_rng(3)
    n_blocked = 0
    for _ in range(80):
        s, g, L = random_case(rng, symmetric=bool(rng.integers(0, 2)))
        lim = _lim(L)
        p = plan_state_to_state(s, g, lim)
        T = p.duration * (1.0 + float(rng.choice([1e-9, 0.01, 0.3, 2.0])))
        if T == 0.0:
            continue
        try:
            q = plan_state_to_state(s, g, lim, duration=T)
        except BlockedDurationError as err:
            n_blocked += 1
            lo, hi = err.interval
            assert lo <= T <= hi
            q = plan_state_to_state(s, g, lim, duration=hi)
            assert q.duration == pytest.approx(hi, rel=1e-12)
            _assert_valid(q, lim)
            continue
        assert q.duration == pytest.approx(T, rel=1e-12)
        assert q.min_duration == pytest.approx(p.duration, rel=1e-12)
        _assert_valid(q, lim)
    assert n_blocked < 40


def test_blocked_interval_is_reported():
    # cruising at 0.5 towards a goal 0.5 ahead that must be passed at 0.5:
    # the fastest way speeds up and slows down (0.947 s), cruising takes 1 s,
    # but between about 1.078 s and 3.350 s no profile keeps the limits
    # (the axis cannot lose enough distance without stopping and coming back)
    lim = AxisLimits(v_max=1.0, a_max=1.0, j_max=1.0)
    s, g = (0.0, 0.5, 0.0), (0.5, 0.5, 0.0)
    p = plan_state_to_state(s, g, lim)
    assert p.duration == pytest.approx(ruckig_duration(s, g, 1.0, 1.0, 1.0), rel=1e-9)
    _assert_valid(plan_state_to_state(s, g, lim, duration=1.0), lim)
    with pytest.raises(BlockedDurationError, match=r"lies in a blocked interval \(1.07") as err:
        plan_state_to_state(s, g, lim, duration=2.0)
    lo, hi = err.value.interval
    assert err.value.minimum == pytest.approx(p.duration)
    # ruckig (asked for at least T) agrees on both ends of the gap
    assert ruckig_fixed(s, g, 1.0, 1.0, 1.0, lo * (1 - 1e-6)) == pytest.approx(lo * (1 - 1e-6), rel=1e-9)
    assert ruckig_fixed(s, g, 1.0, 1.0, 1.0, lo * (1 + 1e-6)) == pytest.approx(hi, rel=1e-9)
    _assert_valid(plan_state_to_state(s, g, lim, duration=hi), lim)
    _assert_valid(plan_state_to_state(s, g, lim, duration=lo), lim)


# ------------------------------------------------------------- brake
def test_brake_from_overspeed():
    p = plan_state_to_state((0.0, 1.5, 0.0), (3.0, 0.0, 0.0), ASYM)
    assert p.brake_duration > 0.0
    _assert_valid(p, ASYM)  # every limit holds after the pre-phase
    # during the pre-phase the axis slows down monotonically, at the decel limits
    t = np.linspace(0.0, p.brake_duration, 200)
    s = p.sample(t)
    assert np.all(np.diff(s.velocity) <= 1e-15)
    assert np.all(s.acceleration >= -ASYM.a_max_decel * (1 + 1e-12))
    assert s.velocity[-1] == pytest.approx(1.0, rel=1e-12)


def test_brake_from_excess_acceleration_and_carry_over():
    # acceleration above a_max: ramped back first
    p = plan_state_to_state((0.0, 0.0, 3.0), (1.0, 0.0, 0.0), ASYM)
    assert p.brake_duration > 0.0
    _assert_valid(p, ASYM)
    # acceleration that carries the velocity past v_max: v + a^2/(2J) > V
    p = plan_state_to_state((0.0, 0.9, 1.5), (2.0, 0.0, 0.0), ASYM)
    assert p.brake_duration > 0.0
    _assert_valid(p, ASYM)
    # the unavoidable overshoot is the minimum: v_peak = v0 + a0^2/(2 j_max),
    # reached at a phase boundary (a = 0)
    assert p.boundary_states()[:, 1].max() == pytest.approx(0.9 + 1.5 ** 2 / 20.0, rel=1e-12)



def test_brake_through_a_reversal_from_a_tiny_velocity():
    # slowing down from a velocity tiny against a^2 / j (it reverses within
    # 2e-11 s) with an acceleration above a_max: the brake's first phase must
    # end exactly at the reversal (a phase end computed with cancellation ran
    # past it, into the other leg, and every brake was then rejected)
    lim = AxisLimits(v_max=math.inf, a_max=1.7403704598486787e18, j_max=1.99813845878492e21,
                     a_max_decel=5.619767827928509e18, j_max_decel=5.294870042984362e17)
    s = (-593725282907.4779, -59946820.41835076, 2.609957055048959e18)
    p = plan_state_to_state(s, (-593725282920.8503, -986357433.897477, 1.5809719727e18), lim)
    assert p.brake_duration > 0.0
    _assert_valid(p, lim)
    # the acceleration is back within a_max after the reversal at the speeding-up
    # leg's jerk: the brake takes (a0 - a_max) / j_max and the reversal's instant
    t_rev = 59946820.41835076 / 2.609957055048959e18
    assert p.brake_duration == pytest.approx(
        t_rev + (2.609957055048959e18 - lim.a_max) / lim.j_max, rel=1e-6)

# ----------------------------------------------------- velocity interface
def _stop_time(v, a_dec, j_dec):
    v = abs(v)
    if v * j_dec >= a_dec ** 2:
        return v / a_dec + a_dec / j_dec
    return 2.0 * math.sqrt(v / j_dec)


@pytest.mark.parametrize("v0", [0.01, 0.1, 0.5, 1.0, -0.3, -1.0])
def test_controlled_stop_is_minimum_time(v0):
    p = plan_velocity((2.0, v0, 0.0), 0.0, limits=ASYM)
    assert p.duration == pytest.approx(_stop_time(v0, 1.0, 3.0), rel=1e-12)
    assert p.goal_state[1:] == (0.0, 0.0)
    _assert_valid(p, ASYM)



def test_a_reversal_inside_a_jerk_phase_takes_the_speeding_up_leg():
    # at rest with a tiny acceleration backwards, to a forward velocity, under a
    # braking jerk 3600 times the speeding-up one: the phase that raises the
    # acceleration passes the reversal 1.35e-5 s in, at |v| < 3e-10 (below the
    # sliver tolerance of the velocity's scale); the kernel's check gave that
    # part of the phase the looser leg, the verifier the leg of its neighbour
    # (speeding up), which the braking jerk exceeded 3600 times. Both now take
    # the neighbour's leg.
    lim = AxisLimits(v_max=1.4185555384310544, a_max=6.30385356707215e-05,
                     j_max=0.0008014203268284044, a_max_decel=0.16116005296974517,
                     j_max_decel=2.9130090499527097)
    p = plan_velocity((513.2397788797516, 0.0, -6.515005347482839e-07), 0.4095842612530327,
                      7.288731853440163e-06, limits=lim)
    _assert_valid(p, lim)
    assert verify_state_profile(p).ok

def test_velocity_interface_with_duration():
    p = plan_velocity((0.0, 0.2, 0.5), -0.6, 0.3, limits=ASYM)
    q = plan_velocity((0.0, 0.2, 0.5), -0.6, 0.3, limits=ASYM, duration=p.duration + 1.0)
    assert q.duration == pytest.approx(p.duration + 1.0, rel=1e-12)
    assert q.goal_state[1] == -0.6 and q.goal_state[2] == 0.3
    _assert_valid(q, ASYM)
    with pytest.raises(InfeasibleError, match="below the minimum duration") as err:
        plan_velocity((0.0, 0.2, 0.5), -0.6, 0.3, limits=ASYM, duration=0.5 * p.duration)
    assert err.value.minimum == pytest.approx(p.duration)
    with pytest.raises(InvalidInputError, match="goal velocity/acceleration cannot be reached"):
        plan_velocity((0.0, 0.0, 0.0), 2.0, limits=ASYM)


# ------------------------------------------------- asymmetric references
def test_asymmetric_double_s_reference():
    rng = np.random.default_rng(5)
    n = 0
    for _ in range(400):
        V = 10 ** rng.uniform(-1, 1)
        A1, A2 = 10 ** rng.uniform(-1, 1, 2)
        J1, J2 = 10 ** rng.uniform(-1, 1.5, 2)
        v0, vf = rng.uniform(0, V, 2) * rng.integers(0, 2, 2)
        d = 10 ** rng.uniform(-2, 1.5) * V
        ref = double_s_duration(d, v0, vf, V, A1, J1, A2, J2)
        if ref is None:
            continue
        lim = AxisLimits(V, A1, J1, A2, J2)
        p = plan_state_to_state((0.0, v0, 0.0), (d, vf, 0.0), lim)
        assert p.duration == pytest.approx(ref, rel=1e-9), (v0, vf, d, lim)
        n += 1
    assert n > 100


def test_state_profile_type():
    assert isinstance(plan_state_to_state((0, 0, 0), (1, 0, 0), LIM), StateProfile)


@pytest.mark.parametrize("lim", [
    AxisLimits(1.0, 2.0, math.inf),
    AxisLimits(1.0, 2.0, math.inf, 1.0, math.inf),
    AxisLimits(math.inf, 2.0, 10.0),
    AxisLimits(1.0, math.inf, 10.0),
], ids=["trapezoid", "trapezoid-asym", "no-v-limit", "no-a-limit"])
def test_infinite_limits(lim):
    for d in (1e-3, 0.3, 1.0, 5.0):
        p = plan_state_to_state((0.0, 0.0, 0.0), (d, 0.0, 0.0), lim)
        assert p.duration == pytest.approx(plan_move(0.0, d, lim).duration, rel=1e-12)
    rng = np.random.default_rng(1)
    for _ in range(30):
        a_cap = min(lim.a_max, lim.a_max_decel)
        a0 = 0.0 if math.isinf(lim.j_max) else rng.uniform(-0.3, 0.3) * min(a_cap, 2.0)
        s = (0.0, rng.uniform(-0.5, 0.5), a0)
        g = (rng.uniform(-2, 2), rng.uniform(-0.5, 0.5), 0.0)
        p = plan_state_to_state(s, g, lim)
        assert exact_check(p, lim) is None
        assert goal_error(p) < 1e-9


def test_slowing_down_harder_than_a_max_then_reversing():
    # slowing down with |a| above a_max (allowed: a_max_decel applies) and
    # about to reverse: |a| must be within a_max by the reversal; the decel
    # jerk gets it there in time (the velocity-sign-changing bump alone,
    # with the tighter jerk, would not)
    lim = AxisLimits(0.979, 0.6656, 7.481, 7.474, 9.966)
    s = (0.0, 0.019942251693937898, -0.864350318652148)
    p = plan_velocity(s, 0.0, limits=lim)
    assert p.brake_duration == 0.0
    _assert_valid(p, lim)
    q = plan_state_to_state(s, (-0.5, 0.0, 0.0), lim)
    assert q.brake_duration == 0.0
    _assert_valid(q, lim)
