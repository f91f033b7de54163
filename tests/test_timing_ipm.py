"""The banded interior-point method of the path-timing rounds (``timing._ipm``).

* On a problem with a known optimum (every node at the speed cap) it finds it.
* On grid problems of real paths it finds the cone solver's (Clarabel's)
  optimum: the same round times and node states, with and without the rounds'
  jerk rows.
* Where it does not converge the engine gives the round to the cone solver
  and returns the same timing.
* Its compiled and plain-Python runs agree.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from trajkit import AxisLimits
from trajkit.timing import LinearJointPath, _ipm, _socp, plan_path_timing
from trajkit.timing._socp import GridProblem, solve_grid

needs_compiled = pytest.mark.skipif(not _ipm.AVAILABLE, reason="the method runs compiled only")


def _cruise_problem(N: int, cap: float):
    """Intervals of lengths D between nodes moving at the cap: x <= cap at every
    inner node, the node relations x_{i+1} - x_i = D (u_i + u_{i+1}), ends at the
    cap with u = 0. Optimum: x = cap, u = 0, time sum(2 D) / (2 sqrt(cap))."""
    rng = np.random.default_rng(N)
    D = rng.uniform(0.5, 1.5, N)
    w = 2.0 * D
    inner = np.arange(1, N)
    cell = np.minimum(inner, N - 1)  # x_k on the interval that starts at k (slot 0)
    C = np.zeros((inner.size, 4))
    C[:, 0] = 1.0
    h = np.full(inner.size, cap)
    ecell = np.arange(N)
    E = np.column_stack([-np.ones(N), np.ones(N), -D, -D])
    e = np.zeros(N)
    x0 = np.full(N + 1, 0.3 * cap)
    x0[0] = x0[N] = cap
    u0 = np.zeros(N + 1)
    return w, cell, C, h, ecell, E, e, x0, u0, D


@needs_compiled
@pytest.mark.parametrize("N", [2, 3, 10, 80])
def test_known_optimum_every_node_at_the_cap(N):
    cap = 2.5
    w, cell, C, h, ecell, E, e, x0, u0, D = _cruise_problem(N, cap)
    X, U, status, its, f = _ipm.solve_round(w, cell, C, h, ecell, E, e, x0, u0)
    assert status == _ipm.ST_SOLVED and its < _ipm.IPM_MAX_ITER
    assert f == pytest.approx(np.sum(D) / math.sqrt(cap), rel=1e-7)
    np.testing.assert_allclose(X, cap, rtol=1e-7)
    # (u is held only through the chain of node relations from the ends, where an
    # alternating +-c is nearly free: it is known to the stopping tolerance 1e-8
    # times that chain's conditioning, 1e-8 to 1e-7 here)
    np.testing.assert_allclose(U, 0.0, atol=1e-6)
    assert np.all(X <= cap * (1 + 1e-12))  # an interior method: inside the limits


@needs_compiled
def test_plain_python_run_agrees_with_the_compiled_one():
    w, cell, C, h, ecell, E, e, x0, u0, _D = _cruise_problem(6, 1.7)
    none = np.zeros(0, dtype=np.int64)
    args = (6, w, cell.astype(np.int64), C, h, ecell.astype(np.int64), E, e, none, none * 1.0,
            none * 1.0, x0, u0,
            _ipm.IPM_MAX_ITER, _ipm.IPM_TOL, np.zeros(0), np.empty(cell.size))
    a = _ipm._solve(*args)
    b = _ipm._solve.py_func(*args)
    assert a[2] == b[2] == _ipm.ST_SOLVED and a[3] == b[3]
    np.testing.assert_allclose(a[0], b[0], rtol=1e-12)
    np.testing.assert_allclose(a[1], b[1], rtol=1e-12, atol=1e-12)


def _grid_problem(kind: str) -> GridProblem:
    """The grid problem of a joint path: q', q'', q''' on a grid, the joint limits
    (separate legs)."""
    if kind == "line":
        path = LinearJointPath([0.0, 0.2, -0.3], [1.0, -0.6, 0.9])
        s = np.linspace(0.0, path.length, 41)
        _q, d1, d2, d3 = path.derivatives(s)
    else:  # a helix in three joints: q = (cos 2s, sin 2s, s / 2)
        s = np.linspace(0.0, 1.0, 41)
        th = 2.0 * s
        d1 = np.column_stack([-2 * np.sin(th), 2 * np.cos(th), 0.5 + 0 * s])
        d2 = np.column_stack([-4 * np.cos(th), -4 * np.sin(th), 0 * s])
        d3 = np.column_stack([8 * np.sin(th), -8 * np.cos(th), 0 * s])
    m = d1.shape[1]
    v = np.full(m, 1.5)
    a = np.full(m, 6.0)
    j = np.full(m, 60.0)
    return GridProblem(s=s, d1=d1, d2=d2, d3=d3, v_max=v, a_acc=a, a_dec=0.7 * a, j_acc=j,
                       j_dec=0.8 * j, x_cap=np.full(s.size, np.inf))


@needs_compiled
@pytest.mark.parametrize("kind", ["line", "curve"])
@pytest.mark.parametrize("rounds", [1, 4])
def test_rounds_equal_the_cone_solvers(monkeypatch, kind, rounds):
    """One round (jerk-free) and several (with the jerk rows): the same time every
    round as Clarabel's, and the same speeds (the accelerations of a jerk-free
    optimum are not unique where no limit binds them), to the solvers' tolerances."""
    prob = _grid_problem(kind)
    monkeypatch.setattr(_socp, "USE_IPM", True)
    a = solve_grid(prob, max_rounds=rounds)
    monkeypatch.setattr(_socp, "USE_IPM", False)
    b = solve_grid(prob, max_rounds=rounds)
    assert a.rounds == b.rounds
    np.testing.assert_allclose(a.history, b.history, rtol=2e-6)
    assert a.jerk_free_time == pytest.approx(b.jerk_free_time, rel=1e-7)
    scale = float(np.max(b.x))
    np.testing.assert_allclose(a.x, b.x, rtol=0, atol=2e-4 * scale)


