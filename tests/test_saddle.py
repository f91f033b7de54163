"""Saddle curves (Chen et al., 2013): exact implicit equations, arc length with a tested
error bound, machine-axis derivatives, and the saddle machine's axis limits."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
from scipy.integrate import quad

from trajkit import AxisLimits
from trajkit.errors import InvalidInputError
from trajkit.interpolation import SaddleMachine, plan_saddle
from trajkit.interpolation.machine import axis_states, check_axes, check_times
from trajkit.paths import SaddleCurve, chord_deviations
from trajkit.paths._tolerances import SADDLE_LENGTH_RTOL

SWEEP = os.environ.get("TRAJKIT_SWEEP") == "1"
RNG = np.random.default_rng(3)


def random_curve(rng, near_touch=False):
    R = rng.uniform(0.02, 2.0)
    r = R * (rng.uniform(0.9, 0.995) if near_touch else rng.uniform(0.05, 0.95))
    d = rng.uniform(-1, 1) * (R - r) * 0.95
    ang = math.radians(rng.uniform(20, 160))
    return SaddleCurve(R, r, ang, d, theta_start=rng.uniform(-math.pi, math.pi))


def test_orthogonal_seam_is_the_seed_equation():
    R, r = 0.3, 0.1
    c = SaddleCurve(R, r)
    th = np.linspace(0, 2 * math.pi, 721)
    expect = np.column_stack([r * np.sin(th), r * np.cos(th), np.sqrt(R**2 - r**2 * np.sin(th) ** 2)])
    assert np.allclose(c.point_theta(th), expect, atol=1e-16, rtol=0)
    assert np.allclose(c.point(0.0), [0.0, r, R])  # top of the main pipe, on the main axis plane
    assert np.allclose(c.point(c.length), c.point(0.0), atol=1e-15)  # closed


@pytest.mark.parametrize("i", range(400 if SWEEP else 60))
def test_points_lie_on_both_cylinders(i):
    rng = np.random.default_rng(1000 + i)
    c = random_curve(rng, near_touch=(i % 5 == 0))
    s = np.linspace(0.0, c.length, 997)
    p = c.point(s)
    scale = c.main_radius
    assert np.max(np.abs(c.branch_residual(p))) <= 1e-9 * scale
    assert np.max(np.abs(c.main_residual(p))) <= 1e-9 * scale
    # independent form of the main cylinder: |(p - a) x m| = R
    rel = p - c.main_axis_point
    dist = np.linalg.norm(np.cross(rel, c.main_axis_direction), axis=1)
    assert np.max(np.abs(dist - c.main_radius)) <= 1e-9 * scale


@pytest.mark.filterwarnings("ignore::scipy.integrate.IntegrationWarning")  # the reference's own round-off
@pytest.mark.parametrize("i", range(60 if SWEEP else 12))
def test_arc_length_meets_its_stated_bound(i):
    rng = np.random.default_rng(2000 + i)
    c = random_curve(rng, near_touch=(i % 3 == 0))
    ref, err = quad(lambda t: float(c.speed_theta(t)), c.theta_start, c.theta_start + 2 * math.pi,
                    epsabs=0.0, epsrel=2e-14, limit=1000)
    assert abs(c.length - ref) <= SADDLE_LENGTH_RTOL * ref + err
    # partial lengths, and the inverse map
    th = c.theta_start + np.sort(rng.uniform(0, 2 * math.pi, 5))
    for t in th:
        ref_t, err_t = quad(lambda x: float(c.speed_theta(x)), c.theta_start, t, epsabs=0.0,
                            epsrel=2e-14, limit=1000)
        assert abs(c.s_of_theta([t])[0] - ref_t) <= SADDLE_LENGTH_RTOL * c.length + err_t
    s = np.linspace(0, c.length, 2001)
    assert np.max(np.abs(c.s_of_theta(c.theta_of_s(s)) - s)) <= 1e-13 * c.length


def test_arc_length_agrees_with_richardson_extrapolated_polylines():
    """Second, independent computation: inscribed polylines converge as h^2;
    Richardson extrapolation of two of them gives an O(h^4) estimate."""
    c = SaddleCurve(0.25, 0.2, math.radians(60), 0.03)
    th = lambda n: c.theta_start + np.linspace(0, 2 * math.pi, n + 1)  # noqa: E731
    L1 = np.sum(np.linalg.norm(np.diff(c.point_theta(th(20000)), axis=0), axis=1))
    L2 = np.sum(np.linalg.norm(np.diff(c.point_theta(th(40000)), axis=0), axis=1))
    rich = (4 * L2 - L1) / 3
    assert abs(rich - c.length) <= 1e-11 * c.length
    assert L2 < c.length  # an inscribed polyline is shorter


def test_tangent_curvature_and_axis_derivatives_match_finite_differences():
    c = SaddleCurve(0.2, 0.15, math.radians(70), -0.02)
    s = np.linspace(0.01, c.length - 0.01, 40)
    h = 1e-5
    d1 = (c.point(s + h) - c.point(s - h)) / (2 * h)
    d2 = (c.point(s + h) - 2 * c.point(s) + c.point(s - h)) / h**2
    assert np.allclose(d1, c.tangent(s), atol=1e-8)
    assert np.allclose(np.linalg.norm(d2, axis=1), c.curvature(s), rtol=1e-3)
    q = c.machine_axes(s)
    qp, qm = c.machine_axes(s + h), c.machine_axes(s - h)
    for order in range(3):  # derivative k+1 from differences of the exact derivative k
        fd = (qp[:, order] - qm[:, order]) / (2 * h)
        assert np.allclose(fd, q[:, order + 1], rtol=1e-6, atol=1e-6 * np.max(np.abs(q[:, order + 1])))
    # the torch stays on the branch radius: theta and Z rebuild the point
    r = c.branch_radius
    p = np.column_stack([r * np.sin(q[0, 0]), r * np.cos(q[0, 0]), q[1, 0]])
    assert np.allclose(p, c.point(s), atol=1e-15)


@pytest.mark.parametrize(
    "kw,match",
    [
        (dict(main_radius=0.1, branch_radius=0.2), r"r=0.2 plus \|offset\|=0.0 must be below the main radius R=0.1"),
        (dict(main_radius=0.1, branch_radius=0.1), r"do not meet all the way round"),
        (dict(main_radius=0.3, branch_radius=0.2, offset=-0.15),
         r"r=0.2 plus \|offset\|=0.15 must be below the main radius R=0.3"),
        (dict(main_radius=0.3, branch_radius=0.1, angle=0.0), r"branch angle must lie strictly between 0 and 180 deg, got 0.0"),
        (dict(main_radius=0.3, branch_radius=0.1, angle=math.pi), r"got 180.0 deg"),
        (dict(main_radius=-0.3, branch_radius=0.1), r"main pipe radius R should be larger than zero, got -0.3"),
        (dict(main_radius=0.3, branch_radius=math.nan), r"branch pipe radius r must be a number"),
        (dict(main_radius=0.3, branch_radius=0.1, offset=math.inf), r"branch offset must be finite"),
    ],
)
def test_pipes_that_cannot_meet_are_invalid(kw, match):
    with pytest.raises(InvalidInputError, match=match):
        SaddleCurve(**kw)


# ------------------------------------------------------------- the machine
def machine(rng):
    return SaddleMachine(
        AxisLimits(rng.uniform(0.5, 3.0), rng.uniform(2, 20), rng.uniform(20, 200), name="theta"),
        AxisLimits(rng.uniform(0.02, 0.2), rng.uniform(0.2, 2.0), rng.uniform(2, 20), name="z_axis"),
    )


def _fd_peaks(x, dt):
    v = np.diff(x, axis=-1) / dt
    a = np.diff(x, 2, axis=-1) / dt**2
    j = np.diff(x, 3, axis=-1) / dt**3
    return np.stack([np.max(np.abs(v), axis=-1), np.max(np.abs(a), axis=-1), np.max(np.abs(j), axis=-1)], axis=-1)


@pytest.mark.parametrize("i", range(30 if SWEEP else 5))
def test_saddle_plan_holds_every_axis_limit(i):
    rng = np.random.default_rng(500 + i)
    R = rng.uniform(0.05, 0.4)
    r = R * rng.uniform(0.3, 0.95)
    c = SaddleCurve(R, r, math.radians(rng.uniform(30, 150)), rng.uniform(-1, 1) * (R - r) * 0.9)
    m = machine(rng)
    feed = rng.uniform(0.02, 0.3)
    tol = rng.uniform(5e-6, 1e-4)
    dt = float(rng.choice([0.002, 0.005, 0.01]))
    plan = plan_saddle(c, feed, 1.0, 10.0, m, tol, dt)
    lim = m.limits_array()
    # 1. the planner's own check (analytic values at every piece boundary and 8 points per period)
    assert plan.check.ok
    # 2. an independent, finer reference grid (up to 40 points per period)
    t = np.linspace(0, plan.duration, min(int(plan.duration / dt) * 40 + 2, 80_001))
    st = plan.axes(t)
    peaks = np.max(np.abs(st[:, 1:]), axis=2)
    assert np.all(peaks <= lim * (1 + 1e-9)), (peaks / lim)
    # 3. finite differences of the setpoints at the period are weighted means
    #    of the exact derivative (positive B-spline kernels): bounded by the limits too
    fs, ax = plan.setpoints(dt)
    assert np.all(_fd_peaks(ax[:, 0], dt) <= lim * (1 + 1e-6))
    # start and end at rest, the whole seam covered
    assert fs.s[0] == 0.0 and fs.s[-1] == c.length
    assert fs.v[0] == 0.0 and fs.v[-1] == 0.0
    assert np.all(np.abs(ax[:, 1:3, [0, -1]]) <= 1e-12)  # v = a = 0 (jerk may start at once)
    assert np.all(np.diff(fs.s) >= 0)
    # never faster than the feed; chords between setpoints within the tolerance
    assert np.max(fs.v) <= feed * (1 + 1e-12)
    s_nodes = np.unique(fs.s)
    assert np.max(chord_deviations(c, s_nodes)) <= tol * (1 + 1e-9)
    # each slowdown names an axis quantity (or the chord error); a velocity or chord
    # limit bounds the speed itself (an acceleration or jerk "limit" is the speed
    # that reaches the axis limit at constant speed: the path's own acceleration
    # may offset the axis' part from the curvature, so the speed may pass it while
    # the axis keeps its limit, checked above)
    for z in plan.slowdowns:
        assert z.speed < feed
        if z.reason.endswith("velocity") or z.reason.startswith("chord"):
            assert z.speed <= z.limit * (1 + 1e-12)
        assert z.reason.split()[0] in ("theta", "z_axis", "chord")


def test_theta_speed_limit_slows_the_whole_seam_and_reports_it():
    """A rotary axis too slow for the feed: ds/dt = sigma dtheta/dt with
    sigma = ds/dtheta >= r, so the speed is limited to omega_max * min(sigma)."""
    c = SaddleCurve(0.2, 0.1)
    w = math.radians(30)
    m = SaddleMachine(AxisLimits(w, 100.0, 10000.0), AxisLimits(1.0, 100.0, 10000.0))
    plan = plan_saddle(c, 0.1, 1.0, 10.0, m, 1e-4, 0.01)
    assert len(plan.slowdowns) == 1
    z = plan.slowdowns[0]
    assert z.reason == "theta velocity"
    assert z.s_start == 0.0 and z.s_end == pytest.approx(c.length)
    sig = c.speed_theta(np.linspace(0, 2 * math.pi, 100001))
    # the planned speed where the limit binds: the theta limit over the seam (within
    # the engine's grid resolution), and never above it
    assert w * sig.min() * (1 - 1e-3) <= z.speed <= w * sig.min() * (1 + 1e-9)
    rep = plan.report()[0]
    assert rep["theta_start_deg"] == 0.0 and rep["theta_end_deg"] == pytest.approx(360.0)


def test_z_axis_velocity_slowdown_is_local_and_smooth():
    """R close to r: Z moves fast on the flanks (four symmetric stretches around
    the angles where |dZ/ds| peaks); only there the feed drops."""
    c = SaddleCurve(0.11, 0.1)
    m = SaddleMachine(AxisLimits(10.0, 1000.0, 1e5), AxisLimits(0.05, 5.0, 500.0))
    plan = plan_saddle(c, 0.1, 1.0, 20.0, m, 1e-4, 0.005)
    assert {z.reason for z in plan.slowdowns} == {"z_axis velocity"}
    rep = plan.report()
    assert len(rep) == 4
    mids = [(r["theta_start_deg"] + r["theta_end_deg"]) / 2 for r in rep]
    assert mids[0] + mids[1] == pytest.approx(180.0, abs=1e-6)  # mirror symmetry about 90 deg
    assert mids[2] + mids[3] == pytest.approx(540.0, abs=1e-6)
    # the angle where |dZ/ds| peaks lies inside the first stretch, and the
    # speed there is the Z limit over that peak
    th = np.linspace(0, math.pi / 2, 200001)
    z = c.z_derivatives(th)
    dzds = np.abs(z[1]) / c.speed_theta(th)
    k = int(np.argmax(dzds))
    assert rep[0]["theta_start_deg"] < math.degrees(th[k]) < rep[0]["theta_end_deg"]
    # the planned speed there (the report reads it at the grid nodes: within 1 %)
    assert plan.slowdowns[0].speed == pytest.approx(0.05 / dzds[k], rel=1e-2)
    # smooth: tangential acceleration and jerk bounded; the cruise runs at the feed
    t = np.linspace(0, plan.duration, 20001)
    fs = plan.feed_plan.sample(t, points=False)
    assert np.max(np.abs(fs.a)) <= plan.feed_plan.a_max * (1 + 1e-9)
    assert np.max(np.abs(fs.j)) <= plan.feed_plan.j_max * (1 + 1e-9)
    assert np.max(fs.v) == pytest.approx(0.1, rel=1e-9)


def test_saddle_plan_input_errors():
    c = SaddleCurve(0.2, 0.1)
    m = SaddleMachine(AxisLimits(1.0, 10.0, 100.0), AxisLimits(0.1, 1.0, 10.0))
    with pytest.raises(InvalidInputError, match=r"feed should be larger than zero, got -1.0"):
        plan_saddle(c, -1.0, 1.0, 10.0, m, 1e-4, 0.01)
    with pytest.raises(InvalidInputError, match=r"tolerance must be finite"):
        plan_saddle(c, 0.1, 1.0, 10.0, m, math.inf, 0.01)
    with pytest.raises(InvalidInputError, match=r"period 0.5 s is outside the supported range \[0.0001, 0.1\] s"):
        plan_saddle(c, 0.1, 1.0, 10.0, m, 1e-4, 0.5)
    with pytest.raises(InvalidInputError, match=r"period 5e-05 s is outside"):
        plan_saddle(c, 0.1, 1.0, 10.0, m, 1e-4, 5e-5)
    with pytest.raises(InvalidInputError, match=r"machine must be a SaddleMachine"):
        plan_saddle(c, 0.1, 1.0, 10.0, None, 1e-4, 0.01)


def test_axis_states_chain_rule_matches_finite_differences_in_time():
    c = SaddleCurve(0.15, 0.12, math.radians(75), 0.01)
    m = SaddleMachine(AxisLimits(2.0, 20.0, 200.0), AxisLimits(0.08, 1.0, 10.0))
    plan = plan_saddle(c, 0.08, 0.5, 5.0, m, 5e-5, 0.002)
    t = np.linspace(0.3, plan.duration - 0.3, 30)
    h = 1e-5
    st = plan.axes(t)
    for order in range(3):
        fd = (plan.axes(t + h)[:, order] - plan.axes(t - h)[:, order]) / (2 * h)
        scale = np.max(np.abs(st[:, order + 1]), axis=1, keepdims=True)
        assert np.all(np.abs(fd - st[:, order + 1]) <= 1e-4 * scale + 1e-9)


def test_compiled_arc_length_inversion_equals_the_numpy_steps(monkeypatch):
    """theta(s) by the compiled Newton loop and by the numpy one: the same angles to
    a few ulps, on the four benchmark seams (offset and oblique ones included)."""
    from trajkit.paths import _saddle_jit

    rng = np.random.default_rng(3)
    for R, r, ang, off in ((0.11, 0.1, 90, 0.0), (0.2, 0.1, 90, 0.0), (0.15, 0.1, 60, 0.0),
                           (0.16, 0.1, 90, 0.04)):
        curve = SaddleCurve(R, r, math.radians(ang), off)
        s = np.concatenate([[0.0, curve.length], rng.uniform(0.0, curve.length, 3000)])
        got = curve.theta_of_s(s)
        monkeypatch.setattr(_saddle_jit, "AVAILABLE", False)
        ref = curve.theta_of_s(s)
        monkeypatch.setattr(_saddle_jit, "AVAILABLE", True)
        assert np.abs(got - ref).max() <= 8 * np.spacing(2 * math.pi)
        np.testing.assert_allclose(curve.s_of_theta(got), s, rtol=0, atol=1e-12)


def _reference_theta(curve, s):
    """theta at arc length s by scipy: adaptive quadrature of an independent scalar
    ds/dtheta, root by brentq; returns (theta, the quadrature's error estimate [m])."""
    from scipy.optimize import brentq

    r, R, d, a = curve.branch_radius, curve.main_radius, curve.offset, curve.angle

    def speed(t):
        w = r * math.sin(t) - d
        z1 = -r * math.cos(a) / math.sin(a) * math.sin(t) - w * r * math.cos(t) / (math.sqrt(R * R - w * w) * math.sin(a))
        return math.sqrt(r * r + z1 * z1)

    th0 = curve.theta_start
    err = [0.0]

    def f(t):
        v, e = quad(speed, th0, t, epsabs=0.0, epsrel=2e-14, limit=200)
        err[0] = max(err[0], e)
        return v - s

    lo, hi = th0, th0 + 2 * math.pi
    if s <= 0.0:
        return lo, 0.0
    th = brentq(f, lo, hi, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200)
    return th, err[0]


@pytest.mark.filterwarnings("ignore::scipy.integrate.IntegrationWarning")  # the reference's own round-off
@pytest.mark.parametrize("args", [(0.11, 0.1, 90, 0.0, 0.0), (0.16, 0.1, 90, 0.04, 0.0), (0.15, 0.1, 60, 0.0, 1.0),
                                  (1.0, 0.99999, 90, 0.0, -0.5), (0.05, 0.0025, 23, 0.01, -3.0)])
def test_theta_of_s_meets_its_residual_and_matches_an_independent_inversion(args):
    """theta(s): s(theta(s)) = s within the documented tolerance (ARC_INVERSION_RTOL of the
    length), and theta within the arc length's stated bound of a scipy quad + brentq
    inversion; the same angles in any order of s; s = 0, length and the table nodes exact."""
    from trajkit.paths._tolerances import ARC_INVERSION_RTOL

    R, r, ang, off, th0 = args
    c = SaddleCurve(R, r, math.radians(ang), off, th0)
    rng = np.random.default_rng(11)
    s = np.concatenate([[0.0, c.length], rng.uniform(0.0, c.length, 20000)])
    th = c.theta_of_s(s)
    ulp = np.spacing(abs(c.theta_start) + 2 * math.pi)
    assert th[0] == c.theta_start
    assert abs(th[1] - (c.theta_start + 2 * math.pi)) <= 4 * ulp
    assert np.all((th >= c.theta_start) & (th <= c.theta_start + 2 * math.pi))
    assert np.max(np.abs(c.s_of_theta(th) - s)) <= ARC_INVERSION_RTOL * c.length
    # the same angles in any order (the points are independent)
    perm = rng.permutation(s.size)
    assert np.max(np.abs(c.theta_of_s(s[perm]) - th[perm])) <= 4 * ulp
    # at the table nodes: the table's angles
    nodes = c.s_of_theta(c.theta_start + np.linspace(0.0, 2 * math.pi, 65))
    np.testing.assert_allclose(c.theta_of_s(nodes), c.theta_start + np.linspace(0.0, 2 * math.pi, 65),
                               rtol=0, atol=8 * ulp)
    # independent reference: |dtheta| <= (stated bound of s(theta) + quad's error) / min speed (>= r)
    for k in range(2, 22):
        ref, err = _reference_theta(c, float(s[k]))
        assert abs(th[k] - ref) <= (SADDLE_LENGTH_RTOL * c.length + err) / r + 4 * ulp, (k, th[k] - ref)


def test_theta_of_s_series_agrees_with_the_quadrature_newton():
    """Newton on each table interval's Chebyshev series gives the angles of Newton on the
    Gauss-Legendre quadrature (every interval forced back to it) to a few ulps, on the four
    benchmark seams and a near-touching one (where some intervals keep the quadrature)."""
    rng = np.random.default_rng(5)
    for R, r, ang, off in ((0.11, 0.1, 90, 0.0), (0.2, 0.1, 90, 0.0), (0.15, 0.1, 60, 0.0),
                           (0.16, 0.1, 90, 0.04), (1.0, 0.5, 57.3, 0.499999)):
        c = SaddleCurve(R, r, math.radians(ang), off)
        s = np.concatenate([[0.0, c.length], rng.uniform(0.0, c.length, 5000)])
        got = c.theta_of_s(s)
        fitted = int(np.sum(c._deg >= 0))
        assert fitted >= 0.8 * c._deg.size  # the series are the rule, the quadrature the exception
        c._deg = np.full_like(c._deg, -1)
        ref = c.theta_of_s(s)
        assert np.abs(got - ref).max() <= 4 * np.spacing(2 * math.pi)


BENCH_SEAMS = ((0.11, 0.1, 90, 0.0, 0.0), (0.2, 0.1, 90, 0.0, 0.0), (0.15, 0.1, 60, 0.0, 0.0),
               (0.16, 0.1, 90, 0.04, 0.0), (0.3, 0.2, 120, -0.05, 2.0))


def _bench_plan(R, r, ang, off, th0):
    d2r = math.pi / 180
    m = SaddleMachine(AxisLimits(180 * d2r, 720 * d2r, 7200 * d2r, name="theta"),
                      AxisLimits(0.04, 1.0, 10.0, name="z_axis"))
    c = SaddleCurve(R, r, math.radians(ang), off, th0)
    return plan_saddle(c, 0.05, 0.5, 5.0, m, 1e-5, 0.001)


def _reference_peaks(curve, fp, t):
    """The straightforward check: every axis state at the times t, then the largest magnitudes (2, 3)."""
    st = axis_states(curve, fp.sample(t, points=False))
    return np.max(np.abs(st[:, 1:]), axis=2)


@pytest.mark.parametrize("seam", BENCH_SEAMS)
def test_axis_check_peaks_equal_the_axis_states_on_the_check_times(seam):
    """check_axes (one pass with the compiled kernels) checks exactly the times of check_times
    (the grid, every piece boundary and the float before it, no repeats) and finds the peaks of
    axis_states there to a few ulps, at the planning period, a coarse one (the 1000-point floor)
    and a fine one."""
    plan = _bench_plan(*seam)
    c, fp, m = plan.curve, plan.feed_plan, plan.machine
    for period in (0.001, 0.1, 0.0001):
        chk = check_axes(c, fp, m, period)
        t = check_times(fp, period)
        assert np.all(np.diff(t) > 0)
        assert set(fp.motion.t) <= set(t)
        assert set(np.nextafter(fp.motion.t[1:], -np.inf)) <= set(t)
        assert chk.n_points == t.size
        ref = _reference_peaks(c, fp, t)
        assert np.all(np.abs(chk.peaks - ref) <= 4 * np.spacing(ref)), (chk.peaks - ref) / np.spacing(ref)
        np.testing.assert_array_equal(chk.ratio, chk.peaks / m.limits_array())
    assert plan.check.n_points == check_times(fp, 0.001).size


@pytest.mark.parametrize("seam", BENCH_SEAMS[::2])
def test_one_pass_axis_kernel_matches_axis_states(seam):
    """The one-pass kernel itself (compiled, or its Python source under TRAJKIT_NO_JIT) on small
    lists with repeats and times outside the motion (the start and the end at rest): the
    distinct times counted, the peaks of axis_states there to a few ulps; an unsorted list is
    refused (-1)."""
    from trajkit.interpolation.machine import _check_lists
    from trajkit.paths import _saddle_jit

    plan = _bench_plan(*seam)
    c, fp = plan.curve, plan.feed_plan
    mo = fp.motion
    T = fp.duration
    _, bounds = _check_lists(fp, 0.001)
    rng = np.random.default_rng(17)
    grid = np.sort(np.concatenate([np.linspace(-0.05, T + 0.05, 301), rng.choice(bounds, 20),
                                   rng.uniform(0.0, T, 200)]))
    st = mo.state[:-1]

    def run(g, b):
        peaks = np.full((2, 3), np.nan)
        n = _saddle_jit.axis_peaks(g, b, mo.t, st[:, 0].copy(), st[:, 1].copy(), st[:, 2].copy(), mo.jerk,
                                   mo.s0, mo.s_end, c.length, *c._inversion_args(), c.branch_radius ** 2, peaks)
        return n, peaks

    n, peaks = run(grid, bounds)
    t = np.unique(np.concatenate([grid, bounds]))
    assert n == t.size
    ref = _reference_peaks(c, fp, t)
    assert np.all(np.abs(peaks - ref) <= 4 * np.spacing(ref)), (peaks - ref) / np.spacing(ref)
    assert run(grid[::-1].copy(), bounds)[0] == -1
