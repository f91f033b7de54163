"""Rotations and frames (numpy only): the leaf layer under :mod:`trajkit.paths`.

Every function takes and returns float64 arrays; vectors are shape (3,),
rotation matrices shape (3, 3) with orthonormal columns (the frame axes
expressed in the parent frame).
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
]

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

    Seed 002 rotates the plane of a 3-point arc into a frame whose Z' is
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
