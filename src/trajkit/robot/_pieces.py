"""Geometric pieces of a Cartesian motion chain: path + orientation, by arc length.

A piece maps its parameter ``s`` in ``[0, length]`` to tool positions (n, 3)
[m] and orientations (n, 4) (unit quaternions). Lines and arcs come from
:mod:`trajkit.paths`; the corner blend (a quintic, curvature-continuous Bezier
curve) and the
orientation-only piece are defined here.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..paths.base import Path
from ._rotations import SLERP_SMALL_ANGLE, rotation_angle, slerp

__all__ = ["Piece", "BezierBlend", "BLEND_TABLE"]

#: Intervals of the arc-length table of a blend curve (each integrated by
#: Gauss-Legendre quadrature, then inverted by Newton steps: the arc-length
#: parameterisation is exact to rounding, so finite differences of the joints
#: along the blend see the curve, not the table).
BLEND_TABLE = 256

#: Gauss-Legendre points per table interval.
BLEND_GAUSS = 8

#: Newton steps of the arc-length inversion u(s).
BLEND_NEWTON = 4

#: Candidate handle lengths of the corner blend, as fractions of the zone
#: radius; the one with the smallest peak curvature rate |d kappa / ds| (the
#: term that sets the joint jerk along the blend) is used, among those whose
#: control points stay inside the zone.
BLEND_HANDLES = (0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45)

#: Points on which the candidate handles are compared.
BLEND_PROBE = 257

#: Curvature-vector factor of the second/fourth control point: with handles
#: ``h``, ``B'(0) = 5 h t`` and ``B''(0) = 20 c h^2 k``, so ``c = 25/20`` gives
#: the curvature vector ``k`` at the ends.
_G2_FACTOR = 25.0 / 20.0

_GL_X, _GL_W = np.polynomial.legendre.leggauss(BLEND_GAUSS)


class BezierBlend:
    """Quintic Bezier corner blend, curvature-continuous (G2) with the pieces it joins.

    From ``pa`` (unit tangent ``ta``, curvature vector ``ka`` of the incoming
    piece there) to ``pb`` (``tb``, ``kb``). Control points
    ``pa, pa + h ta, pa + 2 h ta + 1.25 h^2 ka`` and symmetrically at ``pb``:
    the blend leaves each piece with the same tangent and curvature vector, so
    the tool (and the joints) keep a continuous acceleration and a bounded
    jerk through it. The curve lies in the convex hull of its control points;
    the handle ``h`` is chosen from :data:`BLEND_HANDLES` so that every control
    point is within ``radius`` of ``corner``. Parameterised by arc length
    (``point``, ``length``).

    Parameters
    ----------
    pa, pb : ndarray, shape (3,) [m]
    ta, tb : ndarray, shape (3,)
        Unit tangents.
    ka, kb : ndarray, shape (3,) [1/m]
        Curvature vectors (kappa times the principal normal); zero on lines.
    radius : float [m]
        Distance of ``pa`` and ``pb`` from the corner along the pieces.
    corner : ndarray, shape (3,), optional
        The corner point (default: the intersection of the two tangent lines,
        approximated by ``pa + radius ta``).
    """

    def __init__(self, pa: np.ndarray, ta: np.ndarray, pb: np.ndarray, tb: np.ndarray,
                 radius: float, ka: np.ndarray | None = None, kb: np.ndarray | None = None,
                 corner: np.ndarray | None = None) -> None:
        pa, pb = np.asarray(pa, dtype=np.float64), np.asarray(pb, dtype=np.float64)
        ta, tb = np.asarray(ta, dtype=np.float64), np.asarray(tb, dtype=np.float64)
        ka = np.zeros(3) if ka is None else np.asarray(ka, dtype=np.float64)
        kb = np.zeros(3) if kb is None else np.asarray(kb, dtype=np.float64)
        corner = pa + radius * ta if corner is None else np.asarray(corner, dtype=np.float64)
        best: tuple[tuple[bool, float], np.ndarray, float] | None = None
        for beta in BLEND_HANDLES:
            h = beta * radius
            ctrl = np.array([pa, pa + h * ta, pa + 2.0 * h * ta + _G2_FACTOR * h * h * ka,
                             pb - 2.0 * h * tb + _G2_FACTOR * h * h * kb, pb - h * tb, pb])
            inside = np.linalg.norm(ctrl - corner, axis=1).max() <= radius * (1.0 + 1e-12)
            rate = self._curvature_rate(ctrl)
            key = (not inside, rate)
            if best is None or key < best[0]:
                best = (key, ctrl, beta)
        assert best is not None  # BLEND_HANDLES is not empty
        self.ctrl = best[1]
        self.handle = best[2] * radius
        edges = np.linspace(0.0, 1.0, BLEND_TABLE + 1)
        seg = self._integral(edges[:-1], edges[1:])
        self._u = edges
        self._cum = np.concatenate([[0.0], np.cumsum(seg)])
        self.length = float(self._cum[-1])

    # ---- Bezier evaluation (Bernstein form) and derivatives in u
    @staticmethod
    def _eval(ctrl: np.ndarray, u: np.ndarray, order: int = 0) -> np.ndarray:
        c = ctrl
        for _ in range(order):
            c = (c.shape[0] - 1) * np.diff(c, axis=0)
        n = c.shape[0] - 1
        u = np.asarray(u, dtype=np.float64)[:, None]
        m = 1.0 - u
        out = np.zeros((u.shape[0], 3))
        for i in range(n + 1):
            out += math.comb(n, i) * m ** (n - i) * u**i * c[i]
        return out

    @classmethod
    def _curvature_rate(cls, ctrl: np.ndarray) -> float:
        """Largest |d kappa / ds| [1/m^2] on BLEND_PROBE points."""
        u = np.linspace(0.0, 1.0, BLEND_PROBE)
        d1 = cls._eval(ctrl, u, 1)
        d2 = cls._eval(ctrl, u, 2)
        sp = np.linalg.norm(d1, axis=1)
        kap = np.linalg.norm(np.cross(d1, d2), axis=1) / sp**3
        s = np.concatenate([[0.0], np.cumsum(0.5 * (sp[1:] + sp[:-1]) * np.diff(u))])
        return float(np.abs(np.diff(kap) / np.diff(s)).max())

    def _speed(self, u: np.ndarray) -> np.ndarray:
        return np.linalg.norm(self._eval(self.ctrl, u.ravel(), 1), axis=1).reshape(u.shape)

    def _integral(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Arc length from ``a`` to ``b`` (n,) by Gauss-Legendre quadrature."""
        half = 0.5 * (b - a)
        x = (0.5 * (a + b))[:, None] + half[:, None] * _GL_X[None, :]
        return half * (self._speed(x) @ _GL_W)

    def u_of_s(self, s: np.ndarray) -> np.ndarray:
        """Bezier parameter at arc lengths ``s`` (n,) [m]: table, then Newton steps."""
        s = np.clip(np.asarray(s, dtype=np.float64), 0.0, self.length)
        u = np.interp(s, self._cum, self._u)
        for _ in range(BLEND_NEWTON):
            k = np.clip(np.searchsorted(self._u, u, side="right") - 1, 0, BLEND_TABLE - 1)
            err = self._cum[k] + self._integral(self._u[k], u) - s
            u = np.clip(u - err / self._speed(u), 0.0, 1.0)
        return u

    def point(self, s: Any) -> np.ndarray:
        """Positions (n, 3) [m] at arc lengths ``s`` (n,) [m]."""
        return self._eval(self.ctrl, self.u_of_s(np.atleast_1d(np.asarray(s, dtype=np.float64))))


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
        return slerp_rows(a, b, smootherstep(s / length))
    return fn


def slerp_rows(a: np.ndarray, b: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Row by row :func:`slerp` of unit quaternions ``a`` and ``b`` (n, 4) at fractions ``w`` (n,)."""
    dot = np.einsum("ij,ij->i", a, b)
    b = np.where((dot < 0.0)[:, None], -b, b)
    th = np.arccos(np.minimum(1.0, np.abs(dot)))
    small = th < SLERP_SMALL_ANGLE
    sn = np.where(small, 1.0, np.sin(th))
    ca = np.where(small, 1.0 - w, np.sin((1.0 - w) * th) / sn)
    cb = np.where(small, w, np.sin(w * th) / sn)
    out = ca[:, None] * a + cb[:, None] * b
    return out / np.linalg.norm(out, axis=1)[:, None]


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