@needs_compiled
@pytest.mark.parametrize("kind", ["line", "curve"])
def test_a_round_started_from_the_multipliers_before(monkeypatch, kind):
    """The last round of a grid problem solved again from its solution: from its
    multipliers too (what a settled round gets from the round before) the method
    takes fewer iterations to the same optimum than from the solution alone; the
    multipliers come back in the order of the rows given."""
    rec = []
    real = _ipm.solve_round

    def spy(*args, **kw):
        out = real(*args, **kw)
        rec.append((args, out))
        return out

    monkeypatch.setattr(_ipm, "solve_round", spy)
    solve_grid(_grid_problem(kind), max_rounds=4)
    args, out = rec[-1]
    w, cell, C, h, ecell, E, e = args[:7]
    X, U = out[0], out[1]
    duals = np.empty(cell.size)
    base = real(w, cell, C, h, ecell, E, e, X, U, *args[9:], lam_out=duals)
    warm = real(w, cell, C, h, ecell, E, e, X, U, *args[9:], lam0=duals)
    assert base[2] == warm[2] == _ipm.ST_SOLVED
    assert warm[3] < base[3]
    assert warm[4] == pytest.approx(base[4], rel=1e-7)  # (the gap tolerance)
    np.testing.assert_allclose(warm[0], base[0], rtol=1e-5)
    assert np.all(duals >= 0.0) and np.sum(duals > 1e-6 * duals.max()) >= 5
    # the rows given in another order: their multipliers in that order
    perm = np.random.default_rng(1).permutation(cell.size)
    again = np.empty(cell.size)
    real(w, cell[perm], C[perm], h[perm], ecell, E, e, X, U, *args[9:], lam_out=again)
    big = duals[perm] > 1e-6 * duals.max()
    np.testing.assert_allclose(again[big], duals[perm][big], rtol=1e-4)


