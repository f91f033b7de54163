"""Streaming interpolator: exact stream, override/pause proofs, controlled stop, brake kernel."""

from __future__ import annotations

import asyncio
import math
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import sweep_size

from trajkit import AxisLimits, InvalidInputError, plan_ptp
from trajkit.profiles.state import plan_velocity
from trajkit.runtime import ProgramSource, Streamer, as_source, brake_profile
from trajkit.runtime._brake import brake_phases
from trajkit.runtime.safety import MONITOR_RTOL, Monitors
from trajkit.runtime.streamer import override_limits

DT = 0.001
TOL = 1e-9

LIMS = [AxisLimits(1.0, 4.0, 40.0, a_max_decel=6.0, j_max_decel=60.0,
                   position_min=-3.0, position_max=3.0, name=n) for n in "XYZ"]


def _ptp():
    return plan_ptp([0.0, 0.0, 0.0], [2.0, -1.5, 0.3], LIMS)


def _arrays(sps):
    return (np.array([s.position for s in sps]), np.array([s.velocity for s in sps]),
            np.array([s.acceleration for s in sps]))


def _check_limits(V, A, lims, rtol=TOL):
    vm = np.array([lm.v_max for lm in lims])
    am = np.array([lm.a_max for lm in lims])
    ad = np.array([lm.a_max_decel for lm in lims])
    assert np.all(np.abs(V) <= vm * (1 + rtol))
    shrinking = V * A < 0
    lim = np.where(shrinking, ad, am)
    assert np.all(np.abs(A) <= lim * (1 + rtol)), np.max(np.abs(A) / lim)


def test_full_override_stream_is_the_plan_sampled_exactly():
    tr = _ptp()
    st = Streamer(tr, DT)
    sps = list(st)
    P, V, A = _arrays(sps)
    t = np.array([s.t for s in sps])
    ref = tr.sample(np.minimum(t, tr.duration))
    assert np.allclose(P, ref.position, rtol=0, atol=1e-12)
    assert np.allclose(V, ref.velocity, rtol=0, atol=1e-12)
    assert np.allclose(A, ref.acceleration, rtol=0, atol=1e-12)
    assert np.allclose(P[-1], tr.goal, rtol=0, atol=1e-12)
    assert sps[-1].state == "idle" and st.finished and sps[-1].progress == 1.0
    assert len(sps) == math.ceil(tr.duration / DT - 1e-9) + 1
    assert [e.kind for e in st.events] == ["start", "finished"]


def _override_run(seed, lims=LIMS, pause=True):
    rng = np.random.default_rng(seed)
    # planned with the override reserve, streamed under the machine's limits
    tr = plan_ptp([0.0, 0.0, 0.0], rng.uniform(-2.5, 2.5, 3), override_limits(lims))
    st = Streamer(tr, DT, limits=lims)
    st.start()
    sps = []
    k = 0
    every = int(rng.integers(20, 200))
    while True:
        if k % every == 0:
            st.set_override(float(rng.choice([0.0, 100.0, rng.uniform(0, 100)])))
        if pause and k == 400:
            st.pause()
        if pause and k == 900:
            st.resume()
        if k == 600 and k % every != 0:
            st.set_override(100.0)
        sps.append(st.step())
        k += 1
        if st.finished or k > 40000:
            break
        if k % every == 0 and k > 6000:
            st.set_override(100.0)
    return tr, st, sps


@pytest.mark.parametrize("seed", range(sweep_size(4)))
def test_override_changes_never_exceed_velocity_or_acceleration(seed):
    tr, st, sps = _override_run(seed)
    P, V, A = _arrays(sps)
    assert st.finished and np.allclose(P[-1], tr.goal, atol=1e-12)
    assert st.fault is None  # no monitor ever trips on an override change
    _check_limits(V, A, LIMS)
    # the velocity look-ahead holds too: a ramp-down at j_max never overspeeds
    peak = np.abs(V) + np.where(V * A > 0, A * A / (2 * 40.0), 0.0)
    assert np.all(peak <= 1.0 * (1 + TOL))
    tau = np.array([s.tau for s in sps])
    assert np.all(np.diff(tau) >= 0)
    # always on the planned path: the output is the plan at program time tau
    ref = tr.sample(tau)
    assert np.allclose(P, ref.position, rtol=0, atol=1e-12)
    # the commanded velocity is the derivative of the commanded position
    mid = 0.5 * (V[1:] + V[:-1])
    assert np.allclose(np.diff(P, axis=0) / DT, mid, atol=5e-3)
    rates = np.array([s.override for s in sps])
    assert rates.min() >= 0.0 and rates.max() <= 1.0


