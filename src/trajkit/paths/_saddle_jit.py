"""Compiled kernels of the saddle curve: the arc-length inversion :func:`theta_of_s`
and the one-pass machine-axis check :func:`axis_peaks`.

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

:func:`axis_peaks` walks sorted check times through a feed's constant-jerk
pieces, inverts each arc length with the same steps, and keeps the largest
machine-axis velocity, acceleration and jerk (the arithmetic of
``SaddleCurve.machine_axes_theta`` and of the chain rule in
``trajkit.interpolation.machine.axis_states``, point by point) without
storing the states.

Pure math: arrays in, arrays out (:func:`axis_peaks` fills the one it is given).
"""

from __future__ import annotations

import numpy as np

from ..profiles._compile import ENABLED
from ..profiles._compile import jit as _jit
from ..profiles._phase import phase_end

__all__ = ["AVAILABLE", "BLOCK", "axis_peaks", "theta_of_s"]

#: True when the compiled loop is used (numba installed and not disabled).
AVAILABLE = ENABLED

#: Points that :func:`axis_peaks` samples before inverting them together.
BLOCK = 256


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
    th = np.empty(ss.size)
    _invert_into(ss, th, ss.size, edges, cum, scale, coef, deg, inv_s, inv_th, inv_dth, inv_k, gx, gw,
                 r, R, d, cot, sin_a, tol, max_iter)
    return th


@_jit
def _invert_into(ss, th, n, edges, cum, scale, coef, deg, inv_s, inv_th, inv_dth, inv_k, gx, gw,
                 r, R, d, cot, sin_a, tol, max_iter):
    """Write the angles [rad] at ``ss[:n]`` [m] into ``th[:n]`` (the loop of :func:`theta_of_s`)."""
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


@_jit
def axis_peaks(grid, bounds, tb, P, V, A, J, s0, s_end, length,
               edges, cum, scale, coef, deg, inv_s, inv_th, inv_dth, inv_k, gx, gw,
               r, R, d, cot, sin_a, tol, max_iter, r2, peaks):
    """Largest machine-axis |velocity|, |acceleration|, |jerk| at the union of two sorted time lists.

    The check times are the distinct values of ``grid`` and ``bounds`` taken
    in increasing order (a merge, the set of ``np.unique`` of both). At each,
    the feed's constant-jerk motion gives the arc length s [m], the speed v
    [m/s], the acceleration a [m/s^2] and the jerk [m/s^3] (the evaluation
    of ``JerkPieces.sample``: the start's state before 0, the end at rest
    from the duration on, s clipped to the motion's range and to
    ``[0, length]``); :data:`BLOCK` of them at a time are inverted to angles
    (:func:`theta_of_s`'s steps) and their axis states are evaluated by the
    chain rule, keeping the running maxima.

    Parameters
    ----------
    grid, bounds : ndarray, shape (n,), (m,)
        Check times [s], each non-decreasing.
    tb : ndarray, shape (k + 1,)
        Piece boundaries of the feed [s] (k >= 1 pieces); ``tb[k]`` is the duration.
    P, V, A, J : ndarray, shape (k,)
        Arc length [m], speed [m/s] and acceleration [m/s^2] at each piece's
        start, and its jerk [m/s^3].
    s0, s_end : float
        Start and end arc lengths [m] of the motion.
    length : float
        Arc length of the seam [m].
    edges, cum, scale, coef, deg, inv_s, inv_th, inv_dth, inv_k, gx, gw, r, R, d, cot, sin_a, tol, max_iter
        The curve's inversion data, as for :func:`theta_of_s`.
    r2 : float
        ``r ** 2`` [m^2].
    peaks : ndarray, shape (2, 3)
        Output: rows theta [rad/s, rad/s^2, rad/s^3], Z [m/s, m/s^2, m/s^3];
        columns |velocity|, |acceleration|, |jerk|.

    Returns
    -------
    int
        Number of distinct check times; -1 when a list is not sorted (then
        ``peaks`` is meaningless).
    """
    nk = J.size
    duration = tb[nk]
    lo = min(s0, s_end)
    hi = max(s0, s_end)
    sb = np.empty(BLOCK)
    vb = np.empty(BLOCK)
    ab = np.empty(BLOCK)
    jb = np.empty(BLOCK)
    thb = np.empty(BLOCK)
    snb = np.empty(BLOCK)
    csb = np.empty(BLOCK)
    mag = np.empty((6, BLOCK))
    for i in range(2):
        for o in range(3):
            peaks[i, o] = 0.0
    ng = grid.size
    nb = bounds.size
    gi = 0
    bi = 0
    k = 0  # the piece of the current time
    count = 0
    fill = 0
    last = 0.0
    while gi < ng or bi < nb:
        if bi >= nb or (gi < ng and grid[gi] <= bounds[bi]):
            x = grid[gi]
            gi += 1
        else:
            x = bounds[bi]
            bi += 1
        if count > 0:
            if x == last:
                continue
            if x < last:
                return -1
        last = x
        count += 1
        if x >= duration:  # the end, at rest
            s, v, a, j = s_end, 0.0, 0.0, 0.0
        elif x < 0.0:  # the start, at rest
            s, v, a, j = s0, 0.0, 0.0, 0.0
        else:
            # k: np.searchsorted(tb[1:nk], x, "right"), walked forward (the times increase)
            while k < nk - 1 and tb[k + 1] <= x:
                k += 1
            j = J[k]
            s, v, a = phase_end(P[k], V[k], A[k], j, x - tb[k])
            s = min(max(s, lo), hi)
        sb[fill] = min(max(s, 0.0), length)
        vb[fill] = v
        ab[fill] = a
        jb[fill] = j
        fill += 1
        if fill == BLOCK:
            _invert_into(sb, thb, fill, edges, cum, scale, coef, deg, inv_s, inv_th, inv_dth, inv_k, gx, gw,
                         r, R, d, cot, sin_a, tol, max_iter)
            _block_peaks(thb, vb, ab, jb, fill, r, R, d, cot, sin_a, r2, snb, csb, mag, peaks)
            fill = 0
    if fill:
        _invert_into(sb, thb, fill, edges, cum, scale, coef, deg, inv_s, inv_th, inv_dth, inv_k, gx, gw,
                     r, R, d, cot, sin_a, tol, max_iter)
        _block_peaks(thb, vb, ab, jb, fill, r, R, d, cot, sin_a, r2, snb, csb, mag, peaks)
    return count


