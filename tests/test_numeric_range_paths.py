"""Supported numeric range of the path geometry, proved by a fuzz sweep over exponents.

Coordinates within +-1e6 m, lengths and radii in [1e-9, 2e6] m
(:mod:`trajkit.paths._tolerances`). Inputs are drawn with magnitudes 10^e,
e in -300..300: every construction either refuses with an InvalidInputError
that names the field, or returns geometry that is finite and exact (points on
the circle / on both pipes, unit tangents, length consistent with the ends).
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from conftest import sweep_size

from trajkit.errors import InvalidInputError
from trajkit.paths import Arc3, Line, SaddleCurve, discretize
from trajkit.paths._tolerances import MAX_COORDINATE, MIN_FEATURE

N = sweep_size(600)


def _mag(rng, size=None):
    return 10.0 ** rng.uniform(-300, 300, size) * rng.choice([-1.0, 1.0], size)


def _check_path(path, scale):
    s = np.linspace(0.0, path.length, 33)
    pts, tan = path.point(s), path.tangent(s)
    assert np.isfinite(path.length) and path.length >= MIN_FEATURE
    assert np.isfinite(pts).all() and np.isfinite(tan).all()
    np.testing.assert_allclose(np.linalg.norm(tan, axis=1), 1.0, atol=1e-9)
    # the chord between neighbouring samples never exceeds the arc between them
    chord = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    assert (chord <= np.diff(s) * (1 + 1e-9) + 1e-15 * scale).all()


def test_lines_over_all_exponents():
    rng = np.random.default_rng(11)
    accepted = refused = 0
    for _ in range(N):
        p0 = _mag(rng, 3) if rng.random() < 0.5 else rng.uniform(-1, 1, 3)
        p1 = p0 + _mag(rng, 3) * (rng.random() < 0.5) + rng.uniform(-1, 1, 3) * 10.0 ** rng.uniform(-12, 6)
        try:
            ln = Line(p0, p1)
        except InvalidInputError as exc:
            assert re.search(r"line (start p0|end p1|length|has zero length)", str(exc)), exc
            refused += 1
            continue
        accepted += 1
        assert np.abs(np.r_[ln.p0, ln.p1]).max() <= MAX_COORDINATE
        _check_path(ln, np.abs(np.r_[p0, p1]).max())
        np.testing.assert_allclose(ln.point(ln.length), ln.p1, rtol=0, atol=1e-15 * max(1.0, np.abs(ln.p1).max()) * 8)
    assert accepted > N // 10 and refused > N // 10


def test_arcs_over_all_exponents():
    rng = np.random.default_rng(12)
    accepted = refused = 0
    for _ in range(N):
        centre = rng.uniform(-1, 1, 3) * 10.0 ** rng.uniform(-3, 7)
        radius = 10.0 ** rng.uniform(-12, 8) if rng.random() < 0.8 else abs(_mag(rng))
        ang = np.sort(rng.uniform(0, 2 * math.pi, 3))
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        u = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
        u /= np.linalg.norm(u)
        w = np.cross(n, u)
        pts = [centre + radius * (math.cos(a) * u + math.sin(a) * w) for a in ang]
        try:
            arc = Arc3(*pts)
        except InvalidInputError as exc:
            assert "arc" in str(exc), exc
            refused += 1
            continue
        accepted += 1
        scale = max(arc.radius, np.abs(arc.centre).max())
        _check_path(arc, scale)
        on = np.linalg.norm(arc.point(np.linspace(0, arc.length, 17)) - arc.centre, axis=1)
        np.testing.assert_allclose(on, arc.radius, rtol=1e-9)
        assert MIN_FEATURE <= arc.radius <= 2 * MAX_COORDINATE
    assert accepted > N // 10 and refused > N // 20


def test_saddles_over_all_exponents():
    rng = np.random.default_rng(13)
    accepted = refused = 0
    for _ in range(max(N // 6, 60)):
        R = abs(_mag(rng)) if rng.random() < 0.5 else 10.0 ** rng.uniform(-10, 7)
        r = R * rng.uniform(0.05, 0.95)
        try:
            sc = SaddleCurve(R, r, angle=rng.uniform(0.3, 2.8), offset=(R - r) * rng.uniform(-0.9, 0.9))
        except InvalidInputError as exc:
            assert "pipe radius" in str(exc) or "offset" in str(exc), exc
            refused += 1
            continue
        accepted += 1
        _check_path(sc, R)
        p = sc.point(np.linspace(0, sc.length, 65))
        assert np.abs(sc.branch_residual(p)).max() <= 1e-9 * R
        assert np.abs(sc.main_residual(p)).max() <= 1e-9 * R
        chords = discretize(sc, 1e-3 * r)
        assert chords.max_error <= 1e-3 * r * (1 + 1e-9)
    assert accepted > 5 and refused > 5


@pytest.mark.parametrize("make, match", [
    (lambda: Arc3([1e150, 0, 0], [0, 1e150, 0], [-1e150, 0, 0]),
     r"arc point p1: coordinate x = 1e\+150 m is outside the supported range \+-1e\+06 m"),
    (lambda: SaddleCurve(1e300, 1e299),
     r"main pipe radius R 1e\+300 m is outside the supported range \[1e-09, 2e\+06\] m"),
    (lambda: Line([0, 0, 0], [0, 0, 1e-10]), r"line length 1e-10 m is outside the supported range"),
    (lambda: Arc3([0, 0, 0], [1, 1e-8, 0], [2, 0, 0]), r"collinear|outside the supported range"),
])
def test_out_of_range_geometry_is_refused(make, match):
    with pytest.raises(InvalidInputError, match=match):
        make()
