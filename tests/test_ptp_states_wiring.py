"""plan_ptp: the form of the input chooses the planner (positions at rest or states),
never the values; the compatibility keywords select the state planner."""

import numpy as np
import pytest

from trajkit import (
    AxisLimits,
    InvalidInputError,
    Profile,
    StateProfile,
    plan_ptp,
    plan_ptp_states,
)

LIM = AxisLimits(1.0, 2.0, 10.0)


def test_the_input_form_chooses_the_planner_not_the_values():
    rest = plan_ptp([0, 0], [1, 2], LIM)
    assert all(isinstance(a, Profile) for a in rest.axes)
    # states given, all at rest: still the state planner (explicit, no silent switch)
    for t in (plan_ptp([[0, 0, 0], [0, 0, 0]], [[1, 0, 0], [2, 0, 0]], LIM),
              plan_ptp([0, 0], [1, 2], LIM, start_velocity=[0, 0], goal_acceleration=[0, 0])):
        assert all(isinstance(a, StateProfile) for a in t.axes)
        assert t.duration == pytest.approx(rest.duration, rel=1e-12)
        assert t.sync == "time"


def test_moving_start_matches_plan_ptp_states_and_hits_states():
    t = plan_ptp([0, 0], [1, 2], LIM, start_velocity=[0.5, 0.2], goal_velocity=[0.1, 0.0])
    ref = plan_ptp_states([[0, 0.5, 0], [0, 0.2, 0]], [[1, 0.1, 0], [2, 0.0, 0]], LIM)
    assert all(isinstance(a, StateProfile) for a in t.axes)
    assert t.duration == pytest.approx(ref.duration, rel=1e-12)
    s0, s1 = t.sample(0.0), t.sample(t.duration)
    np.testing.assert_allclose(s0.velocity[0], [0.5, 0.2], atol=1e-12)
    np.testing.assert_allclose(s1.position[0], [1.0, 2.0], atol=1e-9)
    np.testing.assert_allclose(s1.velocity[0], [0.1, 0.0], atol=1e-9)
    assert [a.duration for a in t.axes] == pytest.approx([t.duration] * 2, rel=1e-12)


def test_rate_arrays_are_validated():
    with pytest.raises(InvalidInputError, match="start_velocity must have 2 entries"):
        plan_ptp([0, 0], [1, 2], LIM, start_velocity=[0.5])
    with pytest.raises(InvalidInputError, match=r"goal_velocity\[1\] must be finite"):
        plan_ptp([0, 0], [1, 2], LIM, goal_velocity=[0.0, float("nan")])
