"""Exact derivatives of a corner blend's orientation along the path.

The blend's orientation (:func:`trajkit.robot._pieces.blended_orientation`)
is a slerp, at the smootherstep fraction ``w(s)``, between two orientations
that turn at constant rates: the incoming motion's slerp continued past the
corner, ``a(s)``, and the outgoing motion's, ``b(s)``. Its Taylor
coefficients in ``s`` come from truncated Taylor series (jets: the
coefficients ``0 .. K - 1`` of a function at a point, ``K = 4``) carried
through the same formula with unit quaternions:

    q(s) = a(s) (h, g v),   (c, v) = conj(a(s)) b(s)  (made c >= 0),
    h = cos(w theta),  g = sin(w theta) / sin(theta),  theta = atan2(|v|, c)

``a`` and ``b`` turn about axes fixed in their own frames, so their jets are
closed form. Where the two orientations are within :data:`SERIES_ANGLE` of
each other, ``h`` and ``g`` come from their series in ``|v|^2`` (both are
analytic there, while the square root ``|v|`` is not where ``v`` passes
zero). The rotation matrix's coefficients follow from the quaternion's.

Compiled by numba when it is installed (one source: the same loops run as
Python otherwise). Pure math: arrays in, arrays out.
"""

from __future__ import annotations

import math

import numpy as np

from ..profiles._compile import jit as _jit

__all__ = ["SERIES_ANGLE", "K", "blend_rotation_taylor"]

#: Below this half angle between the two orientations [rad] the slerp's
#: coefficients come from their series (the terms left out are below 1e-24).
SERIES_ANGLE = 1e-3

#: Taylor coefficients carried (value and three derivatives).
K = 4


@_jit
def _mul(a, b, out):
    """``out`` = the truncated product of the jets ``a`` and ``b`` (K,)."""
    for k in range(K):
        acc = 0.0
        for i in range(k + 1):
            acc += a[i] * b[k - i]
        out[k] = acc


@_jit
def _div(a, b, out):
    """``out`` = ``a / b`` (jets; ``b[0]`` nonzero)."""
    for k in range(K):
        acc = a[k]
        for i in range(k):
            acc -= out[i] * b[k - i]
        out[k] = acc / b[0]


@_jit
def _sqrt(a, out):
    """``out`` = the square root of the jet ``a`` (``a[0] > 0``)."""
    out[0] = math.sqrt(a[0])
    for k in range(1, K):
        acc = a[k]
        for i in range(1, k):
            acc -= out[i] * out[k - i]
        out[k] = acc / (2.0 * out[0])


@_jit
def _sincos(a, sn, cs):
    """Sine and cosine of the jet ``a`` (``k s_k = sum_j j a_j c_(k-j)``,
    ``k c_k = -sum_j j a_j s_(k-j)``)."""
    sn[0] = math.sin(a[0])
    cs[0] = math.cos(a[0])
    for k in range(1, K):
        s = 0.0
        c = 0.0
        for j in range(1, k + 1):
            s += j * a[j] * cs[k - j]
            c -= j * a[j] * sn[k - j]
        sn[k] = s / k
        cs[k] = c / k


@_jit
def _atan2(y, x, out, w1, w2, w3):
    """``out`` = ``atan2(y, x)`` of jets (not both zero): its derivative
    ``(x y' - y x') / (x^2 + y^2)`` integrated term by term (``w1 .. w3``: scratch)."""
    for k in range(K):  # w1: x y' - y x'; w2: x^2 + y^2
        acc = 0.0
        sq = 0.0
        for i in range(k + 1):
            j = k - i
            if j + 1 < K:
                acc += x[i] * (j + 1) * y[j + 1] - y[i] * (j + 1) * x[j + 1]
            sq += x[i] * x[j] + y[i] * y[j]
        w1[k] = acc
        w2[k] = sq
    _div(w1, w2, w3)
    out[0] = math.atan2(y[0], x[0])
    for k in range(1, K):
        out[k] = w3[k - 1] / k


