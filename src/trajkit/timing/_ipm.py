"""A banded primal-dual interior-point method for the grid problem of one round.

The round's problem (see :mod:`._socp`) in the node states alone: with
``x_k = sdot^2`` and ``u_k = sddot`` at the nodes ``k = 0 .. N`` (both end
nodes given),

    minimise   f(x) = sum_i w_i / (sqrt(x_i) + sqrt(x_{i+1}))
    subject to G z <= h,   E z = e

where every row of ``G`` and ``E`` involves one interval ``i`` only: the
coefficients on ``(x_i, x_{i+1}, u_i, u_{i+1})``. ``f`` is the time of the
grid (convex for ``x > 0``), so the cone program's auxiliary variables are
not needed: the Hessian of ``f`` is tridiagonal.

The method is Mehrotra's predictor-corrector on the KKT conditions (slacks
``s``, multipliers ``lam`` of the inequalities, ``nu`` of the equalities).
Eliminating ``s`` and ``lam`` leaves the symmetric quasi-definite system

    [ H + G^T (lam / s) G    E^T   ] [dz]   [r_z]
    [ E                    -delta  ] [dnu] = [r_e]

ordered node by node (``x_k, u_k``, then the equalities whose last node is
``k``): a band of half-width about 6, factored as ``L D L^T`` without
pivoting (quasi-definite, with the small regularisation ``delta``: any order
is stable) in ``O(N)``; a pivot that cancels in floating point (nearly
dependent active rows, whose terms ``lam / s`` grow past 1e14) is raised to a
small fraction of its diagonal entry with its exact sign instead of failing
the round (:data:`PIVOT_RTOL`); the solves are not refined against the unregularised
matrix (:data:`REFINE`: the convergence tests are on the true residuals, and
a step of refinement changed neither the iterations nor the round times
beyond 2e-9 on the benchmark's motions, at an eighth of the method's time).
The rows are grouped by their interval, so that every pass over them reads
the interval's four unknowns once and adds one 4 x 4 block (or four
entries) into the system per interval. The start is centred (every slack
times its multiplier equal), or, for a round whose rows are those of the
round before (the rounds have settled), starts the multipliers from that
round's. The steps go 0.99 of the way to the boundary at most, with
separate lengths: the primal one (``x, u`` and the slacks) to the boundary
of ``s > 0`` and half the way to ``x = 0`` (the objective's domain, see
:data:`X_STEP_FRACTION`), the dual one (the multipliers ``lam`` and ``nu``)
to that of ``lam > 0``. One common length,
the smaller, takes 12-17 % more iterations (the benchmark's arm motions, 80
random lines and arcs on two arms, waypoints and seams).

Compiled by numba when it is installed (the engine uses the cone solver
otherwise; the plain-Python run gives the same results, slowly). Pure math:
arrays in, arrays out.
"""

from __future__ import annotations

import math

import numpy as np

from ..profiles._compile import ENABLED, jit, numba

__all__ = ["AVAILABLE", "IPM_TOL", "IPM_MAX_ITER", "ST_SOLVED", "ST_MAXITER", "ST_FAILED", "solve_round"]

#: Stopping tolerance: relative primal and dual residuals and the complementarity
#: gap over the objective.
IPM_TOL = 1e-8

#: Iterations at most (most rounds take fewer than 45; the first round with the
#: jerk rows on the coarse grid of a hard path up to 85).
IPM_MAX_ITER = 100

#: Regularisation of the quasi-definite system: a constant and a part proportional
#: to its largest diagonal entry (refinement steps, if any, remove its effect).
REG = 1e-10
REG_PROP = 1e-30

#: Pivots of the factorisation that cancel to below this fraction of their
#: diagonal entry are raised to it (see ``_ldl``).
PIVOT_RTOL = 1e-12

#: Status codes.
ST_SOLVED = 0
ST_MAXITER = 1
ST_FAILED = 2

#: The step goes this fraction of the way to the boundary at most.
STEP_FRACTION = 0.99

#: ... and this fraction of the way to ``x = 0`` (the objective's domain), where
#: the objective's curvature grows like ``x^-3/2``: a step 0.99 of the way there
#: left a node at 1 % of its speed squared, the multipliers collapsed and the
#: iterates climbed back and fell again, 100 iterations without converging (a
#: round of a random UR5 arc, 3 of 77 random arm motions handed a round to the
#: cone solver). With half the way: the same iterations on the benchmark's
#: motions (1086 against 1085), 5 % fewer on those 77, none handed over.
X_STEP_FRACTION = 0.5

