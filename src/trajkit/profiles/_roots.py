"""Real roots of the low-degree polynomials the shape equations reduce to.

Each profile shape (see :mod:`._shapes`) reduces to one polynomial equation
``N(u) = 0`` of known degree (at most :data:`MAX_DEGREE`) in one shape
parameter ``u`` on a known interval ``[lo, hi]``. :func:`interp_unit` builds
the polynomial from its values at ``deg + 1`` Chebyshev nodes of the
interval (the values are exact integrations of the candidate profile, so the
polynomial is exact up to round-off); :func:`real_roots_unit` returns every
real root in ``[-1, 1]`` by the derivative recursion: the roots of
``N^(k+1)`` split the interval into pieces on which ``N^(k)`` is monotone,
and each sign change is refined by safeguarded Newton steps. Tangential
(double) roots are reported where a local extremum of ``N`` lies within
round-off of zero. No grid, no scan: every real root is found.
"""

from __future__ import annotations

import math

import numpy as np

from ._compile import jit_raw

__all__ = ["sort_ascending", "merge_equal", "illinois",
           "MAX_DEGREE", "cheb_nodes", "interp_unit", "real_roots_unit", "horner", "no_root_certain",
           "quartic_roots_unit"]

#: Highest polynomial degree a shape equation reduces to.
MAX_DEGREE = 12

#: Newton/bisection steps per root (each halves the bracket at worst).
ROOT_MAX_ITER = 80

#: A local extremum of ``N`` within this fraction of ``sum |c_k|`` of zero is
#: reported as a (double) root.
TOUCH_RTOL = 1e-11


def _tables():
    nmax = MAX_DEGREE + 1
    nodes = np.zeros((nmax + 1, nmax))
    mats = np.zeros((nmax + 1, nmax, nmax))
    for N in range(1, nmax + 1):
        k = np.arange(N)
        th = math.pi * (2 * k + 1) / (2 * N)
        x = np.cos(th)
        nodes[N, :N] = x
        # Chebyshev coefficients a_j = (2/N) sum_k f_k cos(j th_k), a_0 halved;
        # T_j as monomials by T_{j+1} = 2 x T_j - T_{j-1}
        T = np.zeros((N, N))  # T[j, i]: coefficient of x^i in T_j
        T[0, 0] = 1.0
        if N > 1:
            T[1, 1] = 1.0
        for j in range(1, N - 1):
            T[j + 1, 1:] = 2.0 * T[j, :-1]
            T[j + 1, :] -= T[j - 1, :]
        C = np.cos(np.outer(np.arange(N), th)) * (2.0 / N)  # C[j, k]
        C[0, :] *= 0.5
        mats[N, :N, :N] = T.T @ C  # mono[i] = sum_j T[j, i] a_j
    return nodes, mats


_NODES, _MATS = _tables()

#: ``NODES[n, :n]``: the ``n`` Chebyshev nodes of :func:`cheb_nodes` (indexed in
#: place by kernels that take no array views).
NODES = _NODES


def _bernstein_tables():
    """``B[n] @ c``: the Bernstein coefficients on ``[-1, 1]`` of the degree-``n``
    polynomial with monomial coefficients ``c`` (``x = 2u - 1``, ``u`` in ``[0, 1]``)."""
    from math import comb

    nmax = MAX_DEGREE
    out = np.zeros((nmax + 1, nmax + 1, nmax + 1))
    for n in range(nmax + 1):
        # monomial in x -> monomial in u: (2u - 1)^k = sum_i C(k, i) 2^i (-1)^(k-i) u^i
        S = np.zeros((n + 1, n + 1))  # S[i, k]
        for k in range(n + 1):
            for i in range(k + 1):
                S[i, k] = comb(k, i) * 2.0 ** i * (-1.0) ** (k - i)
        # monomial in u -> Bernstein: b_j = sum_{i <= j} C(j, i) / C(n, i) d_i
        Bm = np.zeros((n + 1, n + 1))
        for j in range(n + 1):
            for i in range(j + 1):
                Bm[j, i] = comb(j, i) / comb(n, i)
        out[n, : n + 1, : n + 1] = Bm @ S
    return out


_BERN = _bernstein_tables()