@_jit
def _larger(p, x):
    """``max(p, x)`` that keeps a nan (as ``np.max``): once either is nan, nan."""
    return x if (x > p or x != x) else p


@_jit
def _block_peaks(th, v, a, jk, n, r, R, d, cot, sin_a, r2, sn, cs, mag, peaks):
    """Raise ``peaks`` (2, 3) to the axis states' magnitudes at the first ``n`` points.

    Three loops over the block: the sines and cosines (library calls), the
    arithmetic (straight-line, which the compiler vectorises), the maxima.

    Parameters
    ----------
    th : ndarray, shape (>= n,)
        Seam angles [rad].
    v, a, jk : ndarray, shape (>= n,)
        Tool speed [m/s], acceleration [m/s^2] and jerk [m/s^3] there.
    n : int
    r, R, d, cot, sin_a, r2 : float
        The curve (as for :func:`axis_peaks`).
    sn, cs : ndarray, shape (>= n,)
        Work space.
    mag : ndarray, shape (6, >= n)
        Work space: the magnitudes, in the order of ``peaks.ravel()``.
    peaks : ndarray, shape (2, 3)
        Running maxima, updated in place.
    """
    k = r * cot
    for i in range(n):
        sn[i] = np.sin(th[i])
        cs[i] = np.cos(th[i])
    for i in range(n):
        # z(theta) and its derivatives (SaddleCurve.z_derivatives)
        w = r * sn[i] - d
        w1 = r * cs[i]
        w2 = -r * sn[i]
        w3 = -r * cs[i]
        q = np.sqrt(R * R - w * w)
        q1 = -w * w1 / q
        q2 = (-(w1 * w1 + w * w2) - q1 * q1) / q
        q3 = (-(3.0 * w1 * w2 + w * w3) - 3.0 * q1 * q2) / q
        z1 = -k * sn[i] + q1 / sin_a
        z2 = -k * cs[i] + q2 / sin_a
        z3 = k * sn[i] + q3 / sin_a
        # derivatives in arc length (SaddleCurve.machine_axes_theta)
        sig = np.sqrt(r2 + z1 * z1)
        sig1 = z1 * z2 / sig
        sig2 = (z2 * z2 + z1 * z3 - sig1 * sig1) / sig
        sig3 = sig * sig * sig
        t1 = 1.0 / sig
        t2 = -sig1 / sig3
        t3 = (-sig2 / sig3 + 3.0 * (sig1 * sig1) / (sig3 * sig)) / sig
        y1 = z1 * t1
        y2 = z2 * (t1 * t1) + z1 * t2
        y3 = z3 * (t1 * t1 * t1) + 3.0 * z2 * t1 * t2 + z1 * t3
        # the chain rule in time (axis_states)
        vi = v[i]
        ai = a[i]
        ji = jk[i]
        v3 = vi * vi * vi
        mag[0, i] = abs(t1 * vi)
        mag[1, i] = abs(t2 * vi * vi + t1 * ai)
        mag[2, i] = abs(t3 * v3 + 3.0 * t2 * vi * ai + t1 * ji)
        mag[3, i] = abs(y1 * vi)
        mag[4, i] = abs(y2 * vi * vi + y1 * ai)
        mag[5, i] = abs(y3 * v3 + 3.0 * y2 * vi * ai + y1 * ji)
    for o in range(6):
        p = peaks[o // 3, o % 3]
        for i in range(n):
            p = _larger(p, mag[o, i])
        peaks[o // 3, o % 3] = p
