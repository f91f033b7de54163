"""Fault injection: each fault detected on the right cycle, the stop within limits,
the pulse count equal to the position held; state machine and event log."""

from __future__ import annotations

import numpy as np
import pytest

from trajkit import AxisLimits, InvalidInputError, SafetyFault, plan_ptp
from trajkit.profiles.state import plan_velocity
from trajkit.runtime import (
    RuntimeFault,
    SafetyConfig,
    ServoParams,
    Streamer,
    pulse_counts,
)

DT = 0.001
EQ = 1e-6  # pulse equivalent [m/pulse]
TOL = 1e-9


def _lims(v=1.0, pmin=-3.0, pmax=3.0):
    return [AxisLimits(v, 4.0, 40.0, a_max_decel=6.0, j_max_decel=60.0,
                       position_min=pmin, position_max=pmax, name=n) for n in "XY"]


def _arrays(sps):
    return (np.array([s.position for s in sps]), np.array([s.velocity for s in sps]),
            np.array([s.acceleration for s in sps]))


def _within(V, A, lims):
    vm = np.array([lm.v_max for lm in lims])
    am = np.array([lm.a_max for lm in lims])
    ad = np.array([lm.a_max_decel for lm in lims])
    assert np.all(np.abs(V) <= vm * (1 + TOL))
    lim = np.where(V * A < 0, ad, am)
    assert np.all(np.abs(A) <= lim * (1 + TOL))


def _pulses_hold(sps):
    last = sps[-1]
    assert np.array_equal(last.pulse_count, pulse_counts(last.position, EQ))
    total = np.sum([s.pulses for s in sps], axis=0)
    assert np.array_equal(total, last.pulse_count - pulse_counts(sps[0].position, EQ)
                          + sps[0].pulses)


def test_overspeed_command_detected_on_the_right_cycle():
    fast = plan_ptp([0.0, 0.0], [2.0, 1.0], _lims(v=1.6))  # planned for 1.6 m/s
    lims = _lims(v=1.0)  # the machine allows 1.0 m/s
    st = Streamer(fast, DT, limits=lims, pulse_equivalents=EQ)
    sps = list(st)
    f = st.fault
    assert isinstance(f, RuntimeFault) and isinstance(f, SafetyFault)
    assert f.quantity == "velocity" and f.axis == "X" and f.limit == 1.0
    # independent: first cycle whose state would overspeed (now, or on the jerk-limited
    # ramp-down of its acceleration)
    s = fast.sample(np.arange(len(sps) + 2000) * DT)
    v, a = s.velocity, s.acceleration
    peak = np.abs(v) + np.where(v * a > 0, a * a / (2 * 40.0), 0.0)
    expected = int(np.nonzero(np.any(peak > 1.0 * (1 + TOL), axis=1))[0][0])
    assert f.cycle == expected
    assert sps[f.cycle].fault is f
    assert "velocity" in str(f) and "of axis X exceeds the limit 1.0" in str(f)
    assert str(f).endswith(f"at cycle {expected} (t = {expected * DT:.6g} s)")
    P, V, A = _arrays(sps)
    assert np.allclose(P[:f.cycle], s.position[:f.cycle], atol=1e-12)  # normal until then
    _within(V, A, lims)  # the stop too
    assert sps[-1].state == "fault" and np.all(V[-1] == 0) and np.all(A[-1] == 0)
    _pulses_hold(sps)
    assert [e.kind for e in st.events] == ["start", "fault", "stopped"]


def test_target_beyond_soft_limit_stops_inside_it():
    prog = plan_ptp([0.0, 0.0], [1.0, 0.2], _lims())
    lims = _lims(pmax=0.6)
    st = Streamer(prog, DT, limits=lims, pulse_equivalents=EQ)
    sps = list(st)
    f = st.fault
    assert f.quantity == "position" and f.axis == "X" and f.limit == 0.6
    assert f.value > 0.6
    assert "(where its minimum-time brake would end) of axis X exceeds the limit 0.6" in str(f)
    # independent: the first cycle whose minimum-time brake (state-profile planner)
    # would end beyond the limit
    s = prog.sample(np.arange(f.cycle + 1) * DT)
    free = AxisLimits(1.0, 4.0, 40.0, a_max_decel=6.0, j_max_decel=60.0)  # no range: oracle only
    stops = [plan_velocity((s.position[k, 0], s.velocity[k, 0], s.acceleration[k, 0]), 0.0,
                           limits=free).goal for k in range(f.cycle + 1)]
    over = np.nonzero(np.array(stops) > 0.6 * (1 + TOL))[0]
    assert over.size and f.cycle == int(over[0])
    P, V, A = _arrays(sps)
    assert P[:, 0].max() <= 0.6 and P[-1, 0] > 0.6 - 0.01  # stopped inside, close to it
    _within(V, A, lims)
    assert sps[-1].state == "fault"
    _pulses_hold(sps)


