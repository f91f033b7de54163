"""Compiled limit checks of the path-timing engine.

The engine checks a timing (constant-jerk pieces of the path parameter
``s(t)``) at samples ``t[piece] + dt``: every joint's velocity, acceleration
and jerk over its limit (the accel or decel leg), the path's speed over its
cap, the norm of the path acceleration and the path jerk. Here one pass over
the samples does all of it, sample by sample, without temporaries over
(samples, joints):

* the sample's path state from its piece's start state and jerk, ``s``
  clipped to the grid; a sample at the end of its piece that lands on a grid
  node takes the cell below (the derivatives from below: the end belongs to
  that piece);
* the joint-path derivatives ``q'``, ``q''``, ``q'''`` in the sample's cell:
  cubic Hermite interpolation of the first two (the next derivative as the
  slope), linear of the third, from the cell's left node and the values held
  for its right end (the left-limits at a breakpoint), plus, in cells where
  the true derivatives were evaluated, the Lagrange polynomial in the cell's
  fraction that is 0 at both nodes and the interpolation's error at the
  evaluated points; or derivatives given per sample;
* the joint velocity, acceleration and jerk ``q' sdot``,
  ``q'' sdot^2 + q' sddot``, ``q''' sdot^3 + 3 q'' sdot sddot + q' sdddot``
  and the leg from the sign of ``qdot * qddot``; a joint at rest (``|qdot|``
  at most ``rest_rtol`` of its limit) takes the product at its piece's middle
  (where that joint is at rest too: speeding up where the path speeds up,
  slowing down where it slows down, as from and to a stop);
* the largest ratios per joint and of the path.

The formulas and their order of operations are the engine's numpy ones
(``engine._evaluate``), except that the cube of the cell fraction and of
``sdot`` are products here (``pow`` there) and ``hypot`` is the compiled one:
the two agree to a few ulps. Compiled by numba when it is installed and
enabled (``TRAJKIT_NO_JIT``); the engine uses its numpy formulation otherwise
(the plain-Python run of these functions gives the same results, slowly).
Pure math: arrays in, arrays out.
"""

from __future__ import annotations

import math

import numpy as np

from ..profiles._compile import ENABLED, numba
from ..profiles._compile import jit as _jit

__all__ = ["AVAILABLE", "sample_positions", "sample_states", "rest_pieces", "mid_products", "sample_ratios",
           "sample_ratios_into", "splice_ratios"]


def _inline(fn):
    """A helper compiled into its callers (numba's IR inlining: no call with every
    array passed field by field in the sample loop)."""
    if not ENABLED or numba is None:
        return fn
    return numba.njit(inline="always", error_model="numpy")(fn)


#: Whether the kernels are compiled (numba installed and enabled).
AVAILABLE = ENABLED and numba is not None


@_inline
def _cell_of(s, x, guess):
    """Grid cell of ``x``: the last node ``i`` with ``s[i] <= x``, clipped to
    ``[0, N - 2]`` (``searchsorted(s, x, 'right') - 1``); ``guess`` is tried first."""
    last = s.size - 2
    if 0 <= guess <= last and (guess == 0 or s[guess] <= x) and (guess == last or x < s[guess + 1]):
        return guess
    if x != x:  # NaN sorts last
        return last
    lo = 0
    hi = s.size
    while lo < hi:
        mid = (lo + hi) // 2
        if s[mid] <= x:
            lo = mid + 1
        else:
            hi = mid
    return min(max(lo - 1, 0), last)


@_inline
def _state(t, st, jerk, s, p, d, guess):
    """Path state of piece ``p`` at ``d`` after its start: ``s`` clipped to the grid,
    the ``s`` where the derivatives are taken, ``sdot``, ``sddot``, ``sdddot``, cell."""
    p0 = st[p, 0]
    v0 = st[p, 1]
    a0 = st[p, 2]
    jk = jerk[p]
    S = p0 + d * (v0 + d * (0.5 * a0 + d * jk / 6.0))
    V = v0 + d * (a0 + 0.5 * d * jk)
    A = a0 + d * jk
    S = min(max(S, s[0]), s[-1])
    x = S
    if d >= t[p + 1] - t[p]:  # the piece's end: in the cell of its start or before
        c0 = _cell_of(s, p0, guess)
        x = max(min(S, np.nextafter(s[c0 + 1], -np.inf)), s[0])
    return S, x, V, A, jk, _cell_of(s, x, guess)


