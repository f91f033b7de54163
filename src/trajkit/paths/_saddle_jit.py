"""Compiled arc-length inversion of the saddle curve: :func:`theta_newton`.

The Newton iteration of :meth:`trajkit.paths.saddle.SaddleCurve.theta_of_s`
in one compiled loop: the arc length from the table node below ``theta`` by
Gauss-Legendre quadrature of ``ds/dtheta = sqrt(r^2 + z'^2)``, the step,
clipped to the node's interval, until the step taken after a residual within
the tolerance (which squares it). The numpy version steps all the points
until the largest residual is within it: a point steps there once or twice
more after it has converged, which moves it by a few ulps at most. Used only
when numba is available (:data:`AVAILABLE`).

Pure math: arrays in, arrays out.
"""

from __future__ import annotations

import numpy as np

from ..profiles._compile import ENABLED
from ..profiles._compile import jit as _jit

__all__ = ["AVAILABLE", "theta_newton"]

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
def theta_newton(ss, th0, k, edges, cum, gx, gw, r, R, d, cot, sin_a, tol, max_iter):
    """Angles [rad] at arc lengths ``ss`` (n,) [m] from first guesses ``th0``.

    Parameters
    ----------
    ss, th0 : ndarray, shape (n,)
        Arc lengths and first guesses of the angle.
    k : ndarray of int64, shape (n,)
        Each point's interval of the arc-length table (``edges[k] .. edges[k + 1]``).
    edges, cum : ndarray, shape (T + 1,)
        The table: angles and the arc length up to each.
    gx, gw : ndarray
        Gauss-Legendre nodes and weights on [-1, 1].
    r, R, d, cot, sin_a : float
        The curve: branch and main radii [m], offset [m], cot and sin of the
        angle between the axes.
    tol : float
        Residual [m] after which a point takes no further step.
    max_iter : int

    Returns
    -------
    ndarray, shape (n,)
    """
    n = ss.size
    th = np.empty(n)
    ng = gx.size
    for i in range(n):
        a = edges[k[i]]
        b = edges[k[i] + 1]
        t = min(max(th0[i], a), b)
        for _ in range(max_iter):
            h = t - a
            acc = 0.0
            for g in range(ng):
                acc += _speed(a + (h / 2.0) * (1.0 + gx[g]), r, R, d, cot, sin_a) * gw[g]
            res = cum[k[i]] + (h / 2.0) * acc - ss[i]
            t = min(max(t - res / _speed(t, r, R, d, cot, sin_a), a), b)
            if abs(res) <= tol:  # the step just taken squares the residual
                break
        th[i] = t
    return th