def test_encoder_jump_trips_following_error_on_that_cycle():
    prog = plan_ptp([0.0, 0.0], [1.0, -0.5], _lims())
    st = Streamer(prog, DT, servo=ServoParams(), pulse_equivalents=EQ,
                  safety=SafetyConfig(following_error=1e-3))
    st.start()
    sps = [st.step() for _ in range(400)]
    assert all(s.fault is None for s in sps)
    st.inject_encoder_jump(1, 2e-3)
    sps += list(st)
    f = st.fault
    assert f.quantity == "following error" and f.axis == "Y" and f.cycle == 400
    assert f.value > 1e-3 and f.limit == 1e-3
    # emergency reaction: output cleared (last output held), brakes engaged
    held = sps[399].position
    assert all(np.array_equal(s.position, held) for s in sps[400:])
    assert np.all(sps[-1].velocity == 0) and st.servo.braking
    assert sps[-1].state == "fault"
    _pulses_hold(sps)
    assert np.array_equal(sps[-1].pulse_count, pulse_counts(held, EQ))


def test_following_error_trip_with_a_heavy_load():
    prog = plan_ptp([0.0, 0.0], [1.0, 0.5], _lims())
    servo = ServoParams(inertia_ratio=3.0, ff_acceleration=0.0, ff_velocity=0.0)
    st = Streamer(prog, DT, servo=servo, pulse_equivalents=EQ,
                  safety=SafetyConfig(following_error=0.02,
                                      reactions={"following error": "controlled"}))
    sps = list(st)
    f = st.fault
    assert f.quantity == "following error" and f.axis == "X"
    fe = np.array([np.abs(s.following_error) for s in sps[:f.cycle]])
    assert np.all(fe <= 0.02)  # not before
    assert f.value > 0.02  # and on this cycle
    # without velocity feedforward the steady error at speed v is v / kp
    v = sps[f.cycle - 1].velocity[0]
    assert f.value == pytest.approx(v / servo.kp, rel=0.3)
    _, V, A = _arrays(sps)
    _within(V, A, _lims())
    assert sps[-1].state == "fault" and np.all(V[-1] == 0)
    _pulses_hold(sps)


def test_emergency_stop_mid_move_then_reset_and_resume():
    prog = plan_ptp([0.0, 0.0], [1.0, -0.7], _lims())
    st = Streamer(prog, DT, servo=ServoParams(brake_deceleration=20.0), pulse_equivalents=EQ)
    st.start()
    sps = [st.step() for _ in range(700)]
    st.estop()
    sps += [st.step() for _ in range(300)]
    e = sps[700]
    assert e.state == "fault" and st.fault.quantity == "emergency stop"
    assert np.array_equal(e.position, sps[699].position)
    assert np.all(e.velocity == 0) and np.all(e.acceleration == 0)
    assert np.all(sps[-1].pulses == 0)
    _pulses_hold(sps)
    # the load coasts on the brake: distance v^2 / (2 b) from its velocity at the stop
    assert np.all(np.abs(st.servo.v) == 0)
    v0 = (sps[699].actual - sps[698].actual) / DT
    dist = sps[-1].actual - sps[699].actual
    assert dist == pytest.approx(np.sign(v0) * v0 ** 2 / (2 * 20.0), rel=0.02, abs=1e-4)
    st.start()  # rejected: resume only after reset
    st.step()
    assert st.state == "fault" and st.events[-1].kind == "rejected"
    st.reset()
    sp = st.step()
    assert sp.state == "idle" and st.fault is None
    st.start()
    rest = list(st)
    assert st.finished and np.allclose(rest[-1].position, prog.goal, atol=1e-12)
    assert np.array_equal(rest[-1].pulse_count, pulse_counts(prog.goal, EQ))
    kinds = [ev.kind for ev in st.events]
    for want in ("estop", "rejected", "reset", "start", "reentry", "finished"):
        assert want in kinds
    _within(*_arrays(rest)[1:], _lims())


def test_pulse_rate_fault_and_config_errors():
    prog = plan_ptp([0.0, 0.0], [1.0, 0.5], _lims())
    st = Streamer(prog, DT, pulse_equivalents=EQ, max_pulse_rate=300_000.0)
    sps = list(st)
    f = st.fault
    assert f.quantity == "pulse rate" and f.limit == 300_000.0 and f.value > 300_000.0
    prev = sps[f.cycle - 1].velocity
    assert np.max(np.abs(prev)) / EQ <= 300_000.0 * 1.01
    _pulses_hold(sps)
    with pytest.raises(InvalidInputError, match="reaction 'halt' for velocity must be one of"):
        SafetyConfig(reactions={"velocity": "halt"})
    with pytest.raises(InvalidInputError, match="unknown quantity 'jerk'"):
        SafetyConfig(reactions={"jerk": "controlled"})
    with pytest.raises(InvalidInputError, match="following_error limits must be > 0"):
        Streamer(prog, DT, safety=SafetyConfig(following_error=-1.0))
