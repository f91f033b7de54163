"""trajkit.spatial: rotations and frames, checked against independent constructions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from trajkit.errors import InvalidInputError
from trajkit.spatial import (
    angle_between,
    frame_from_normal,
    matrix_from_quaternion,
    quaternion_from_matrix,
    rotation_from_axis_angle,
    slerp,
    unit,
)

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


def test_quaternion_round_trip_and_axis_angle():
    for _ in range(300):
        axis = RNG.normal(size=3)
        ang = RNG.uniform(-math.pi, math.pi)
        R = rotation_from_axis_angle(axis, ang)
        q = quaternion_from_matrix(R)
        assert np.linalg.norm(q) == pytest.approx(1.0, abs=1e-15) and q[0] >= 0
        assert np.allclose(matrix_from_quaternion(q), R, atol=1e-14)
        # independent: q = (cos(a/2), sin(a/2) k) up to sign
        k = axis / np.linalg.norm(axis)
        ref = np.concatenate([[math.cos(ang / 2)], math.sin(ang / 2) * k])
        ref = ref if ref[0] >= 0 else -ref
        assert np.allclose(q, ref, atol=1e-12)
    # the branches of Shepperd's method: rotations by pi about each axis
    for k in np.eye(3):
        q = quaternion_from_matrix(rotation_from_axis_angle(k, math.pi))
        assert np.allclose(np.abs(q), np.concatenate([[0.0], k]), atol=1e-15)


def test_slerp_turns_at_a_constant_rate_about_one_axis():
    for _ in range(100):
        R0 = rotation_from_axis_angle(RNG.normal(size=3), RNG.uniform(-3, 3))
        axis = RNG.normal(size=3)
        ang = RNG.uniform(0.01, math.pi - 0.01)
        R1 = rotation_from_axis_angle(axis, ang) @ R0
        u = np.linspace(0, 1, 11)
        qs = slerp(quaternion_from_matrix(R0), quaternion_from_matrix(R1), u)
        assert np.allclose(np.linalg.norm(qs, axis=1), 1.0, atol=1e-15)
        for ui, q in zip(u, qs):
            expect = rotation_from_axis_angle(axis, ui * ang) @ R0
            assert np.allclose(matrix_from_quaternion(q), expect, atol=1e-12)
    # shortest way: q1 and -q1 give the same path
    q0 = quaternion_from_matrix(np.eye(3))
    q1 = quaternion_from_matrix(rotation_from_axis_angle([0, 0, 1], 0.5))
    assert np.allclose(slerp(q0, q1, 0.5), slerp(q0, -q1, 0.5), atol=1e-15)
    assert np.allclose(slerp(q0, q0, [0.0, 0.3, 1.0]), q0, atol=1e-15)


def test_quaternion_errors():
    with pytest.raises(InvalidInputError, match=r"rotation matrix must be orthonormal with det \+1"):
        quaternion_from_matrix(np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(InvalidInputError, match=r"rotation matrix must have shape \(3, 3\), got \(2, 2\)"):
        quaternion_from_matrix(np.eye(2))
    with pytest.raises(InvalidInputError, match=r"q1 has zero length"):
        slerp([1, 0, 0, 0], [0, 0, 0, 0], 0.5)
    with pytest.raises(InvalidInputError, match=r"slerp fraction u must lie in \[0, 1\], got 1.5"):
        slerp([1, 0, 0, 0], [0, 1, 0, 0], 1.5)