def test_pause_stops_on_the_path_and_resume_continues():
    # the reserve makes the stop on the path slower than a per-axis brake (about
    # 2.5 s from full speed here): a long move, paused early
    tr = plan_ptp([0.0, 0.0, 0.0], [2.9, -2.9, 0.3], override_limits(LIMS))
    st = Streamer(tr, DT, limits=LIMS)
    st.start()
    for _ in range(400):
        st.step()
    st.pause()
    sps = [st.step() for _ in range(3000)]
    paused = [s for s in sps if s.state == "running" and np.all(s.velocity == 0) and s.override == 0]
    assert paused, "never came to rest"
    held = paused[0].position
    assert all(np.array_equal(s.position, held) for s in paused)
    assert np.allclose(held, tr.sample(paused[0].tau).position, atol=1e-12)
    assert any(e.kind == "paused" for e in st.events)
    _check_limits(*_arrays(sps)[1:], LIMS)
    st.resume()
    rest = list(st)
    assert st.finished and np.allclose(rest[-1].position, tr.goal, atol=1e-12)
    _check_limits(*_arrays(rest)[1:], LIMS)


def test_controlled_stop_on_ptp_brakes_each_axis_in_minimum_time():
    tr = _ptp()
    st = Streamer(tr, DT)
    st.start()
    for _ in range(300):
        last = st.step()
    st.stop()
    sps = list(st)
    assert sps[-1].state == "idle" and not st.finished
    P, V, A = _arrays(sps)
    _check_limits(V, A, LIMS)
    for k, lm in enumerate(LIMS):
        b = brake_profile(last.position[k], last.velocity[k], last.acceleration[k], lm)
        ref = b.sample(np.arange(1, len(sps) + 1) * DT)
        assert np.allclose(P[:, k], ref.position, atol=1e-12)
        assert P[-1, k] == pytest.approx(b.stop_position, abs=1e-12)
        moving = np.nonzero(np.abs(V[:, k]) > 0)[0]
        n_moving = moving[-1] + 1 if moving.size else 0
        assert abs(n_moving - b.duration / DT) <= 1  # moving exactly as long as its brake
    kinds = [e.kind for e in st.events]
    assert kinds[-2:] == ["stop", "stopped"]
    st.start()  # resumes: re-entry move back to the path, then the rest of the program
    rest = list(st)
    assert st.finished and np.allclose(rest[-1].position, tr.goal, atol=1e-12)
    assert "reentry" in [e.kind for e in st.events]
    _check_limits(*_arrays(rest)[1:], LIMS)


def _line_source():
    """A straight line in (x, y) as a continuous-path program (feed by an S-curve)."""
    from trajkit import plan_move

    sl = plan_move(0.0, 1.0, AxisLimits(0.5, 2.0, 20.0))
    d = np.array([0.6, 0.8])
    lims = [AxisLimits(1.0, 4.0, 40.0, name=n) for n in "xy"]

    def f(tau):
        s = sl.sample(tau)
        return (np.outer(s.position, d), np.outer(s.velocity, d), np.outer(s.acceleration, d))

    # its exact envelope: the feed's limits along d (slack to the machine's limits)
    env = np.outer([0.5, 2.0, 2.0, 20.0], d)
    return ProgramSource(f, sl.duration, lims, path_intervals=[(0.0, sl.duration)],
                         envelope=env), d


def test_stop_on_a_continuous_path_stays_on_the_line():
    src, d = _line_source()
    st = Streamer(src, DT)
    st.start()
    for _ in range(700):
        st.step()
    st.stop()
    sps = list(st)
    P, V, A = _arrays(sps)
    cross = P[:, 0] * d[1] - P[:, 1] * d[0]
    assert np.max(np.abs(cross)) < 1e-12  # on the line through the origin
    assert np.all(np.abs(V[-1]) == 0) and sps[-1].state == "idle"
    _check_limits(V, A, src.limits)
    st.start()  # no re-entry needed: still on the path
    rest = list(st)
    assert "reentry" not in [e.kind for e in st.events]
    assert np.allclose(rest[-1].position, d, atol=1e-12)