@needs_compiled
def test_a_round_it_does_not_solve_goes_to_the_cone_solver(monkeypatch):
    """With too few iterations allowed the method never converges: every round is
    Clarabel's, and the timing is the cone solver's alone."""
    path = LinearJointPath([0.0, 0.5], [1.0, -0.4])
    lims = [AxisLimits(1.0, 4.0, 40.0), AxisLimits(1.5, 3.0, 20.0, 2.0, 10.0)]
    monkeypatch.setattr(_socp, "USE_IPM", False)
    want = plan_path_timing(path, lims)
    calls = []
    real = _ipm.solve_round

    def starved(*args, **kw):
        out = real(*args, max_iter=2)
        calls.append(out[2])
        return out

    monkeypatch.setattr(_socp, "USE_IPM", True)
    monkeypatch.setattr(_ipm, "solve_round", starved)
    got = plan_path_timing(path, lims)
    assert calls and all(st != _ipm.ST_SOLVED for st in calls)
    assert got.duration == want.duration
    np.testing.assert_array_equal(got.t, want.t)


@needs_compiled
def test_known_optimum_with_the_curvature_rows():
    """The path acceleration with a curvature, (kappa x)^2 + u^2 <= a^2, binding at
    every node: x = a / kappa, u = 0 (the speed cap is looser)."""
    N, cap, a, kappa = 12, 4.0, 3.0, 1.5
    w, cell, C, h, ecell, E, e, x0, u0, D = _cruise_problem(N, cap)
    x0[0] = x0[N] = a / kappa
    inner = np.arange(1, N)
    quad = (inner, np.full(inner.size, (kappa / a) ** 2), np.full(inner.size, 1.0 / a**2))
    X, U, status, _its, f = _ipm.solve_round(w, cell, C, h, ecell, E, e, x0, u0, quad)
    assert status == _ipm.ST_SOLVED
    np.testing.assert_allclose(X, a / kappa, rtol=1e-7)
    np.testing.assert_allclose(U, 0.0, atol=1e-7)
    assert f == pytest.approx(np.sum(D) / math.sqrt(a / kappa), rel=1e-7)
    # (a curved row is met to the solver's tolerance, as a cone solver meets its cones)
    assert np.all((kappa * X[1:-1]) ** 2 + U[1:-1] ** 2 <= a * a * (1 + 1e-8))


@needs_compiled
def test_rounds_with_the_curvature_rows_equal_the_cone_solvers(monkeypatch):
    prob = _grid_problem("curve")
    prob.kappa = np.full(prob.s.size, 2.0)
    prob.a_path = 2.0
    monkeypatch.setattr(_socp, "USE_IPM", True)
    a = solve_grid(prob, max_rounds=4)
    monkeypatch.setattr(_socp, "USE_IPM", False)
    b = solve_grid(prob, max_rounds=4)
    assert a.rounds == b.rounds
    np.testing.assert_allclose(a.history, b.history, rtol=2e-6)
    np.testing.assert_allclose(a.x, b.x, rtol=0, atol=2e-4 * float(np.max(b.x)))


@needs_compiled
def test_path_acceleration_rows_that_cannot_bind_are_left_out(monkeypatch):
    """Where the joints' velocity and acceleration rows keep the path's
    acceleration vector inside its limit, its rows are left out: the same
    rounds as with every row, with fewer rows, and the limit still binding
    where the curvature is large."""
    prob = _grid_problem("curve")
    prob.kappa = np.linspace(0.0, 12.0, prob.s.size)
    prob.a_path = 5.0
    rows = []
    real = _ipm.solve_round

    def counted(w, cell, *args, **kw):
        rows.append(cell.size + (0 if args[7] is None else args[7][0].size))
        return real(w, cell, *args, **kw)

    monkeypatch.setattr(_ipm, "solve_round", counted)
    monkeypatch.setattr(_socp, "BIND_RTOL", 0.0)  # every row
    every = solve_grid(prob, max_rounds=4)
    n_every = sum(rows)
    rows.clear()
    monkeypatch.setattr(_socp, "BIND_RTOL", 0.999)
    some = solve_grid(prob, max_rounds=4)
    assert sum(rows) < n_every
    assert some.rounds == every.rounds
    np.testing.assert_allclose(some.history, every.history, rtol=1e-7)
    np.testing.assert_allclose(some.x, every.x, rtol=1e-5, atol=1e-6 * float(np.max(every.x)))
    use = np.hypot(prob.kappa * some.x, some.u) / prob.a_path
    assert use.max() > 0.999 and use[:5].max() < 0.9