#: Starting point: slacks of at least this (the rows are normalised to
#: coefficients <= 1 and the problem to times of order one), and every product
#: of a slack and its multiplier equal to START_MU (a centred point; from the
#: previous round's solution the method then needs 9-17 iterations, 10-30 for a
#: jerk-free round from the engine's first guess).
START_SLACK = 1e-2
START_MU = 1e-3

#: Warm start (the previous round's multipliers): slacks of at least this, and
#: every product of a slack and its multiplier at least WARM_MU.
WARM_SLACK = 1e-4
WARM_MU = 1e-5

#: Steps of iterative refinement of every linear solve (none: see the module text).
REFINE = 0


#: Whether the compiled solver is available (numba installed and enabled).
AVAILABLE = ENABLED and numba is not None


@jit
def _layout(N, ecell):
    """Positions in the KKT system: ``px[k]``, ``pu[k]`` of the inner nodes'
    ``x`` and ``u`` (-1 for the end nodes), ``pe[j]`` of every equality; size."""
    px = np.full(N + 1, -1, dtype=np.int64)
    pu = np.full(N + 1, -1, dtype=np.int64)
    p = ecell.size
    place = np.empty(p, dtype=np.int64)
    count = np.zeros(N + 1, dtype=np.int64)
    for j in range(p):
        k = min(ecell[j] + 1, N - 1)
        k = max(k, 1)
        place[j] = k
        count[k] += 1
    start = np.zeros(N + 1, dtype=np.int64)
    pos = 0
    for k in range(1, N):
        px[k] = pos
        pu[k] = pos + 1
        pos += 2
        start[k] = pos
        pos += count[k]
    pe = np.empty(p, dtype=np.int64)
    fill = np.zeros(N + 1, dtype=np.int64)
    for j in range(p):
        k = place[j]
        pe[j] = start[k] + fill[k]
        fill[k] += 1
    return px, pu, pe, pos


@jit
def _fold(cell, C, h, px, pu, X, U):
    """The rows on the unknowns alone: every row's four KKT positions and
    coefficients, the end nodes' (given) values moved to the right-hand side. A
    coefficient on an end node, or zero, becomes 0 on the row's first unknown
    (so that every loop over the rows runs without branches); a row on end
    nodes alone is left out (``keep`` false) and its feasibility returned."""
    m = cell.size
    pos = np.zeros((m, 4), dtype=np.int64)
    cf = np.zeros((m, 4))
    hh = np.empty(m)
    keep = np.ones(m, dtype=np.bool_)
    feasible = True
    for r in range(m):
        i = cell[r]
        q = (px[i], px[i + 1], pu[i], pu[i + 1])
        val = (X[i], X[i + 1], U[i], U[i + 1])
        first = -1
        b = h[r]
        for a in range(4):
            if q[a] >= 0 and C[r, a] != 0.0:
                if first < 0:
                    first = q[a]
            elif C[r, a] != 0.0:
                b -= C[r, a] * val[a]
        hh[r] = b
        if first < 0:
            keep[r] = False
            feasible = feasible and b >= 0.0
            continue
        for a in range(4):
            if q[a] >= 0 and C[r, a] != 0.0:
                pos[r, a] = q[a]
                cf[r, a] = C[r, a]
            else:
                pos[r, a] = first
    return pos, cf, hh, keep, feasible


@jit
def _dot4(pos, cf, r, z):
    return (cf[r, 0] * z[pos[r, 0]] + cf[r, 1] * z[pos[r, 1]]
            + cf[r, 2] * z[pos[r, 2]] + cf[r, 3] * z[pos[r, 3]])


@jit
def _band_add(M, a, b, v):
    """Add ``v`` at ``(a, b)`` of the symmetric matrix in lower band storage."""
    if a >= b:
        M[a, a - b] += v
    else:
        M[b, b - a] += v


