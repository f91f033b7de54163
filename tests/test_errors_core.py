"""Bad input to the core planners: typed errors whose messages name field, axis, value, bound."""

from __future__ import annotations

import math

import pytest

from trajkit import (
    AxisLimits,
    InfeasibleError,
    InvalidInputError,
    TrajkitError,
    min_duration,
    plan_move,
    plan_moves,
    plan_ptp,
)

LIM = AxisLimits(1.0, 2.0, 10.0, position_min=-1.0, position_max=6.0, name="B")
LIMS3 = [AxisLimits(1.0, 2.0, 10.0, name=n) for n in "ABC"]


# ------------------------------------------------------------ plan_move
@pytest.mark.parametrize("start,goal,match", [
    (math.nan, 1.0, r"^start of axis B must be finite, got nan$"),
    (0.0, math.inf, r"^goal of axis B must be finite, got inf$"),
    (0.0, -math.inf, r"^goal of axis B must be finite, got -inf$"),
    (-2.0, 1.0, r"^start -2\.0 of axis B is outside the position range \[-1\.0, 6\.0\]$"),
    (0.0, 6.5, r"^goal 6\.5 of axis B is outside the position range \[-1\.0, 6\.0\]$"),
])
def test_plan_move_bad_positions(start, goal, match):
    with pytest.raises(InvalidInputError, match=match):
        plan_move(start, goal, LIM)


@pytest.mark.parametrize("duration,match", [
    (math.nan, r"^duration of axis B must be finite and >= 0 s, got nan$"),
    (-1.0, r"^duration of axis B must be finite and >= 0 s, got -1\.0$"),
    (math.inf, r"^duration of axis B must be finite and >= 0 s, got inf$"),
    ("soon", r"^duration must be a number of seconds, got 'soon'$"),
])
def test_plan_move_bad_duration(duration, match):
    with pytest.raises(InvalidInputError, match=match):
        plan_move(0.0, 1.0, LIM, duration=duration)


def test_plan_move_needs_axis_limits():
    with pytest.raises(InvalidInputError, match=r"^limits must be an AxisLimits, got dict$"):
        plan_move(0.0, 1.0, {"v_max": 1.0})


def test_plan_move_duration_below_minimum():
    tmin = min_duration(5.0, LIM)  # 5.7 s
    with pytest.raises(InfeasibleError,
                       match=r"^duration 3\.0 s of axis B is below the minimum duration 5\.7 s "
                             r"for a move of distance 5\.0$") as ei:
        plan_move(0.0, 5.0, LIM, duration=3.0)
    assert ei.value.minimum == tmin
    assert isinstance(ei.value, TrajkitError) and not isinstance(ei.value, ValueError)
    # the printed minimum is accepted when passed back
    assert plan_move(0.0, 5.0, LIM, duration=5.7).duration == pytest.approx(5.7)


def test_invalid_input_is_value_error():
    with pytest.raises(ValueError):
        plan_move(math.nan, 0.0, LIM)


# ------------------------------------------------------------ plan_ptp
@pytest.mark.parametrize("start,goal,limits,match", [
    ([0.0, math.nan, 0.0], [1.0, 1.0, 1.0], LIMS3, r"^start of axis B must be finite, got nan$"),
    ([0.0, 0.0, 0.0], [1.0, 1.0, math.inf], LIMS3, r"^goal of axis C must be finite, got inf$"),
    ([0.0, 0.0], [1.0, 1.0, 1.0], LIMS3, r"^start has 2 axes but goal has 3$"),
    ([0.0, 0.0], [1.0, 1.0], LIMS3, r"^limits has 3 entries but start/goal have 2 axes$"),
    ([[0.0, 0.0]], [[1.0, 1.0]], LIMS3,
     r"^start must have shape \(n_axes, 3\) \(position, velocity, acceleration per axis\) "
     r"or \(n_axes,\), got shape \(1, 2\)$"),
    ([], [], LIMS3, r"^start and goal must have at least one axis$"),
    ([0.0, 0.0, 7.0], [1.0, 1.0, 1.0],
     LIMS3[:2] + [AxisLimits(1.0, 2.0, 10.0, position_max=6.0, name="C")],
     r"^start 7\.0 of axis C is outside the position range \[-inf, 6\.0\]$"),
    ([0.0], [1.0], ["fast"], r"^limits\[0\] must be an AxisLimits, got str$"),
    ([0.0], [1.0], 3.0, r"^limits must be an AxisLimits or a sequence of them, got float$"),
    (["a"], [1.0], LIMS3[:1], r"^start must be an array of numbers, got \['a'\]$"),
])
def test_plan_ptp_bad_input(start, goal, limits, match):
    with pytest.raises(InvalidInputError, match=match):
        plan_ptp(start, goal, limits)


