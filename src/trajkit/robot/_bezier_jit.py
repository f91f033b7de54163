"""Compiled arc-length inversion of a blend's Bezier curve (:func:`points_at`)
and its derivatives in arc length (:func:`arc_derivatives`).

The same steps as :meth:`trajkit.robot._pieces.BezierBlend.u_of_s` (the
arc-length table, then Newton steps on the arc length from the table node
below, each integrated by Gauss-Legendre quadrature) and the curve's point
there, point by point in one compiled loop; the point by de Casteljau's
algorithm, the speed |B'(u)| by Horner's scheme on the derivative's
power-basis coefficients; a point's steps end early at a fixed point. The
same values as the numpy version to round-off. :func:`arc_derivatives`
evaluates the curve's first three derivatives in its parameter by de
Casteljau's algorithm on the differenced control points and turns them into
derivatives in arc length with the formulas of
:meth:`trajkit.robot._pieces.BezierBlend.derivatives`. Used only when numba
is available (:data:`AVAILABLE`).

Pure math: arrays in, arrays out.
"""

from __future__ import annotations

import numpy as np

from ..profiles._compile import ENABLED
from ..profiles._compile import jit as _jit

__all__ = ["AVAILABLE", "arc_derivatives", "points_at"]

#: True when the compiled loop is used (numba installed and not disabled).
AVAILABLE = ENABLED


@_jit
def _casteljau(c, u, work, out):
    """The Bezier curve of control points ``c`` (k, 3) at ``u`` into ``out`` (3,)."""
    k = c.shape[0]
    for i in range(k):
        for d in range(3):
            work[i, d] = c[i, d]
    m = 1.0 - u
    for r in range(k - 1, 0, -1):
        for i in range(r):
            for d in range(3):
                work[i, d] = m * work[i, d] + u * work[i + 1, d]
    for d in range(3):
        out[d] = work[0, d]


@_jit
def _speed(mono, u):
    """|B'(u)| from the derivative's power-basis coefficients ``mono`` (k, 3)
    (Horner's scheme)."""
    k = mono.shape[0]
    x = mono[k - 1, 0]
    y = mono[k - 1, 1]
    z = mono[k - 1, 2]
    for i in range(k - 2, -1, -1):
        x = x * u + mono[i, 0]
        y = y * u + mono[i, 1]
        z = z * u + mono[i, 2]
    return np.sqrt(x * x + y * y + z * z)


@_jit
def _power_basis(c):
    """Power-basis coefficients (k, 3) of the Bezier curve of control points ``c``
    (k, 3): ``sum_j a_j u^j`` with ``a_j = C(n, j) sum_i (-1)^(j - i) C(j, i) c_i``."""
    k = c.shape[0]
    n = k - 1
    out = np.zeros((k, 3))
    for j in range(k):
        bnj = 1.0
        for t in range(j):
            bnj = bnj * (n - t) / (t + 1)
        for i in range(j + 1):
            bji = 1.0
            for t in range(i):
                bji = bji * (j - t) / (t + 1)
            sign = 1.0 if (j - i) % 2 == 0 else -1.0
            for d in range(3):
                out[j, d] += bnj * sign * bji * c[i, d]
    return out


@_jit
def _below(table, x):
    """Index ``j`` of the last entry of the increasing ``table`` with
    ``table[j] <= x`` (``searchsorted(table, x, "right") - 1``; -1 below all)."""
    lo = 0
    hi = table.shape[0]
    while lo < hi:
        mid = (lo + hi) // 2
        if table[mid] <= x:
            lo = mid + 1
        else:
            hi = mid
    return lo - 1


