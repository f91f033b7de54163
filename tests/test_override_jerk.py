"""Feed override never exceeds a limit, jerk included (issue 6): random override/pause sweeps."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
from conftest import sweep_size

from trajkit import AxisLimits, InvalidInputError, plan_ptp
from trajkit.runtime import Streamer, as_source
from trajkit.runtime.streamer import (
    OVERRIDE_RESERVE,
    RATE_LIMIT_FRACTION,
    override_limits,
    override_rate_limits,
    reserve_rate,
    slowdown_rate_table,
)

DT = 0.01
TOL = 1e-9
SYM = [AxisLimits(1.0, 4.0, 40.0, position_min=-3.0, position_max=3.0, name=n) for n in "XYZ"]
ASYM = [AxisLimits(0.8, 3.0, 30.0, a_max_decel=5.0, j_max_decel=20.0,
                   position_min=-3.0, position_max=3.0, name=n) for n in "ABC"]
RUNS_PER_CASE = 30  # x seeds x 2 limit sets: a few hundred random override sequences in CI


def _arrays(sps):
    return (np.array([s.position for s in sps]), np.array([s.velocity for s in sps]),
            np.array([s.acceleration for s in sps]))


def _assert_stream_within(V, A, lims, bound=None):
    """Every cycle: |v| <= v_max, a within its leg bound, |Delta a| / period <= jerk (each leg)."""
    vm = np.array([lm.v_max for lm in lims])
    am = np.array([lm.a_max for lm in lims])
    ad = np.array([lm.a_max_decel for lm in lims])
    jm = np.array([min(lm.j_max, lm.j_max_decel) for lm in lims])
    assert np.all(np.abs(V) <= vm * (1 + TOL))
    lim = np.where(V * A < 0, ad, am)
    assert np.all(np.abs(A) <= lim * (1 + TOL)), np.max(np.abs(A) / lim)
    jerk = np.abs(np.diff(A, axis=0)) / DT
    # the proof bounds the jerk by min(j_max, j_max_decel): whichever leg the cycle is on
    assert np.all(jerk <= jm * (1 + 1e-7)), np.max(jerk / jm)
    if bound is not None:
        assert np.all(jerk <= bound * (1 + 1e-7) + 1e-9)
    # the velocity look-ahead of the monitors holds too
    jv = np.array([lm.j_max for lm in lims])
    peak = np.abs(V) + np.where(V * A > 0, A * A / (2 * jv), 0.0)
    assert np.all(peak <= vm * (1 + TOL))
    return float(np.max(jerk / jm))


def _random_drive(st, rng, n_max=20000):
    """Random override steps (0 %, 100 %, anything between) and pauses, then 100 % to the end."""
    st.start()
    sps = []
    every = int(rng.integers(3, 40))
    pause_at = int(rng.integers(0, 100))
    resume_at = pause_at + int(rng.integers(1, 200))
    k = 0
    while not st.finished and st.state not in ("fault",) and k < n_max:
        if k % every == 0 and k < 400:
            st.set_override(float(rng.choice([0.0, 100.0, rng.uniform(0.0, 100.0)])))
        if k == pause_at:
            st.pause()
        if k == resume_at:
            st.resume()
        if k == 400:
            st.set_override(100.0)
        sps.append(st.step())
        k += 1
    return sps


def _run_case(rng, lims):
    goal = rng.uniform(-2.0, 2.0, 3)
    tr = plan_ptp([0.0, 0.0, 0.0], goal, override_limits(lims))
    st = Streamer(tr, DT, limits=lims)
    assert st.rate_ceiling == 1.0
    sps = _random_drive(st, rng)
    P, V, A = _arrays(sps)
    assert st.fault is None and st.finished  # no monitor ever trips
    assert np.array_equal(P[-1], tr.goal)  # the goal exactly
    assert st.clip_count == 0  # the admissible-interval clip never acts: the proof suffices
    tau = np.array([s.tau for s in sps])
    assert np.all(np.diff(tau) >= 0)
    assert np.allclose(P, tr.sample(tau).position, rtol=0, atol=1e-12)  # on the path
    return _assert_stream_within(V, A, lims, st.jerk_bound)


@pytest.mark.parametrize("lims", [SYM, ASYM], ids=["symmetric", "asymmetric"])
@pytest.mark.parametrize("seed", range(sweep_size(2)))
def test_random_override_sequences_never_exceed_velocity_acceleration_or_jerk(seed, lims):
    rng = np.random.default_rng(1000 * seed + len(lims[0].name))
    worst = max(_run_case(rng, lims) for _ in range(RUNS_PER_CASE))
    assert 0.0 < worst <= 1.0 + 1e-7


def test_jerk_bound_is_tight_enough_to_matter():
    """The proven per-axis bound is the machine's jerk (the slack is used, not wasted)."""
    tr = plan_ptp([0.0, 0.0, 0.0], [2.0, -1.5, 0.3], override_limits(ASYM))
    st = Streamer(tr, DT, limits=ASYM)
    jm = np.array([min(lm.j_max, lm.j_max_decel) for lm in ASYM])
    assert np.all(st.jerk_bound <= jm) and np.all(st.jerk_bound >= 0.99 * jm)
    s1, s2 = st.rate_limits
    env = st.source.envelope
    # the inequalities of the proof, recomputed here
    V, Aa, Ad, J = env
    assert np.all(Aa + V * s1 <= np.array([lm.a_max for lm in ASYM]) + 1e-12)
    assert np.all(Ad + V * s1 <= np.array([lm.a_max_decel for lm in ASYM]) + 1e-12)
    assert np.all(J + 3 * np.maximum(Aa, Ad) * s1 + V * s2 <= jm + 1e-12)


