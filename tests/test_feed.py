"""Feed along a path: the core S-curve in arc length, fixed-period setpoints,
constant cruise speed, slowdowns below a speed-limit curve, stops at corners."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

from trajkit import AxisLimits, plan_move
from trajkit.errors import InvalidInputError
from trajkit.interpolation import CHORD_REASON, plan_feed, setpoint_times
from trajkit.interpolation._pieces import velocity_change
from trajkit.paths import Arc3, CompositePath, Line, SaddleCurve, chord_deviations
from trajkit.timing.engine import PathTiming

SWEEP = os.environ.get("TRAJKIT_SWEEP") == "1"


def test_without_limits_the_feed_is_the_core_profile():
    arc = Arc3([0.1, 0, 0], [0, 0.1, 0.02], [-0.1, 0, 0])
    plan = plan_feed(arc, 0.05, 0.4, 4.0)
    ref = plan_move(0.0, arc.length, AxisLimits(0.05, 0.4, 4.0))
    assert plan.duration == pytest.approx(ref.duration, rel=1e-14)
    t = np.linspace(-0.1, ref.duration + 0.1, 5001)
    fs = plan.sample(t)
    rs = ref.sample(t)
    assert np.allclose(fs.s, rs.position, atol=1e-14)
    assert np.allclose(fs.v, rs.velocity, atol=1e-14)
    assert np.allclose(fs.a, rs.acceleration, atol=1e-13)
    assert np.allclose(fs.points, arc.point(fs.s), atol=0)
    assert plan.profiles[0] is not None and plan.slowdowns == ()


@pytest.mark.parametrize("period", [1e-4, 1e-3, 0.01, 0.1])
def test_fixed_period_setpoints_on_the_path_at_rest_at_both_ends(period):
    arc = Arc3([0.05, 0, 0], [0, 0.05, 0], [-0.05, 0, 0], full_circle=True)
    plan = plan_feed(arc, 0.02, 0.2, 2.0)
    fs = plan.setpoints(period)
    assert np.array_equal(fs.t, np.arange(fs.t.size) * period)  # k * period, no drift
    assert fs.t[-1] >= plan.duration > fs.t[-2]
    assert fs.s[0] == 0.0 and fs.s[-1] == arc.length
    assert fs.v[0] == fs.v[-1] == 0.0 and fs.a[0] == fs.a[-1] == 0.0
    # every setpoint is the exact path point at the planned arc length
    assert np.max(np.linalg.norm(fs.points - arc.point(fs.s), axis=1)) == 0.0
    assert np.max(np.abs(np.linalg.norm(fs.points - arc.centre, axis=1) - arc.radius)) <= 1e-15
    # the tool speed between setpoints in cruise is the feed within 0.1 %
    cruise = plan.cruise_mask(fs.t[:-1]) & plan.cruise_mask(fs.t[1:])
    assert cruise.sum() >= 1
    speed = np.linalg.norm(np.diff(fs.points, axis=0), axis=1) / period
    assert np.all(np.abs(speed[cruise] - 0.02) <= 1e-3 * 0.02)


def test_setpoint_times_errors():
    with pytest.raises(InvalidInputError, match=r"period 0.2 s is outside the supported range"):
        setpoint_times(1.0, 0.2)
    with pytest.raises(InvalidInputError, match=r"period should be larger than zero, got -0.001"):
        setpoint_times(1.0, -0.001)
    with pytest.raises(InvalidInputError, match=r"period must be a number, got nan"):
        setpoint_times(1.0, math.nan)


def test_chord_error_at_the_period_slows_the_feed_and_holds_the_band():
    """Jiang (1987): too high a speed for the period leaves the path. A 20 mm
    circle at 0.5 m/s and a 10 ms period would step 5 mm (sagitta 0.16 mm);
    with a 10 um tolerance the feed drops to arc(K, E) / period."""
    K, E, dt = 0.02, 1e-5, 0.01
    circle = Arc3([K, 0, 0], [0, K, 0], [-K, 0, 0], full_circle=True)
    plan = plan_feed(circle, 0.5, 5.0, 50.0, tolerance=E, period=dt)
    assert [z.reason for z in plan.slowdowns] == [CHORD_REASON]
    v_ok = 2 * K * math.acos(1 - E / K) / dt
    assert plan.slowdowns[0].limit == pytest.approx(v_ok, rel=1e-9)
    assert plan.peak_speed == pytest.approx(v_ok, rel=1e-9)
    fs = plan.setpoints(dt)
    dev = chord_deviations(circle, np.unique(fs.s))
    assert np.max(dev) <= E * (1 + 1e-9)
    assert np.max(dev) >= 0.99 * E  # the limit is used, not wasted


def test_composite_path_stops_at_the_corner():
    p = CompositePath([Line([0, 0, 0], [0.1, 0, 0]), Line([0.1, 0, 0], [0.1, 0.05, 0])])
    plan = plan_feed(p, 0.05, 0.5, 5.0)
    d1 = plan_move(0, 0.1, AxisLimits(0.05, 0.5, 5.0)).duration
    d2 = plan_move(0, 0.05, AxisLimits(0.05, 0.5, 5.0)).duration
    assert plan.duration == pytest.approx(d1 + d2, rel=1e-13)
    fs = plan.sample([d1])
    assert fs.s[0] == pytest.approx(0.1, abs=1e-15) and abs(fs.v[0]) <= 1e-15
    assert np.allclose(plan.stops, [0.0, 0.1, 0.15])


def _random_limit(rng, L):
    """Speed-limit curve: a few dips of random depth and width."""
    centres = rng.uniform(0, L, rng.integers(1, 5))
    widths = rng.uniform(0.002, 0.2, centres.size) * L
    depths = rng.uniform(0.05, 0.95, centres.size)

    def fn(s):
        v = np.full(np.size(s), np.inf)
        why = np.zeros(np.size(s), dtype=int)
        for k, (c, w, d) in enumerate(zip(centres, widths, depths)):
            val = 0.1 * (1 - d * np.exp(-(((s - c) / w) ** 2)))
            low = val < v
            v = np.where(low, val, v)
            why = np.where(low, k, why)
        return v, why

    return fn, [f"dip {k}" for k in range(centres.size)]


@pytest.mark.parametrize("i", [35, 71, 83, 121, 159, 183])
def test_plateau_planner_ends_exactly_where_the_engine_split_a_rest_interval(i):
    """Cases of the long sweep below where the engine put a node where the
    ramp from rest ends, 3.5e-7 m from the start, and a short interval next to
    it: the short interval's settling changed that node's speed without its
    acceleration, the rest interval's jerk phase then missed it by 3.5e-6 of
    its speed, and the feed's pieces, chained from rest, ended 4e-9 of the
    length short of it. The rest interval's inner node keeps its relation."""
    rng = np.random.default_rng(70 + i)
    L = rng.uniform(0.01, 2.0)
    feed = rng.uniform(0.02, 0.3)
    A, J = (rng.uniform(0.002, 0.05), rng.uniform(0.02, 0.5)) if i % 2 else \
        (rng.uniform(0.05, 5.0), rng.uniform(0.5, 50.0))
    fn, names = _random_limit(rng, L)
    plan = plan_feed(Line([0, 0, 0], [L, 0, 0]), feed, A, J, speed_limit=fn, reasons=names)
    assert plan.motion.state[-1, 0] == pytest.approx(L, rel=1e-12, abs=1e-15)
    for prof in plan.profiles:  # each engine stretch: its pieces chained from its start
        if isinstance(prof, PathTiming):
            s = v = a = 0.0
            for d, jk in zip(np.diff(prof.t), prof.jerk):
                s, v, a = s + d * (v + d * (0.5 * a + d * jk / 6.0)), v + d * (a + 0.5 * d * jk), a + d * jk
            assert s == pytest.approx(prof.path.length, rel=1e-12)
            assert abs(v) <= 1e-12 * feed and abs(a) <= 1e-9 * A


