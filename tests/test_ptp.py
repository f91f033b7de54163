"""Multi-axis ``plan_ptp``: time / phase / none synchronisation, sampling, export."""

from __future__ import annotations

import csv
import io
import json
import math

import numpy as np
import pytest

from trajkit import AxisLimits, InfeasibleError, InvalidInputError, min_duration, plan_move, plan_ptp
from trajkit.verify import verify_profile, verify_trajectory

EXACT = 1e-12
LINE_RTOL = 1e-12

LIMS = [
    AxisLimits(1.0, 2.0, 10.0, name="A"),
    AxisLimits(0.5, 1.0, 5.0, a_max_decel=3.0, j_max_decel=2.0, name="B"),
    AxisLimits(2.0, math.inf, 40.0, name="C"),
    AxisLimits(0.8, 4.0, math.inf, a_max_decel=1.0, name="D"),
]
START = [0.0, 1.0, -2.0, 0.5]
GOAL = [1.5, -0.3, 0.7, 0.5]  # D does not move


def _random_problem(rng, n):
    lims = []
    for _ in range(n):
        v, a, j = np.exp(rng.uniform(np.log(1e-2), np.log(1e2), 3))
        ra, rj = np.exp(rng.uniform(np.log(0.05), np.log(20.0), 2))
        jd = j * rj
        if rng.random() < 0.15:
            j = jd = math.inf
        lims.append(AxisLimits(v, a, j, a * ra, jd))
    s = rng.uniform(-5, 5, n)
    g = s + rng.uniform(-10, 10, n) * (rng.random(n) < 0.85)
    return s, g, lims


def test_time_sync_all_arrive_at_slowest_minimum():
    tr = plan_ptp(START, GOAL, LIMS, sync="time")
    mins = [min_duration(g - s, lim) for s, g, lim in zip(START, GOAL, LIMS)]
    assert tr.duration == max(mins)
    assert all(p.duration == tr.duration for p in tr.axes)
    verify_trajectory(tr).raise_if_failed()
    slow = int(np.argmax(mins))
    ref = plan_move(START[slow], GOAL[slow], LIMS[slow])
    assert tr.axes[slow].phase_durations == ref.phase_durations
    assert tr.names == ("A", "B", "C", "D")


def test_phase_sync_is_a_straight_line_in_joint_space():
    tr = plan_ptp(START, GOAL, LIMS, sync="phase")
    rep = verify_trajectory(tr)
    rep.raise_if_failed()
    t = np.linspace(0.0, tr.duration, 4001)
    s = tr.sample(t)
    d = np.array(GOAL) - np.array(START)
    moving = d != 0
    u = (s.position[:, moving] - np.array(START)[moving]) / d[moving]
    assert np.max(u.max(axis=1) - u.min(axis=1)) <= LINE_RTOL
    assert np.all(np.diff(u[:, 0]) >= 0.0) and u[0, 0] == 0.0 and u[-1, 0] == 1.0
    # velocities proportional to the distances too
    v = s.velocity[:, moving] / d[moving]
    assert np.max(np.abs(v - v[:, :1])) <= LINE_RTOL * np.max(np.abs(v))
    # the still axis stays put
    assert np.all(s.position[:, ~moving] == np.array(START)[~moving])
    assert tr.duration >= plan_ptp(START, GOAL, LIMS, sync="time").duration
    # at least one axis reaches one of its limits (the line is as fast as allowed)
    assert max(rep.ratios.values()) == pytest.approx(1.0, rel=1e-9)


def test_none_sync_each_axis_at_its_own_minimum():
    tr = plan_ptp(START, GOAL, LIMS, sync="none")
    for s, g, lim, p in zip(START, GOAL, LIMS, tr.axes):
        assert p.duration == min_duration(g - s, lim)
        verify_profile(p).raise_if_failed()
    assert tr.duration == max(p.duration for p in tr.axes)
    # after its own end an axis holds its goal
    short = int(np.argmin([p.duration for p in tr.axes[:3]]))
    s = tr.sample(tr.duration)
    assert s.position[0, short] == GOAL[short]