@jit
def _ldl(M, bw, L, d, sign):
    """``M = L D L^T`` of the band matrix ``M`` (lower band, half-width ``bw``).

    ``sign`` (n,): the sign every pivot has in exact arithmetic (the
    quasi-definite system: + for the unknowns, - for the equalities). A pivot
    that cancels to below PIVOT_RTOL of its diagonal entry, or to the wrong
    sign (two rows nearly parallel and both active: their terms ``lam / s``
    grow to 1e14 and more and swamp the regularisation), is set to that size
    with its sign (a dynamic regularisation of that one direction). Returns
    the number of pivots raised, -1 for a pivot that is not a number."""
    n = M.shape[0]
    raised = 0
    for j in range(n):
        s = M[j, 0]
        for k in range(max(0, j - bw), j):
            ljk = L[j, j - k]
            s -= ljk * ljk * d[k]
        if s != s:
            return -1
        floor = max(PIVOT_RTOL * abs(M[j, 0]), REG)
        if sign[j] * s < floor:
            s = sign[j] * floor
            raised += 1
        d[j] = s
        for i in range(j + 1, min(n, j + bw + 1)):
            s2 = M[i, i - j]
            for k in range(max(0, i - bw), j):
                s2 -= L[i, i - k] * L[j, j - k] * d[k]
            L[i, i - j] = s2 / d[j]
    return raised


@jit
def _ldl_solve(L, d, bw, b, x):
    n = b.size
    for i in range(n):
        s = b[i]
        for k in range(max(0, i - bw), i):
            s -= L[i, i - k] * x[k]
        x[i] = s
    for i in range(n):
        x[i] /= d[i]
    for i in range(n - 1, -1, -1):
        s = x[i]
        for k in range(i + 1, min(n, i + bw + 1)):
            s -= L[k, k - i] * x[k]
        x[i] = s


@jit
def _band_mul(M, bw, x, out):
    """``out = M x`` for the symmetric band matrix ``M``."""
    n = x.size
    for i in range(n):
        out[i] = M[i, 0] * x[i]
    for i in range(n):
        for k in range(1, min(bw, i) + 1):
            v = M[i, k]
            out[i] += v * x[i - k]
            out[i - k] += v * x[i]


@jit
def _objective(X, w):
    f = 0.0
    for i in range(w.size):
        f += w[i] / (math.sqrt(X[i]) + math.sqrt(X[i + 1]))
    return f


@jit
def _solve_linear(M, L, dd, bw, rhs, sol, res, tmp, refine):
    """``sol`` from the factors of the regularised matrix, refined ``refine``
    times against ``M`` (the matrix without the regularisation)."""
    _ldl_solve(L, dd, bw, rhs, sol)
    for _ in range(refine):
        _band_mul(M, bw, sol, res)
        for q in range(rhs.size):
            res[q] = rhs[q] - res[q]
        _ldl_solve(L, dd, bw, res, tmp)
        for q in range(rhs.size):
            sol[q] += tmp[q]


@jit
def _cells(N, px, pu, nk):
    """The KKT positions of every interval's ``(x_i, x_{i+1}, u_i, u_{i+1})``,
    ``(N, 4)``; ``nk`` (a spare slot past the system, always zero in ``z``)
    for an end node's (given) value."""
    cp = np.empty((N, 4), dtype=np.int64)
    for i in range(N):
        q = (px[i], px[i + 1], pu[i], pu[i + 1])
        for a in range(4):
            cp[i, a] = q[a] if q[a] >= 0 else nk
    return cp


@jit
def _fold_cells(N, cell, C, h, px, X, U, qnode):
    """The inequality rows grouped by interval (in their order within one), for
    the per-interval loops: coefficients ``(m, 4)`` with the end nodes' given
    values moved to the right-hand side (their coefficients zeroed), the
    right-hand sides, the first row of every interval ``(N + 1,)``, the
    position of every quadratic row (one per node ``k``, on the interval
    starting at ``k``, after its linear rows; coefficients set per iterate)
    and the feasibility of the rows left out (on end nodes alone)."""
    m0 = cell.size
    keep = np.zeros(m0, dtype=np.bool_)
    rhs = np.empty(m0)
    count = np.zeros(N + 1, dtype=np.int64)
    feasible = True
    for r in range(m0):
        i = cell[r]
        val = (X[i], X[i + 1], U[i], U[i + 1])
        free = (px[i] >= 0, px[i + 1] >= 0, px[i] >= 0, px[i + 1] >= 0)
        b = h[r]
        any_free = False
        for a in range(4):
            if C[r, a] != 0.0:
                if free[a]:
                    any_free = True
                else:
                    b -= C[r, a] * val[a]
        rhs[r] = b
        if any_free:
            keep[r] = True
            count[i] += 1
        else:
            feasible = feasible and b >= 0.0
    for j in range(qnode.size):
        count[qnode[j]] += 1
    ptr = np.zeros(N + 1, dtype=np.int64)
    for i in range(N):
        ptr[i + 1] = ptr[i] + count[i]
    m = ptr[N]
    cf = np.zeros((m, 4))
    hh = np.zeros(m)
    fill = ptr[:N].copy()
    where = np.full(m0, -1, dtype=np.int64)
    for r in range(m0):
        if not keep[r]:
            continue
        i = cell[r]
        free = (px[i] >= 0, px[i + 1] >= 0, px[i] >= 0, px[i + 1] >= 0)
        q = fill[i]
        where[r] = q
        for a in range(4):
            if free[a]:
                cf[q, a] = C[r, a]
        hh[q] = rhs[r]
        fill[i] += 1
    qrow = np.empty(qnode.size, dtype=np.int64)
    for j in range(qnode.size):
        k = qnode[j]
        qrow[j] = fill[k]
        fill[k] += 1
    return cf, hh, ptr, qrow, feasible, where