@pytest.mark.parametrize("i", range(200 if SWEEP else 25))
def test_plateau_planner_stays_below_the_speed_limit(i):
    rng = np.random.default_rng(70 + i)
    L = rng.uniform(0.01, 2.0)
    path = Line([0, 0, 0], [L, 0, 0])
    feed = rng.uniform(0.02, 0.3)
    if i % 2:  # gentle tangential limits: speed changes longer than the plateaus,
        A = rng.uniform(0.002, 0.05)  # so plateaus get lowered and merged
        J = rng.uniform(0.02, 0.5)
    else:
        A = rng.uniform(0.05, 5.0)
        J = rng.uniform(0.5, 50.0)
    fn, names = _random_limit(rng, L)
    plan = plan_feed(path, feed, A, J, speed_limit=fn, reasons=names)
    m = plan.motion
    # the exact end state: the planned distances add up
    assert m.state[-1, 0] == pytest.approx(L, rel=1e-9, abs=1e-12)
    assert abs(m.state[-1, 1]) <= 1e-9 * feed and abs(m.state[-1, 2]) <= 1e-9 * A
    t = np.unique(np.concatenate([np.linspace(0, plan.duration, 20001), m.t]))
    fs = plan.sample(t, points=False)
    vlim, _ = fn(fs.s)
    assert np.all(fs.v <= np.minimum(vlim, feed) * (1 + 1e-9))
    assert np.all(fs.v >= -1e-12)
    assert np.max(np.abs(fs.a)) <= A * (1 + 1e-9)
    assert np.max(np.abs(fs.j)) <= J * (1 + 1e-9)
    # the engine's timings need no large uniform slow-down (at most 1.008 over the
    # 200 cases of the sweep; with two nodes an ulp apart where a cap sample met a
    # grid node, four of them were slowed down 2,500-30,000 times: case 3 took a week)
    for prof in plan.profiles:
        if isinstance(prof, PathTiming):
            assert prof.time_scale <= 1.02, (prof.time_scale, plan.duration)
    assert np.all(np.diff(fs.s) >= -1e-15)
    for z in plan.slowdowns:
        assert z.reason in names and z.speed <= z.limit * (1 + 1e-12)


