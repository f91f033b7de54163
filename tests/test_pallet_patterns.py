"""Layer patterns: the seed preset, generators, alternate layers and fit checks."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

from trajkit.errors import InvalidInputError
from trajkit.palletizing import (
    BoxSize,
    LayerPattern,
    StackPattern,
    check_layer_fit,
    column_layer,
    interlock_layer,
    make_pattern,
    pinwheel_layer,
    seed_layer,
)
from trajkit.palletizing.patterns import FIT_ATOL

N = 2000 if os.environ.get("TRAJKIT_SWEEP") else 150
BOX = BoxSize(0.6, 0.4, 0.2)


def _area_ok(layer, L, W):
    """Independent check: total box area <= pallet area, every corner inside."""
    fp = layer.footprints()
    assert np.all(np.abs(fp[..., 0]) <= L / 2 + FIT_ATOL)
    assert np.all(np.abs(fp[..., 1]) <= W / 2 + FIT_ATOL)
    assert layer.n_boxes * layer.box.length * layer.box.width <= L * W * (1 + 1e-12)


def test_seed_layer_is_the_issue_pattern():
    lay = seed_layer()
    assert lay.offsets * 1000 == pytest.approx(
        np.array([[-300, -300], [300, -300], [-400, 200], [0, 200], [400, 200]]), abs=1e-9)
    assert np.degrees(lay.yaw) == pytest.approx([0, 0, 90, 90, 90], abs=1e-12)
    check_layer_fit(lay, 1.2, 1.0)  # exactly fills 1200 x 1000
    fp = lay.footprints()
    assert fp[..., 0].max() == pytest.approx(0.6) and fp[..., 1].max() == pytest.approx(0.5)


def test_interlock_on_seed_pallet_equals_seed_layer():
    a, b = interlock_layer(1.2, 1.0, BOX), seed_layer()
    assert a.offsets == pytest.approx(b.offsets, abs=1e-12)
    assert a.yaw == pytest.approx(b.yaw, abs=1e-12)


def test_column_layer_counts_and_fits():
    lay = column_layer(1.2, 1.0, BOX)
    assert lay.n_boxes == 4 and np.all(lay.yaw == 0.0)
    # a pallet where turned boxes fit better
    lay2 = column_layer(0.8, 1.2, BOX)
    assert lay2.n_boxes == 4 and np.allclose(lay2.yaw, math.pi / 2)
    _area_ok(lay2, 0.8, 1.2)


def test_pinwheel_four_fold_symmetry_and_gap():
    lay = pinwheel_layer(1.2, 1.0, BOX)
    assert lay.n_boxes == 4
    check_layer_fit(lay, 1.0, 1.0)  # lives in a (l + w) square
    # turning the layer by 90 deg maps the set of centres onto itself
    rot = lay.offsets @ np.array([[0.0, 1.0], [-1.0, 0.0]])
    for c in rot:
        assert np.min(np.hypot(*(lay.offsets - c).T)) < 1e-12
    two = pinwheel_layer(2.0, 2.0, BoxSize(0.6, 0.25, 0.2), per_arm=2)
    assert two.n_boxes == 8
    check_layer_fit(two, 1.1, 1.1)  # square of side l + 2 w
    with pytest.raises(InvalidInputError, match="over the pallet edge"):
        check_layer_fit(two, 1.09, 1.2)
    with pytest.raises(InvalidInputError, match=r"pinwheel blocks are square \(600 mm\)"):
        pinwheel_layer(2.0, 2.0, BoxSize(0.6, 0.2, 0.2), per_arm=3)


def test_alternate_layers():
    st = StackPattern(seed_layer(), "rotate180")
    l1 = st.layer_at(1)
    assert l1.offsets == pytest.approx(-seed_layer().offsets, abs=0)
    assert st.layer_at(2) is st.layer
    m = StackPattern(seed_layer(), "mirror").layer_at(3)
    assert m.offsets[:, 1] == pytest.approx(-seed_layer().offsets[:, 1], abs=0)
    poses = st.box_poses(5, [0.0, 1.4, 0.4])
    assert poses.shape == (25, 4)
    assert np.unique(poses[:, 2]) == pytest.approx([0.6, 0.8, 1.0, 1.2, 1.4], abs=1e-15)
    assert poses[5, :2] == pytest.approx([0.3, 1.7], abs=1e-15)
    with pytest.raises(InvalidInputError, match="alternate must be one of"):
        StackPattern(seed_layer(), "twist")
    with pytest.raises(InvalidInputError, match="layers must be an integer >= 1, got 0"):
        st.box_poses(0, [0, 0, 0])


def test_fit_errors_name_box_side_and_bound():
    with pytest.raises(InvalidInputError, match=r"box 0 .* over the pallet edge on the -x side: "
                                                r"it reaches 600.0 mm .* edge is at 550.0 mm"):
        check_layer_fit(seed_layer(), 1.1, 1.0)
    over = LayerPattern(np.array([[0.0, 0.0], [0.5, 0.0]]), np.zeros(2), BOX, "bad")
    with pytest.raises(InvalidInputError, match=r"boxes 0 and 1 of layer pattern 'bad' overlap"):
        check_layer_fit(over, 2.0, 2.0)
    touching = LayerPattern(np.array([[0.0, 0.0], [0.6, 0.0]]), np.zeros(2), BOX, "ok")
    check_layer_fit(touching, 2.0, 2.0)
    tilted = LayerPattern(np.array([[0.0, 0.0], [0.62, 0.1]]), np.array([0.0, 0.3]), BOX, "tilt")
    with pytest.raises(InvalidInputError, match="boxes 0 and 1 of layer pattern 'tilt' overlap"):
        check_layer_fit(tilted, 3.0, 3.0)
    apart = LayerPattern(np.array([[0.0, 0.0], [0.9, 0.0]]), np.array([0.0, 0.3]), BOX, "apart")
    check_layer_fit(apart, 3.0, 3.0)
    # overhang allowance
    check_layer_fit(seed_layer(), 1.1, 1.0, overhang=0.05)
    with pytest.raises(InvalidInputError, match="does not fit on the pallet"):
        column_layer(0.3, 0.3, BOX)
    with pytest.raises(InvalidInputError, match="pattern must be one of"):
        make_pattern("spiral", 1.2, 1.0, BOX)
    with pytest.raises(InvalidInputError, match="box width should be larger than zero, got -0.4"):
        BoxSize(0.6, -0.4, 0.2)


def test_generated_patterns_always_fit_sweep():
    rng = np.random.default_rng(7)
    for _ in range(N):
        L, W = rng.uniform(0.6, 2.0, 2)
        l = rng.uniform(0.2, 0.7)
        w = rng.uniform(0.25, 1.0) * l
        box = BoxSize(l, w, 0.1)
        for name in ("column", "interlock", "pinwheel"):
            for alt in ("rotate180", "mirror"):
                try:
                    st = make_pattern(name, L, W, box, alt)
                except InvalidInputError as exc:
                    assert "does not fit" in str(exc) or "pinwheel" in str(exc)
                    continue
                for k in (0, 1):
                    _area_ok(st.layer_at(k), L, W)
                    check_layer_fit(st.layer_at(k), L, W)
