"""Servo simulation: exact discretisation vs fine integration, closed forms, settling,
planned vs simulated time."""

from __future__ import annotations

import numpy as np
import pytest

from trajkit import AxisLimits, InvalidInputError, plan_move, plan_ptp
from trajkit.runtime import RuntimeFault, ServoBank, ServoParams, simulate

DT = 0.001
LIM = AxisLimits(1.0, 4.0, 40.0, name="X")


def _euler(params: ServoParams, x_ref, v_ref, a_ref, n_sub=40):
    """Independent reference: explicit fine-step integration of the documented loop."""
    p = params
    x = x_ref[0]
    v = 0.0
    integ = 0.0
    out = []
    h = DT / n_sub
    for k in range(len(x_ref)):
        out.append(x)
        for i in range(n_sub):
            s = i * h
            xr = x_ref[k] + s * (v_ref[k] + 0.5 * s * a_ref[k])
            vr = v_ref[k] + s * a_ref[k]
            vc = p.ff_velocity * vr + p.kp * (xr - x)
            u = p.ff_acceleration * a_ref[k] + p.kv * (vc - v) + integ
            integ += p.ki * (vc - v) * h
            acc = u / p.inertia_ratio
            x += v * h + 0.5 * acc * h * h
            v += acc * h
    return np.array(out)


@pytest.mark.parametrize("params", [
    ServoParams(),
    ServoParams(inertia_ratio=1.8, ff_acceleration=0.5, kp=25.0),
    ServoParams(ff_velocity=0.0, ff_acceleration=0.0, ki=0.0),
])
def test_exact_discretisation_matches_fine_integration(params):
    prof = plan_move(0.0, 0.05, LIM)
    t = np.arange(int(prof.duration / DT) + 100) * DT
    s = prof.sample(t)
    bank = ServoBank(params, 1, DT, [0.0])
    xs = []
    for k in range(t.size):
        xs.append(bank.x[0])
        bank.step(s.position[k:k + 1], s.velocity[k:k + 1], s.acceleration[k:k + 1])
    ref = _euler(params, s.position, s.velocity, s.acceleration)
    fe = np.max(np.abs(s.position - ref))
    assert fe > 0
    assert np.max(np.abs(np.array(xs) - ref)) < 0.02 * fe  # first-order reference: 2 %


def test_following_error_closed_forms():
    # full feedforward, exact load: only the jerk leaves an error (tiny)
    prof = plan_move(0.0, 1.0, LIM)
    rep = simulate(prof, DT, ServoParams(), exact_stop=False)
    assert rep.max_following_error[0] < 1e-5
    # no feedforward: at cruise speed v the error settles to v / kp
    p = ServoParams(ff_velocity=0.0, ff_acceleration=0.0)
    long = plan_move(0.0, 3.0, LIM)
    rep = simulate(long, DT, p, exact_stop=False)
    cruise = (rep.t > 1.0) & (rep.t < 2.5)
    assert np.allclose(rep.following_error[cruise, 0], LIM.v_max / p.kp, rtol=1e-3)


def test_heavier_load_settles_later_and_simulated_time_adds_up():
    tr = plan_ptp([0.0, 0.0], [0.5, -0.3], [LIM, LIM.with_name("Y")])
    light = simulate(tr, DT, ServoParams())
    heavy = simulate(tr, DT, ServoParams(inertia_ratio=2.0, in_position=2e-5))
    for rep in (light, heavy):
        assert rep.planned_s == pytest.approx(tr.duration)
        assert rep.simulated_s >= rep.planned_s
        assert sum(m.simulated_s for m in rep.motions) == pytest.approx(rep.simulated_s)
        assert sum(m.planned_s for m in rep.motions) == pytest.approx(rep.planned_s)
        # at the release every axis had been in the window for settle_cycles periods
        end = rep.t.size - 1
        n = rep.servo[0].settle_cycles
        assert np.all(np.abs(rep.following_error[end - n + 1:end + 1]) <= rep.servo[0].in_position)
    assert heavy.simulated_s > light.simulated_s
    assert heavy.max_following_error[0] > 10 * light.max_following_error[0]


def test_brake_and_drive_limit():
    bank = ServoBank(ServoParams(brake_deceleration=5.0), 1, DT, [0.0])
    bank.v = np.array([0.5])
    bank.engage_brake()
    for _ in range(200):
        bank.step(np.zeros(1), np.zeros(1), np.zeros(1))
    assert bank.x[0] == pytest.approx(0.5 ** 2 / (2 * 5.0), rel=1e-12)
    assert bank.v[0] == 0.0
    # a drive limit below the demand: the load lags, but still arrives
    prof = plan_move(0.0, 0.2, LIM)
    rep = simulate(prof, DT, ServoParams(a_drive=3.0), exact_stop=True)
    ref = simulate(prof, DT, ServoParams(), exact_stop=True)
    assert rep.max_following_error[0] > 100 * ref.max_following_error[0]
    assert rep.simulated_s > ref.simulated_s
    # far below the demand the saturated loop never settles: the in-position monitor trips
    with pytest.raises(RuntimeFault, match=r"in position .* s \(following error .* > window "
                                           r"0\.0001\) of axis X exceeds the limit 0\.5 at cycle"):
        simulate(prof, DT, ServoParams(a_drive=2.0, settle_timeout=0.5))


@pytest.mark.parametrize("kw,pattern", [
    ({"kp": 0.0}, "kp should be larger than zero, got 0.0"),
    ({"ff_velocity": 1.5}, r"ff_velocity must be in \[0, 1\], got 1.5"),
    ({"ki": -1.0}, r"ki must be >= 0, got -1.0"),
    ({"settle_cycles": 0}, "settle_cycles must be an integer >= 1, got 0"),
])
def test_servo_params_errors(kw, pattern):
    with pytest.raises(InvalidInputError, match=pattern):
        ServoParams(**kw)


def test_following_error_plot_needs_the_recorded_series():
    pytest.importorskip("matplotlib")
    from trajkit.plot.runtime import plot_following_error

    rep = simulate(plan_move(0.0, 1.0, LIM), DT, ServoParams(), record=False)
    with pytest.raises(InvalidInputError, match="record=True"):
        plot_following_error(rep)
