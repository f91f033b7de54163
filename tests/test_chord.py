"""Coarse stage: chord error (Chen et al., 2013, eqs. 11-13), adaptive discretisation,
and the seed's worked example for r = 100."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

from trajkit.errors import InvalidInputError
from trajkit.paths import (
    Arc3,
    CompositePath,
    Line,
    SaddleCurve,
    arc_step_for_tolerance,
    chord_deviations,
    chord_error,
    discretize,
    max_chord_length,
    uniform_chord_count,
)

SWEEP = os.environ.get("TRAJKIT_SWEEP") == "1"


def test_chord_error_is_the_circle_sagitta():
    rng = np.random.default_rng(11)
    K = rng.uniform(1e-3, 1e3, 1000)
    phi = rng.uniform(1e-6, math.pi, 1000)  # subtended angle
    L = 2 * K * np.sin(phi / 2)
    # K (1 - cos(phi/2)) = 2 K sin^2(phi/4), the form without cancellation
    assert np.allclose(chord_error(L, K), 2 * K * np.sin(phi / 4) ** 2, rtol=1e-12, atol=0)
    # eq. 13 inverts eq. 11
    E = chord_error(L, K)
    mask = E < K
    assert np.allclose([max_chord_length(k, e) for k, e in zip(K[mask], E[mask])], L[mask], rtol=1e-9)
    assert np.allclose([arc_step_for_tolerance(k, e) for k, e in zip(K[mask], E[mask])], (K * phi)[mask], rtol=1e-7)


def test_chen2013_worked_example_corrected():
    """Chen et al. (2013): r = 100, 100 points per turn (3.6 deg) and 200 (1.8 deg).

    The chord of a 3.6 deg step is L = 2 r sin(1.8 deg); eq. 11 gives
    E = r (1 - cos 1.8 deg) = 4.934e-2, and 1.233e-2 for 1.8 deg. The seed
    prints 2.47e-4 and 6.17e-5: it wrote 200 sin^2(1.8 deg) for L^2 = (200 sin 1.8 deg)^2,
    which makes every error 200 times too small."""
    r = 100.0
    e1 = chord_error(2 * r * math.sin(math.radians(1.8)), r)
    e2 = chord_error(2 * r * math.sin(math.radians(0.9)), r)
    assert e1 == pytest.approx(2 * r * math.sin(math.radians(0.9)) ** 2, rel=1e-13)
    assert e2 == pytest.approx(2 * r * math.sin(math.radians(0.45)) ** 2, rel=1e-13)
    assert e1 == pytest.approx(4.9343e-2, rel=1e-4)
    assert e2 == pytest.approx(1.2337e-2, rel=1e-4)
    assert e1 / e2 == pytest.approx(4.0, rel=1e-3)  # halving the step quarters the error
    # the seed's printed numbers follow from its mistyped expression only
    seed1 = 100 - math.sqrt(100**2 - 200 * math.sin(math.radians(1.8)) ** 2 / 4)
    seed2 = 100 - math.sqrt(100**2 - 200 * math.sin(math.radians(0.9)) ** 2 / 4)
    assert round(seed1, 6) == pytest.approx(2.47e-4, rel=1e-2) and seed2 == pytest.approx(6.17e-5, rel=1e-3)
    assert e1 / seed1 == pytest.approx(200.0, rel=1e-3)
    # and the dense check on the real circle agrees with eq. 11
    circle = Arc3([r, 0, 0], [0, r, 0], [-r, 0, 0], full_circle=True)
    for n, e in ((100, e1), (200, e2)):
        dev = chord_deviations(circle, np.linspace(0, circle.length, n + 1))
        assert np.allclose(dev, e, rtol=1e-9)


def test_uniform_count_on_a_circle_is_the_closed_form():
    rng = np.random.default_rng(5)
    for _ in range(6):
        K = rng.uniform(0.01, 1.0)
        E = K * rng.uniform(1e-6, 1e-2)
        circle = Arc3([K, 0, 0], [0, K, 0], [-K, 0, 0], full_circle=True)
        n = math.ceil(2 * math.pi / (2 * math.acos(1 - E / K)))
        assert uniform_chord_count(circle, E) == n
        cs = discretize(circle, E)
        assert cs.count in (n, n + 1)
        assert cs.max_error <= E


def _brute_force_deviation(path, s0, s1, n=4001):
    s = np.linspace(s0, s1, n)
    p = path.point(s)
    a, b = p[0], p[-1]
    d = b - a
    t = np.clip((p - a) @ d / (d @ d), 0, 1)
    return float(np.max(np.linalg.norm(p - a - t[:, None] * d, axis=1)))


@pytest.mark.parametrize("i", range(40 if SWEEP else 6))
def test_every_chord_holds_the_tolerance_on_an_independent_dense_check(i):
    rng = np.random.default_rng(900 + i)
    R = rng.uniform(0.05, 1.0)
    r = R * rng.uniform(0.2, 0.97)
    c = SaddleCurve(R, r, math.radians(rng.uniform(30, 150)), rng.uniform(-1, 1) * (R - r) * 0.9)
    E = R * 10 ** rng.uniform(-5, -3)
    cs = discretize(c, E)
    assert cs.s[0] == 0 and cs.s[-1] == c.length and np.all(np.diff(cs.s) > 0)
    assert cs.max_error <= E
    idx = rng.choice(cs.count, size=min(cs.count, 25), replace=False)
    for k in idx:
        brute = _brute_force_deviation(c, cs.s[k], cs.s[k + 1])
        assert brute <= E * (1 + 1e-9)
        assert brute <= cs.errors[k] * (1 + 1e-9)  # the refined check is never below the brute force
    # adaptive steps: fewer chords than equal theta steps on a curve whose curvature varies
    if i < 2:
        assert cs.count <= uniform_chord_count(c, E, start=cs.count)


def test_adaptive_beats_uniform_theta_steps_on_a_seam():
    c = SaddleCurve(0.2, 0.19)
    cs = discretize(c, 1e-4)
    n_uniform = uniform_chord_count(c, 1e-4, start=cs.count)
    assert cs.count < 0.75 * n_uniform
    assert float(np.max(chord_deviations(c, c.uniform_nodes(n_uniform)))) <= 1e-4
    assert float(np.max(chord_deviations(c, c.uniform_nodes(n_uniform - 1)))) > 1e-4


def test_lines_need_one_chord_and_corners_are_nodes():
    ln = Line([0, 0, 0], [1, 2, 3])
    assert discretize(ln, 1e-6).count == 1
    p = CompositePath([Line([0, 0, 0], [1, 0, 0]), Line([1, 0, 0], [1, 1, 0])])
    cs = discretize(p, 1e-6)
    assert cs.count == 2 and np.allclose(cs.points[1], [1, 0, 0])
    cs = discretize(ln, 1e-6, max_chord=0.3)
    assert np.all(np.diff(cs.s) <= 0.3 + 1e-15)


def test_chord_polyline_points_stay_in_the_band():
    c = SaddleCurve(0.3, 0.2, math.radians(60), 0.05)
    cs = discretize(c, 2e-5)
    s = np.linspace(0, c.length, 2001)
    p = cs.point_at(s)
    exact = c.point(s)
    # a polyline point is within E of the chord's curve stretch: compare with the
    # nearest of a dense set of curve points
    dense = c.point(np.linspace(0, c.length, 50001))
    from scipy.spatial import cKDTree

    d, _ = cKDTree(dense).query(p)
    spacing = c.length / 50000
    assert np.max(d) <= 2e-5 + spacing / 2
    assert np.max(np.linalg.norm(p - exact, axis=1)) < np.max(np.diff(cs.s))


def test_chord_errors():
    with pytest.raises(InvalidInputError, match=r"chord tolerance should be larger than zero, got 0.0"):
        discretize(Line([0, 0, 0], [1, 0, 0]), 0.0)
    with pytest.raises(InvalidInputError, match=r"chord tolerance must be finite"):
        max_chord_length(1.0, math.inf)
    with pytest.raises(InvalidInputError, match=r"longer than the diameter"):
        chord_error(3.0, 1.0)
    with pytest.raises(InvalidInputError, match=r"radius of curvature must be finite and > 0"):
        chord_error(1.0, -1.0)