def test_plan_ptp_unknown_sync():
    with pytest.raises(InvalidInputError,
                       match=r"^sync must be one of \('time', 'phase', 'none'\), got 'fastest'$"):
        plan_ptp([0.0], [1.0], LIM, sync="fastest")


@pytest.mark.parametrize("sync,duration,match", [
    ("none", 3.0, r'^duration cannot be given with sync="none"$'),
    ("time", -1.0, r"^duration must be finite and >= 0 s, got -1\.0$"),
    ("phase", math.nan, r"^duration must be finite and >= 0 s, got nan$"),
    ("time", "later", r"^duration must be a number of seconds, got 'later'$"),
])
def test_plan_ptp_bad_duration(sync, duration, match):
    with pytest.raises(InvalidInputError, match=match):
        plan_ptp([0.0, 0.0], [1.0, 2.0], LIMS3[:2], sync=sync, duration=duration)


def test_plan_ptp_duration_below_minimum_states_minimum():
    tmin = plan_ptp([0.0, 0.0], [1.0, 5.0], LIMS3[:2]).duration
    with pytest.raises(InfeasibleError,
                       match=r"^duration 1\.0 s is below the minimum synchronised duration 5\.7 s$"
                       ) as ei:
        plan_ptp([0.0, 0.0], [1.0, 5.0], LIMS3[:2], duration=1.0)
    assert ei.value.minimum == tmin


def test_plan_ptp_phase_duration_below_minimum_states_minimum():
    tmin = plan_ptp([0.0, 0.0], [1.0, 5.0], LIMS3[:2], sync="phase").duration
    with pytest.raises(InfeasibleError, match=r"below the minimum duration 5\.7 s") as ei:
        plan_ptp([0.0, 0.0], [1.0, 5.0], LIMS3[:2], sync="phase", duration=1.0)
    assert ei.value.minimum == pytest.approx(tmin, rel=1e-12)


# ------------------------------------------------------------ plan_moves
@pytest.mark.parametrize("kwargs,match", [
    (dict(starts=[0.0, 0.0, 0.0]), r"^starts and goals must have the same shape, got \(3,\) and \(2,\)$"),
    (dict(starts=0.0), r"^starts must have 1 dimension\(s\), got shape \(\)$"),
    (dict(goals=[[1.0, 2.0]]), r"^goals must have 1 dimension\(s\), got shape \(1, 2\)$"),
    (dict(a_max=[1.0, 2.0, 3.0]), r"^a_max must be a scalar or have 2 entries, got shape \(3,\)$"),
    (dict(v_max=[1.0, 0.0]), r"^v_max\[1\] should be larger than zero, got 0\.0$"),
    (dict(j_max_decel=[math.nan, 1.0]), r"^j_max_decel\[0\] should be larger than zero, got nan$"),
    (dict(v_max="x"), r"^v_max must be a number or an array of numbers, got 'x'$"),
    (dict(durations=["a", 1.0]), r"^durations must be a number or an array of numbers"),
])
def test_plan_moves_bad_input(kwargs, match):
    args = dict(starts=[0.0, 0.0], goals=[1.0, 2.0], v_max=1.0, a_max=2.0, j_max=10.0)
    args.update(kwargs)
    with pytest.raises(InvalidInputError, match=match):
        plan_moves(**args)
