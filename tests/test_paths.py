"""Lines, 3-point arcs and composite paths: exact geometry and input errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from trajkit.errors import InvalidInputError
from trajkit.paths import Arc3, CompositePath, Line, circle_through

RNG = np.random.default_rng(7)


def _random_arc_points(rng):
    centre = rng.uniform(-1, 1, 3)
    radius = rng.uniform(0.01, 2.0)
    n = rng.normal(size=3)
    n /= np.linalg.norm(n)
    u = np.cross(n, rng.normal(size=3))
    u /= np.linalg.norm(u)
    w = np.cross(n, u)
    ang = np.sort(rng.uniform(0.05, 2 * math.pi - 0.05, 2))
    if ang[1] - ang[0] < 0.02:
        ang[1] = ang[0] + 0.02
    pts = [centre + radius * (math.cos(a) * u + math.sin(a) * w) for a in (0.0, *ang)]
    return centre, radius, n, ang[1], pts


def test_line_is_exact():
    ln = Line([1.0, 2.0, 3.0], [4.0, 6.0, 3.0])
    assert ln.length == 5.0
    s = np.linspace(0, 5, 11)
    assert np.allclose(ln.point(s), [1, 2, 3] + s[:, None] * np.array([0.6, 0.8, 0.0]), atol=1e-15)
    assert np.array_equal(ln.point(5.0), [4.0, 6.0, 3.0])
    assert np.allclose(ln.tangent(s), [0.6, 0.8, 0.0], atol=1e-16)
    assert np.all(ln.curvature(s) == 0.0)
    assert ln.point(2.5).shape == (3,) and ln.curvature(1.0) == 0.0


def test_arc_passes_exactly_through_its_three_points_random():
    for _ in range(300):
        centre, radius, normal, sweep, pts = _random_arc_points(RNG)
        arc = Arc3(*pts)
        assert np.allclose(arc.centre, centre, atol=1e-9 * max(1, radius))
        assert arc.radius == pytest.approx(radius, rel=1e-9)
        assert np.allclose(arc.normal, normal, atol=1e-9)
        assert arc.sweep == pytest.approx(sweep, rel=1e-9)
        assert np.linalg.norm(arc.point(0.0) - pts[0]) <= 1e-12 * max(1, radius)
        assert np.linalg.norm(arc.point(arc.length) - pts[2]) <= 1e-9 * max(1, radius)
        # the via point lies on the arc, before the end
        s2 = radius * math.atan2(np.dot(pts[1] - arc.centre, arc.w), np.dot(pts[1] - arc.centre, arc.u)) % (
            2 * math.pi * radius)
        assert 0 < s2 < arc.length
        assert np.linalg.norm(arc.point(s2) - pts[1]) <= 1e-9 * max(1, radius)


def test_arc_centre_matches_jiang1987_linear_system():
    """Independent computation: the centre solves the seed's 3x3 system
    (plane through the points; equal distances to p1, p2 and p3) by Cramer's rule."""
    for _ in range(100):
        _, _, _, _, (a, b, c) = _random_arc_points(RNG)
        n = np.cross(b - a, c - a)
        M = np.array([n, 2 * (b - a), 2 * (c - a)])
        rhs = np.array([n @ a, b @ b - a @ a, c @ c - a @ a])
        det = np.linalg.det(M)
        cram = np.array([np.linalg.det(np.column_stack([rhs if k == i else M[:, k] for k in range(3)]))
                         for i in range(3)]) / det
        centre, radius, _ = circle_through(a, b, c)
        assert np.allclose(centre, cram, atol=1e-8 * (1 + radius))


def test_arc_tangent_and_curvature_are_derivatives_of_the_point():
    arc = Arc3([1.0, 0.0, 0.0], [0.0, 1.0, 0.5], [-1.0, 0.2, 0.0])
    s = np.linspace(0.01, arc.length - 0.01, 50)
    h = 1e-5
    d1 = (arc.point(s + h) - arc.point(s - h)) / (2 * h)
    d2 = (arc.point(s + h) - 2 * arc.point(s) + arc.point(s - h)) / h**2
    assert np.allclose(d1, arc.tangent(s), atol=1e-9)
    assert np.allclose(np.linalg.norm(d2, axis=1), arc.curvature(s), rtol=1e-4)
    assert np.allclose(np.linalg.norm(arc.tangent(s), axis=1), 1.0, atol=1e-15)