@_inline
def _weights(s, c, x):
    """Fraction ``w`` of ``x`` in cell ``c`` and the cubic Hermite weights of the
    values and (times the cell's length) the slopes at both nodes."""
    s0 = s[c]
    s1 = s[c + 1]
    h = s1 - s0
    w = (x - s0) / (s1 - s0)
    w2 = w * w
    w3 = w2 * w
    return w, 2.0 * w3 - 3.0 * w2 + 1.0, (w3 - 2.0 * w2 + w) * h, -2.0 * w3 + 3.0 * w2, (w3 - w2) * h


@_inline
def _lagrange(w, xs, basis):
    """The Lagrange basis of the inner points ``xs[1:-1]`` at ``w`` into ``basis``."""
    for k in range(basis.size):
        b = 1.0
        for i in range(xs.size):
            if i != k + 1:
                b *= (w - xs[i]) / (xs[k + 1] - xs[i])
        basis[k] = b


@_jit
def _mid_row(t, st, jerk, s, p, d1, d2, d3, r1, r2, r3, done, err, xs, tol, mid, basis):
    """``mid[p]``: ``qdot * qddot`` at the middle of piece ``p`` from the interpolated
    derivatives; where the joint is at rest there, 1 where the path speeds up
    (``sddot >= 0``), else -1."""
    _, x, V, A, _, c = _state(t, st, jerk, s, p, 0.5 * (t[p + 1] - t[p]), -1)
    w, h00, k10, h01, k11 = _weights(s, c, x)
    corr = done.size > 0 and done[c]
    if corr:
        _lagrange(w, xs, basis)
    for j in range(tol.size):
        g1 = h00 * d1[c, j] + k10 * d2[c, j] + h01 * r1[c, j] + k11 * r2[c, j]
        g2 = h00 * d2[c, j] + k10 * d3[c, j] + h01 * r2[c, j] + k11 * r3[c, j]
        if corr:
            e1 = 0.0
            e2 = 0.0
            for k in range(basis.size):
                e1 += basis[k] * err[c, k, 0, j]
                e2 += basis[k] * err[c, k, 1, j]
            g1 += e1
            g2 += e2
        qd = g1 * V
        qdd = g2 * (V * V) + g1 * A
        mid[p, j] = (1.0 if A >= 0.0 else -1.0) if abs(qd) <= tol[j] else qd * qdd


@_inline
def _nanmax(a, b):
    """The larger of two floats, NaN when either is (as numpy's ``max``)."""
    return b if (b > a or b != b) else a


@_jit
def sample_states(t, st, jerk, s, piece, dt):
    """Path states at the samples ``t[piece] + dt`` of constant-jerk pieces.

    Parameters
    ----------
    t : ndarray, shape (k + 1,)
        Piece boundaries [s].
    st : ndarray, shape (k + 1, 3)
        ``s`` [path unit], ``sdot`` [/s], ``sddot`` [/s^2] at every piece's start.
    jerk : ndarray, shape (k,)
        Path jerk of every piece [path unit/s^3].
    s : ndarray, shape (N,)
        Grid nodes, increasing [path unit].
    piece : ndarray of int, shape (n,)
        The piece of every sample.
    dt : ndarray, shape (n,)
        Time of every sample after its piece's start [s]; ``t[piece + 1] -
        t[piece]`` (or more) marks the piece's end.

    Returns
    -------
    S, S_eval, V, A : ndarray, shape (n,)
        ``s`` clipped to the grid, the ``s`` where the derivatives are taken
        (below the node where a piece's end lands on one), ``sdot``, ``sddot``.
    cell : ndarray of int64, shape (n,)
        Grid cell of ``S_eval``.
    """
    n = piece.size
    S = np.empty(n)
    X = np.empty(n)
    V = np.empty(n)
    A = np.empty(n)
    cell = np.empty(n, dtype=np.int64)
    c = 0
    for i in range(n):
        S[i], X[i], V[i], A[i], _, c = _state(t, st, jerk, s, piece[i], dt[i], c)
        cell[i] = c
    return S, X, V, A, cell