def test_static_rows_in_interval_form_equal_the_sparse_assembly():
    """The rounds' fixed rows (``_StaticRows``: interval form, normalised) equal
    the rows assembled entry by entry as a sparse matrix and normalised by
    scaling its rows: the products ``A z`` to a few ulps (the same sums in the
    same order, but scipy's compiled loop may fuse a multiply-add where numpy
    does not), the right-hand sides, the nonzero entries and every row's
    first node (0 for a row without a coefficient)."""
    import scipy.sparse as sp

    rng = np.random.default_rng(12)
    n = 30
    for _trial in range(100):
        rows = _socp._StaticRows(n)
        ref_r, ref_c, ref_v, ref_b = [], [], [], []
        nr = 0
        for _block in range(int(rng.integers(1, 6))):
            k = int(rng.integers(0, 12))
            cell = rng.integers(0, n - 1, k)
            coefs = []
            for _a in range(4):
                c = rng.normal(size=k) * 10.0 ** rng.integers(-3, 4, k)
                c[rng.random(k) < 0.3] = 0.0  # some coefficients zero (some rows empty)
                coefs.append(c if rng.random() < 0.8 else float(c[0]) if k else 0.0)
            b = rng.normal(size=k) * 10.0 ** rng.integers(-3, 4, k)
            rows.add(cell, *coefs, b)
            cols = (cell, cell + 1, n + cell, n + cell + 1)
            for a in range(4):
                ref_r.append(nr + np.arange(k))
                ref_c.append(cols[a])
                ref_v.append(np.broadcast_to(coefs[a], (k,)))
            ref_b.append(b)
            nr += k
        rows.finish()
        A = sp.coo_matrix((np.concatenate(ref_v), (np.concatenate(ref_r), np.concatenate(ref_c))),
                          shape=(nr, 2 * n)).tocsr()
        b = np.concatenate(ref_b)
        big = np.maximum(np.maximum(abs(A).max(axis=1).toarray().ravel(), np.abs(b)), 1e-300)
        A = (sp.diags(1.0 / big) @ A).tocsc().tocsr()  # (columns sorted in every row)
        np.testing.assert_array_equal(rows.b, b / big)
        for _z in range(3):
            z = rng.normal(size=2 * n) * 10.0 ** rng.integers(-2, 3)
            ref = A @ z
            got = rows.times(z)
            scale = abs(A) @ np.abs(z)  # (the round-off of a sum is relative to its terms)
            assert np.all(np.abs(got - ref) <= 4 * np.finfo(float).eps * scale)
        r, c, v = rows.entries()
        got = sp.coo_matrix((v, (r, c)), shape=(nr, 2 * n)).tocsr()
        got.sort_indices()
        A.sort_indices()
        np.testing.assert_array_equal(got.indptr, A.indptr)
        np.testing.assert_array_equal(got.indices, A.indices)
        np.testing.assert_array_equal(got.data, A.data)
        coo = A.tocoo()
        first = np.full(nr, n, dtype=np.int64)
        np.minimum.at(first, coo.row, coo.col % n)
        first[first == n] = 0
        np.testing.assert_array_equal(rows.node, first)