@_jit
def _qmul(a, b, out, t):
    """``out`` (4, K) = the Hamilton product of the quaternion jets ``a``, ``b``
    (4, K); ``t`` (K,): scratch."""
    for r in range(4):
        for k in range(K):
            out[r, k] = 0.0
    for p in range(4):
        for q in range(4):
            # the component of the product and its sign for the pair (p, q)
            if p == 0:
                r, sg = q, 1.0
            elif q == 0:
                r, sg = p, 1.0
            elif p == q:
                r, sg = 0, -1.0
            else:
                r = 6 - p - q  # the third axis
                sg = 1.0 if (q - p) % 3 == 1 else -1.0
            _mul(a[p], b[q], t)
            for k in range(K):
                out[r, k] += sg * t[k]


@_jit
def _quat_turn(q, v, out):
    """``out`` (4,) = ``q (cos |v|, sin |v| v / |v|)`` for the half-angle vector ``v`` (3,)."""
    nv = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    sinc = math.sin(nv) / nv if nv > 1e-8 else 1.0 - nv * nv / 6.0
    e0, e1, e2, e3 = math.cos(nv), sinc * v[0], sinc * v[1], sinc * v[2]
    out[0] = q[0] * e0 - q[1] * e1 - q[2] * e2 - q[3] * e3
    out[1] = q[0] * e1 + q[1] * e0 + q[2] * e3 - q[3] * e2
    out[2] = q[0] * e2 - q[1] * e3 + q[2] * e0 + q[3] * e1
    out[3] = q[0] * e3 + q[1] * e2 - q[2] * e1 + q[3] * e0


@_jit
def _turning(q, rate, out, turn, t):
    """``out`` (4, K): the jet of ``q`` (4,) turning on at the constant half-angle
    rate ``rate`` (3,) about an axis fixed in its own frame; ``turn`` (4, K),
    ``t`` (K,): scratch."""
    r2 = rate[0] * rate[0] + rate[1] * rate[1] + rate[2] * rate[2]
    cw = (1.0, 0.0, -r2 / 2.0, 0.0)
    sv = (0.0, 1.0, 0.0, -r2 / 6.0)
    const = np.zeros((4, K))
    for k in range(K):
        turn[0, k] = cw[k]
        for d in range(3):
            turn[d + 1, k] = rate[d] * sv[k]
    for r in range(4):
        const[r, 0] = q[r]
    _qmul(const, turn, out, t)