@jit
def _solve(N, w, cell, C, h, ecell, E, e, qnode, qxx, quu, X0, U0, max_iter, tol, lam0, lam_out):
    """The compiled solver (see :func:`solve_round`)."""
    px, pu, pe, nk = _layout(N, ecell)
    X = X0.copy()
    U = U0.copy()
    for j in range(qnode.size):
        if px[qnode[j]] < 0:
            return X, U, ST_FAILED, 0, math.nan
    cf, hh, ptr, qrow, feas, where = _fold_cells(N, cell, C, h, px, X, U, qnode)
    epos, ecf, ee, ekeep, efeas = _fold(ecell, E, e, px, pu, X, U)
    if not (feas and efeas and ekeep.all()):
        return X, U, ST_FAILED, 0, math.nan
    cp = _cells(N, px, pu, nk)
    m = hh.size
    p = ee.size
    mq = qnode.size
    # half-width of the band (the quadratic rows: x_k and u_k, next to each other)
    bw = 1
    for i in range(N):
        for r in range(ptr[i], ptr[i + 1]):
            for a in range(4):
                if cf[r, a] != 0.0 and cp[i, a] < nk:
                    for b in range(a):
                        if cf[r, b] != 0.0 and cp[i, b] < nk:
                            bw = max(bw, abs(cp[i, a] - cp[i, b]))
    for j in range(p):
        for a in range(4):
            bw = max(bw, abs(pe[j] - epos[j, a]))
    for i in range(1, N - 1):
        bw = max(bw, px[i + 1] - px[i])
    # the iterate: z (x, u of the inner nodes; nu in the equalities' places; the
    # spare slot nk stays zero), s, lam
    xs = 0.0
    for k in range(1, N):
        xs = max(xs, X[k])
    floor = 1e-6 * xs if xs > 0.0 else 1e-6
    z = np.zeros(nk + 1)
    for k in range(1, N):
        X[k] = max(X[k], floor)
        z[px[k]] = X[k]
        z[pu[k]] = U[k]
    s = np.empty(m)
    lam = np.empty(m)
    _quad_rows(qnode, qxx, quu, px, pu, z, cf, hh, qrow)
    # a centred start: the slacks at the starting point (at least START_SLACK),
    # every product slack x multiplier equal to START_MU
    for i in range(N):
        z0, z1, z2, z3 = z[cp[i, 0]], z[cp[i, 1]], z[cp[i, 2]], z[cp[i, 3]]
        for r in range(ptr[i], ptr[i + 1]):
            gz = cf[r, 0] * z0 + cf[r, 1] * z1 + cf[r, 2] * z2 + cf[r, 3] * z3
            s[r] = max(hh[r] - gz, START_SLACK)
            lam[r] = START_MU / s[r]
    # a warm start: the previous round's multipliers where a row was there (its
    # slack kept small where the multiplier says the row is active)
    if lam0.size:
        for r0 in range(lam0.size):
            r = where[r0]
            if r < 0 or not (lam0[r0] > 0.0):
                continue
            i = cell[r0]
            gz = (cf[r, 0] * z[cp[i, 0]] + cf[r, 1] * z[cp[i, 1]] + cf[r, 2] * z[cp[i, 2]]
                  + cf[r, 3] * z[cp[i, 3]])
            s[r] = max(hh[r] - gz, WARM_SLACK)
            lam[r] = max(lam0[r0], WARM_MU / s[r])
    M = np.zeros((nk, bw + 1))
    L = np.zeros((nk, bw + 1))
    dd = np.zeros(nk)
    gf = np.zeros(nk)
    rz = np.zeros(nk + 1)
    rhs = np.zeros(nk + 1)
    sol = np.zeros(nk + 1)
    res = np.zeros(nk)
    tmp = np.zeros(nk)
    reg = np.zeros(nk)
    sgn = np.ones(nk)  # the pivots' signs: + the unknowns, - the equalities
    for j in range(p):
        sgn[pe[j]] = -1.0
    rhs_k = rhs[:nk]
    sol_k = sol[:nk]
    rin = np.zeros(m)
    Dg = np.zeros(m)
    ds = np.zeros(m)
    dl = np.zeros(m)
    ds_a = np.zeros(m)
    dl_a = np.zeros(m)
    req = np.zeros(p)
    # the scale of the primal residual: the linear rows' right-hand sides (the
    # quadratic rows' change with the iterate)
    linear = np.ones(m, dtype=np.bool_)
    for j in range(mq):
        linear[qrow[j]] = False
    hn = 1.0
    for r in range(m):
        if linear[r]:
            hn = max(hn, abs(hh[r]))
    en = 1.0
    for j in range(p):
        en = max(en, abs(ee[j]))
    status = ST_MAXITER
    it = 0
    # the step of the previous iteration still to be taken by the slacks and
    # multipliers (in the next pass over the rows: every pass over the rows reads
    # and writes them once)
    ap = 0.0
    ad = 0.0
    gt = np.zeros(nk + 1)  # G^T of the predictor's row terms
    ga = np.zeros(nk + 1)  # G^T of the second-order terms ds_a dl_a / s
    gb = np.zeros(nk + 1)  # G^T of 1 / s
    while it < max_iter:
        # ---- residuals at the iterate; the objective's gradient and Hessian
        for k in range(1, N):
            X[k] = z[px[k]]
            U[k] = z[pu[k]]
        _quad_rows(qnode, qxx, quu, px, pu, z, cf, hh, qrow)
        gf[:] = 0.0
        M[:, :] = 0.0
        for i in range(N):
            a = math.sqrt(X[i])
            b = math.sqrt(X[i + 1])
            S = a + b
            f2 = w[i] / (S * S)
            f3 = 2.0 * f2 / S
            # w / S: first derivative -w S_x / S^2, second w (2 S_x^2 / S^3 - S_xx / S^2)
            if px[i] >= 0:
                Sa = 0.5 / a
                gf[px[i]] -= f2 * Sa
                M[px[i], 0] += f3 * Sa * Sa + f2 * 0.25 / (a * X[i])
            if px[i + 1] >= 0:
                Sb = 0.5 / b
                gf[px[i + 1]] -= f2 * Sb
                M[px[i + 1], 0] += f3 * Sb * Sb + f2 * 0.25 / (b * X[i + 1])
            if px[i] >= 0 and px[i + 1] >= 0:
                _band_add(M, px[i + 1], px[i], f3 * (0.5 / a) * (0.5 / b))
        # one pass over the rows, interval by interval: the previous step of the
        # slacks and multipliers; the residuals r_in = G z + s - h and r_d = grad f
        # + G^T lam (+ E^T nu below); the matrix H + G^T D G (a 4 x 4 block per
        # interval, D = lam / s) and the predictor's G^T (D r_in - lam)
        for q in range(nk + 1):
            rz[q] = gf[q] if q < nk else 0.0
            gt[q] = 0.0
        pres = 0.0
        gap = 0.0
        for i in range(N):
            z0, z1, z2, z3 = z[cp[i, 0]], z[cp[i, 1]], z[cp[i, 2]], z[cp[i, 3]]
            g0 = g1 = g2 = g3 = 0.0
            h0 = h1 = h2 = h3 = 0.0
            m00 = m11 = m22 = m33 = m10 = m20 = m21 = m30 = m31 = m32 = 0.0
            for r in range(ptr[i], ptr[i + 1]):
                sr = s[r] + ap * ds[r]
                lr = lam[r] + ad * dl[r]
                s[r] = sr
                lam[r] = lr
                c0, c1, c2, c3 = cf[r, 0], cf[r, 1], cf[r, 2], cf[r, 3]
                v = c0 * z0 + c1 * z1 + c2 * z2 + c3 * z3 + sr - hh[r]
                rin[r] = v
                pres = max(pres, abs(v))
                gap += sr * lr
                g0 += c0 * lr
                g1 += c1 * lr
                g2 += c2 * lr
                g3 += c3 * lr
                dr = lr / sr
                Dg[r] = dr
                t = dr * v - lr
                h0 += c0 * t
                h1 += c1 * t
                h2 += c2 * t
                h3 += c3 * t
                t0 = dr * c0
                t1 = dr * c1
                t2 = dr * c2
                t3 = dr * c3
                m00 += t0 * c0
                m11 += t1 * c1
                m22 += t2 * c2
                m33 += t3 * c3
                m10 += t1 * c0
                m20 += t2 * c0
                m21 += t2 * c1
                m30 += t3 * c0
                m31 += t3 * c1
                m32 += t3 * c2
            _scatter(rz, cp, i, g0, g1, g2, g3)
            _scatter(gt, cp, i, h0, h1, h2, h3)
            q0, q1, q2, q3 = cp[i, 0], cp[i, 1], cp[i, 2], cp[i, 3]
            _block_add(M, nk, q0, q0, m00)
            _block_add(M, nk, q1, q1, m11)
            _block_add(M, nk, q2, q2, m22)
            _block_add(M, nk, q3, q3, m33)
            _block_add(M, nk, q1, q0, m10)
            _block_add(M, nk, q2, q0, m20)
            _block_add(M, nk, q2, q1, m21)
            _block_add(M, nk, q3, q0, m30)
            _block_add(M, nk, q3, q1, m31)
            _block_add(M, nk, q3, q2, m32)
        ap = 0.0
        ad = 0.0
        pres /= hn  # (the largest quotient is the quotient of the largest: hn > 0)
        for j in range(p):
            req[j] = _dot4(epos, ecf, j, z) - ee[j]
            pres = max(pres, abs(req[j]) / en)
            nu = z[pe[j]]
            for a in range(4):
                rz[epos[j, a]] += ecf[j, a] * nu
        dres = 0.0
        gn = 1.0
        for k in range(1, N):
            dres = max(dres, abs(rz[px[k]]), abs(rz[pu[k]]))
            gn = max(gn, abs(gf[px[k]]))
        dres /= gn
        fval = _objective(X, w)
        mu = gap / max(m, 1)
        if pres < tol and dres < tol and gap < tol * (1.0 + fval):
            status = ST_SOLVED
            break
        # ---- the rest of the matrix: the quadratic rows' curvature, E, regularisation
        for j in range(mq):  # lam grad^2 g
            k = qnode[j]
            M[px[k], 0] += 2.0 * lam[qrow[j]] * qxx[j]
            M[pu[k], 0] += 2.0 * lam[qrow[j]] * quu[j]
        scale = 0.0
        for k in range(1, N):
            scale = max(scale, M[px[k], 0], M[pu[k], 0])
        delta = REG + REG_PROP * scale
        for j in range(p):
            for a in range(4):
                _band_add(M, pe[j], epos[j, a], ecf[j, a])
        for k in range(1, N):
            reg[px[k]] = delta
            reg[pu[k]] = delta
        for j in range(p):
            reg[pe[j]] = -delta
        for q in range(nk):
            M[q, 0] += reg[q]
        raised = _ldl(M, bw, L, dd, sgn)
        for q in range(nk):
            M[q, 0] -= reg[q]
        if raised < 0:
            status = ST_FAILED
            break
        # ---- predictor (affine, into ds_a, dl_a) and corrector with the same factors:
        # right-hand side -r_d - G^T (D r_in - r_c / s); -r_eq (r_c: s lam for the
        # predictor; the corrector adds its second-order term and the centring)
        for q in range(nk):
            rhs[q] = -rz[q] - gt[q]
        for j in range(p):
            rhs[pe[j]] = -req[j]
        _solve_linear(M, L, dd, bw, rhs_k, sol_k, res, tmp, REFINE)
        # ds = -r_in - G dz; dlam = D (G dz + r_in) - lam; the largest affine steps,
        # and what the corrector needs: sum (s + ap ds)(lam + ad dlam) in parts and
        # G^T of ds dlam / s and of 1 / s
        for q in range(nk + 1):
            ga[q] = 0.0
            gb[q] = 0.0
        aa = 1.0
        aq = 1.0
        s_dl = 0.0
        ds_l = 0.0
        ds_dl = 0.0
        for i in range(N):
            x0, x1, x2, x3 = sol[cp[i, 0]], sol[cp[i, 1]], sol[cp[i, 2]], sol[cp[i, 3]]
            e0 = e1 = e2 = e3 = 0.0
            b0 = b1 = b2 = b3 = 0.0
            for r in range(ptr[i], ptr[i + 1]):
                c0, c1, c2, c3 = cf[r, 0], cf[r, 1], cf[r, 2], cf[r, 3]
                sr = s[r]
                lr = lam[r]
                gdz = c0 * x0 + c1 * x1 + c2 * x2 + c3 * x3
                dsr = -rin[r] - gdz
                dlr = Dg[r] * (gdz + rin[r]) - lr
                ds_a[r] = dsr
                dl_a[r] = dlr
                if dsr < 0.0:
                    aa = min(aa, -sr / dsr)
                if dlr < 0.0:
                    aq = min(aq, -lr / dlr)
                s_dl += sr * dlr
                ds_l += dsr * lr
                ds_dl += dsr * dlr
                inv = 1.0 / sr
                t = dsr * dlr * inv
                e0 += c0 * t
                e1 += c1 * t
                e2 += c2 * t
                e3 += c3 * t
                b0 += c0 * inv
                b1 += c1 * inv
                b2 += c2 * inv
                b3 += c3 * inv
            _scatter(ga, cp, i, e0, e1, e2, e3)
            _scatter(gb, cp, i, b0, b1, b2, b3)
        for k in range(1, N):
            q = px[k]
            if sol[q] < 0.0:
                aa = min(aa, -z[q] / sol[q])
        # the affine step's complementarity and the centring
        mu_aff = (gap + aq * s_dl + aa * ds_l + aa * aq * ds_dl) / max(m, 1)
        sigma = (mu_aff / mu) ** 3 if mu > 0.0 else 0.0
        sigma = min(max(sigma, 0.0), 1.0)
        sigma_mu = sigma * mu
        for q in range(nk):
            rhs[q] = -rz[q] - gt[q] + ga[q] - sigma_mu * gb[q]
        for j in range(p):
            rhs[pe[j]] = -req[j]
        _solve_linear(M, L, dd, bw, rhs_k, sol_k, res, tmp, REFINE)
        # the corrector's ds, dlam and the step lengths
        ap = 1.0
        ad = 1.0
        for i in range(N):
            x0, x1, x2, x3 = sol[cp[i, 0]], sol[cp[i, 1]], sol[cp[i, 2]], sol[cp[i, 3]]
            for r in range(ptr[i], ptr[i + 1]):
                sr = s[r]
                lr = lam[r]
                gdz = cf[r, 0] * x0 + cf[r, 1] * x1 + cf[r, 2] * x2 + cf[r, 3] * x3
                dsr = -rin[r] - gdz
                rcr = sr * lr + ds_a[r] * dl_a[r] - sigma_mu
                dlr = Dg[r] * (gdz + rin[r]) - rcr / sr
                ds[r] = dsr
                dl[r] = dlr
                if dsr < 0.0:
                    ap = min(ap, -STEP_FRACTION * sr / dsr)
                if dlr < 0.0:
                    ad = min(ad, -STEP_FRACTION * lr / dlr)
        for k in range(1, N):
            q = px[k]
            if sol[q] < 0.0:
                ap = min(ap, -X_STEP_FRACTION * z[q] / sol[q])
        if not (ap > 0.0 and ad > 0.0):
            ap = 0.0
            ad = 0.0
            status = ST_FAILED
            break
        for k in range(1, N):
            z[px[k]] += ap * sol[px[k]]
            z[pu[k]] += ap * sol[pu[k]]
        for j in range(p):
            z[pe[j]] += ad * sol[pe[j]]
        it += 1
    # (the last step of the slacks and multipliers, if not taken yet)
    if ap > 0.0 or ad > 0.0:
        for r in range(m):
            s[r] += ap * ds[r]
            lam[r] += ad * dl[r]
    for k in range(1, N):
        X[k] = z[px[k]]
        U[k] = z[pu[k]]
    for r0 in range(lam_out.size):
        lam_out[r0] = lam[where[r0]] if where[r0] >= 0 else math.nan
    return X, U, status, it, _objective(X, w)


