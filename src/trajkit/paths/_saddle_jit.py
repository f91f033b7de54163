"""Compiled arc-length inversion of the saddle curve: :func:`theta_of_s`.

The steps of :meth:`trajkit.paths.saddle.SaddleCurve.theta_of_s` in one
compiled loop over the points: the table interval (the last node at or below
the arc length, searched from the interval of the inverse table's node below
it, or by bisection while that table is being built), the first guess (cubic
Hermite on the inverse table, or linear in the table interval), then Newton on
the arc length from the interval's lower node, clipped to the interval, until
the step taken after a residual within the tolerance (which squares it).

The arc length from the node is ``(theta - a) * Q(x)``: ``Q``, the mean of
``ds/dtheta`` over ``[a, theta]``, is a Chebyshev series in
``x = (theta - a) * scale - 1`` on ``[-1, 1]`` (fitted and validated against the
quadrature when the curve is built); intervals without a series (degree -1)
use the Gauss-Legendre quadrature of ``ds/dtheta`` instead. The numpy version
steps all the points until the largest residual is within the tolerance: a
point steps there once or twice more after it has converged, which moves it
by a few ulps at most. Used only when numba is available (:data:`AVAILABLE`).

Pure math: arrays in, arrays out.
"""

from __future__ import annotations

import numpy as np

from ..profiles._compile import ENABLED
from ..profiles._compile import jit as _jit

__all__ = ["AVAILABLE", "theta_of_s"]

#: True when the compiled loop is used (numba installed and not disabled).
AVAILABLE = ENABLED


@_jit
def _speed(th, r, R, d, cot, sin_a):
    """ds/dtheta [m/rad] at ``th`` (the curve's ``speed_theta``)."""
    sn, cs = np.sin(th), np.cos(th)
    w = r * sn - d
    z1 = -r * cot * sn - w * (r * cs) / (np.sqrt(R * R - w * w) * sin_a)
    return np.sqrt(r * r + z1 * z1)


@_jit
def _clenshaw(c, m, x):
    """Chebyshev series ``sum_{j <= m} c[j] T_j(x)`` by Clenshaw's recurrence."""
    b1 = 0.0
    b2 = 0.0
    for j in range(m, 0, -1):
        b0 = c[j] + 2.0 * x * b1 - b2
        b2 = b1
        b1 = b0
    return c[0] + x * b1 - b2


@_jit
def theta_of_s(ss, edges, cum, scale, coef, deg, inv_s, inv_th, inv_dth, inv_k, gx, gw,
               r, R, d, cot, sin_a, tol, max_iter):
    """Angles [rad] at arc lengths ``ss`` (n,) [m], in any order.

    Parameters
    ----------
    ss : ndarray, shape (n,)
        Arc lengths [m], within ``[0, cum[-1]]``.
    edges, cum : ndarray, shape (T + 1,)
        The arc-length table: angles [rad] and the arc length [m] up to each.
    scale : ndarray, shape (T,)
        ``2 / (edges[k + 1] - edges[k])`` [1/rad].
    coef : ndarray, shape (T, M)
        Chebyshev coefficients [m/rad] of each interval's mean speed ``Q``.
    deg : ndarray of int64, shape (T,)
        Degree of each interval's series; -1: the interval uses the quadrature.
    inv_s, inv_th, inv_dth : ndarray, shape (G + 1,)
        Inverse table: equally spaced arc lengths [m], their angles [rad] and
        ``dtheta/ds`` [rad/m] there; empty: linear first guesses in the
        table interval.
    inv_k : ndarray of int64, shape (G + 1,)
        Table interval of each ``inv_s`` (where the search for a point's
        interval starts; empty when the inverse table is).
    gx, gw : ndarray
        Gauss-Legendre nodes and weights on [-1, 1].
    r, R, d, cot, sin_a : float
        The curve: branch and main radii [m], offset [m], cot and sin of the
        angle between the axes.
    tol : float
        Residual [m] after which a point takes one last step.
    max_iter : int

    Returns
    -------
    ndarray, shape (n,)
    """
    n = ss.size
    th = np.empty(n)
    ng = gx.size
    last = edges.size - 2
    ninv = inv_s.size
    step = inv_s[1] - inv_s[0] if ninv > 1 else 1.0
    for i in range(n):
        s = ss[i]
        # k: the last table node at or below s (np.searchsorted(cum, s, "right") - 1,
        # clipped to the intervals), from the inverse-table node's interval
        if ninv > 1:
            j = min(max(int(s / step), 0), ninv - 2)
            k = inv_k[j]
            while k > 0 and cum[k] > s:
                k -= 1
            while k < last and cum[k + 1] <= s:
                k += 1
        else:  # bisection
            k = 0
            hi = last + 1
            while hi - k > 1:
                mid = (k + hi) // 2
                if cum[mid] <= s:
                    k = mid
                else:
                    hi = mid
        a = edges[k]
        b = edges[k + 1]
        if ninv > 1:
            u = (s - inv_s[j]) / step
            v2 = (1 - u) * (1 - u)
            h00 = (1 + 2 * u) * v2
            h10 = u * v2
            h01 = u * u * (3 - 2 * u)
            h11 = u * u * (u - 1)
            t = (h00 * inv_th[j] + h10 * step * inv_dth[j] + h01 * inv_th[j + 1]
                 + h11 * step * inv_dth[j + 1])
        else:
            t = a + (b - a) * (s - cum[k]) / (cum[k + 1] - cum[k])
        t = min(max(t, a), b)
        m = deg[k]
        for _ in range(max_iter):
            if m >= 0:
                res = cum[k] + (t - a) * _clenshaw(coef[k], m, (t - a) * scale[k] - 1.0) - s
            else:
                h = t - a
                acc = 0.0
                for g in range(ng):
                    acc += _speed(a + (h / 2.0) * (1.0 + gx[g]), r, R, d, cot, sin_a) * gw[g]
                res = cum[k] + (h / 2.0) * acc - s
            t = min(max(t - res / _speed(t, r, R, d, cot, sin_a), a), b)
            if abs(res) <= tol:  # the step just taken squares the residual
                break
        th[i] = t
    return th