def test_velocity_change_is_exact():
    for v1, v2, A, J in [(0.0, 1.0, 2.0, 10.0), (1.0, 0.2, 2.0, 100.0), (0.3, 0.31, 2.0, 10.0)]:
        pieces, dist = velocity_change(v1, v2, A, J)
        p, v, a = 0.0, v1, 0.0
        for h, j in pieces:
            p += h * (v + h * (a / 2 + h * j / 6))
            v += h * (a + h * j / 2)
            a += h * j
        assert v == pytest.approx(v2, abs=1e-14) and abs(a) <= 1e-13
        assert p == pytest.approx(dist, rel=1e-13)
        assert max(abs(a) for a in np.cumsum([h * j for h, j in pieces])) <= A * (1 + 1e-12)


def test_saddle_seam_setpoints_at_constant_feed():
    """The plain feed on a seam (no machine limits): cruise speed within 0.1 %
    measured from the setpoints, every setpoint on the seam."""
    c = SaddleCurve(0.15, 0.1)
    plan = plan_feed(c, 0.03, 0.3, 3.0, tolerance=1e-5, period=0.004)
    fs = plan.setpoints(0.004)
    assert np.max(np.abs(c.branch_residual(fs.points))) <= 1e-12
    assert np.max(np.abs(c.main_residual(fs.points))) <= 1e-12
    cruise = plan.cruise_mask(fs.t[:-1]) & plan.cruise_mask(fs.t[1:])
    speed = np.linalg.norm(np.diff(fs.points, axis=0), axis=1) / 0.004
    assert cruise.mean() > 0.8
    assert np.all(np.abs(speed[cruise] / 0.03 - 1) <= 1e-3)