@jit
def _scatter(out, cp, i, v0, v1, v2, v3):
    """Add ``v0 .. v3`` at the positions of interval ``i``'s four unknowns."""
    out[cp[i, 0]] += v0
    out[cp[i, 1]] += v1
    out[cp[i, 2]] += v2
    out[cp[i, 3]] += v3


@jit
def _block_add(M, nk, a, b, v):
    """Add ``v`` at ``(a, b)`` (``a, b`` positions of one interval) of the band
    matrix, unless one of them is the spare slot or ``v`` is zero (a pair of
    positions no row couples may lie outside the band)."""
    if a < nk and b < nk and v != 0.0:
        _band_add(M, a, b, v)


@jit
def _quad_rows(qn, qk, qa, px, pu, z, cf, hh, qrow):
    """The quadratic rows ``g = qk x^2 + qa u^2 - 1 <= 0`` at the iterate (row
    ``qrow[j]``, on the interval starting at its node): the gradient as
    coefficients (on ``x`` and ``u`` of the node), the right-hand side
    ``grad . z - g`` (so that the row's ``G z - h`` is ``g(z)``)."""
    for j in range(qn.size):
        k = qn[j]
        x = z[px[k]]
        u = z[pu[k]]
        r = qrow[j]
        cf[r, 0] = 2.0 * qk[j] * x
        cf[r, 1] = 0.0
        cf[r, 2] = 2.0 * qa[j] * u
        cf[r, 3] = 0.0
        hh[r] = qk[j] * x * x + qa[j] * u * u + 1.0