def test_commands_from_another_thread_and_asyncio_form():
    tr = _ptp()
    st = Streamer(tr, DT)
    st.start()
    barrier = threading.Event()
    done = threading.Event()

    def hmi():
        barrier.wait()
        for pct in (30.0, 80.0, 50.0, 100.0):
            st.set_override(pct)
            time.sleep(0.001)
        done.set()

    th = threading.Thread(target=hmi)
    th.start()
    sps = []
    for sp in st:
        sps.append(sp)
        if sp.cycle == 100:
            barrier.set()
        if 100 <= sp.cycle < 400 and not done.is_set():
            time.sleep(0.0002)  # give the other thread time while the loop runs
        if sp.cycle == 400:
            assert done.wait(10.0)
    th.join()
    assert st.finished
    assert [e.message for e in st.events if e.kind == "override"] == [
        "override 30 %", "override 80 %", "override 50 %", "override 100 %"]
    _check_limits(*_arrays(sps)[1:], LIMS)

    async def collect():
        st2 = Streamer(tr, DT)
        return [sp async for sp in st2.astream(paced=False)]

    asps = asyncio.run(collect())
    assert len(asps) == len(list(Streamer(tr, DT))) and asps[-1].state == "idle"
    assert np.allclose(asps[-1].position, tr.goal, atol=1e-12)

    async def paced():
        short = plan_ptp([0.0], [0.01], [LIMS[0]])
        st3 = Streamer(short, 0.002)
        loop = asyncio.get_running_loop()
        t0 = loop.time()
        n = 0
        async for _ in st3.astream(paced=True):
            n += 1
        return n, loop.time() - t0

    n, wall = asyncio.run(paced())
    assert wall >= (n - 1) * 0.002  # paced: never ahead of the clock


def test_robot_program_source_has_cp_intervals_and_streams():
    from trajkit.io.program import load_program

    prog = load_program(Path(__file__).resolve().parent.parent / "examples" / "data" / "scara_pick.yaml")
    run = prog.run()
    src = as_source(run)
    assert src.n_axes == 4 and src.duration == pytest.approx(run.duration)
    assert len(src.motion_starts) == len(run.segments)
    kinds = [sg.kind for sg in run.segments]
    assert len(src.path_intervals) == kinds.count("CP")
    tau = np.linspace(0, run.duration, 7)
    q, _, _ = src.sample(tau)
    assert np.allclose(q, run.sample(tau).q)


def test_input_errors_name_field_and_value():
    tr = _ptp()
    st = Streamer(tr, DT)
    with pytest.raises(InvalidInputError, match=r"override must be in \[0, 100\] %, got 150\.0"):
        st.set_override(150)
    with pytest.raises(InvalidInputError, match="override .*nan"):
        st.set_override(float("nan"))
    with pytest.raises(InvalidInputError, match="period"):
        Streamer(tr, 0.0)
    with pytest.raises(InvalidInputError, match="pulse_equivalents must have 3 values, got 2"):
        Streamer(tr, DT, pulse_equivalents=[1e-6, 1e-6])
    with pytest.raises(InvalidInputError, match="limits must have 3 AxisLimits, got 1"):
        Streamer(tr, DT, limits=[LIMS[0]])
    with pytest.raises(InvalidInputError, match="cannot stream an object of type str"):
        as_source("program.yaml")
    with pytest.raises(InvalidInputError, match="needs the servo simulation"):
        st.inject_encoder_jump(0, 1.0)


# ------------------------------------------------------------------ brake kernel
BL = AxisLimits(1.0, 2.0, 10.0, a_max_decel=3.0, j_max_decel=20.0, name="B")


def _random_states(rng, n):
    v = rng.uniform(-1.0, 1.0, n)
    a = rng.uniform(-1.0, 1.0, n) * np.where(v * rng.uniform(-1, 1, n) > 0, 2.0, 3.0)
    return v, a


