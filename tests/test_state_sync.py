"""Many axes between moving states: plan_ptp_states."""

from __future__ import annotations

import numpy as np
import pytest
from state_reference import exact_check, goal_error

from trajkit import AxisLimits
from trajkit.errors import InfeasibleError, InvalidInputError
from trajkit.profiles.state import plan_state_to_state
from trajkit.sync_states import plan_ptp_states

LIMS = [
    AxisLimits(1.0, 2.0, 10.0, name="A"),
    AxisLimits(0.5, 1.0, 5.0, 0.5, 2.0, name="B"),
    AxisLimits(2.0, 4.0, 40.0, name="C"),
]


def _random_states(rng, lims):
    out = []
    for lim in lims:
        v = rng.uniform(-0.5, 0.5) * lim.v_max
        a = rng.uniform(-0.3, 0.3) * min(lim.a_max, lim.a_max_decel)
        out.append((rng.uniform(-1, 1), v, a))
    return np.array(out)


def test_time_sync_all_axes_arrive_together():
    rng = np.random.default_rng(8)
    for _ in range(25):
        s = _random_states(rng, LIMS)
        g = _random_states(rng, LIMS)
        tr = plan_ptp_states(s, g, LIMS, sync="time")
        mins = [plan_state_to_state(s[k], g[k], LIMS[k]).duration for k in range(3)]
        assert tr.sync == "time"
        assert tr.duration >= max(mins) * (1 - 1e-12)
        for k, prof in enumerate(tr.axes):
            assert prof.duration == pytest.approx(tr.duration, rel=1e-12)
            assert exact_check(prof, LIMS[k]) is None
            assert goal_error(prof) < 1e-9
        end = tr.sample(tr.duration)
        np.testing.assert_allclose(end.position[0], g[:, 0], atol=1e-9)
        np.testing.assert_allclose(end.velocity[0], g[:, 1], atol=1e-9)


def test_time_sync_skips_blocked_interval():
    # axis 0 alone would take 0.947 s, but axis 1 needs 1.75 s, inside axis 0's
    # blocked interval (1.078, 3.350) s: the common duration moves past it
    lims = [AxisLimits(1.0, 1.0, 1.0), AxisLimits(0.4, 1.0, 10.0)]
    s = np.array([[0.0, 0.5, 0.0], [0.0, 0.0, 0.0]])
    g = np.array([[0.5, 0.5, 0.0], [0.5, 0.0, 0.0]])
    t1 = plan_state_to_state(s[1], g[1], lims[1]).duration
    assert 1.08 < t1 < 3.35
    tr = plan_ptp_states(s, g, lims)
    assert tr.duration == pytest.approx(3.3502617411, rel=1e-6)
    for k in range(2):
        assert exact_check(tr.axes[k], lims[k]) is None
        assert goal_error(tr.axes[k]) < 1e-9
    with pytest.raises(InfeasibleError, match=r"blocked interval .* of axis 0"):
        plan_ptp_states(s, g, lims, duration=2.0)


def test_phase_sync_straight_line_when_collinear():
    lim = AxisLimits(1.0, 2.0, 10.0)
    D = np.array([1.0, -0.5, 0.25])
    s = np.column_stack([np.zeros(3), 0.3 * D, 0.1 * D])
    g = np.column_stack([D, 0.1 * D, 0.0 * D])
    tr = plan_ptp_states(s, g, lim, sync="phase")
    assert tr.sync == "phase"
    t = np.linspace(0, tr.duration, 500)
    x = tr.sample(t).position
    # every sample lies on the segment start -> goal
    u = D / np.linalg.norm(D)
    off = x - np.outer(x @ u, u)
    np.testing.assert_allclose(off, 0.0, atol=1e-12)
    for prof in tr.axes:
        assert exact_check(prof, lim) is None
        assert goal_error(prof) < 1e-9


def test_phase_falls_back_to_time_when_not_collinear():
    lim = AxisLimits(1.0, 2.0, 10.0)
    s = np.array([[0.0, 0.3, 0.0], [0.0, 0.0, 0.0]])
    g = np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    tr = plan_ptp_states(s, g, lim, sync="phase")
    assert tr.sync == "time"


def test_none_and_inputs():
    lim = AxisLimits(1.0, 2.0, 10.0)
    tr = plan_ptp_states([0.0, 0.0], [1.0, 2.0], lim, sync="none")
    assert tr.axes[0].duration < tr.axes[1].duration
    with pytest.raises(InvalidInputError, match=r"shape \(n_axes, 3\)"):
        plan_ptp_states(np.zeros((2, 2)), np.zeros((2, 2)), lim)
    with pytest.raises(InvalidInputError, match="sync must be one of"):
        plan_ptp_states([0.0], [1.0], lim, sync="fast")
    with pytest.raises(InvalidInputError, match="start has 2 axes but goal has 1"):
        plan_ptp_states([0.0, 0.0], [1.0], lim)
    with pytest.raises(InfeasibleError, match="below the minimum synchronised duration"):
        plan_ptp_states([0.0, 0.0], [1.0, 2.0], lim, duration=0.1)


def test_axes_made_on_first_access_are_the_planned_ones():
    """The compiled synchronisation leaves the profile objects for the first access of
    ``axes`` (unbounded axes) or makes them at once (an axis with a position range, which
    is checked): both give the same profiles and ``duration`` is the longest of theirs."""
    import pickle

    rng = np.random.default_rng(21)
    free = [AxisLimits(lim.v_max, lim.a_max, lim.j_max, lim.a_max_decel, lim.j_max_decel)
            for lim in LIMS]
    ranged = [AxisLimits(lim.v_max, lim.a_max, lim.j_max, lim.a_max_decel, lim.j_max_decel,
                         position_min=-1e3, position_max=1e3) for lim in LIMS]
    for _ in range(20):
        s = [tuple(r) for r in _random_states(rng, LIMS).tolist()]
        g = [tuple(r) for r in _random_states(rng, LIMS).tolist()]
        lazy = plan_ptp_states(s, g, free)
        assert "axes" not in vars(lazy)  # not made yet
        copy = pickle.loads(pickle.dumps(lazy))
        eager = plan_ptp_states(s, g, ranged)
        assert "axes" in vars(eager)
        assert lazy.duration == max(p.duration for p in lazy.axes) == eager.duration
        for traj in (lazy, copy):
            for a, b in zip(traj.axes, eager.axes):
                assert a.phase_durations == b.phase_durations
                assert a.jerks == b.jerks and a.family == b.family
                assert a.start_state == b.start_state and a.end_state == b.end_state