@_jit
def blend_rotation_taylor(qa0, rot_a, len_a, sa, qb0, rot_b, len_b, sb, length, s, series):
    """Taylor coefficients ``0 .. K - 1`` in ``s`` of a corner blend's rotation matrix.

    Parameters
    ----------
    qa0, qb0 : ndarray, shape (4,)
        Start orientations (unit quaternions) of the incoming and the outgoing
        motion's slerps.
    rot_a, rot_b : ndarray, shape (3,)
        Their whole turns as rotation vectors in the start frames [rad]
        (:func:`trajkit.robot._rotations.relative_rotvec`), over the motions'
        lengths ``len_a``, ``len_b`` [m].
    sa, sb : float
        Arc length of the incoming motion at the blend's start, of the outgoing
        one at its end [m].
    length : float
        The blend's parameter length [m].
    s : ndarray, shape (n,)
        Points of the blend [m], in ``[0, length]``.
    series : float
        :data:`SERIES_ANGLE`.

    Returns
    -------
    ndarray, shape (n, K, 3, 3)
        ``R^(k)(s) / k!``.
    """
    n = s.size
    out = np.empty((n, K, 3, 3))
    qa, qb, v = np.empty(4), np.empty(4), np.empty(3)
    rate_a, rate_b = np.empty(3), np.empty(3)
    A, B, D = np.empty((4, K)), np.empty((4, K)), np.empty((4, K))
    E, Q, turn = np.empty((4, K)), np.empty((4, K)), np.empty((4, K))
    y, w, h, g, t1 = np.empty(K), np.empty(K), np.empty(K), np.empty(K), np.empty(K)
    t2, t3, t4, t5, t6 = np.empty(K), np.empty(K), np.empty(K), np.empty(K), np.empty(K)
    one = np.zeros(K)
    one[0] = 1.0
    for d in range(3):
        rate_a[d] = 0.5 * rot_a[d] / len_a
        rate_b[d] = 0.5 * rot_b[d] / len_b
    lim = math.sin(series)
    for p in range(n):
        ua = (sa + s[p]) / len_a
        ub = (sb - (length - s[p])) / len_b
        for d in range(3):
            v[d] = 0.5 * ua * rot_a[d]
        _quat_turn(qa0, v, qa)
        for d in range(3):
            v[d] = 0.5 * ub * rot_b[d]
        _quat_turn(qb0, v, qb)
        _turning(qa, rate_a, A, turn, t1)
        _turning(qb, rate_b, B, turn, t1)
        for k in range(K):  # conj(A) into turn
            turn[0, k] = A[0, k]
            for d in range(1, 4):
                turn[d, k] = -A[d, k]
        _qmul(turn, B, D, t1)
        if D[0, 0] < 0.0:  # the short arc, as the slerp takes it
            for r in range(4):
                for k in range(K):
                    D[r, k] = -D[r, k]
        # y = |v|^2 (the squared sine), w: the smootherstep fraction's jet
        for k in range(K):
            y[k] = 0.0
        for d in range(1, 4):
            _mul(D[d], D[d], t1)
            for k in range(K):
                y[k] += t1[k]
        x = min(max(s[p] / length, 0.0), 1.0)
        w[0] = x * x * x * (x * (6.0 * x - 15.0) + 10.0)
        w[1] = 30.0 * x * x * (x * (x - 2.0) + 1.0) / length
        w[2] = 60.0 * x * (x * (2.0 * x - 3.0) + 1.0) / (2.0 * length * length)
        w[3] = 60.0 * (x * (6.0 * x - 6.0) + 1.0) / (6.0 * length * length * length)
        if math.sqrt(y[0]) >= lim:
            _sqrt(y, t1)  # |v|
            _atan2(t1, D[0], t2, t3, t4, t5)  # theta
            _mul(w, t2, t3)
            _sincos(t3, t4, h)  # sin(w theta), cos(w theta)
            _div(t4, t1, g)
        else:  # theta^2 = asin(|v|)^2 = y + y^2 / 3 + 8 y^3 / 45 + ...
            _mul(y, y, t1)
            _mul(t1, y, t2)
            for k in range(K):
                t3[k] = y[k] + t1[k] / 3.0 + 8.0 * t2[k] / 45.0  # theta^2
            _mul(w, w, t4)  # w^2
            _mul(t4, t3, t5)  # (w theta)^2
            _mul(t5, t5, t1)
            _mul(t1, t5, t2)
            for k in range(K):
                h[k] = one[k] - t5[k] / 2.0 + t1[k] / 24.0 - t2[k] / 720.0
            # sin(w theta) / sin(theta)
            #   = w (1 + (1 - w^2) theta^2 / 6 + (1 - w^2) (7 - 3 w^2) theta^4 / 360 + ...)
            for k in range(K):
                t1[k] = one[k] - t4[k]  # 1 - w^2
                t2[k] = 7.0 * one[k] - 3.0 * t4[k]
            _mul(t1, t3, t5)  # (1 - w^2) theta^2
            _mul(t1, t2, t6)
            _mul(t3, t3, t1)  # theta^4
            _mul(t6, t1, t2)
            for k in range(K):
                t6[k] = one[k] + t5[k] / 6.0 + t2[k] / 360.0
            _mul(w, t6, g)
        for k in range(K):
            E[0, k] = h[k]
        for d in range(1, 4):
            _mul(g, D[d], t1)
            for k in range(K):
                E[d, k] = t1[k]
        _qmul(A, E, Q, t1)
        # the rotation matrix: quadratic in the quaternion
        for r in range(3):
            for c in range(3):
                for k in range(K):
                    out[p, k, r, c] = 0.0
        for i in range(4):
            for j in range(i, 4):
                _mul(Q[i], Q[j], t1)
                f = 1.0 if i == j else 2.0
                for k in range(K):
                    val = f * t1[k]
                    if i == 0 and j == 0:
                        pass
                    elif i == 0:  # w x, w y, w z
                        if j == 1:
                            out[p, k, 2, 1] += val
                            out[p, k, 1, 2] -= val
                        elif j == 2:
                            out[p, k, 0, 2] += val
                            out[p, k, 2, 0] -= val
                        else:
                            out[p, k, 1, 0] += val
                            out[p, k, 0, 1] -= val
                    elif i == j:  # x x, y y, z z
                        for d in range(3):
                            if d != i - 1:
                                out[p, k, d, d] -= 2.0 * val
                    else:  # x y, x z, y z
                        out[p, k, i - 1, j - 1] += val
                        out[p, k, j - 1, i - 1] += val
        for d in range(3):
            out[p, 0, d, d] += 1.0
    return out