def test_full_limit_program_with_the_old_default_rates_is_refused():
    """The old failure: a program at full limits with the old rates (half of a/v and j/v)
    reached 1.8 x j_max. Such rate limits are now refused, and without them the program
    gets a proven ceiling below 100 % (rate changes above it wait for a stop point)."""
    lims = SYM
    tr = plan_ptp([0.0, 0.0, 0.0], [2.0, -1.5, 0.3], lims)
    old = (RATE_LIMIT_FRACTION * 4.0 / 1.0, RATE_LIMIT_FRACTION * 40.0 / 1.0)
    with pytest.raises(InvalidInputError, match=r"rate_limits.* of axis X.*exceed"):
        Streamer(tr, DT, rate_limits=old)
    assert override_rate_limits(as_source(tr).envelope, lims) is None  # no slack at all
    st = Streamer(tr, DT)
    expected = OVERRIDE_RESERVE ** (1 / 3)  # J s^3 = reserve * j on the jerk-limited axes
    assert st.rate_ceiling == pytest.approx(min(expected, OVERRIDE_RESERVE ** 0.5))
    worst = []
    for seed in range(sweep_size(20)):
        st = Streamer(tr, DT)
        sps = _random_drive(st, np.random.default_rng(seed))
        P, V, A = _arrays(sps)
        assert st.fault is None and st.finished and np.array_equal(P[-1], tr.goal)
        assert st.clip_count == 0
        worst.append(_assert_stream_within(V, A, lims))
    assert max(worst) <= 1.0 + 1e-7


def test_pause_and_override_on_a_ceiling_program_wait_for_a_stop_point():
    """Above the proven ceiling the rate holds; it switches at once at a stop point (rest)."""
    tr = plan_ptp([0.0, 0.0, 0.0], [2.0, -1.5, 0.3], SYM)
    st = Streamer(tr, DT)
    st.start()
    sps = [st.step() for _ in range(50)]
    st.set_override(40.0)
    sps += list(st)
    rates = np.array([s.override for s in sps])
    assert np.all(rates[:-1] == 1.0)  # the program's only stop point is its end
    _assert_stream_within(*_arrays(sps)[1:], SYM)
    # HMI-style: max_rate = reserve_rate gives a proof at once, override applies while moving
    env = as_source(tr).envelope
    top = reserve_rate(env, SYM)
    st = Streamer(tr, DT, max_rate=top)
    assert st.rate_ceiling == top and override_rate_limits(env, SYM, top) is not None
    st.start()
    sps = [st.step() for _ in range(50)]
    st.set_override(40.0)
    sps += list(st)
    rates = np.array([s.override for s in sps])
    assert rates[49] == pytest.approx(top) and rates[-2] == pytest.approx(0.4 * top)
    assert st.clip_count == 0
    _assert_stream_within(*_arrays(sps)[1:], SYM, st.jerk_bound)