@pytest.mark.parametrize("path_jerk", [True, False])
def test_compiled_jerk_rows_equal_the_numpy_ones(path_jerk):
    """The rounds' jerk rows (``_jerk_jit.jerk_rows``, compiled where numba is)
    equal the numpy formulation to a few ulps: random node states (some at
    rest), derivatives with zeros (a joint at rest picks the smaller leg),
    separate legs, intervals held to the smaller leg, with and without the
    path's jerk row."""
    from trajkit.timing import _jerk_jit

    rng = np.random.default_rng(31 + path_jerk)
    for _trial in range(50):
        n = int(rng.integers(3, 40))
        m = int(rng.integers(1, 8))
        x = rng.uniform(0.0, 2.0, n) * (rng.random(n) > 0.15)
        u = rng.normal(size=n)
        ecorr = 0.01 * rng.normal(size=n - 1)
        g = np.flatnonzero(rng.random(n - 1) < 0.8).astype(np.int64)
        d1, d2, d3 = (rng.normal(size=(n, m)) * (rng.random((n, m)) > 0.2) for _ in range(3))
        sig = np.sign(d1)
        j_acc = rng.uniform(0.5, 5.0, (n, m))
        j_dec = rng.uniform(0.5, 5.0, (n, m))
        j_both = np.minimum(j_acc, j_dec)
        mixed = rng.random((n - 1, m)) < 0.2
        D = rng.uniform(0.01, 0.1, n - 1)
        j_path = float(rng.uniform(1.0, 10.0)) if path_jerk else math.inf
        C, b = _jerk_jit.jerk_rows(x, u, ecorr, g, sig, d1, d2, d3, j_acc, j_dec, j_both, mixed, D,
                                   j_path, _socp.TINY_X)
        C2, b2 = _socp._jerk_coefs_numpy(j_path, x, u, ecorr, g, (g, g + 1), sig, d1, d2, d3, j_acc,
                                         j_dec, j_both, mixed, D)
        assert C.shape == C2.shape == (4 * g.size * m + (2 * g.size if path_jerk else 0), 4)
        np.testing.assert_allclose(C, C2, rtol=4e-16 * 8, atol=1e-300)
        np.testing.assert_allclose(b, b2, rtol=4e-16 * 8, atol=1e-300)
        assert np.abs(C).max(axis=1, initial=0.0).max(initial=1.0) <= 1.0