@pytest.mark.parametrize("sync", ["time", "phase"])
@pytest.mark.parametrize("factor", [1.0, 1.0 + 1e-12, 1.3, 10.0])
def test_requested_duration(sync, factor):
    T = plan_ptp(START, GOAL, LIMS, sync=sync).duration * factor
    tr = plan_ptp(START, GOAL, LIMS, sync=sync, duration=T)
    assert tr.duration == T
    assert all(p.duration == T for p in tr.axes)
    verify_trajectory(tr).raise_if_failed()


@pytest.mark.parametrize("sync", ["time", "phase"])
def test_requested_duration_below_minimum(sync):
    tmin = plan_ptp(START, GOAL, LIMS, sync=sync).duration
    with pytest.raises(InfeasibleError, match=r"below the minimum") as ei:
        plan_ptp(START, GOAL, LIMS, sync=sync, duration=0.9 * tmin)
    assert ei.value.minimum == pytest.approx(tmin, rel=EXACT)


def test_random_sweep_all_modes():
    rng = np.random.default_rng(4242)
    for _ in range(80):
        n = int(rng.integers(1, 7))
        s, g, lims = _random_problem(rng, n)
        durations = {}
        for sync in ("time", "phase", "none"):
            tr = plan_ptp(s, g, lims, sync=sync)
            verify_trajectory(tr, n_samples=101).raise_if_failed()
            durations[sync] = tr.duration
        assert durations["time"] == durations["none"]
        assert durations["phase"] >= durations["time"] * (1 - EXACT)
        T = durations["phase"] * float(np.exp(rng.uniform(0, np.log(5))))
        for sync in ("time", "phase"):
            tr = plan_ptp(s, g, lims, sync=sync, duration=T)
            assert tr.duration == T
            verify_trajectory(tr, n_samples=101).raise_if_failed()


def test_single_axis_phase_equals_plan_move():
    lim = AxisLimits(1.0, 2.0, 10.0, 0.7, 3.0)
    tr = plan_ptp([0.3], [-2.0], lim, sync="phase")
    p = plan_move(0.3, -2.0, lim)
    assert tr.duration == pytest.approx(p.duration, rel=EXACT)
    t = np.linspace(0, p.duration, 101)
    np.testing.assert_allclose(tr.sample(t).position[:, 0], p.sample(t).position, atol=1e-12)


def test_all_axes_still():
    tr = plan_ptp([1.0, 2.0], [1.0, 2.0], LIMS[0], sync="phase")
    assert tr.duration == 0.0
    verify_trajectory(tr).raise_if_failed()


def test_single_limits_object_is_shared_and_axes_named_by_index():
    lim = AxisLimits(1.0, 2.0, 10.0)
    tr = plan_ptp([0.0, 0.0], [1.0, 2.0], lim)
    assert tr.names == ("q0", "q1")
    assert all(p.limits is lim for p in tr.axes)
    # messages still name the axis by its index
    with pytest.raises(InvalidInputError, match="of axis 1"):
        plan_ptp([0.0, 0.0], [1.0, float("nan")], lim)


# ------------------------------------------------------------ sampling, export
def test_sample_shapes():
    tr = plan_ptp(START, GOAL, LIMS)
    s = tr.sample(0.25)
    assert s.position.shape == (1, 4) and s.t.shape == (1,)
    t = np.linspace(-0.1, tr.duration + 0.1, 17)
    s = tr.sample(t)
    for arr in (s.position, s.velocity, s.acceleration, s.jerk):
        assert arr.shape == (17, 4)
    np.testing.assert_array_equal(s.position[0], START)
    np.testing.assert_array_equal(s.position[-1], GOAL)
    for k, p in enumerate(tr.axes):
        np.testing.assert_array_equal(s.velocity[:, k], p.sample(t).velocity)


def test_times_end_exactly_at_duration():
    tr = plan_ptp(START, GOAL, LIMS)
    t = tr.times(0.001)
    assert t[0] == 0.0 and t[-1] == tr.duration
    assert np.all(np.diff(t) > 0) and np.all(np.diff(t) <= 0.001 * (1 + EXACT))