@pytest.mark.parametrize("seed", range(2))
def test_brake_matches_plan_velocity_and_keeps_limits(seed):
    """The closed form against the other engineer's numerical state-to-velocity planner."""
    rng = np.random.default_rng(seed)
    n = sweep_size(150)
    v, a = _random_states(rng, n)
    checked = 0
    for vi, ai in zip(v, a):
        lm = BL
        if abs(ai) > (lm.a_max if vi * ai > 0 else lm.a_max_decel):
            continue
        if vi * ai < 0 and abs(vi) < ai * ai / (2 * lm.j_max_decel):
            continue  # reversal case: conservative by design (see _brake.py)
        if vi * ai > 0 and abs(vi) + ai * ai / (2 * lm.j_max) > lm.v_max:
            continue  # a state that must overspeed before it can brake
        b = brake_profile(0.3, vi, ai, lm)
        ref = plan_velocity((0.3, vi, ai), 0.0, limits=lm)
        assert b.duration == pytest.approx(ref.duration, rel=1e-9, abs=1e-12)
        assert b.stop_position == pytest.approx(ref.goal, rel=1e-9, abs=1e-12)
        # exact rest at the end, limits on the phase boundaries and dense samples
        t = np.concatenate([np.linspace(0, b.duration, 400), np.cumsum(b.phase_durations)])
        s = b.sample(t)
        lim = np.where(s.velocity * s.acceleration > 0, lm.a_max, lm.a_max_decel)
        assert np.all(np.abs(s.acceleration) <= lim * (1 + TOL))
        assert np.all(np.abs(s.jerk) <= max(lm.j_max, lm.j_max_decel) * (1 + TOL))
        assert np.all(np.abs(s.velocity) <= lm.v_max * (1 + TOL))
        end = b.sample(b.duration)
        assert abs(float(end.velocity)) <= 1e-12 and abs(float(end.acceleration)) <= 1e-12
        checked += 1
    assert checked > n // 3


def test_brake_reversal_and_overspeed_cases_end_at_rest():
    for v, a in [(0.01, -2.9), (-0.02, 2.5), (1.3, 1.9), (0.0, 1.0), (0.0, 0.0)]:
        ph = brake_phases(v, a, BL.a_max, BL.j_max, BL.a_max_decel, BL.j_max_decel)
        b = brake_profile(0.0, v, a, BL)
        end = b.sample([b.duration])
        assert abs(end.velocity[0]) < 1e-12 and abs(end.acceleration[0]) < 1e-12
        # the phases really end at rest (integrated, not just held)
        vv, aa = v, a
        for dt, j in ph:
            vv += dt * (aa + 0.5 * dt * j)
            aa += dt * j
        assert abs(vv) < 1e-12 and abs(aa) < 1e-12


def test_stop_distance_bound_of_the_look_ahead_monitor_is_an_upper_bound():
    rng = np.random.default_rng(3)
    mon = Monitors([BL], ["B"], np.array([np.inf]), True)
    v, a = rng.uniform(-1.5, 1.5, 300), rng.uniform(-3.5, 3.5, 300)
    for vi, ai in zip(v, a):
        b = brake_profile(0.0, vi, ai, BL)
        x = np.abs(b.sample(np.linspace(0, b.duration, 100)).position).max()
        assert x <= mon._reach(0, vi, ai) * (1 + MONITOR_RTOL)


def test_pallet_plan_source_waits_in_position_at_each_trip_end():
    from trajkit.palletizing import plan_cycle, seed_scenario
    from trajkit.runtime import ServoParams

    plan = plan_cycle(seed_scenario(), "merged")
    src = as_source(plan)
    ends = np.asarray(plan.trip_starts) + [tr.duration for tr in plan.trips]
    assert np.allclose(src.stop_points, ends) and src.motion_labels[0] == "trip 0 (load)"
    st = Streamer(src, DT, servo=ServoParams(inertia_ratio=1.3), wait_in_position=True)
    n = int((ends[1] + 0.2) / DT)
    sps = st.run(max_cycles=n)
    assert len(st.stop_log) == 2
    for (tau, since, release), end in zip(st.stop_log, ends[:2]):
        assert tau == end and release > since
        i = int(round(release / DT)) - 1  # the last cycle of the wait
        fe = np.array([s.following_error for s in sps[i - 4:i + 1]])
        assert np.all(np.abs(fe) <= 1e-4)  # in the window for settle_cycles periods
    assert sps[-1].motion == 2 and 0 < sps[-1].progress < 1
    # waiting holds program time: the stream is later than the plan by the settling
    lag = sps[-1].t - sps[-1].tau
    assert lag == pytest.approx(sum(r - s for _, s, r in st.stop_log), abs=3 * DT)


def test_override_step_sequence_while_accelerating_does_not_trip_the_monitors():
    """Regression: the rate ramping back to 100 % while an axis sits at a_max used to
    leave it at an acceleration from which the jerk-limited ramp-down overspeeds."""
    st = Streamer(plan_ptp([0.0, 0.0, 0.0], [2.0, -1.5, 0.3], override_limits(LIMS)), DT, limits=LIMS)
    st.start()
    sps = []
    script = {100: 30.0, 101: 80.0, 102: 50.0, 104: 100.0}
    while not st.finished and st.state != "fault":
        if len(sps) in script:
            st.set_override(script[len(sps)])
        sps.append(st.step())
    assert st.fault is None and st.finished
    _check_limits(*_arrays(sps)[1:], LIMS)