def test_bad_max_rate_and_rate_limits_are_named():
    tr = plan_ptp([0.0], [1.0], override_limits(SYM[:1]))
    with pytest.raises(InvalidInputError, match=r"max_rate must be in \(0, 1\], got 1\.5"):
        Streamer(tr, DT, limits=SYM[:1], max_rate=1.5)
    with pytest.raises(InvalidInputError, match=r"rate_limits\[0\] 5\.0 of axis X exceeds"):
        Streamer(tr, DT, limits=SYM[:1], rate_limits=(5.0, 1.0))


def _scara_run(derated: bool):
    from trajkit.io.program import load_program

    prog = load_program(Path(__file__).resolve().parent.parent / "examples" / "data" / "scara_pick.yaml")
    robot = prog.robot
    if derated:
        robot = copy.copy(robot)
        robot.limits = tuple(override_limits(prog.robot.limits))
    from trajkit.robot import run_motions

    return prog.robot, run_motions(robot, prog.motions, prog.start)


def test_lin_circ_robot_program_keeps_every_limit_under_random_override():
    machine, run = _scara_run(derated=True)
    src = as_source(run)
    assert src.path_intervals  # LIN/CIRC segments
    # the joint jerk of LIN/CIRC segments comes from IK of a Cartesian feed: the
    # planner bounds it through finite differences on its grid, so the envelope is
    # measured on samples and the stream runs at the rate that leaves the reserve's
    # slack (as the HMI does); the planner keeps the jerk, so that rate is 100 %
    assert src.envelope_kind == "estimated"
    top = reserve_rate(src.envelope, machine.limits)
    assert 0.0 < top <= 1.0
    st0 = Streamer(src, DT, limits=machine.limits, max_rate=top)
    assert st0.rate_ceiling == top
    worst = []
    for seed in range(sweep_size(3)):
        st = Streamer(src, DT, limits=machine.limits, max_rate=top)
        sps = _random_drive(st, np.random.default_rng(seed), n_max=60000)
        P, V, A = _arrays(sps)
        assert st.fault is None and st.finished, st.fault
        assert st.clip_count == 0
        assert np.allclose(P[-1], src.sample(src.duration)[0][0], rtol=0, atol=1e-12)
        tau = np.array([s.tau for s in sps])
        assert np.allclose(P, src.sample(tau)[0], rtol=0, atol=1e-12)  # on the path
        worst.append(_assert_stream_within(V, A, machine.limits))
    assert max(worst) <= 1.0 + 1e-7


def test_derated_limits_cost_little_time():
    """The reserve's price on a sample program, and the derating helper's semantics."""
    full = plan_ptp([0.0, 0.0, 0.0], [2.0, -1.5, 0.3], SYM)
    red = plan_ptp([0.0, 0.0, 0.0], [2.0, -1.5, 0.3], override_limits(SYM))
    assert full.duration < red.duration < full.duration / OVERRIDE_RESERVE
    lm = override_limits(ASYM)[0]
    assert lm.a_max == pytest.approx(0.8 * 3.0) and lm.a_max_decel == pytest.approx(0.8 * 5.0)
    assert lm.j_max == lm.j_max_decel == pytest.approx(0.8 * 20.0) and lm.v_max == 0.8


def test_stop_on_the_path_uses_larger_rate_limits_as_the_rate_falls():
    """Pause from full speed: the per-level rate limits (slowdown_rate_table) stop sooner.

    Each level's pair is admissible at that level and the pairs never shrink
    as the rate falls, so the stream keeps every limit (checked per cycle)
    while stopping in about half the time of the single top-level pair.
    """
    tr = plan_ptp([0.0, 0.0, 0.0], [2.0, -1.5, 0.3], override_limits(SYM))
    us, arr = slowdown_rate_table(as_source(tr).envelope, SYM, 1.0)
    assert us.shape == (arr.shape[0],) and arr.shape[1] == 2
    assert np.all(arr[1:] <= arr[:-1]) and arr[0, 0] > 2.0 * arr[-1, 0]
    times = {}
    for use_table in (False, True):
        st = Streamer(tr, DT, limits=SYM)
        if not use_table:
            st._slow_table = None  # the single pair of the top level
        st.start()
        sps = [st.step() for _ in range(90)]
        st.pause()
        k = 0
        while True:
            sps.append(st.step())
            k += 1
            if np.all(sps[-1].velocity == 0.0):
                break
        times[use_table] = k * DT
        assert st.clip_count == 0
        _assert_stream_within(*_arrays(sps)[1:], SYM, st.jerk_bound)
    assert times[True] < 0.6 * times[False]