@pytest.mark.parametrize(
    "kw,match",
    [
        (dict(feed=0.0), r"feed should be larger than zero, got 0.0"),
        (dict(feed=math.inf), r"feed must be finite"),
        (dict(a_max=-1.0), r"tangential acceleration a_max should be larger than zero, got -1.0"),
        (dict(j_max=math.nan), r"tangential jerk j_max must be a number"),
        (dict(tolerance=1e-5), r"tolerance and period must be given together"),
        (dict(tolerance=-1e-5, period=0.001), r"tolerance should be larger than zero, got -1e-05"),
    ],
)
def test_feed_errors(kw, match):
    args = dict(feed=0.1, a_max=1.0, j_max=10.0)
    args.update(kw)
    with pytest.raises(InvalidInputError, match=match):
        plan_feed(Line([0, 0, 0], [1, 0, 0]), **args)


def _check_plan_below(plan, fn, feed, A, J, L):
    m = plan.motion
    assert m.state[-1, 0] == pytest.approx(L, rel=1e-9, abs=1e-12)
    assert abs(m.state[-1, 1]) <= 1e-9 * feed and abs(m.state[-1, 2]) <= 1e-9 * A
    t = np.unique(np.concatenate([np.linspace(0, plan.duration, 20001), m.t]))
    fs = plan.sample(t, points=False)
    vlim, _ = fn(fs.s)
    assert np.all(fs.v <= np.minimum(vlim, feed) * (1 + 1e-9))
    assert np.max(np.abs(fs.a)) <= A * (1 + 1e-9) and np.max(np.abs(fs.j)) <= J * (1 + 1e-9)
    return fs


def test_short_fast_stretch_between_zones_is_lowered():
    """Two slow zones 5 mm apart, gentle tangential limits: the stretch between
    them cannot reach the feed, but the feed rises there (no plateau held over
    both zones), and so does the first stretch before the first zone."""
    L, feed, A, J = 0.2, 0.1, 0.02, 0.2

    def fn(s):
        dip = ((s > 0.05) & (s < 0.08)) | ((s > 0.085) & (s < 0.12))
        return np.where(dip, 0.03, np.inf), np.zeros(np.size(s), dtype=int)

    plan = plan_feed(Line([0, 0, 0], [L, 0, 0]), feed, A, J, speed_limit=fn, reasons=["dip"])
    fs = _check_plan_below(plan, fn, feed, A, J, L)
    assert [z.reason for z in plan.slowdowns] == ["dip", "dip"]
    z1, z2 = plan.slowdowns
    assert z1.s_end < 0.08 + 1e-3 and z2.s_start > 0.085 - 1e-3
    gap = (fs.s > 0.08) & (fs.s < 0.085)
    vp = float(np.max(fs.v[gap]))
    assert 0.03 < vp < feed
    first = fs.s < 0.05
    v1 = float(np.max(fs.v[first]))
    assert 0.03 < v1 < feed
    # inside the zones the feed runs at their limit
    inside = (fs.s > 0.06) & (fs.s < 0.07)
    assert fs.v[inside].min() == pytest.approx(0.03, rel=3e-3)


def test_stretch_too_short_for_its_speed_change():
    """A 0.2 mm stretch between a 0.01 m/s zone and a 0.03 m/s zone cannot even
    hold the change from 0.01 to 0.03 m/s: the speed change runs on inside the
    faster zone (below its limit), and both zones are reported with their reasons."""
    L, feed, A, J = 0.3, 0.1, 0.02, 0.2

    def fn(s):
        v = np.where((s > 0.05) & (s < 0.08), 0.01, np.inf)
        v = np.where((s > 0.0802) & (s < 0.2), 0.03, v)
        return v, np.where(v == 0.01, 0, 1)

    plan = plan_feed(Line([0, 0, 0], [L, 0, 0]), feed, A, J, speed_limit=fn, reasons=["slow", "medium"])
    fs = _check_plan_below(plan, fn, feed, A, J, L)
    z1, z2 = plan.slowdowns[:2]
    assert (z1.reason, z2.reason) == ("slow", "medium")
    at_gap_end = np.interp(0.0802, fs.s, fs.v)
    assert 0.01 <= at_gap_end < 0.03
    assert fs.v[(fs.s > 0.15) & (fs.s < 0.19)].min() == pytest.approx(0.03, rel=3e-3)