def test_csv_round_trip(tmp_path):
    tr = plan_ptp(START, GOAL, LIMS, sync="time")
    path = tmp_path / "ptp.csv"
    text = tr.to_csv(path, period=0.01)
    assert path.read_text() == text
    rows = list(csv.reader(io.StringIO(text)))
    header, data = rows[0], np.array(rows[1:], dtype=float)
    assert header == ["t_s"] + [f"{n}_{q}" for n in "ABCD" for q in
                                ("position_m", "velocity_m_s", "acceleration_m_s2", "jerk_m_s3")]
    t = data[:, 0]
    np.testing.assert_array_equal(t, tr.times(0.01))
    s = tr.sample(t)
    for k in range(4):
        np.testing.assert_array_equal(data[:, 1 + 4 * k], s.position[:, k])
        np.testing.assert_array_equal(data[:, 2 + 4 * k], s.velocity[:, k])
        np.testing.assert_array_equal(data[:, 3 + 4 * k], s.acceleration[:, k])
        np.testing.assert_array_equal(data[:, 4 + 4 * k], s.jerk[:, k])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ptp.csv"]


def test_json_round_trip_reintegrates(tmp_path):
    """Integrating the exported phases reproduces the goal of every axis."""
    tr = plan_ptp(START, GOAL, LIMS, sync="phase")
    path = tmp_path / "ptp.json"
    text = tr.to_json(path)
    doc = json.loads(path.read_text())
    assert json.loads(text) == doc
    assert doc["sync"] == "phase" and doc["duration_s"] == tr.duration
    assert [a["name"] for a in doc["axes"]] == ["A", "B", "C", "D"]
    for ax, p in zip(doc["axes"], tr.axes):
        assert [ph["duration_s"] for ph in ax["phases"]] == list(p.phase_durations)
        assert [ph["jerk"] for ph in ax["phases"]] == list(p.jerks)
        # rebuild the motion from the document alone
        sgn = 1.0 if ax["goal"] > ax["start"] else -1.0
        acc_in = [0.0, sgn * ax["peak_acceleration"], sgn * ax["peak_acceleration"], 0.0,
                  0.0, -sgn * ax["peak_deceleration"], -sgn * ax["peak_deceleration"]]
        x, v = 0.0, 0.0
        for ph, a0 in zip(ax["phases"], acc_in):
            dt, j = ph["duration_s"], ph["jerk"]
            x += dt * v + a0 * dt * dt / 2 + j * dt ** 3 / 6
            v += a0 * dt + j * dt * dt / 2
        dist = ax["goal"] - ax["start"]
        assert abs(x - dist) <= 1e-12 * max(abs(dist), 1.0)
        assert abs(v) <= 1e-12 * max(abs(ax["peak_velocity"]), 1.0)


def test_export_failure_leaves_nothing(tmp_path):
    tr = plan_ptp(START, GOAL, LIMS)
    target = tmp_path / "missing-dir" / "out.csv"
    with pytest.raises(OSError):
        tr.to_csv(target)
    assert not target.exists()


def test_phase_sync_is_the_fastest_straight_line():
    """Duration = reference minimum of u: 0 -> 1 under the tightest scaled limits.

    On the line every axis speeds up and slows down together, so the accel
    (decel) limits of all axes bind u's accel (decel) leg at once.
    """
    import reference as R

    rng = np.random.default_rng(99)
    for _ in range(40):
        n = int(rng.integers(2, 6))
        s, g, lims = _random_problem(rng, n)
        d = np.abs(g - s)
        m = d > 0
        if not m.any():
            continue
        scaled = [min(getattr(lim, f) / dk for lim, dk, mk in zip(lims, d, m) if mk)
                  for f in ("v_max", "a_max", "j_max", "a_max_decel", "j_max_decel")]
        ref = R.min_duration(1.0, *scaled)
        tr = plan_ptp(s, g, lims, sync="phase")
        assert tr.duration == pytest.approx(ref, rel=1e-9)
