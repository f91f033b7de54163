"""Geometric pieces of a Cartesian motion chain: path + orientation, by arc length.

A piece maps its parameter ``s`` in ``[0, length]`` to tool positions (n, 3)
[m] and orientations (n, 4) (unit quaternions). Lines and arcs come from
:mod:`trajkit.paths`; the corner blend (a degree-7 Bezier curve, continuous in
tangent, curvature and curvature rate with the pieces it joins) and the
orientation-only piece are defined here.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..paths.arc import Arc3
from ..paths.base import Path
from ..paths.line import Line
from . import _bezier_jit, _orient_jets
from ._rotations import SLERP_SMALL_ANGLE, matrix_from_quat, relative_rotvec, rotation_angle, slerp

__all__ = ["Piece", "BezierBlend", "BLEND_TABLE", "sub_path_derivatives"]

#: Intervals of the arc-length table of a blend curve (each integrated by
#: Gauss-Legendre quadrature, then inverted by Newton steps: the arc-length
#: parameterisation is exact to rounding, so finite differences of the joints
#: along the blend see the curve, not the table).
BLEND_TABLE = 256

#: Gauss-Legendre points per table interval.
BLEND_GAUSS = 8

#: Newton steps of the arc-length inversion u(s).
BLEND_NEWTON = 4

#: Handle fractions ``(h1, h2, h3)`` of the corner blend at an end on a
#: line: control points ``p + h1 d t``, ``p + h2 d t``, ``p + h3 d t``, with
#: ``d`` the end's tangent reach (``_tangent_reach``; the zone radius between
#: two lines). Measured with the path-timing engine on UR5 and Panda corners
#: of 45 to 135 deg and zones of 10 to 70 mm, these are at or within 1 % of
#: the fastest of a grid of handle sets, and 4-22 % faster than a quintic G2
#: blend of the same zone (whose curvature rate steps at its ends): here the
#: curvature rises from zero with zero slope, so the centripetal jerk starts
#: from zero, and the feed enters the blend fast and slows down while the
#: curvature grows (the centripetal acceleration can stay level).
BLEND_HANDLES = (0.25, 0.6, 0.9)

#: The same at an end on an arc (plus its curvature terms). Measured on a LIN
#: into a tangent CIRC on UR5 and Panda: 2-3 % faster than a quintic G2 blend;
#: shorter handles there let the curvature overshoot the arc's or dip first.
BLEND_HANDLES_CURVED = (0.5, 1.0, 1.5)

#: Shortest tangent reach of a blend end, as a fraction of the zone radius
#: (see ``_tangent_reach``).
BLEND_REACH_MIN = 0.25

#: When a control point of an end with curvature falls outside the zone, the
#: handles are scaled by these factors in turn until every control point is
#: inside (the last one is kept otherwise).
BLEND_SHRINK = (1.0, 0.85, 0.7, 0.55, 0.4, 0.3, 0.2)

#: Least share of every control-polygon edge along the chord from the blend's
#: start to its end (see ``_acceptable``); a handle set that breaks it is
#: shortened, then replaced by the line handles.
BLEND_MONOTONE = 0.0

#: Largest peak curvature of a blend, as a multiple of that of the circle
#: tangent to both tangent lines ``r`` from the corner: the handles above keep
#: within it up to corners of 135 deg (5.8 times there, 3.1 at 90 deg); past
#: that the curvature of the full handles grows fast (8.6 times at 150 deg, 25
#: at 170 deg, where the joints' third derivatives vary over a fraction of a
#: millimetre), and the handles are shortened (BLEND_SHRINK) until it is
#: within, or to the lowest peak.
BLEND_KAPPA_RATIO = 6.0

#: Points on which the peak curvature of a blend is measured.
BLEND_PROBE = 257

#: Curvature-vector factors of the degree-7 blend's third and fourth control
#: points: with ``B'(0) = 7 h1 t`` and ``B''(0) = 42 (P2 - 2 P1 + P0)``,
#: ``P2 = p + h2 t + (7/6) h1^2 k`` gives the curvature vector ``k`` at the end;
#: ``P3 = p + h3 t + (7/2 h1^2 + 21/5 h1 (h2 - 2 h1)) k`` makes the normal part
#: of the third derivative by arc length zero, that of a line or an arc (no
#: curvature rate, no torsion).
_G2_FACTOR = 7.0 / 6.0
_G3_FACTOR_A = 7.0 / 2.0
_G3_FACTOR_B = 21.0 / 5.0

_GL_X, _GL_W = np.polynomial.legendre.leggauss(BLEND_GAUSS)


def _end_points(p: np.ndarray, t: np.ndarray, k: np.ndarray, h1: float, h2: float,
                h3: float) -> list[np.ndarray]:
    """Four control points at one end of the blend (tangent ``t`` pointing into it)."""
    kk = _G3_FACTOR_A * h1 * h1 + _G3_FACTOR_B * h1 * (h2 - 2.0 * h1)
    return [p, p + h1 * t, p + h2 * t + _G2_FACTOR * h1 * h1 * k, p + h3 * t + kk * k]


def _tangent_reach(pa: np.ndarray, ta: np.ndarray, pb: np.ndarray, tb: np.ndarray,
                   radius: float) -> tuple[float, float]:
    """Distances [m] from ``pa`` along ``ta`` and back from ``pb`` along ``tb`` to where
    the two tangent lines meet (their closest points when skew), each kept within
    ``[BLEND_REACH_MIN * radius, radius]``; ``radius`` for both when the tangents are
    parallel. Between two lines they are ``radius``; at an arc they are shorter (the
    arc's tangent line meets the other one sooner) and the handles follow, so the
    control polygon does not run past the corner and back (an inflection)."""
    c = float(np.dot(ta, tb))
    if 1.0 - abs(c) < 1e-9:
        return radius, radius
    w = pb - pa
    # pa + da ta and pb - db tb closest: da + c db = w.ta, c da + db = w.tb
    det = 1.0 - c * c
    wa, wb = float(np.dot(w, ta)), float(np.dot(w, tb))
    da = (wa - c * wb) / det
    db = (wb - c * wa) / det
    lo = BLEND_REACH_MIN * radius
    return min(max(da, lo), radius), min(max(db, lo), radius)


def _acceptable(ctrl: np.ndarray, corner: np.ndarray, radius: float, chord: np.ndarray) -> bool:
    """Whether a blend's control points all lie within ``radius`` of ``corner`` and its
    control polygon runs forward along ``chord`` (every edge's projection on it at
    least :data:`BLEND_MONOTONE` of the edge): then ``B'(u) . chord > 0`` on the whole
    curve, which cannot fold back on itself (a near-cusp, where the curvature would
    grow without bound)."""
    if np.linalg.norm(ctrl - corner, axis=1).max() > radius * (1.0 + 1e-12):
        return False
    cn = float(np.linalg.norm(chord))
    if cn <= 1e-9 * radius:  # a reversal: no forward direction to keep
        return True
    edges = np.diff(ctrl, axis=0)
    proj = edges @ (chord / cn)
    return bool((proj >= BLEND_MONOTONE * np.linalg.norm(edges, axis=1)).all())


class BezierBlend:
    """Degree-7 Bezier corner blend, G3 with the pieces it joins.

    From ``pa`` (unit tangent ``ta``, curvature vector ``ka`` of the incoming
    piece there) to ``pb`` (``tb``, ``kb``). At each end the blend has the
    piece's tangent, curvature vector and a zero rate of curvature and of
    torsion (those of a line or an arc): the tool's and the joints'
    accelerations are continuous and their jerk too, but for the terms of the
    speed's own changes. Control points ``pa + h1 ta``, ``pa + h2 ta + 7/6
    h1^2 ka``, ``pa + h3 ta + c ka`` (``h`` from :data:`BLEND_HANDLES` or
    :data:`BLEND_HANDLES_CURVED` times the end's tangent reach,
    ``_G3_FACTOR_A``/``_G3_FACTOR_B`` for ``c``), and symmetrically at ``pb``.
    The curve lies in the convex hull of its control points; on lines they
    all lie within ``radius`` of ``corner``, and where a curvature term puts
    one outside, the handles are shortened (:data:`BLEND_SHRINK`) until none
    is. Parameterised by arc length (``point``, ``length``).

    Parameters
    ----------
    pa, pb : ndarray, shape (3,) [m]
    ta, tb : ndarray, shape (3,)
        Unit tangents.
    radius : float [m]
        Distance of ``pa`` and ``pb`` from the corner along the pieces.
    ka, kb : ndarray, shape (3,) [1/m], optional
        Curvature vectors (kappa times the principal normal); zero on lines.
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
        da, db = _tangent_reach(pa, ta, pb, tb, radius)
        chord = pb - pa
        # the curvature of the circle tangent to both tangent lines r from the
        # corner (or the ends' own, if larger): what the blend's peak is measured by
        c = float(np.clip(np.dot(ta, tb), -1.0, 1.0))
        k_ref = max(math.sqrt(max(1.0 - c, 0.0) / (1.0 + c)) / radius if c > -1.0 else math.inf,
                    float(np.linalg.norm(ka)), float(np.linalg.norm(kb)))
        # the handle sets in order of preference: the end's own (curved or line
        # handles), shortened step by step; then the line handles, shortened. The
        # first whose control polygon is acceptable and whose peak curvature is
        # within BLEND_KAPPA_RATIO of k_ref is taken, else the acceptable one with
        # the lowest peak curvature (a sharp corner), else the last
        sets = [(BLEND_HANDLES_CURVED if ka.any() else BLEND_HANDLES,
                 BLEND_HANDLES_CURVED if kb.any() else BLEND_HANDLES)]
        if ka.any() or kb.any():
            sets.append((BLEND_HANDLES, BLEND_HANDLES))
        chosen: tuple[float, np.ndarray, float] | None = None
        ctrl = np.empty((8, 3))
        handle = 0.0
        for fa, fb in sets:
            for scale in BLEND_SHRINK:
                ha = [scale * f * da for f in fa]
                hb = [scale * f * db for f in fb]
                ctrl = np.array(_end_points(pa, ta, ka, *ha) + _end_points(pb, -tb, kb, *hb)[::-1])
                handle = ha[0]
                if not _acceptable(ctrl, corner, radius, chord):
                    continue
                peak = self._peak_curvature(ctrl)
                if peak <= BLEND_KAPPA_RATIO * k_ref:
                    chosen = (peak, ctrl, handle)
                    break
                if chosen is None or peak < chosen[0]:
                    chosen = (peak, ctrl, handle)
            else:
                continue
            break
        if chosen is not None:
            peak, ctrl, handle = chosen
        else:
            peak = self._peak_curvature(ctrl)
        self.ctrl = ctrl
        #: Largest curvature of the blend [1/m] (on the probe points).
        self.peak_curvature = peak
        self.handle = handle
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
    def _peak_curvature(cls, ctrl: np.ndarray) -> float:
        """Largest curvature [1/m] of the curve on BLEND_PROBE points."""
        u = np.linspace(0.0, 1.0, BLEND_PROBE)
        d1 = cls._eval(ctrl, u, 1)
        d2 = cls._eval(ctrl, u, 2)
        sp = np.linalg.norm(d1, axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            kap = np.linalg.norm(np.cross(d1, d2), axis=1) / sp**3
        return float(np.nan_to_num(kap, nan=np.inf).max())

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
        s = np.atleast_1d(np.asarray(s, dtype=np.float64))
        if _bezier_jit.AVAILABLE:  # the same steps, compiled
            return _bezier_jit.points_at(self.ctrl, self._u, self._cum, _GL_X, _GL_W, BLEND_NEWTON,
                                         np.ascontiguousarray(s.ravel()))[0]
        return self._eval(self.ctrl, self.u_of_s(s))

    def derivatives(self, s: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Positions and their first three derivatives in arc length at ``s`` (n,) [m].

        Exact in the curve parameter ``u``: with ``B', B'', B'''`` the curve's
        derivatives in ``u`` and ``sigma = |B'|`` (``ds/du``),
        ``p' = B' / sigma``, ``p'' = N / sigma^3`` with ``N = B'' sigma - B' sigma'``,
        ``p''' = (N' / sigma^3 - 3 N sigma' / sigma^4) / sigma`` with
        ``N' = B''' sigma - B' sigma''``.

        Returns
        -------
        p, d1, d2, d3 : ndarray, shape (n, 3)
            [m], [1], [1/m], [1/m^2].
        """
        s = np.atleast_1d(np.asarray(s, dtype=np.float64)).ravel()
        if _bezier_jit.AVAILABLE:  # the same formulas, compiled
            p, u = _bezier_jit.points_at(self.ctrl, self._u, self._cum, _GL_X, _GL_W, BLEND_NEWTON,
                                         np.ascontiguousarray(s))
            return (p, *_bezier_jit.arc_derivatives(self.ctrl, u))
        u = self.u_of_s(s)
        return (self._eval(self.ctrl, u), *self._arc_derivatives(self.ctrl, u))

    @classmethod
    def _arc_derivatives(cls, ctrl: np.ndarray, u: np.ndarray) -> tuple:
        """``p', p'', p'''`` (each (n, 3)) at the curve parameters ``u`` (n,), in
        numpy (:func:`._bezier_jit.arc_derivatives` is the compiled twin)."""
        b1, b2, b3 = (cls._eval(ctrl, u, k) for k in (1, 2, 3))
        sig = np.linalg.norm(b1, axis=1)[:, None]
        d12 = np.sum(b1 * b2, axis=1)[:, None]
        sig1 = d12 / sig
        sig2 = (np.sum(b2 * b2, axis=1)[:, None] + np.sum(b1 * b3, axis=1)[:, None]) / sig \
            - d12 * sig1 / sig**2
        num = b2 * sig - b1 * sig1
        num1 = b3 * sig - b1 * sig2
        return b1 / sig, num / sig**3, (num1 / sig**3 - 3.0 * num * sig1 / sig**4) / sig


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
    feature : float, optional
        Radius of the piece's tightest curvature [m] (inf for a line): the
        length over which its geometry turns, which numerical derivatives
        along the piece have to resolve.
    derivatives : callable, optional
        ``derivatives(s (n,)) -> (p, p', p'', p''')`` (each (n, 3)): the
        positions and their exact derivatives in ``s``.
    """

    def __init__(self, kind: str, length: float, point, q0: np.ndarray, q1: np.ndarray,
                 cap: float, motion: int, tool_rate: float, cap_reason: str = "",
                 programmed: float | None = None, quat_fn=None, feature: float = math.inf,
                 derivatives=None) -> None:
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
        self.feature = float(feature)
        self._derivatives = derivatives
        self.angle = rotation_angle(q0, q1)
        # the slerp's constant rate in the tool frame [rad per unit of s], as hat(omega)
        omega = relative_rotvec(q0, q1) / self.length if self.length > 0 else np.zeros(3)
        self._omega_hat = np.array([[0.0, -omega[2], omega[1]], [omega[2], 0.0, -omega[0]],
                                    [-omega[1], omega[0], 0.0]])
        self._rate = float(np.linalg.norm(omega))
        self._rot_basis: np.ndarray | None = None  # (see rotation_taylor)

    def point(self, s: np.ndarray) -> np.ndarray:
        return self._point(np.clip(s, 0.0, self.length))

    def derivatives(self, s: np.ndarray):
        """``(p, p', p'', p''')`` (each (n, 3)) at ``s`` (n,), exact; None when the
        piece has no closed form for them."""
        if self._derivatives is None:
            return None
        return self._derivatives(np.clip(np.atleast_1d(np.asarray(s, dtype=np.float64)), 0.0,
                                         self.length))

    def rotation_taylor(self, s: np.ndarray) -> np.ndarray | None:
        """Taylor coefficients 0..3 of the tool's rotation matrix in ``s`` at ``s`` (n,),
        shape (n, 4, 3, 3): ``R`` and its first three derivatives over ``k!``, exact;
        for an orientation given by ``quat_fn``, its ``taylor`` (a corner blend's
        cross-fade: :class:`BlendedOrientation`), None if it has none.

        The slerp from ``q0`` to ``q1`` turns at a constant rate about an axis fixed
        in the tool frame, ``R(s) = R(0) Exp(s hat(omega))``, so the k-th derivative
        is ``R(s) hat(omega)^k``; with Rodrigues' formula for ``Exp``, every
        coefficient is a fixed matrix plus ``sin(|omega| s)`` and ``1 - cos(|omega|
        s)`` times two more (the same rotations as :meth:`quat`'s to a few ulps)."""
        if self.quat_fn is not None:
            taylor = getattr(self.quat_fn, "taylor", None)
            if taylor is None:
                return None
            return taylor(np.clip(np.atleast_1d(np.asarray(s, dtype=np.float64)), 0.0, self.length))
        # Rodrigues: R(s) = R(0) (I + sin(w s) K + (1 - cos(w s)) K^2), K = hat(omega) / w,
        # so every coefficient R(s) hat(omega)^k / k! is C0 + sin(w s) C1 + (1 - cos(w s)) C2
        # with three fixed (4, 3, 3) bases
        if self._rot_basis is None:
            w = self._omega_hat
            K = w / self._rate if self._rate > 0.0 else np.zeros((3, 3))
            R0 = matrix_from_quat(self.q0)
            powers = [np.eye(3), w, w @ w / 2.0, w @ w @ w / 6.0]
            self._rot_basis = np.stack([np.stack([M @ P for P in powers])
                                        for M in (R0, R0 @ K, R0 @ K @ K)])
        s = np.atleast_1d(np.asarray(s, dtype=np.float64))
        th = self._rate * np.clip(s, 0.0, self.length)
        half = np.sin(0.5 * th)
        c0, c1, c2 = self._rot_basis
        return (c0[None] + np.sin(th)[:, None, None, None] * c1[None]
                + (2.0 * half * half)[:, None, None, None] * c2[None])

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
    return BlendedOrientation(qa0, qa1, len_a, sa, qb0, qb1, len_b, sb, length)


class BlendedOrientation:
    """A corner blend's orientation (see :func:`blended_orientation`): called with
    ``s`` (n,), the unit quaternions (n, 4); :meth:`taylor`, the rotation
    matrix's exact Taylor coefficients."""

    def __init__(self, qa0, qa1, len_a: float, sa: float, qb0, qb1, len_b: float, sb: float,
                 length: float) -> None:
        self.qa0, self.qa1, self.len_a, self.sa = qa0, qa1, float(len_a), float(sa)
        self.qb0, self.qb1, self.len_b, self.sb = qb0, qb1, float(len_b), float(sb)
        self.length = float(length)

    def __call__(self, s: np.ndarray) -> np.ndarray:
        ua = (self.sa + s) / self.len_a
        ub = (self.sb - (self.length - s)) / self.len_b
        a = slerp_any(self.qa0, self.qa1, ua)
        b = slerp_any(self.qb0, self.qb1, ub)
        return slerp_rows(a, b, smootherstep(s / self.length))

    def taylor(self, s: np.ndarray) -> np.ndarray:
        """Taylor coefficients 0..3 (n, 4, 3, 3) of the rotation matrix at ``s`` (n,)."""
        f64 = np.float64
        return _orient_jets.blend_rotation_taylor(
            np.ascontiguousarray(self.qa0, dtype=f64), relative_rotvec(self.qa0, self.qa1), self.len_a,
            self.sa, np.ascontiguousarray(self.qb0, dtype=f64), relative_rotvec(self.qb0, self.qb1),
            self.len_b, self.sb, self.length,
            np.ascontiguousarray(np.atleast_1d(s), dtype=f64), float(_orient_jets.SERIES_ANGLE))


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


def sub_path_derivatives(path: Path, a: float):
    """``derivatives`` callable (see :class:`Piece`) of a line or a circular arc
    ``path`` from its arc length ``a`` on; None for another path."""
    if isinstance(path, Line):
        p0, u, length = path.p0, path.direction, path.length

        def line(s: np.ndarray):  # (Line's own formula: p0 + s u)
            z = np.zeros((s.size, 3))
            at = np.clip(a + s, 0.0, length)
            return p0 + at[:, None] * u, np.broadcast_to(u, (s.size, 3)).copy(), z, z.copy()
        return line
    if isinstance(path, Arc3):
        def arc(s: np.ndarray):
            at = np.clip(a + s, 0.0, path.length)
            p = path.point(at)
            t = path.tangent(at)
            r2 = path.radius**2
            return p, t, (path.centre - p) / r2, -t / r2
        return arc
    return None


def constant_point(p: np.ndarray):
    """``point`` callable of an orientation-only piece (the tool stays at ``p``)."""
    def point(s: np.ndarray) -> np.ndarray:
        return np.broadcast_to(p, (np.atleast_1d(s).size, 3)).copy()
    return point


def constant_point_derivatives(p: np.ndarray):
    """``derivatives`` callable (see :class:`Piece`) of an orientation-only piece."""
    def derivatives(s: np.ndarray):
        z = np.zeros((np.atleast_1d(s).size, 3))
        return np.broadcast_to(p, z.shape).copy(), z, z.copy(), z.copy()
    return derivatives


def angle_between_tangents(ta: np.ndarray, tb: np.ndarray) -> float:
    """Angle [rad] between two unit tangents."""
    return math.acos(max(-1.0, min(1.0, float(np.dot(ta, tb)))))