@_jit
def sample_positions(t, st, jerk, s, piece, dt):
    """``s`` at the samples ``t[piece] + dt`` clipped to the grid (n,) (the arguments
    as for :func:`sample_states`)."""
    n = piece.size
    S = np.empty(n)
    lo = s[0]
    hi = s[-1]
    for i in range(n):
        p = piece[i]
        d = dt[i]
        S[i] = min(max(st[p, 0] + d * (st[p, 1] + d * (0.5 * st[p, 2] + d * jerk[p] / 6.0)), lo), hi)
    return S


@_jit
def rest_pieces(f1, t, st, jerk, s, piece, dt, tol, k):
    """Pieces with a sample where a joint is at rest.

    Parameters
    ----------
    f1 : ndarray, shape (n, m)
        ``dq/ds`` at the samples.
    t, st, jerk, s, piece, dt
        The samples, as for :func:`sample_states`.
    tol : ndarray, shape (m,)
        ``|qdot|`` at rest [joint unit/s]: at most this.
    k : int
        Number of pieces.

    Returns
    -------
    ndarray of bool, shape (k,)
    """
    out = np.zeros(k, dtype=np.bool_)
    c = 0
    for i in range(piece.size):
        p = piece[i]
        if out[p]:
            continue
        _, _, V, _, _, c = _state(t, st, jerk, s, p, dt[i], c)
        for j in range(f1.shape[1]):
            if abs(f1[i, j] * V) <= tol[j]:
                out[p] = True
                break
    return out


@_jit
def mid_products(f1, f2, V, A, tol):
    """``qdot * qddot`` (n, m) from ``dq/ds``, ``d2q/ds2`` (n, m), ``sdot``, ``sddot``
    (n,); where the joint is at rest (``|qdot| <= tol`` (m,)), 1 where the path
    speeds up (``sddot >= 0``), else -1: the leg of a piece whose middle is at
    rest is the path's (speeding up from a stop, slowing down to one)."""
    n, m = f1.shape
    out = np.empty((n, m))
    for i in range(n):
        for j in range(m):
            qd = f1[i, j] * V[i]
            qdd = f2[i, j] * (V[i] * V[i]) + f1[i, j] * A[i]
            out[i, j] = (1.0 if A[i] >= 0.0 else -1.0) if abs(qd) <= tol[j] else qd * qdd
    return out


