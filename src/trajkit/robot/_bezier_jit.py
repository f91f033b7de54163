"""Compiled arc-length inversion of a blend's Bezier curve: :func:`points_at`.

The same steps as :meth:`trajkit.robot._pieces.BezierBlend.u_of_s` (the
arc-length table, then Newton steps on the arc length from the table node
below, each integrated by Gauss-Legendre quadrature) and the curve's point
there, point by point in one compiled loop; the point by de Casteljau's
algorithm, the speed |B'(u)| by Horner's scheme on the derivative's
power-basis coefficients; a point's steps end early at a fixed point. The
same values as the numpy version to round-off. Used only when numba is available (:data:`AVAILABLE`).

Pure math: arrays in, arrays out.
"""

from __future__ import annotations

import numpy as np

from ..profiles._compile import ENABLED
from ..profiles._compile import jit as _jit

__all__ = ["AVAILABLE", "points_at"]

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