@jit_raw
def no_root_certain(c, deg):
    """True when ``sum_k c[k] x^k`` certainly has no root (nor a touching one, see
    :data:`TOUCH_RTOL`) in ``[-1, 1]``: its Bernstein coefficients there all
    have one sign, away from zero (the polynomial lies in their convex hull)."""
    B = _BERN[deg]
    scale = 0.0
    for k in range(deg + 1):
        scale += abs(c[k])
    tol = TOUCH_RTOL * scale * 4.0
    lo = math.inf
    hi = -math.inf
    for j in range(deg + 1):
        b = 0.0
        for k in range(deg + 1):
            b += B[j, k] * c[k]
        if b < lo:
            lo = b
        if b > hi:
            hi = b
        if lo <= tol and hi >= -tol:
            return False
    return True


@jit_raw
def cheb_nodes(n_nodes):
    """Chebyshev nodes on ``[-1, 1]`` (descending), ``n_nodes <= MAX_DEGREE + 1``."""
    return _NODES[n_nodes, :n_nodes]


@jit_raw
def interp_unit(vals, n_nodes, coef):
    """Monomial coefficients (on ``[-1, 1]``) of the polynomial through ``vals``
    at :func:`cheb_nodes` ``(n_nodes)``; written to ``coef[:n_nodes]``."""
    M = _MATS[n_nodes]
    for i in range(n_nodes):
        s = 0.0
        for k in range(n_nodes):
            s += M[i, k] * vals[k]
        coef[i] = s


@jit_raw
def horner(c, deg, x):
    """``sum_k c[k] x^k`` for ``k <= deg``."""
    r = c[deg]
    for k in range(deg - 1, -1, -1):
        r = r * x + c[k]
    return r


@jit_raw
def sort_ascending(x, n):
    """Sort ``x[:n]`` in place, ascending (insertion sort: a handful of values)."""
    for i in range(1, n):
        v = x[i]
        k = i - 1
        while k >= 0 and x[k] > v:
            x[k + 1] = x[k]
            k -= 1
        x[k + 1] = v


@jit_raw
def merge_equal(x, n, rtol):
    """Compact the ascending ``x[:n]`` in place, dropping every value within ``rtol``
    (relative) of the last one kept; returns the count kept."""
    m = 0
    for i in range(n):
        if m == 0 or x[i] - x[m - 1] > rtol * max(x[i], 1e-300):
            x[m] = x[i]
            m += 1
    return m


@jit_raw
def illinois(x, fx, a, fa, b, fb, side):
    """One bracket update of regula falsi, Illinois variant: ``[a, b]`` (``fa fb < 0``)
    shrinks to the side of ``x`` where the sign still changes, and the value kept at
    the end that stays twice in a row is halved. Returns ``(a, fa, b, fb, side)``."""
    if (fx < 0.0) == (fa < 0.0):
        if side == -1:
            fb *= 0.5
        return x, fx, b, fb, -1
    if side == 1:
        fa *= 0.5
    return a, fa, x, fx, 1


@jit_raw
def _refine(D, m, deg, a, b, fa, fb):
    """Root of the monotone level-``m`` derivative in ``[a, b]`` (``fa fb < 0``):
    Newton steps kept inside the shrinking bracket; a step that leaves it is
    replaced by regula falsi (Illinois), then by bisection."""
    x = a - fa * (b - a) / (fb - fa)
    if not (a < x < b):
        x = 0.5 * (a + b)
    side = 0
    for _ in range(ROOT_MAX_ITER):
        fx = horner(D[m], deg, x)
        if fx == 0.0:
            return x
        a, fa, b, fb, side = illinois(x, fx, a, fa, b, fb, side)
        d = horner(D[m + 1], deg - 1, x)
        xn = x - fx / d if d != 0.0 else a - 1.0
        if not (a < xn < b):
            xn = a - fa * (b - a) / (fb - fa)
            if not (a < xn < b):
                xn = 0.5 * (a + b)
        # x lies in [-1, 1]: an absolute step of a few ulp of 1 is converged
        if abs(xn - x) <= 4.4e-16 or b - a <= 8.8e-16:
            return xn
        x = xn
    return x