@_jit
def sample_ratios(t, st, jerk, s, piece, dt, d1, d2, d3, r1, r2, r3, done, err, xs,
                  F1, F2, F3, vlim, aacc, adec, jacc, jdec, tol, kappa, cap, cap_s, mid, have):
    """Limit ratios at the samples ``t[piece] + dt`` and their largest values.

    Parameters
    ----------
    t, st, jerk, s, piece, dt
        The pieces, the grid (N,) and the samples (n,), as for :func:`sample_states`.
    d1, d2, d3 : ndarray, shape (N, m)
        ``dq/ds``, ``d2q/ds2``, ``d3q/ds3`` at the grid nodes.
    r1, r2, r3 : ndarray, shape (N - 1, m)
        The same for the right end of every cell (the left-limits where it ends
        at a breakpoint).
    done : ndarray of bool, shape (N - 1,) or (0,)
        Cells with the interpolation's error known (empty: none).
    err : ndarray, shape (N - 1, P, 3, m) or (0, P, 3, m)
        That error of the three derivatives at the cells' fractions ``xs[1:-1]``.
    xs : ndarray, shape (P + 2,)
        0, the fractions, 1.
    F1, F2, F3 : ndarray, shape (n, m) or (0, m)
        Derivatives given at every sample (at ``S_eval``); empty: interpolated.
    vlim, aacc, adec, jacc, jdec : ndarray, shape (m,)
        Joint velocity limits [joint unit/s] and the acceleration [/s^2] and
        jerk [/s^3] limits of both legs (speeding up, slowing down).
    tol : ndarray, shape (m,)
        ``|qdot|`` at rest [joint unit/s]: at most this.
    kappa : ndarray, shape (N,) or (0,)
        Path curvature at the nodes [1/path unit] (interpolated linearly;
        empty: the acceleration norm is ``|sddot|``).
    cap : ndarray, shape (N,) or (0,)
        Speed cap at the nodes [path unit/s] (a sample takes the smaller of its
        cell's two; empty: none).
    cap_s : ndarray, shape (n,) or (0,)
        Speed cap at every sample's ``S`` [path unit/s] (a cap function's; it
        counts only with ``cap``; empty: none).
    mid : ndarray, shape (k, m)
        ``qdot * qddot`` at the middle of the pieces (:func:`mid_products`);
        rows filled in here where ``have`` is False and the derivatives are
        interpolated.
    have : ndarray of bool, shape (k,)
        Rows of ``mid`` that hold values (set here as they are filled).

    Returns
    -------
    cell : ndarray of int64, shape (n,)
    rv, ra, rj : ndarray, shape (n, m)
        ``|qdot| / v_max``, ``|qddot| / a_max``, ``|qdddot| / j_max`` of the leg.
    rs : ndarray, shape (n,)
        ``sdot`` over the speed cap (0 where it is infinite or absent).
    worst : ndarray, shape (n,)
        The largest of every sample's ratios.
    peak : ndarray, shape (3, m)
        Largest ``rv``, ``ra``, ``rj`` of every joint (0 for no sample).
    path_peak : ndarray, shape (3,)
        Largest acceleration norm, ``|sdddot|`` and ``rs`` (0 for no sample).
    """
    n = piece.size
    m = vlim.size
    cell = np.empty(n, dtype=np.int64)
    rv = np.empty((n, m))
    ra = np.empty((n, m))
    rj = np.empty((n, m))
    rs = np.empty(n)
    worst = np.empty(n)
    peak, path_peak = sample_ratios_into(t, st, jerk, s, piece, dt, d1, d2, d3, r1, r2, r3, done,
                                         err, xs, F1, F2, F3, vlim, aacc, adec, jacc, jdec, tol,
                                         kappa, cap, cap_s, mid, have, cell, rv, ra, rj, rs, worst)
    return cell, rv, ra, rj, rs, worst, peak, path_peak


