"""Rotations and frames (numpy only): the leaf layer under :mod:`trajkit.paths`.

Every function takes and returns float64 arrays; vectors are shape (3,),
rotation matrices shape (3, 3) with orthonormal columns (the frame axes
expressed in the parent frame), unit quaternions shape (4,) as
``(w, x, y, z)`` (scalar first).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._validate import check_array
from ..errors import InvalidInputError

__all__ = [
    "MIN_NORM",
    "unit",
    "rotation_from_axis_angle",
    "frame_from_normal",
    "angle_between",
    "quaternion_from_matrix",
    "matrix_from_quaternion",
    "slerp",
]

#: Largest |R R^T - I| accepted for a rotation matrix.
ROTATION_ATOL = 1e-6

#: Vectors shorter than this (relative to 1, in the caller's units) have no
#: direction: normalising them is an error.
MIN_NORM = 1e-12


def unit(vector: Any, field: str = "vector") -> np.ndarray:
    """Return ``vector / |vector|``.

    Parameters
    ----------
    vector : array_like, shape (3,)
    field : str
        Name used in error messages.

    Returns
    -------
    ndarray, shape (3,)

    Raises
    ------
    InvalidInputError
        When the vector is not finite or shorter than :data:`MIN_NORM`.
    """
    v = check_array(vector, field, ndim=1, size=3)
    n = float(np.linalg.norm(v))
    if n < MIN_NORM:
        raise InvalidInputError(f"{field} has no direction: its length {n!r} is below {MIN_NORM}")
    return v / n


def rotation_from_axis_angle(axis: Any, angle: float) -> np.ndarray:
    """Rotation matrix of ``angle`` [rad] about ``axis`` (Rodrigues' formula).

    Parameters
    ----------
    axis : array_like, shape (3,)
        Rotation axis (any length > 0).
    angle : float
        Right-handed rotation angle [rad].

    Returns
    -------
    ndarray, shape (3, 3)
        ``R`` such that ``R @ v`` rotates ``v``.
    """
    k = unit(axis, "rotation axis")
    a = float(angle)
    if not math.isfinite(a):
        raise InvalidInputError(f"rotation angle must be finite, got {a!r}")
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(a) * kx + (1.0 - math.cos(a)) * (kx @ kx)


def frame_from_normal(normal: Any, x_hint: Any | None = None) -> np.ndarray:
    """Right-handed orthonormal frame whose z axis is ``normal``.

    Jiang (1987) rotates the plane of a 3-point arc into a frame whose Z' is
    the plane normal; this returns that frame.

    Parameters
    ----------
    normal : array_like, shape (3,)
        Direction of the new z axis.
    x_hint : array_like, shape (3,), optional
        Direction the new x axis should point to (its component along the
        normal is removed). Default: the world axis least aligned with the
        normal.

    Returns
    -------
    ndarray, shape (3, 3)
        Columns are the unit x, y, z axes of the frame.
    """
    z = unit(normal, "normal")
    if x_hint is None:
        hint = np.zeros(3)
        hint[int(np.argmin(np.abs(z)))] = 1.0
    else:
        hint = check_array(x_hint, "x_hint", ndim=1, size=3)
    x = hint - np.dot(hint, z) * z
    x = unit(x, "x_hint (component across the normal)")
    y = np.cross(z, x)
    return np.column_stack([x, y, z])


def angle_between(a: Any, b: Any) -> float:
    """Angle between two non-zero vectors [rad], in [0, pi], robust near 0 and pi."""
    ua = unit(a, "first vector")
    ub = unit(b, "second vector")
    return float(math.atan2(np.linalg.norm(np.cross(ua, ub)), float(np.dot(ua, ub))))


def quaternion_from_matrix(R: Any) -> np.ndarray:
    """Unit quaternion ``(w, x, y, z)`` with ``w >= 0`` of a rotation matrix.

    Parameters
    ----------
    R : array_like, shape (3, 3)
        Rotation matrix (orthonormal, det +1, to 1e-6).

    Returns
    -------
    ndarray, shape (4,)

    Raises
    ------
    InvalidInputError
        When ``R`` is not a rotation matrix.
    """
    M = check_array(R, "rotation matrix", ndim=2)
    if M.shape != (3, 3):
        raise InvalidInputError(f"rotation matrix must have shape (3, 3), got {M.shape}")
    err = float(np.max(np.abs(M @ M.T - np.eye(3))))
    if err > ROTATION_ATOL or np.linalg.det(M) < 0:
        raise InvalidInputError(
            f"rotation matrix must be orthonormal with det +1 (|R R^T - I| = {err:.3g}, "
            f"det = {np.linalg.det(M):.6g})"
        )
    # Shepperd's method: pivot on the largest of w^2, x^2, y^2, z^2
    tr = float(np.trace(M))
    d = (tr, M[0, 0], M[1, 1], M[2, 2])
    k = int(np.argmax(d))
    if k == 0:
        w = math.sqrt(1.0 + tr) / 2.0
        q = np.array([w, (M[2, 1] - M[1, 2]) / (4 * w), (M[0, 2] - M[2, 0]) / (4 * w),
                      (M[1, 0] - M[0, 1]) / (4 * w)])
    else:
        i = k - 1
        j, m = (i + 1) % 3, (i + 2) % 3
        v = math.sqrt(max(1.0 + 2.0 * M[i, i] - tr, 0.0)) / 2.0
        q = np.empty(4)
        q[0] = (M[m, j] - M[j, m]) / (4 * v)
        q[1 + i] = v
        q[1 + j] = (M[j, i] + M[i, j]) / (4 * v)
        q[1 + m] = (M[m, i] + M[i, m]) / (4 * v)
    q /= np.linalg.norm(q)
    return q if q[0] >= 0 else -q


def matrix_from_quaternion(q: Any) -> np.ndarray:
    """Rotation matrix of a quaternion ``(w, x, y, z)`` (normalised first).

    Returns
    -------
    ndarray, shape (3, 3)
    """
    w, x, y, z = _unit_quaternion(q, "quaternion")
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def slerp(q0: Any, q1: Any, u: Any) -> np.ndarray:
    """Spherical linear interpolation of orientations, shortest way round.

    Jiang (1987) interpolates the tool orientation along with the position;
    ``slerp`` turns at a constant angular rate about one fixed axis.

    Parameters
    ----------
    q0, q1 : array_like, shape (4,)
        Start and end orientation ``(w, x, y, z)``.
    u : float or array_like, shape (n,)
        Fractions in [0, 1] (0 gives q0, 1 gives q1 or -q1).

    Returns
    -------
    ndarray, shape (4,) or (n, 4)
        Unit quaternions.
    """
    a = _unit_quaternion(q0, "q0")
    b = _unit_quaternion(q1, "q1")
    uu = np.asarray(u, dtype=float)
    scalar = uu.ndim == 0
    uu = np.atleast_1d(uu)
    if np.any(~np.isfinite(uu)) or np.any(uu < 0) or np.any(uu > 1):
        raise InvalidInputError(f"slerp fraction u must lie in [0, 1], got {u!r}")
    d = float(np.dot(a, b))
    if d < 0.0:  # q and -q are the same orientation: take the shorter arc
        b, d = -b, -d
    theta = math.atan2(float(np.linalg.norm(b - d * a)), d)  # angle between them on S^3
    if theta < MIN_NORM:
        out = a + uu[:, None] * (b - a)
    else:
        s = math.sin(theta)
        out = (np.sin((1 - uu) * theta) / s)[:, None] * a + (np.sin(uu * theta) / s)[:, None] * b
    out /= np.linalg.norm(out, axis=1)[:, None]
    return out[0] if scalar else out


def _unit_quaternion(q: Any, field: str) -> np.ndarray:
    v = check_array(q, field, ndim=1, size=4)
    n = float(np.linalg.norm(v))
    if n < MIN_NORM:
        raise InvalidInputError(f"{field} has zero length: not an orientation")
    return v / n