@jit_raw
def _quadratic_in(c0, c1, c2, out):
    """Real roots of ``c0 + c1 x + c2 x^2`` in ``[-1, 1]`` (ascending), count."""
    n = 0
    if c2 == 0.0:
        if c1 != 0.0:
            x = -c0 / c1
            if -1.0 <= x <= 1.0:
                out[0] = x
                n = 1
        return n
    disc = c1 * c1 - 4.0 * c2 * c0
    if disc < 0.0:
        return 0
    sq = math.sqrt(disc)
    q = -0.5 * (c1 + math.copysign(sq, c1))
    if q == 0.0:
        out[0] = 0.0
        return 1
    x1 = q / c2
    x2 = c0 / q
    if x1 > x2:
        x1, x2 = x2, x1
    if -1.0 <= x1 <= 1.0:
        out[n] = x1
        n += 1
    if -1.0 <= x2 <= 1.0 and (n == 0 or x2 != out[n - 1]):
        out[n] = x2
        n += 1
    return n


@jit_raw
def real_roots_unit(c, deg, out, D):
    """Every real root of ``sum_k c[k] x^k`` in ``[-1, 1]``, ascending, into ``out``.

    ``D`` is a scratch array of shape at least ``(deg + 3, deg + 1)`` (the
    derivatives, then two rows for the break points). Returns the number of
    roots. Double roots (a local extremum within :data:`TOUCH_RTOL` of zero)
    are included once.
    """
    while deg > 0 and c[deg] == 0.0:
        deg -= 1
    if deg == 0:
        return 0
    if no_root_certain(c, deg):
        return 0
    for k in range(deg + 1):
        D[0, k] = c[k]
    for m in range(1, deg + 1):
        for k in range(deg + 1 - m):
            D[m, k] = D[m - 1, k + 1] * (k + 1)
    crit = D[deg + 1]
    roots = D[deg + 2]
    # the lowest derivatives of degree <= 2 in closed form
    m = deg - 2 if deg >= 2 else 0
    nc = _quadratic_in(D[m, 0], D[m, 1] if deg - m >= 1 else 0.0,
                       D[m, 2] if deg - m >= 2 else 0.0, crit)
    if m == 0:
        nr = nc
        for i in range(nr):
            roots[i] = crit[i]
        # a double root: the vertex within round-off of zero
        if nr == 0 and deg == 2 and D[0, 2] != 0.0:
            xv = -D[0, 1] / (2.0 * D[0, 2])
            scale = abs(c[0]) + abs(c[1]) + abs(c[2])
            if -1.0 <= xv <= 1.0 and abs(horner(D[0], 2, xv)) <= TOUCH_RTOL * scale:
                roots[0] = xv
                nr = 1
        for i in range(nr):
            out[i] = roots[i]
        return nr
    for m in range(deg - 3, -1, -1):
        dm = deg - m
        nr = 0
        a = -1.0
        fa = horner(D[m], dm, a)
        if fa == 0.0:
            roots[nr] = a
            nr += 1
        for i in range(nc + 1):
            b = crit[i] if i < nc else 1.0
            fb = horner(D[m], dm, b)
            if fb == 0.0:
                if nr == 0 or roots[nr - 1] != b:
                    roots[nr] = b
                    nr += 1
            elif fa != 0.0 and (fa < 0.0) != (fb < 0.0):
                roots[nr] = _refine(D, m, dm, a, b, fa, fb)
                nr += 1
            a = b
            fa = fb
        if m == 0:
            # touching roots: local extrema of N within round-off of zero
            scale = 0.0
            for k in range(deg + 1):
                scale += abs(c[k])
            n0 = nr
            for i in range(nc):
                x = crit[i]
                if abs(horner(D[0], deg, x)) <= TOUCH_RTOL * scale:
                    nr = _add_touching(roots, nr, n0, x)
            sort_ascending(roots, nr)
            for i in range(nr):
                out[i] = roots[i]
            return nr
        for i in range(nr):
            crit[i] = roots[i]
        nc = nr
    return 0


# ------------------------------------------------------------------ quartics
# The same derivative recursion as :func:`real_roots_unit`, specialised to
# degree 4 with the coefficients in scalars (the closed-form step 1 of
# symmetric limits solves a few quartics per plan).

@jit_raw
def _add_touching(out, n, n0, x):
    """Append the touching root ``x`` to ``out[:n]`` unless one of the first ``n0``
    roots (the sign changes) lies within 1e-9 of it: the new count."""
    for r in range(n0):
        if abs(out[r] - x) <= 1e-9:
            return n
    out[n] = x
    return n + 1