@_jit
def sample_ratios_into(t, st, jerk, s, piece, dt, d1, d2, d3, r1, r2, r3, done, err, xs,
                       F1, F2, F3, vlim, aacc, adec, jacc, jdec, tol, kappa, cap, cap_s, mid,
                       have, cell, rv, ra, rj, rs, worst):
    """:func:`sample_ratios` into the given arrays ``cell`` (n,), ``rv, ra, rj``
    (n, m), ``rs, worst`` (n,) (``n = piece.size``: for instance slices of
    larger ones, one per thread): returns ``peak, path_peak``."""
    n = piece.size
    m = vlim.size
    given = F1.shape[0] > 0
    peak = np.zeros((3, m))
    path_peak = np.zeros(3)
    basis = np.empty(xs.size - 2)
    amin = np.minimum(aacc, adec)
    jmin = np.minimum(jacc, jdec)
    curved = kappa.size > 0
    capped = cap.size > 0
    cap_fn = cap_s.size > 0
    c = 0
    acc_peak = 0.0
    jerk_peak = 0.0
    speed_peak = 0.0
    for i in range(n):
        p = piece[i]
        S, x, V, A, jk, c = _state(t, st, jerk, s, p, dt[i], c)
        cell[i] = c
        w, h00, k10, h01, k11 = _weights(s, c, x)
        corr = not given and done.size > 0 and done[c]
        if corr:
            _lagrange(w, xs, basis)
        VV = V * V
        V3 = VV * V
        VA = V * A
        top = 0.0
        for j in range(m):
            if given:
                f1 = F1[i, j]
                f2 = F2[i, j]
                f3 = F3[i, j]
            else:
                a0 = d1[c, j]
                b0 = d2[c, j]
                c0 = d3[c, j]
                a1 = r1[c, j]
                b1 = r2[c, j]
                c1 = r3[c, j]
                f1 = h00 * a0 + k10 * b0 + h01 * a1 + k11 * b1
                f2 = h00 * b0 + k10 * c0 + h01 * b1 + k11 * c1
                f3 = (1.0 - w) * c0 + w * c1
                if corr:
                    e1 = 0.0
                    e2 = 0.0
                    e3 = 0.0
                    for k in range(basis.size):
                        e1 += basis[k] * err[c, k, 0, j]
                        e2 += basis[k] * err[c, k, 1, j]
                        e3 += basis[k] * err[c, k, 2, j]
                    f1 += e1
                    f2 += e2
                    f3 += e3
            qd = f1 * V
            qdd = f2 * VV + f1 * A
            qddd = f3 * V3 + 3.0 * f2 * VA + f1 * jk
            aqd = abs(qd)
            if aqd <= tol[j]:  # at rest: the leg of the piece's middle
                if not have[p] and not given:
                    _mid_row(t, st, jerk, s, p, d1, d2, d3, r1, r2, r3, done, err, xs, tol, mid, basis)
                    have[p] = True
                    if corr:
                        _lagrange(w, xs, basis)
                prod = mid[p, j]
            else:
                prod = qd * qdd
            if prod > 0.0:
                al = aacc[j]
                jl = jacc[j]
            elif prod < 0.0:
                al = adec[j]
                jl = jdec[j]
            else:
                al = amin[j]
                jl = jmin[j]
            a = aqd / vlim[j]
            b = abs(qdd) / al
            e = abs(qddd) / jl
            rv[i, j] = a
            ra[i, j] = b
            rj[i, j] = e
            top = _nanmax(_nanmax(_nanmax(top, a), b), e)
        if curved:
            kap = (1.0 - w) * kappa[c] + w * kappa[c + 1]
            acc = math.hypot(A, kap * V * V)
        else:
            acc = abs(A)
        acc_peak = _nanmax(acc_peak, acc)
        jerk_peak = _nanmax(jerk_peak, abs(jk))
        rs[i] = 0.0
        if capped:
            cp = min(cap[c], cap[c + 1])
            if cap_fn:
                cp = min(cp, cap_s[i])
            if math.isfinite(cp):
                rs[i] = V / cp
            speed_peak = _nanmax(speed_peak, rs[i])
        worst[i] = _nanmax(top, rs[i])
    for i in range(n):  # the joints' largest ratios
        for j in range(m):
            peak[0, j] = _nanmax(peak[0, j], rv[i, j])
            peak[1, j] = _nanmax(peak[1, j], ra[i, j])
            peak[2, j] = _nanmax(peak[2, j], rj[i, j])
    path_peak[0] = acc_peak
    path_peak[1] = jerk_peak
    path_peak[2] = speed_peak
    return peak, path_peak


@_jit
def splice_ratios(sel, rv, ra, rj, worst, rv2, ra2, rj2, worst2):
    """Write the ratios of the samples ``sel`` (k,) evaluated again (``rv2, ra2, rj2``
    (k, m), ``worst2`` (k,)) into the full check's ``rv, ra, rj`` (n, m) and ``worst``
    (n,), in place, and return the joints' largest ratios over all samples
    ``(3, m)`` (as ``peak`` of :func:`sample_ratios`)."""
    m = rv.shape[1]
    for q in range(sel.size):
        i = sel[q]
        worst[i] = worst2[q]
        for j in range(m):
            rv[i, j] = rv2[q, j]
            ra[i, j] = ra2[q, j]
            rj[i, j] = rj2[q, j]
    peak = np.zeros((3, m))
    for i in range(rv.shape[0]):
        for j in range(m):
            peak[0, j] = _nanmax(peak[0, j], rv[i, j])
            peak[1, j] = _nanmax(peak[1, j], ra[i, j])
            peak[2, j] = _nanmax(peak[2, j], rj[i, j])
    return peak