@_jit
def points_at(ctrl, utab, cum, gl_x, gl_w, newton, s):
    """Points (n, 3) of the Bezier curve ``ctrl`` (k, 3) at arc lengths ``s`` (n,).

    Parameters
    ----------
    ctrl : ndarray, shape (k, 3)
        Control points [m].
    utab, cum : ndarray, shape (T + 1,)
        The arc-length table: curve parameters and the arc length [m] up to each.
    gl_x, gl_w : ndarray
        Gauss-Legendre nodes and weights on [-1, 1].
    newton : int
        Newton steps.
    s : ndarray, shape (n,)
        Arc lengths [m] (clipped to the curve).

    Returns
    -------
    points : ndarray, shape (n, 3)
    u : ndarray, shape (n,)
        The curve parameters of the points.
    """
    k = ctrl.shape[0]
    d1 = np.empty((k - 1, 3))
    for i in range(k - 1):
        for d in range(3):
            d1[i, d] = (k - 1) * (ctrl[i + 1, d] - ctrl[i, d])
    mono = _power_basis(d1)
    nt = utab.shape[0] - 1
    length = cum[nt]
    work = np.empty((k, 3))
    tmp = np.empty(3)
    n = s.shape[0]
    pts = np.empty((n, 3))
    us = np.empty(n)
    for p in range(n):
        sp = min(max(s[p], 0.0), length)
        # the table (linear interpolation of u in s)
        j = _below(cum, sp)
        if j >= nt:
            u = utab[nt]
        elif j < 0:
            u = utab[0]
        else:
            u = (utab[j + 1] - utab[j]) / (cum[j + 1] - cum[j]) * (sp - cum[j]) + utab[j]
        for _ in range(newton):
            kk = min(max(_below(utab, u), 0), nt - 1)
            a = utab[kk]
            half = 0.5 * (u - a)
            mid = 0.5 * (a + u)
            acc = 0.0
            for g in range(gl_x.shape[0]):
                acc += _speed(mono, mid + half * gl_x[g]) * gl_w[g]
            err = cum[kk] + half * acc - sp
            u_next = min(max(u - err / _speed(mono, u), 0.0), 1.0)
            if u_next == u:  # a fixed point: the steps left would repeat it
                break
            u = u_next
        us[p] = u
        _casteljau(ctrl, u, work, tmp)
        for d in range(3):
            pts[p, d] = tmp[d]
    return pts, us


@_jit
def _differenced(c):
    """Control points (k - 1, 3) of the derivative of the Bezier curve ``c`` (k, 3)."""
    k = c.shape[0]
    out = np.empty((max(k - 1, 0), 3))
    for i in range(k - 1):
        for d in range(3):
            out[i, d] = (k - 1) * (c[i + 1, d] - c[i, d])
    return out


@_jit
def arc_derivatives(ctrl, u):
    """First three derivatives in arc length of the Bezier curve ``ctrl`` (k, 3)
    at the curve parameters ``u`` (n,): ``p', p'', p'''`` (each (n, 3)) [1],
    [1/m], [1/m^2].

    With ``B', B'', B'''`` the curve's derivatives in ``u`` and
    ``sigma = |B'|``: ``p' = B' / sigma``, ``p'' = N / sigma^3`` with
    ``N = B'' sigma - B' sigma'``, ``p''' = (N' / sigma^3 - 3 N sigma' /
    sigma^4) / sigma`` with ``N' = B''' sigma - B' sigma''``.
    """
    c1 = _differenced(ctrl)
    c2 = _differenced(c1)
    c3 = _differenced(c2)
    k = ctrl.shape[0]
    work = np.empty((k, 3))
    b1 = np.zeros(3)
    b2 = np.zeros(3)
    b3 = np.zeros(3)
    n = u.shape[0]
    d1 = np.empty((n, 3))
    d2 = np.empty((n, 3))
    d3 = np.empty((n, 3))
    for p in range(n):
        if c1.shape[0]:
            _casteljau(c1, u[p], work, b1)
        if c2.shape[0]:
            _casteljau(c2, u[p], work, b2)
        if c3.shape[0]:
            _casteljau(c3, u[p], work, b3)
        sig = np.sqrt(b1[0] * b1[0] + b1[1] * b1[1] + b1[2] * b1[2])
        d12 = b1[0] * b2[0] + b1[1] * b2[1] + b1[2] * b2[2]
        sig1 = d12 / sig
        sig2 = (b2[0] * b2[0] + b2[1] * b2[1] + b2[2] * b2[2]
                + b1[0] * b3[0] + b1[1] * b3[1] + b1[2] * b3[2]) / sig - d12 * sig1 / sig**2
        for d in range(3):
            num = b2[d] * sig - b1[d] * sig1
            num1 = b3[d] * sig - b1[d] * sig2
            d1[p, d] = b1[d] / sig
            d2[p, d] = num / sig**3
            d3[p, d] = (num1 / sig**3 - 3.0 * num * sig1 / sig**4) / sig
    return d1, d2, d3