def test_the_jerk_free_rounds_start_is_the_speed_the_ends_allow():
    """The starting point of the jerk-free round (``_socp._reachable``): the min-plus
    scans equal the step-by-step recursion ``x_(i+1) = min(cap, x_i + 2 D a)``
    from both ends, on a path whose joint rates vary (and a zero-rate stretch)."""
    rng = np.random.default_rng(2)
    n = 40
    s = np.sort(np.concatenate([[0.0, 1.0], rng.uniform(0.0, 1.0, n - 2)]))
    d1 = np.column_stack([np.cos(3 * s), 0.5 + 0 * s])
    d1[10:14] = 0.0  # no joint moves there: no bound from the accelerations
    prob = GridProblem(s=s, d1=d1, d2=0 * d1, d3=0 * d1, v_max=np.array([1.0, 2.0]),
                       a_acc=np.array([3.0, 5.0]), a_dec=np.array([2.0, 5.0]),
                       j_acc=np.array([30.0, 50.0]), j_dec=np.array([30.0, 50.0]),
                       x_cap=np.full(n, np.inf), x0=0.0, xN=0.04)
    D = np.diff(s)
    xv = rng.uniform(0.5, 2.0, n)
    xv[20:25] = np.inf
    got = _socp._reachable(xv, D, prob)
    with np.errstate(divide="ignore"):
        um = np.min(np.where(np.abs(d1) > 0, np.minimum([3.0, 5.0], [2.0, 5.0]) / np.abs(d1), np.inf), axis=1)
    cap = xv.copy()
    cap[0], cap[-1] = 0.0, 0.04
    fwd, bwd = cap.copy(), cap.copy()
    for i in range(n - 1):
        fwd[i + 1] = min(cap[i + 1], fwd[i] + 2 * D[i] * min(um[i], um[i + 1]))
    for i in range(n - 2, -1, -1):
        bwd[i] = min(cap[i], bwd[i + 1] + 2 * D[i] * min(um[i], um[i + 1]))
    want = np.minimum(fwd, bwd)
    finite = np.isfinite(want)
    assert finite.sum() > n // 2 and got[0] == 0.0 and got[-1] == 0.04
    np.testing.assert_allclose(got[finite], want[finite], rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_a_pivot_that_cancels_is_raised_not_a_failure(sign):
    """Two nearly parallel active rows make terms of 1e16 whose difference cancels
    to zero in floating point: the factorisation raises that pivot, with the sign
    it has in exact arithmetic, to PIVOT_RTOL of its diagonal entry (a dynamic
    regularisation) instead of failing; a pivot that is not a number fails."""
    big = 1e16
    # lower band storage (half-width 1) of [[big, big], [big, big + sign]]: the
    # second pivot is +-1 exactly, 0.0 after the round-off of big + sign
    M = np.array([[big, 0.0], [big + sign, big]])
    L = np.zeros((2, 2))
    d = np.zeros(2)
    signs = np.array([1.0, sign])
    raised = _ipm._ldl(M, 1, L, d, signs)
    assert raised == 1
    assert d[0] == big and L[1, 1] == 1.0
    assert d[1] == sign * _ipm.PIVOT_RTOL * big
    # a well-conditioned matrix keeps its exact pivots
    M2 = np.array([[4.0, 0.0], [3.0, 1.0]])
    assert _ipm._ldl(M2, 1, L, d, np.ones(2)) == 0
    np.testing.assert_allclose(d, [4.0, 3.0 - 0.25], rtol=1e-15)
    M3 = np.array([[np.nan, 0.0], [1.0, 1.0]])
    assert _ipm._ldl(M3, 1, L, d, np.ones(2)) == -1


@needs_compiled
def test_a_step_towards_zero_speed_is_damped_so_the_iterates_do_not_cycle():
    """A jerk-free round of a random UR5 CIRC (its rows stored): a Newton step that
    goes most of the way to ``x = 0`` at a node puts the iterate where the
    objective's Hessian is huge, its multipliers collapse and the iterates
    climb back and fall again (with steps of 0.99 of the way there: 100
    iterations without converging). With the step to ``x = 0`` damped
    (:data:`_ipm.X_STEP_FRACTION`) it converges in a few iterations to a feasible point."""
    d = np.load(Path(__file__).parent / "data" / "ipm_cycling_round.npz")
    quad = (d["qnode"], d["qxx"], d["quu"])
    X, U, status, its, f = _ipm.solve_round(d["w"], d["cell"], d["C"], d["h"], d["ecell"], d["E"],
                                            d["e"], d["x0"], d["u0"], quad)
    assert status == _ipm.ST_SOLVED and its <= 30, (status, its)
    x4 = np.column_stack([X[d["cell"]], X[d["cell"] + 1], U[d["cell"]], U[d["cell"] + 1]])
    assert (np.einsum("ij,ij->i", d["C"], x4) <= d["h"] + 1e-7 * np.maximum(1.0, np.abs(d["h"]))).all()
    e4 = np.column_stack([X[d["ecell"]], X[d["ecell"] + 1], U[d["ecell"]], U[d["ecell"] + 1]])
    assert np.abs(np.einsum("ij,ij->i", d["E"], e4) - d["e"]).max() < 1e-7
    k = d["qnode"]
    assert (d["qxx"] * X[k] ** 2 + d["quu"] * U[k] ** 2 <= 1.0 + 1e-7).all()
    assert (X[1:-1] > 0).all()
    assert f == pytest.approx(np.sum(d["w"] / (np.sqrt(X[:-1]) + np.sqrt(X[1:]))), rel=1e-12)
