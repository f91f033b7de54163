"""Online re-targeting of the runtime streamer (Streamer.set_target).

Random goal states sent at 100 Hz to a 1 kHz stream: every re-plan starts
from the commanded state of that cycle, no limit is ever exceeded (exactly on
every planned trajectory, and on the stream itself), and the final target is
reached and held exactly.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import sweep_size

from trajkit import AxisLimits, InvalidInputError
from trajkit.runtime import Streamer
from trajkit.verify import verify_motion

PERIOD = 1e-3
EVERY = 10  # cycles between targets: 100 Hz

SYM = [AxisLimits(1.0, 4.0, 40.0, name="X"), AxisLimits(0.5, 2.0, 30.0, name="Y"),
       AxisLimits(2.0, 8.0, 100.0, name="Z")]
ASYM = [AxisLimits(1.0, 4.0, 40.0, 2.0, 15.0, name="X"),
        AxisLimits(0.5, 2.0, 30.0, 3.0, 60.0, name="Y"),
        AxisLimits(2.0, 8.0, 100.0, 5.0, 50.0, name="Z")]


def _random_goal(rng, lims, moving):
    n = len(lims)
    p = rng.uniform(-1.0, 1.0, n)
    v = np.array([rng.uniform(-1, 1) * lm.v_max if moving else 0.0 for lm in lims])
    return p, v


def _run(lims, seed, n_targets):
    rng = np.random.default_rng(seed)
    st = Streamer.hold_at(np.zeros(len(lims)), PERIOD, lims)
    plans = []
    orig = st._apply_target

    def spy(goal, sync, limits):
        orig(goal, sync, limits)
        if st._online is not None and st._online[1] == 0:
            plans.append((np.column_stack([st._q, st._v, st._a]), st._online[0]))

    st._apply_target = spy
    sps = []
    for k in range(n_targets):
        p, v = _random_goal(rng, lims, moving=rng.random() < 0.7)
        st.set_target(p, v, sync="time" if k % 3 else "none")
        for _ in range(EVERY):
            sps.append(st.step())
    final = rng.uniform(-1.0, 1.0, len(lims))
    st.set_target(final)
    for _ in range(20000):
        sps.append(st.step())
        if st.state == "idle":
            break
    return st, sps, plans, final


@pytest.mark.parametrize("lims", [SYM, ASYM], ids=["symmetric", "asymmetric"])
def test_random_targets_at_100_hz_keep_every_limit_and_reach_the_last(lims):
    st, sps, plans, final = _run(lims, 7 if lims is SYM else 8, sweep_size(150))
    assert st.fault is None and st.state == "idle"
    assert len(plans) > 100
    # every re-plan starts exactly at the commanded state of its cycle, and is valid
    for start, traj in plans:
        np.testing.assert_array_equal(traj.start_states, start)
        for ax in traj.axes:
            assert ax.n_brake_phases == 0  # the commanded state is always inside the limits
            verify_motion(ax, n_samples=0).raise_if_failed()
    # the stream itself: velocity, acceleration with its leg, jerk between samples
    Q = np.array([sp.position for sp in sps])
    V = np.array([sp.velocity for sp in sps])
    A = np.array([sp.acceleration for sp in sps])
    for k, lm in enumerate(lims):
        assert np.abs(V[:, k]).max() <= lm.v_max * (1 + 1e-9)
        speeding = V[:, k] * A[:, k] > 0
        cap = np.where(speeding, lm.a_max, lm.a_max_decel)
        assert np.all(np.abs(A[:, k]) <= cap * (1 + 1e-9) + 1e-12)
        jerk = np.abs(np.diff(A[:, k])) / PERIOD
        assert jerk.max() <= max(lm.j_max, lm.j_max_decel) * (1 + 1e-9)
        # continuity of the commanded position with the velocity
        dq = np.diff(Q[:, k])
        assert np.all(np.abs(dq) <= lm.v_max * PERIOD * (1 + 1e-9))
    # the final target is reached and held exactly
    np.testing.assert_array_equal(sps[-1].position, final)
    assert not np.any(sps[-1].velocity) and not np.any(sps[-1].acceleration)
    assert st.events[-1].kind == "target_reached"


def test_target_replans_within_the_same_cycle():
    st = Streamer.hold_at([0.0, 0.0], PERIOD, SYM[:2])
    st.set_target([1.0, -0.5])
    sp = st.step()  # the command is applied at the start of this cycle
    assert st._mode == "target" and sp.state == "running"
    assert sp.velocity[0] > 0.0 > sp.velocity[1]  # already moving on the new plan
    for _ in range(200):
        st.step()
    q, v, a = st._q.copy(), st._v.copy(), st._a.copy()
    st.set_target([-1.0, 0.5], [0.2, 0.0])
    sp = st.step()
    traj = st._online[0]
    np.testing.assert_array_equal(traj.start_states, np.column_stack([q, v, a]))
    s = traj.sample(PERIOD)
    np.testing.assert_array_equal(sp.position, s.position[0])


def test_target_errors_and_refusals():
    st = Streamer.hold_at([0.0], PERIOD, [AxisLimits(1.0, 2.0, 10.0, position_min=-1.0,
                                                     position_max=1.0, name="X")])
    with pytest.raises(InvalidInputError, match="target position must be finite"):
        st.set_target([math.nan])
    with pytest.raises(InvalidInputError, match="target velocity must have 1 entries"):
        st.set_target([0.5], [0.1, 0.2])
    with pytest.raises(InvalidInputError, match="target sync"):
        st.set_target([0.5], sync="phase")
    st.set_target([2.0])  # outside the range: refused when applied, nothing moves
    st.step()
    assert st.events[-1].kind == "rejected" and "outside the position range" in st.events[-1].message
    assert st._mode == "hold"
    st.set_target([0.5])
    st.step()
    st.stop()  # a controlled stop brakes every axis
    for _ in range(2000):
        st.step()
        if st.state == "idle":
            break
    assert st.state == "idle" and st._v[0] == 0.0


def test_target_with_lower_limits_brakes_to_them_and_keeps_them():
    """A target with its own (lower) limits: a faster axis is braked down to them first."""
    lim = AxisLimits(1.0, 4.0, 40.0, name="X")
    st = Streamer.hold_at([0.0], PERIOD, [lim])
    st.set_target([5.0])
    for _ in range(int(1.0 / PERIOD)):  # at full speed after 0.35 s
        st.step()
    assert st._v[0] == pytest.approx(1.0)
    slow = AxisLimits(0.25, 4.0, 40.0, name="X")
    st.set_target([1.5], limits=[slow])
    v, a, q = [], [], []
    for _ in range(10000):
        sp = st.step()
        v.append(sp.velocity[0])
        a.append(sp.acceleration[0])
        q.append(sp.position[0])
        if st.state == "idle":
            break
    assert st.state == "idle" and q[-1] == 1.5
    v, a = np.array(v), np.array(a)
    assert np.all(np.abs(a) <= 4.0 * (1 + 1e-9))
    # once braked below the slow speed, the axis stays within it
    k = int(np.argmax(v <= 0.25 * (1 + 1e-9)))
    assert k > 0 and np.all(v[k:] <= 0.25 * (1 + 1e-9))
    with pytest.raises(InvalidInputError, match=r"limits\[0\].v_max = 2.0 exceeds the axis' limit 1.0 \(X\)"):
        st.set_target([0.0], limits=[AxisLimits(2.0, 4.0, 40.0)])
    with pytest.raises(InvalidInputError, match="target limits must be 1 AxisLimits"):
        st.set_target([0.0], limits=[slow, slow])