@jit_raw
def _poly4(c0, c1, c2, c3, c4, x):
    return (((c4 * x + c3) * x + c2) * x + c1) * x + c0


@jit_raw
def _bracket4(c0, c1, c2, c3, c4, a, b, fa, fb, tol):
    """Root in ``[a, b]`` (``fa fb < 0``) of ``c0 + ... + c4 x^4``, monotone there:
    Newton steps kept inside the shrinking bracket, else regula falsi (Illinois),
    else bisection; converged when a step is below ``tol``."""
    x = a - fa * (b - a) / (fb - fa)
    if not (a < x < b):
        x = 0.5 * (a + b)
    side = 0
    for _ in range(ROOT_MAX_ITER):
        fx = _poly4(c0, c1, c2, c3, c4, x)
        if fx == 0.0:
            return x
        a, fa, b, fb, side = illinois(x, fx, a, fa, b, fb, side)
        d = ((4.0 * c4 * x + 3.0 * c3) * x + 2.0 * c2) * x + c1
        xn = x - fx / d if d != 0.0 else a - 1.0
        if not (a < xn < b):
            xn = a - fa * (b - a) / (fb - fa)
            if not (a < xn < b):
                xn = 0.5 * (a + b)
        if abs(xn - x) <= tol or b - a <= 2.0 * tol:
            return xn
        x = xn
    return x


@jit_raw
def _monotone_roots(c0, c1, c2, c3, c4, brk, nb, out, n, tol):
    """Roots of ``c0 + ... + c4 x^4`` on the pieces between ``-1``, ``brk[:nb]``
    (ascending) and ``1``, on each of which it is monotone, appended to
    ``out[n:]``: the new count."""
    a = -1.0
    fa = _poly4(c0, c1, c2, c3, c4, a)
    if fa == 0.0:
        out[n] = a
        n += 1
    for i in range(nb + 1):
        b = brk[i] if i < nb else 1.0
        if not (b > a):
            continue
        fb = _poly4(c0, c1, c2, c3, c4, b)
        if fb == 0.0:
            if n == 0 or out[n - 1] != b:
                out[n] = b
                n += 1
        elif fa != 0.0 and (fa < 0.0) != (fb < 0.0):
            out[n] = _bracket4(c0, c1, c2, c3, c4, a, b, fa, fb, tol)
            n += 1
        a = b
        fa = fb
    return n


@jit_raw
def quartic_roots_unit(c, out, tmp):
    """Every real root of ``c[0] + ... + c[4] x^4`` (``c[4] != 0``) in ``[-1, 1]``,
    ascending, into ``out`` (length >= 8); ``tmp``: scratch of length >= 8.

    The roots of ``N''`` (closed form) split ``[-1, 1]`` into pieces where ``N'``
    is monotone, its roots (the local extrema of ``N``) into pieces where ``N``
    is monotone, and each sign change is refined by :func:`_bracket4`. A local
    extremum within :data:`TOUCH_RTOL` of zero is a (double) root, as in
    :func:`real_roots_unit`. Returns the number of roots.
    """
    c0, c1, c2, c3, c4 = c[0], c[1], c[2], c[3], c[4]
    # inflection points: N'' = 2 c2 + 6 c3 x + 12 c4 x^2
    ni = _quadratic_in(2.0 * c2, 6.0 * c3, 12.0 * c4, tmp)
    # local extrema: N' = c1 + 2 c2 x + 3 c3 x^2 + 4 c4 x^3 (monotone between them)
    nc = _monotone_roots(c1, 2.0 * c2, 3.0 * c3, 4.0 * c4, 0.0, tmp, ni, tmp[4:], 0, 1e-13)
    crit = tmp[4:4 + nc]
    n = _monotone_roots(c0, c1, c2, c3, c4, crit, nc, out, 0, 4.4e-16)
    scale = abs(c0) + abs(c1) + abs(c2) + abs(c3) + abs(c4)
    n0 = n
    for i in range(nc):
        x = crit[i]
        if abs(_poly4(c0, c1, c2, c3, c4, x)) <= TOUCH_RTOL * scale:
            n = _add_touching(out, n, n0, x)
    sort_ascending(out, n)
    return n
