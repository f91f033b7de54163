"""Saddle curves: the seam where a branch pipe meets a main pipe (Chen et al., 2013).

Convention: the branch axis is the z axis, the seam is
parameterised by the angle theta around it, measured from the +y axis
towards +x. The main pipe's axis passes through ``(offset, 0, 0)`` with
direction ``m = (0, sin(angle), cos(angle))``: ``angle`` is the angle between
the branch axis and the main axis (pi/2: perpendicular, main axis = y axis).

Every seam point lies on the branch cylinder ``x^2 + y^2 = r^2``:

    x = r sin(theta),  y = r cos(theta)

and on the main cylinder (distance R from the main axis). Putting the
point into the main cylinder's equation gives a quadratic in z whose upper
root is exact:

    z(theta) = r cos(theta) cot(angle) + sqrt(R^2 - (r sin(theta) - offset)^2) / sin(angle)

For ``angle = pi/2, offset = 0`` this is the equation of Chen et al. (2013)
``z = sqrt(R^2 - r^2 sin^2 theta)``. The branch meets the main pipe all the
way round iff ``|offset| + r < R``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.fft import dct
from scipy.special import roots_legendre

from .._validate import check_finite, check_positive
from ..errors import InvalidInputError
from . import _saddle_jit
from ._tolerances import (
    ARC_INVERSION_MAX_ITER,
    ARC_INVERSION_RTOL,
    GAUSS_ORDER,
    MAX_COORDINATE,
    NEWTON_LAST_STEP,
    SADDLE_FIT_CHOP,
    SADDLE_FIT_RTOL,
    SADDLE_LENGTH_RTOL,
    THETA_RANGE_ATOL,
)
from .base import Path, check_size

__all__ = ["SaddleCurve"]

_TWO_PI = 2.0 * math.pi
#: First size of the arc-length table (intervals per turn); doubled until
#: two successive tables agree to SADDLE_LENGTH_RTOL.
_TABLE_START = 32
_TABLE_MAX = 1 << 16
#: Intervals of the inverse table theta(s) (first guesses for Newton).
_INVERSE_TABLE = 4096

#: Chebyshev points (plus one) of ds/dtheta per table interval, the largest
#: degree kept, and the angles per interval where the series is checked
#: against the quadrature (:meth:`SaddleCurve._fit_table`).
_FIT_SAMPLES = 32
_FIT_MAX_DEGREE = 24
_FIT_CHECKS = 6

#: Points evaluated at once by the arc-length inversions (bounds their memory:
#: the quadrature holds GAUSS_ORDER values per point).
_CHUNK = 1 << 15


class SaddleCurve(Path):
    """Intersection of a branch pipe (radius r) with a main pipe (radius R).

    Parameters
    ----------
    main_radius : float
        R [m], > 0.
    branch_radius : float
        r [m], > 0.
    angle : float
        Angle between the branch axis and the main axis [rad], in (0, pi);
        ``pi/2`` (default) is the orthogonal tee of Chen et al. (2013).
    offset : float
        Distance [m] along x between the main axis and the branch axis
        (0: the axes meet).
    theta_start : float
        Angle [rad] where the seam (and the feed) starts; one full turn.

    Raises
    ------
    InvalidInputError
        For non-positive radii, an angle outside (0, pi), or pipes that do
        not meet all the way round (``|offset| + r >= R``; at equality the
        seam has corners).

    Notes
    -----
    Point, tangent and curvature are exact functions of theta. The arc
    length ``s(theta) = int sqrt(r^2 + z'(theta)^2) dtheta`` is computed by
    composite Gauss-Legendre quadrature on a table refined until two
    tables agree to :data:`SADDLE_LENGTH_RTOL` (relative error bound of
    ``length`` and of every ``s(theta)``); ``theta(s)`` is the Newton root of
    ``s(theta) = s`` to :data:`ARC_INVERSION_RTOL` of the length. Inside each
    table interval that Newton iteration evaluates ``s(theta)`` by a
    Chebyshev series fitted at construction and checked against the
    quadrature to :data:`SADDLE_FIT_RTOL` of the interval's arc length
    (intervals where it is not met, near-touching pipes, keep the
    quadrature); :meth:`s_of_theta` is always the quadrature.
    """

    closed = True

    def __init__(
        self,
        main_radius: float,
        branch_radius: float,
        angle: float = math.pi / 2,
        offset: float = 0.0,
        theta_start: float = 0.0,
    ) -> None:
        R = check_size(check_positive(main_radius, "main pipe radius R"), "main pipe radius R")
        r = check_size(check_positive(branch_radius, "branch pipe radius r"), "branch pipe radius r")
        a = check_finite(angle, "branch angle")
        d = check_finite(offset, "branch offset")
        if abs(d) > MAX_COORDINATE:
            raise InvalidInputError(f"branch offset {d:.6g} m is outside the supported range "
                                    f"+-{MAX_COORDINATE:g} m")
        th0 = check_finite(theta_start, "theta_start")
        if not 0.0 < a < math.pi:
            raise InvalidInputError(
                f"branch angle must lie strictly between 0 and 180 deg, got {math.degrees(a)!r} deg"
            )
        if abs(d) + r >= R:
            raise InvalidInputError(
                f"the pipes do not meet all the way round: branch radius r={r!r} plus "
                f"|offset|={abs(d)!r} must be below the main radius R={R!r} "
                f"(r + |offset| = {r + abs(d)!r})"
            )
        self.main_radius = R
        self.branch_radius = r
        self.angle = a
        self.offset = d
        self.theta_start = th0
        self._cot = math.cos(a) / math.sin(a)
        self._sin = math.sin(a)
        self.main_axis_point = np.array([d, 0.0, 0.0])
        self.main_axis_direction = np.array([0.0, math.sin(a), math.cos(a)])
        self._build_table()

    # ------------------------------------------------------------- geometry
    def z_derivatives(self, theta: Any) -> np.ndarray:
        """z(theta) and its first three derivatives, exact.

        Parameters
        ----------
        theta : array_like, shape (n,)
            Angles [rad].

        Returns
        -------
        ndarray, shape (4, n)
            ``z, dz/dtheta, d2z/dtheta2, d3z/dtheta3`` [m, m/rad, ...].
        """
        th = np.atleast_1d(np.asarray(theta, dtype=float))
        r, R, d = self.branch_radius, self.main_radius, self.offset
        sn, cs = np.sin(th), np.cos(th)
        w, w1, w2, w3 = r * sn - d, r * cs, -r * sn, -r * cs
        q = np.sqrt(R * R - w * w)
        q1 = -w * w1 / q
        q2 = (-(w1 * w1 + w * w2) - q1 * q1) / q
        q3 = (-(3.0 * w1 * w2 + w * w3) - 3.0 * q1 * q2) / q
        k, s = r * self._cot, self._sin
        out = np.empty((4,) + th.shape)
        np.add(k * cs, q / s, out=out[0])
        np.add(-k * sn, q1 / s, out=out[1])
        np.add(-k * cs, q2 / s, out=out[2])
        np.add(k * sn, q3 / s, out=out[3])
        return out

    def point_theta(self, theta: Any) -> np.ndarray:
        """Seam points at angles ``theta`` [rad]: shape (n, 3) [m]."""
        th = np.atleast_1d(np.asarray(theta, dtype=float))
        z = self.z_derivatives(th)[0]
        r = self.branch_radius
        return np.column_stack([r * np.sin(th), r * np.cos(th), z])

    def derivatives_theta(self, theta: Any) -> np.ndarray:
        """dc/dtheta, d2c/dtheta2, d3c/dtheta3 of the seam, exact.

        Returns
        -------
        ndarray, shape (3, n, 3)
        """
        th = np.atleast_1d(np.asarray(theta, dtype=float))
        z = self.z_derivatives(th)
        r = self.branch_radius
        sn, cs = np.sin(th), np.cos(th)
        d1 = np.column_stack([r * cs, -r * sn, z[1]])
        d2 = np.column_stack([-r * sn, -r * cs, z[2]])
        d3 = np.column_stack([-r * cs, r * sn, z[3]])
        return np.stack([d1, d2, d3])

    def speed_theta(self, theta: Any) -> np.ndarray:
        """ds/dtheta = sqrt(r^2 + z'^2) [m/rad], shape (n,)."""
        th = np.asarray(theta, dtype=float)
        r, R, d = self.branch_radius, self.main_radius, self.offset
        sn, cs = np.sin(th), np.cos(th)
        w = r * sn - d
        z1 = -r * self._cot * sn - w * (r * cs) / (np.sqrt(R * R - w * w) * self._sin)
        return np.sqrt(r * r + z1 * z1)

    def branch_residual(self, points: Any) -> np.ndarray:
        """Distance from the branch axis minus r [m] (0 on the branch cylinder), shape (n,)."""
        p = np.atleast_2d(np.asarray(points, dtype=float))
        return np.hypot(p[:, 0], p[:, 1]) - self.branch_radius

    def main_residual(self, points: Any) -> np.ndarray:
        """Distance from the main axis minus R [m] (0 on the main cylinder), shape (n,)."""
        p = np.atleast_2d(np.asarray(points, dtype=float)) - self.main_axis_point
        along = p @ self.main_axis_direction
        perp = p - along[:, None] * self.main_axis_direction
        return np.linalg.norm(perp, axis=1) - self.main_radius

    # ---------------------------------------------------------- arc length
    def _table(self, n: int) -> np.ndarray:
        edges = self.theta_start + np.linspace(0.0, _TWO_PI, n + 1)
        h = np.diff(edges)
        x = (edges[:-1, None] + edges[1:, None]) / 2.0 + (h[:, None] / 2.0) * self._gx
        seg = (h / 2.0) * (self.speed_theta(x.ravel()).reshape(x.shape) @ self._gw)
        return np.concatenate([[0.0], np.cumsum(seg)])

    def _build_table(self) -> None:
        self._gx, self._gw = roots_legendre(GAUSS_ORDER)
        n = _TABLE_START
        prev = self._table(n)
        while True:
            cur = self._table(2 * n)
            err = float(np.max(np.abs(cur[::2] - prev)))
            n *= 2
            if err <= SADDLE_LENGTH_RTOL * cur[-1] or n >= _TABLE_MAX:
                break
            prev = cur
        if err > SADDLE_LENGTH_RTOL * cur[-1]:  # pragma: no cover - only for near-touching pipes
            raise InvalidInputError(
                f"saddle arc length does not converge (pipes nearly touching: r + |offset| = "
                f"{self.branch_radius + abs(self.offset)!r}, R = {self.main_radius!r})"
            )
        self._edges = self.theta_start + np.linspace(0.0, _TWO_PI, n + 1)
        self._cum = cur
        self.length = float(cur[-1])
        self.length_error_estimate = err
        self._fit_table()
        # inverse table theta(s) on equal arc-length steps, for Hermite first guesses
        empty = np.zeros(0)
        self._inv = (empty, empty, empty, np.zeros(0, dtype=np.int64))
        sg = np.linspace(0.0, self.length, _INVERSE_TABLE + 1)
        thg = self._invert(sg)
        kg = np.clip(np.searchsorted(self._cum, sg, side="right") - 1, 0, len(self._edges) - 2)
        self._inv = (sg, thg, 1.0 / self.speed_theta(thg), kg.astype(np.int64))

    def _fit_table(self) -> None:
        """Chebyshev series of the arc length inside every table interval.

        In the interval ``[a, b]`` with ``x = 2 (theta - a) / (b - a) - 1``,
        ``ds/dtheta`` is interpolated at ``_FIT_SAMPLES + 1`` Chebyshev points
        and its series cut after the last coefficient above
        :data:`SADDLE_FIT_CHOP` of the first (the mean speed). The arc length
        from ``a`` is ``(theta - a) Q(x)``, ``Q`` = the integral of that series
        from -1 to x divided by ``x + 1`` (exact polynomial division; the
        mean speed over ``[a, theta]``). Each series is then compared with
        the Gauss-Legendre quadrature from ``a`` at ``_FIT_CHECKS`` angles of
        the interval (its end included); an interval whose series needs a
        degree above ``_FIT_MAX_DEGREE`` or misses the quadrature by more than
        :data:`SADDLE_FIT_RTOL` of the interval's arc length keeps the
        quadrature (degree -1).
        """
        a, b = self._edges[:-1], self._edges[1:]
        T, N = a.size, _FIT_SAMPLES
        xc = np.cos(np.pi * np.arange(N + 1) / N)
        f = self.speed_theta((a + b)[:, None] / 2.0 + ((b - a) / 2.0)[:, None] * xc)
        c = dct(f, type=1, axis=1) / N  # Chebyshev coefficients of ds/dtheta
        c[:, 0] /= 2.0
        c[:, N] /= 2.0
        big = np.abs(c) > SADDLE_FIT_CHOP * np.abs(c[:, :1])
        deg = N - np.argmax(big[:, ::-1], axis=1)
        deg = np.where(deg <= _FIT_MAX_DEGREE, deg, -1)
        M = _FIT_MAX_DEGREE
        cp = np.zeros((T, M + 3))  # c_0 .. c_M, then zeros
        cp[:, :M + 1] = np.where(np.arange(M + 1) <= deg[:, None], c[:, :M + 1], 0.0)
        # A(x) = int_{-1}^x sum c_j T_j: C_n = (c_{n-1} - c_{n+1}) / (2 n), A(-1) = 0
        C = np.zeros((T, M + 3))
        C[:, 2:M + 2] = (cp[:, 1:M + 1] - cp[:, 3:M + 3]) / (2.0 * np.arange(2, M + 2))
        C[:, 1] = cp[:, 0] - cp[:, 2] / 2.0
        C[:, 0] = -(C[:, 1:] @ (-1.0) ** np.arange(1, M + 3))
        # A = (1 + x) D: C_n = d_n + (d_{n-1} + d_{n+1}) / 2 (n >= 2), C_1 = d_1 + d_0 + d_2 / 2
        D = np.zeros((T, M + 3))
        for j in range(M + 1, 1, -1):
            D[:, j - 1] = 2.0 * (C[:, j] - D[:, j]) - D[:, j + 1]
        D[:, 0] = C[:, 1] - D[:, 1] - D[:, 2] / 2.0
        self._scale = 2.0 / (b - a)
        self._coef = np.ascontiguousarray(D[:, :M + 1])
        self._deg = deg.astype(np.int64)
        # validation against the quadrature
        u = np.concatenate([(1.0 - np.cos(np.pi * (np.arange(_FIT_CHECKS - 1) + 0.5) / (_FIT_CHECKS - 1))) / 2.0,
                            [1.0]])
        k = np.repeat(np.flatnonzero(deg >= 0), u.size)
        th = np.minimum(a[k] + (b - a)[k] * np.tile(u, k.size // u.size), b[k])
        miss = np.abs(self._fitted_arc(k, th) - self._quadrature_arc(k, th))
        bad = np.zeros(T, dtype=bool)
        np.logical_or.at(bad, k, miss > SADDLE_FIT_RTOL * np.diff(self._cum)[k])
        self._deg[bad] = -1

    def s_of_theta(self, theta: Any) -> np.ndarray:
        """Arc length [m] from ``theta_start`` to ``theta`` (in [theta_start, theta_start + 2 pi]).

        Returns
        -------
        ndarray, shape (n,)
        """
        th = np.atleast_1d(np.asarray(theta, dtype=float))
        lo, hi = self.theta_start, self.theta_start + _TWO_PI
        if th.size and (np.min(th) < lo - THETA_RANGE_ATOL or np.max(th) > hi + THETA_RANGE_ATOL):
            raise InvalidInputError(
                f"theta must lie in [{lo!r}, {hi!r}] rad, got a value in "
                f"[{float(np.min(th))!r}, {float(np.max(th))!r}]"
            )
        th = np.clip(th, lo, hi)
        out = np.empty_like(th)
        for i in range(0, th.size, _CHUNK):
            part = th[i:i + _CHUNK]
            k = np.clip(np.searchsorted(self._edges, part, side="right") - 1, 0, len(self._edges) - 2)
            out[i:i + _CHUNK] = self._partial(k, part)
        return out

    def _partial(self, k: np.ndarray, th: np.ndarray) -> np.ndarray:
        return self._cum[k] + self._quadrature_arc(k, th)

    def _quadrature_arc(self, k: np.ndarray, th: np.ndarray) -> np.ndarray:
        """Arc length [m] from the table node ``k`` to ``th`` by Gauss-Legendre quadrature, shape (n,)."""
        a = self._edges[k]
        h = th - a
        x = a[:, None] + (h[:, None] / 2.0) * (1.0 + self._gx)
        return (h / 2.0) * (self.speed_theta(x.ravel()).reshape(x.shape) @ self._gw)

    def _fitted_arc(self, k: np.ndarray, th: np.ndarray) -> np.ndarray:
        """Arc length [m] from the table node ``k`` to ``th`` by the interval's
        series (:meth:`_fit_table`; intervals with one only), shape (n,)."""
        a = self._edges[k]
        x = (th - a) * self._scale[k] - 1.0
        coef = self._coef[k]
        b1 = np.zeros_like(x)
        b2 = np.zeros_like(x)
        for j in range(int(np.max(self._deg[k], initial=0)), 0, -1):  # Clenshaw
            b1, b2 = coef[:, j] + 2.0 * x * b1 - b2, b1
        return (th - a) * (coef[:, 0] + x * b1 - b2)

    def theta_of_s(self, s: Any) -> np.ndarray:
        """Angle theta [rad] at arc length ``s`` [m] (Newton on the arc length).

        Parameters
        ----------
        s : array_like, shape (n,)
            Arc lengths [m] in [0, length], in any order.

        Returns
        -------
        ndarray, shape (n,)
            Angles in [theta_start, theta_start + 2 pi]; ``s_of_theta`` of
            them is ``s`` to round-off (the Newton step after a residual
            within the tolerance squares it).
        """
        ss, _ = self._prep(s)
        return self._invert(ss)

    def _invert(self, ss: np.ndarray) -> np.ndarray:
        """theta_of_s of arc lengths ``ss`` (n,) [m] already within [0, length]."""
        if _saddle_jit.AVAILABLE:  # the same steps, compiled
            return _saddle_jit.theta_of_s(np.ascontiguousarray(ss, dtype=np.float64), *self._inversion_args())
        tol = self._inversion_tol()
        out = np.empty_like(ss)
        for i in range(0, ss.size, _CHUNK):
            part = ss[i:i + _CHUNK]
            out[i:i + _CHUNK] = self._newton(part, tol)
        return out

    def _inversion_tol(self) -> float:
        """Residual [m] after which the arc-length inversion takes its last Newton step."""
        return max(ARC_INVERSION_RTOL * self.length, NEWTON_LAST_STEP * self.branch_radius)

    def _inversion_args(self) -> tuple:
        """The curve's data for the compiled inversion, in the order of
        :func:`~trajkit.paths._saddle_jit.theta_of_s` after the arc lengths (tables,
        geometry, tolerance [m], iteration limit)."""
        sg, thg, dg, kg = self._inv
        return (self._edges, self._cum, self._scale, self._coef, self._deg, sg, thg, dg, kg,
                self._gx, self._gw, self.branch_radius, self.main_radius, self.offset, self._cot,
                self._sin, self._inversion_tol(), ARC_INVERSION_MAX_ITER)

    def _newton(self, ss: np.ndarray, tol: float) -> np.ndarray:
        k = np.clip(np.searchsorted(self._cum, ss, side="right") - 1, 0, len(self._edges) - 2)
        a, b = self._edges[k], self._edges[k + 1]
        sg, thg, dg, _ = self._inv
        if sg.size > 1:  # cubic Hermite on the inverse table
            h = sg[1] - sg[0]
            j = np.clip((ss / h).astype(np.int64), 0, len(sg) - 2)
            u = (ss - sg[j]) / h
            h00, h10 = (1 + 2 * u) * (1 - u) ** 2, u * (1 - u) ** 2
            h01, h11 = u * u * (3 - 2 * u), u * u * (u - 1)
            th = h00 * thg[j] + h10 * h * dg[j] + h01 * thg[j + 1] + h11 * h * dg[j + 1]
        else:  # linear in the table interval (while the inverse table is built)
            ca, cb = self._cum[k], self._cum[k + 1]
            th = a + (b - a) * (ss - ca) / (cb - ca)
        th = np.clip(th, a, b)
        fit = self._deg[k] >= 0
        kf, kq = k[fit], k[~fit]
        res = np.empty_like(ss)
        for _ in range(ARC_INVERSION_MAX_ITER):
            res[fit] = self._cum[kf] + self._fitted_arc(kf, th[fit]) - ss[fit]
            if kq.size:
                res[~fit] = self._cum[kq] + self._quadrature_arc(kq, th[~fit]) - ss[~fit]
            th = np.clip(th - res / self.speed_theta(th), a, b)
            # residual below NEWTON_LAST_STEP * r: the step just taken squares
            # it (quadratic convergence), far below ARC_INVERSION_RTOL
            if np.max(np.abs(res), initial=0.0) <= tol:
                break
        return th

    # ------------------------------------------------------ Path interface
    def _point(self, s):
        return self.point_theta(self.theta_of_s(s))

    def _tangent(self, s):
        d1 = self.derivatives_theta(self.theta_of_s(s))[0]
        return d1 / np.linalg.norm(d1, axis=1)[:, None]

    def _curvature(self, s):
        return self.curvature_theta(self.theta_of_s(s))

    def curvature_theta(self, theta: Any) -> np.ndarray:
        """Curvature |c' x c''| / |c'|^3 [1/m] at angles ``theta``, exact; shape (n,)."""
        d = self.derivatives_theta(theta)
        return np.linalg.norm(np.cross(d[0], d[1]), axis=1) / np.linalg.norm(d[0], axis=1) ** 3

    def curvature_grid(self, n: int = 4097) -> tuple[np.ndarray, np.ndarray]:
        th = self.theta_start + np.linspace(0.0, _TWO_PI, n)
        return self.s_of_theta(th), self.curvature_theta(th)

    def uniform_nodes(self, n: int) -> np.ndarray:
        """Arc lengths of ``n`` equal theta steps (the "points per turn" of Chen et al., 2013)."""
        th = self.theta_start + np.linspace(0.0, _TWO_PI, int(n) + 1)
        out = self.s_of_theta(th)
        out[0], out[-1] = 0.0, self.length
        return out

    # --------------------------------------------------------- machine axes
    def machine_axes(self, s: Any) -> np.ndarray:
        """Machine axes theta [rad] and Z [m] and their derivatives in arc length.

        The seam lies on the branch cylinder, so the torch needs only the
        rotary axis theta (around the branch) and the linear axis Z (along
        it); its distance from the branch axis is always r (no radial axis).

        Parameters
        ----------
        s : array_like, shape (n,)
            Arc lengths [m].

        Returns
        -------
        ndarray, shape (2, 4, n)
            ``[axis][order]``: axis 0 = theta [rad], 1 = Z [m]; order 0..3 =
            value, d/ds, d2/ds2, d3/ds3 (per metre of seam, exact).
        """
        ss, _ = self._prep(s)
        return self.machine_axes_theta(self.theta_of_s(ss))

    def machine_axes_theta(self, theta: Any) -> np.ndarray:
        """:meth:`machine_axes` at the angles ``theta`` [rad] (n,) instead of arc lengths."""
        th = np.asarray(theta, dtype=float)
        z = self.z_derivatives(th)
        out = np.empty((2, 4) + th.shape)  # written in place: no stacked copies
        r2 = self.branch_radius ** 2
        sig = np.sqrt(r2 + z[1] ** 2)
        sig1 = z[1] * z[2] / sig
        sig2 = (z[2] ** 2 + z[1] * z[3] - sig1 ** 2) / sig
        sig3 = sig ** 3
        out[0, 0] = th
        t1 = np.divide(1.0, sig, out=out[0, 1])
        t2 = np.divide(-sig1, sig3, out=out[0, 2])
        t3 = np.divide(-sig2 / sig3 + 3.0 * sig1 ** 2 / sig ** 4, sig, out=out[0, 3])
        out[1, 0] = z[0]
        np.multiply(z[1], t1, out=out[1, 1])  # dZ/ds
        np.add(z[2] * t1 ** 2, z[1] * t2, out=out[1, 2])
        np.add(z[3] * t1 ** 3 + 3.0 * z[2] * t1 * t2, z[1] * t3, out=out[1, 3])
        return out

    def to_dict(self) -> dict:
        return {
            "type": "SaddleCurve", "length": self.length, "main_radius": self.main_radius,
            "branch_radius": self.branch_radius, "angle": self.angle, "offset": self.offset,
            "theta_start": self.theta_start,
        }

    def __repr__(self) -> str:
        return (f"SaddleCurve(main_radius={self.main_radius!r}, branch_radius={self.branch_radius!r}, "
                f"angle={self.angle!r}, offset={self.offset!r})")