def test_full_circle_closes_and_passes_through_all_points():
    pts = [[2.0, 0.0, 1.0], [0.0, 2.0, 1.0], [-2.0, 0.0, 1.0]]
    c = Arc3(*pts, full_circle=True)
    assert c.closed and c.sweep == 2 * math.pi
    assert c.length == pytest.approx(4 * math.pi, rel=1e-15)
    assert np.allclose(c.point(c.length), pts[0], atol=1e-15)
    assert np.allclose(c.point(c.length / 4), pts[1], atol=1e-15)
    assert np.allclose(c.point(c.length / 2), pts[2], atol=1e-15)
    half = Arc3(*pts)
    assert half.length == pytest.approx(2 * math.pi, rel=1e-15)


def test_arc_direction_follows_the_via_point():
    # the same end points, via point on the other side: the complementary arc
    a = Arc3([1, 0, 0], [0, 1, 0], [0, -1, 0])
    b = Arc3([1, 0, 0], [math.sqrt(0.5), -math.sqrt(0.5), 0], [0, -1, 0])
    assert a.sweep == pytest.approx(1.5 * math.pi, rel=1e-12)
    assert b.sweep == pytest.approx(0.5 * math.pi, rel=1e-12)


def test_composite_path_concatenates_and_finds_corners():
    l1 = Line([0, 0, 0], [1, 0, 0])
    arc = Arc3([1, 0, 0], [1 + math.sqrt(0.5), 1 - math.sqrt(0.5), 0], [2, 1, 0])  # tangent to l1
    l2 = Line([2, 1, 0], [2, 3, 0])  # tangent to the arc end
    l3 = Line([2, 3, 0], [0, 3, 0])  # corner of 90 deg
    p = CompositePath([l1, arc, l2, l3])
    assert p.length == pytest.approx(1 + math.pi / 2 + 2 + 2, rel=1e-15)
    assert np.allclose(p.corners(), [1 + math.pi / 2 + 2])
    s = np.linspace(0, p.length, 1001)
    pts = p.point(s)
    assert np.all(np.linalg.norm(np.diff(pts, axis=0), axis=1) <= np.diff(s) * (1 + 1e-12))
    assert np.allclose(p.point(1.0 + 1e-12), [1, 0, 0], atol=1e-11)
    assert p.curvature(1.5) == pytest.approx(1.0)
    assert np.allclose(p.end_point, [0, 3, 0], atol=1e-15)


@pytest.mark.parametrize(
    "args,match",
    [
        (([1, 2, 3], [1, 2, 3]), r"line has zero length: p0=\[1.0, 2.0, 3.0\]"),
        (([0, 0, math.nan], [1, 0, 0]), r"line start p0\[2\] must be finite"),
    ],
)
def test_line_errors(args, match):
    with pytest.raises(InvalidInputError, match=match):
        Line(*args)


@pytest.mark.parametrize(
    "pts,match",
    [
        (([0, 0, 0], [1, 1, 1], [2, 2, 2]), r"collinear"),
        (([0, 0, 0], [0, 0, 0], [2, 2, 0]), r"p1=\[0.0, 0.0, 0.0\] and p2=\[0.0, 0.0, 0.0\] coincide"),
        (([0, 0, 0], [1, 0, 0], [1, 0, 0]), r"p2=.* and p3=.* coincide"),
        (([0, 0, 0], [1, 0, 0], [0, 0, 0]), r"p1=.* and p3=.* coincide"),
        (([0, 0, 0], [1, 0, 0], [0, math.inf, 0]), r"arc point p3\[1\] must be finite"),
    ],
)
def test_arc_errors(pts, match):
    with pytest.raises(InvalidInputError, match=match):
        Arc3(*pts)


def test_composite_and_argument_errors():
    with pytest.raises(InvalidInputError, match="segment 1 starts 1 m away from the end of segment 0"):
        CompositePath([Line([0, 0, 0], [1, 0, 0]), Line([2, 0, 0], [3, 0, 0])])
    with pytest.raises(InvalidInputError, match="at least one segment"):
        CompositePath([])
    ln = Line([0, 0, 0], [1, 0, 0])
    with pytest.raises(InvalidInputError, match=r"arc length s=1.5 is outside the path \[0, 1.0\] m"):
        ln.point([0.5, 1.5])
    with pytest.raises(InvalidInputError, match=r"arc length s=-0.1 is outside"):
        ln.tangent(-0.1)


def test_corner_angle_threshold():
    l1 = Line([0, 0, 0], [1, 0, 0])
    kink = 1e-4  # rad
    l2 = Line([1, 0, 0], [2, math.tan(kink), 0])
    assert CompositePath([l1, l2]).corners().size == 1  # default: 1e-6 rad
    assert CompositePath([l1, l2], corner_angle=2e-4).corners().size == 0
    assert CompositePath([l1, l2], corner_angle=0.5e-4).corners().size == 1
    with pytest.raises(InvalidInputError, match=r"corner_angle must lie in \[0, pi\) rad, got -1"):
        CompositePath([l1, l2], corner_angle=-1)
