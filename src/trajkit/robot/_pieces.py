"""Geometric pieces of a Cartesian motion chain: path + orientation, by arc length.

A piece maps its parameter ``s`` in ``[0, length]`` to tool positions (n, 3)
[m] and orientations (n, 4) (unit quaternions). Lines and arcs come from
:mod:`trajkit.paths`; the corner blend (a cubic Bezier curve) and the
orientation-only piece are defined here.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..paths.base import Path
from ._rotations import SLERP_SMALL_ANGLE, rotation_angle, slerp

__all__ = ["Piece", "BezierBlend", "BLEND_TABLE"]

#: Points of the arc-length table of a blend curve.
BLEND_TABLE = 2049

#: Handle length of the corner blend, as a fraction of the zone radius
#: (2/3: the degree-elevated quadratic Bezier through the corner point).
BLEND_HANDLE = 2.0 / 3.0


class BezierBlend:
    """Cubic Bezier corner blend from ``pa`` (tangent ``ta``) to ``pb`` (tangent ``tb``).

    Parameterised by arc length through a dense table (``point``, ``tangent``
    and ``length``); the curve lies in the convex hull of its control points.
    """

    def __init__(self, pa: np.ndarray, ta: np.ndarray, pb: np.ndarray, tb: np.ndarray,
                 radius: float) -> None:
        h = BLEND_HANDLE * radius
        self.ctrl = np.array([pa, pa + h * ta, pb - h * tb, pb])
        u = np.linspace(0.0, 1.0, BLEND_TABLE)
        d = self._deriv(u)
        speed = np.linalg.norm(d, axis=1)
        # trapezoid cumulative arc length (the table is dense; error ~ 1e-8 relative)
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * np.diff(u))])
        self._u = u
        self._cum = cum
        self.length = float(cum[-1])

    def _bez(self, u: np.ndarray) -> np.ndarray:
        c = self.ctrl
        m = 1.0 - u
        return ((m**3)[:, None] * c[0] + (3 * m * m * u)[:, None] * c[1]
                + (3 * m * u * u)[:, None] * c[2] + (u**3)[:, None] * c[3])

    def _deriv(self, u: np.ndarray) -> np.ndarray:
        c = self.ctrl
        m = 1.0 - u
        return ((3 * m * m)[:, None] * (c[1] - c[0]) + (6 * m * u)[:, None] * (c[2] - c[1])
                + (3 * u * u)[:, None] * (c[3] - c[2]))

    def u_of_s(self, s: np.ndarray) -> np.ndarray:
        return np.interp(s, self._cum, self._u)

    def point(self, s: Any) -> np.ndarray:
        return self._bez(self.u_of_s(np.atleast_1d(np.asarray(s, dtype=np.float64))))


class Piece:
    """One piece of a chain.

    Parameters
    ----------
    kind : {"path", "blend", "orient"}
    length : float
        Parameter length [m] (for ``"orient"``: rotation angle times the
        robot's length scale).
    point : callable
        ``point(s (n,)) -> (n, 3)`` positions [m].
    q0, q1 : ndarray, shape (4,)
        Orientations at the start and the end (slerp in between).
    cap : float
        Programmed speed cap [m/s] of the parameter.
    motion : int
        Index of the motion (instruction) this piece belongs to.
    tool_rate : float
        |dp/ds|: 1 for a path or blend, 0 for an orientation-only piece.
    cap_reason : str
        Why ``cap`` is below the programmed speed ("" if it is not).
    programmed : float, optional
        The programmed speed [m/s] (default ``cap``).
    quat_fn : callable, optional
        ``quat_fn(s (n,)) -> (n, 4)`` replacing the slerp from ``q0`` to ``q1``.
    """

    def __init__(self, kind: str, length: float, point, q0: np.ndarray, q1: np.ndarray,
                 cap: float, motion: int, tool_rate: float, cap_reason: str = "",
                 programmed: float | None = None, quat_fn=None) -> None:
        self.kind = kind
        self.length = float(length)
        self._point = point
        self.q0 = q0
        self.q1 = q1
        self.cap = cap
        self.motion = motion
        self.tool_rate = tool_rate
        self.cap_reason = cap_reason
        self.programmed = cap if programmed is None else programmed
        self.quat_fn = quat_fn
        self.angle = rotation_angle(q0, q1)

    def point(self, s: np.ndarray) -> np.ndarray:
        return self._point(np.clip(s, 0.0, self.length))

    def quat(self, s: np.ndarray) -> np.ndarray:
        if self.quat_fn is not None:
            return self.quat_fn(np.clip(np.atleast_1d(np.asarray(s, dtype=np.float64)), 0.0, self.length))
        u = np.clip(np.asarray(s, dtype=np.float64) / self.length, 0.0, 1.0) if self.length > 0 \
            else np.zeros_like(s)
        return slerp(self.q0, self.q1, np.atleast_1d(u))


def sub_path(path: Path, a: float, b: float):
    """``point`` callable of ``path`` restricted to arc lengths [a, b] (re-based at 0)."""
    def point(s: np.ndarray) -> np.ndarray:
        return path.point(np.clip(a + np.atleast_1d(s), 0.0, path.length))
    return point


def smootherstep(x: np.ndarray) -> np.ndarray:
    """``6 x^5 - 15 x^4 + 10 x^3``: 0 -> 1 with zero first and second derivatives at both ends."""
    x = np.clip(x, 0.0, 1.0)
    return x * x * x * (x * (6.0 * x - 15.0) + 10.0)


def blended_orientation(qa0, qa1, len_a: float, sa: float, qb0, qb1, len_b: float, sb: float,
                        length: float):
    """Orientation of a corner blend of parameter length ``length``.

    Cross-fades (smootherstep) from the incoming motion's slerp, continued
    past the corner at its own rate (``qa0 -> qa1`` over ``len_a``, from arc
    length ``sa``), to the outgoing motion's slerp (``qb0 -> qb1`` over
    ``len_b``, reaching arc length ``sb`` at the end), so the orientation
    and its rate are continuous at both ends of the blend.
    """
    def fn(s: np.ndarray) -> np.ndarray:
        ua = (sa + s) / len_a
        ub = (sb - (length - s)) / len_b
        a = slerp_any(qa0, qa1, ua)
        b = slerp_any(qb0, qb1, ub)
        w = smootherstep(s / length)
        out = np.empty((s.size, 4))
        for i in range(s.size):
            out[i] = slerp(a[i], b[i], float(w[i]))
        return out
    return fn


def slerp_any(q0: np.ndarray, q1: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Slerp that also extrapolates (``u`` outside [0, 1]) along the same great circle."""
    a = np.asarray(q0, dtype=np.float64)
    b = np.asarray(q1, dtype=np.float64)
    if float(np.dot(a, b)) < 0.0:
        b = -b
    th = rotation_angle(a, b) / 2.0
    uu = np.atleast_1d(np.asarray(u, dtype=np.float64))
    if th < SLERP_SMALL_ANGLE:
        return np.broadcast_to(a, (uu.size, 4)).copy()
    sn = math.sin(th)
    out = (np.sin((1 - uu) * th) / sn)[:, None] * a + (np.sin(uu * th) / sn)[:, None] * b
    return out / np.linalg.norm(out, axis=1)[:, None]


def constant_point(p: np.ndarray):
    """``point`` callable of an orientation-only piece (the tool stays at ``p``)."""
    def point(s: np.ndarray) -> np.ndarray:
        return np.broadcast_to(p, (np.atleast_1d(s).size, 3)).copy()
    return point


def angle_between_tangents(ta: np.ndarray, tb: np.ndarray) -> float:
    """Angle [rad] between two unit tangents."""
    return math.acos(max(-1.0, min(1.0, float(np.dot(ta, tb)))))
