"""trajkit.spatial: rotations and frames, checked against independent constructions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from trajkit.errors import InvalidInputError
from trajkit.spatial import angle_between, frame_from_normal, rotation_from_axis_angle, unit

RNG = np.random.default_rng(20261122)


def test_rotation_is_orthonormal_and_rotates_by_the_angle():
    for _ in range(200):
        axis = RNG.normal(size=3)
        ang = RNG.uniform(-math.pi, math.pi)
        R = rotation_from_axis_angle(axis, ang)
        assert np.allclose(R @ R.T, np.eye(3), atol=1e-14)
        assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-14)
        k = axis / np.linalg.norm(axis)
        assert np.allclose(R @ k, k, atol=1e-14)  # the axis is fixed
        v = np.cross(k, RNG.normal(size=3))  # a vector across the axis
        assert angle_between(v, R @ v) == pytest.approx(abs(ang), abs=1e-12)
        # right-handed: (v x Rv) points along +k for a positive angle
        assert np.sign(np.dot(np.cross(v, R @ v), k)) == np.sign(ang)


def test_rotation_composes_additively_about_one_axis():
    axis = np.array([1.0, 2.0, -0.5])
    a, b = 0.7, -1.9
    assert np.allclose(rotation_from_axis_angle(axis, a) @ rotation_from_axis_angle(axis, b),
                       rotation_from_axis_angle(axis, a + b), atol=1e-14)


def test_frame_from_normal_is_right_handed_with_z_along_normal():
    for _ in range(200):
        n = RNG.normal(size=3)
        F = frame_from_normal(n)
        assert np.allclose(F.T @ F, np.eye(3), atol=1e-14)
        assert np.linalg.det(F) == pytest.approx(1.0, abs=1e-14)
        assert np.allclose(F[:, 2], n / np.linalg.norm(n), atol=1e-15)
    F = frame_from_normal([0, 0, 2.0], x_hint=[1.0, 1.0, 5.0])
    assert np.allclose(F[:, 0], np.array([1, 1, 0]) / math.sqrt(2), atol=1e-15)


def test_angle_between_is_accurate_near_zero_and_pi():
    assert angle_between([1, 0, 0], [1, 1e-9, 0]) == pytest.approx(1e-9, rel=1e-9)
    assert angle_between([1, 0, 0], [-1, 1e-9, 0]) == pytest.approx(math.pi - 1e-9, abs=1e-15)


def test_errors_name_the_field():
    with pytest.raises(InvalidInputError, match="normal has no direction"):
        frame_from_normal([0, 0, 0])
    with pytest.raises(InvalidInputError, match="rotation axis has no direction"):
        rotation_from_axis_angle([0, 0, 0], 1.0)
    with pytest.raises(InvalidInputError, match="rotation angle must be finite"):
        rotation_from_axis_angle([0, 0, 1], math.nan)
    with pytest.raises(InvalidInputError, match=r"vector\[1\] must be finite"):
        unit([1.0, math.inf, 0.0])
    with pytest.raises(InvalidInputError, match="x_hint"):
        frame_from_normal([0, 0, 1], x_hint=[0, 0, 3])