def solve_round(w: np.ndarray, cell: np.ndarray, C: np.ndarray, h: np.ndarray,
                ecell: np.ndarray, E: np.ndarray, e: np.ndarray,
                x0: np.ndarray, u0: np.ndarray, quad: tuple | None = None,
                max_iter: int = IPM_MAX_ITER, tol: float = IPM_TOL,
                lam0: np.ndarray | None = None, lam_out: np.ndarray | None = None):
    """Solve one round's grid problem (see the module text).

    Parameters
    ----------
    w : ndarray, shape (N,)
        Objective weights of the intervals.
    cell, C, h : ndarray, shapes (m,), (m, 4), (m,)
        Inequalities ``C[r] . (x_i, x_{i+1}, u_i, u_{i+1}) <= h[r]``, ``i = cell[r]``.
    ecell, E, e : ndarray, shapes (p,), (p, 4), (p,)
        Equalities of the same form.
    x0, u0 : ndarray, shape (N + 1,)
        Starting point; the end nodes' entries are the given end states.
    quad : tuple of 3 ndarray, optional
        Quadratic rows ``qk x_k^2 + qa u_k^2 <= 1``: ``(nodes (inner), qk, qa)``
        (the path's acceleration with a curvature: ``(kappa x)^2 + u^2 <= a^2``).

    Returns
    -------
    x, u : ndarray, shape (N + 1,)
    status : int
        :data:`ST_SOLVED`, :data:`ST_MAXITER` or :data:`ST_FAILED` (the last
        two: not converged; the engine then solves the round with Clarabel).
    iterations : int
    objective : float
    """
    N = int(w.size)
    if N < 2:  # no inner node: nothing to solve here
        return np.array(x0, dtype=float), np.array(u0, dtype=float), ST_FAILED, 0, math.nan
    if quad is None:
        quad = (np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0))
    m0 = int(np.size(cell))
    lam_in = np.zeros(0) if lam0 is None else np.ascontiguousarray(lam0, dtype=np.float64)
    duals = np.empty(m0) if lam_out is None else lam_out
    X, U, status, it, f = _solve(
        N, np.ascontiguousarray(w, dtype=np.float64), np.ascontiguousarray(cell, dtype=np.int64),
        np.ascontiguousarray(C, dtype=np.float64), np.ascontiguousarray(h, dtype=np.float64),
        np.ascontiguousarray(ecell, dtype=np.int64), np.ascontiguousarray(E, dtype=np.float64),
        np.ascontiguousarray(e, dtype=np.float64), np.ascontiguousarray(quad[0], dtype=np.int64),
        np.ascontiguousarray(quad[1], dtype=np.float64),
        np.ascontiguousarray(quad[2], dtype=np.float64), np.array(x0, dtype=np.float64),
        np.array(u0, dtype=np.float64), int(max_iter), float(tol), lam_in, duals)
    return X, U, int(status), int(it), float(f)
