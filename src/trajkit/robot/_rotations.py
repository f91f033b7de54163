"""Unit quaternions and slerp (numpy only; quaternions are (w, x, y, z)).

:mod:`trajkit.spatial` has no quaternion helpers yet; these are kept private
to :mod:`trajkit.robot` until they move there.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["quat_from_matrix", "matrix_from_quat", "slerp", "rotation_angle", "relative_rotvec"]

#: Below this angle [rad] slerp falls back to normalised linear interpolation.
SLERP_SMALL_ANGLE = 1e-9


def quat_from_matrix(r: Any) -> np.ndarray:
    """Unit quaternion (4,) (w >= 0) of a rotation matrix (3, 3) (Shepperd's method)."""
    m = np.asarray(r, dtype=np.float64)
    tr = m[0, 0] + m[1, 1] + m[2, 2]
    cand = np.array([tr, m[0, 0], m[1, 1], m[2, 2]])
    k = int(np.argmax(cand))
    if k == 0:
        w = math.sqrt(max(1.0 + tr, 0.0)) / 2.0
        q = np.array([w, (m[2, 1] - m[1, 2]) / (4 * w), (m[0, 2] - m[2, 0]) / (4 * w),
                      (m[1, 0] - m[0, 1]) / (4 * w)])
    elif k == 1:
        x = math.sqrt(max(1.0 + 2 * m[0, 0] - tr, 0.0)) / 2.0
        q = np.array([(m[2, 1] - m[1, 2]) / (4 * x), x, (m[0, 1] + m[1, 0]) / (4 * x),
                      (m[0, 2] + m[2, 0]) / (4 * x)])
    elif k == 2:
        y = math.sqrt(max(1.0 + 2 * m[1, 1] - tr, 0.0)) / 2.0
        q = np.array([(m[0, 2] - m[2, 0]) / (4 * y), (m[0, 1] + m[1, 0]) / (4 * y), y,
                      (m[1, 2] + m[2, 1]) / (4 * y)])
    else:
        z = math.sqrt(max(1.0 + 2 * m[2, 2] - tr, 0.0)) / 2.0
        q = np.array([(m[1, 0] - m[0, 1]) / (4 * z), (m[0, 2] + m[2, 0]) / (4 * z),
                      (m[1, 2] + m[2, 1]) / (4 * z), z])
    q /= np.linalg.norm(q)
    return -q if q[0] < 0 else q


def matrix_from_quat(q: Any) -> np.ndarray:
    """Rotation matrices from unit quaternions: (4,) -> (3, 3), (n, 4) -> (n, 3, 3)."""
    qq = np.asarray(q, dtype=np.float64)
    single = qq.ndim == 1
    qq = np.atleast_2d(qq)
    w, x, y, z = qq[:, 0], qq[:, 1], qq[:, 2], qq[:, 3]
    out = np.empty((qq.shape[0], 3, 3))
    out[:, 0, 0] = 1 - 2 * (y * y + z * z)
    out[:, 0, 1] = 2 * (x * y - w * z)
    out[:, 0, 2] = 2 * (x * z + w * y)
    out[:, 1, 0] = 2 * (x * y + w * z)
    out[:, 1, 1] = 1 - 2 * (x * x + z * z)
    out[:, 1, 2] = 2 * (y * z - w * x)
    out[:, 2, 0] = 2 * (x * z - w * y)
    out[:, 2, 1] = 2 * (y * z + w * x)
    out[:, 2, 2] = 1 - 2 * (x * x + y * y)
    return out[0] if single else out


def rotation_angle(q0: Any, q1: Any) -> float:
    """Angle [rad] of the shortest rotation between two unit quaternions.

    From the relative rotation ``conj(q0) q1 = (c, v)``: ``2 atan2(|v|, |c|)``,
    accurate to a few ulps at every angle (``2 acos(|c|)`` loses half the
    digits near zero: about 1e-8 rad).
    """
    c, vx, vy, vz = _relative(q0, q1)
    return 2.0 * math.atan2(math.sqrt(vx * vx + vy * vy + vz * vz), abs(c))


def _relative(q0: Any, q1: Any) -> tuple[float, float, float, float]:
    """The relative rotation ``conj(q0) q1`` of two unit quaternions, ``(c, vx, vy, vz)``."""
    w0, x0, y0, z0 = (float(c) for c in q0)
    w1, x1, y1, z1 = (float(c) for c in q1)
    return (w0 * w1 + x0 * x1 + y0 * y1 + z0 * z1,
            w0 * x1 - w1 * x0 - (y0 * z1 - z0 * y1),
            w0 * y1 - w1 * y0 - (z0 * x1 - x0 * z1),
            w0 * z1 - w1 * z0 - (x0 * y1 - y0 * x1))


def relative_rotvec(q0: Any, q1: Any) -> np.ndarray:
    """Rotation vector (3,) [rad] of the shortest rotation from ``q0`` to ``q1``, in
    ``q0``'s frame: ``R(q1) = R(q0) Exp(hat(r))`` (the arc :func:`slerp` follows).

    From the relative rotation ``conj(q0) q1 = (c, v)`` (made ``c >= 0``):
    ``2 atan2(|v|, c) v / |v|``; zero where ``v`` is.
    """
    c, vx, vy, vz = _relative(q0, q1)
    v = np.array([vx, vy, vz])
    if c < 0.0:
        c, v = -c, -v
    nv = float(np.linalg.norm(v))
    if nv == 0.0:
        return np.zeros(3)
    return (2.0 * math.atan2(nv, c) / nv) * v


def slerp(q0: Any, q1: Any, u: Any) -> np.ndarray:
    """Spherical linear interpolation along the shortest arc.

    Parameters
    ----------
    q0, q1 : array_like, shape (4,)
        Unit quaternions at ``u = 0`` and ``u = 1``.
    u : float or array_like, shape (n,)
        Fractions in [0, 1].

    Returns
    -------
    ndarray, shape (4,) or (n, 4)
        Unit quaternions; the rotation angle grows linearly with ``u``.
    """
    a = np.asarray(q0, dtype=np.float64)
    b = np.asarray(q1, dtype=np.float64)
    if float(np.dot(a, b)) < 0.0:
        b = -b
    uu = np.asarray(u, dtype=np.float64)
    scalar = uu.ndim == 0
    uu = np.atleast_1d(uu)
    c = min(1.0, float(np.dot(a, b)))
    th = math.acos(c)
    if th < SLERP_SMALL_ANGLE:
        out = (1 - uu)[:, None] * a + uu[:, None] * b
    else:
        s = math.sin(th)
        out = (np.sin((1 - uu) * th) / s)[:, None] * a + (np.sin(uu * th) / s)[:, None] * b
    out /= np.linalg.norm(out, axis=1)[:, None]
    return out[0] if scalar else out
