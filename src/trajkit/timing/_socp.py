"""The grid problem of the path-timing engine: sequential convex restriction, one SOCP per round.

On a grid ``s_0 < ... < s_N`` of the path parameter the unknowns are, at
every node, ``x = sdot^2`` and ``u = sddot``. Between nodes the path
acceleration is linear in time (one constant path jerk per interval), which
ties the nodes by

    x_{i+1} - x_i = D_i (u_i + u_{i+1}) + (u_{i+1}^2 - u_i^2) tau_i^2 / 12

(``tau_i`` the interval's duration; exact for a constant-jerk interval) and
gives the interval's path jerk ``(u_{i+1} - u_i) / tau_i``, with
``D_i / tau_i = (sqrt(x_i) + sqrt(x_{i+1})) / 2 + (u_i - u_{i+1}) tau_i / 12``.
For every joint ``k`` (``q'``, ``q''``, ``q'''``: derivatives of the joint path
in s):

- velocity   ``|q'| sqrt(x) <= v_max``,
- acceleration ``q'' x + q' u`` within the leg limits (``a_max`` while the
  joint speeds up, ``a_max_decel`` while it slows down),
- jerk       ``|r (q''' x + 3 q'' u) + q' w| <= j / v`` at both ends of every
  interval, with ``w = (u_{i+1} - u_i) / D_i``, ``v`` the interval's mean
  speed and ``r`` the node terms' speed factor: the joint jerk at a node is
  ``sdot (q''' x + 3 q'' u) + q' v w``, so the factor is exact at
  ``r = rho``, the node's speed over ``v``. At the interval's faster end
  the rows take ``r = rho`` (the largest speed over the interval); at its
  slower end, ``(1 + rho) / 2`` (the mean speed of the node's half
  interval: the jerk between the node and the middle, not only at the node)
  where the node terms add to the row's value at the previous round's
  states, and ``rho`` where they subtract from it (there the larger factor
  would loosen the row below the node's own jerk: the check found excesses
  of up to 0.94 % at such nodes); ``r = 1`` at both ends leaves the faster
  end's jerk too loose, which the check corrects by re-solving,

and the path's own limits (speed cap per node, tangential acceleration and
jerk). The time ``sum D_i / mean speed`` is convex in ``x`` (a second-order
cone program, as in Verscheure et al. 2009); the jerk bound ``j / v`` is a
convex function of ``x``, so replacing it by its tangent plane at the
previous round's solution restricts the feasible set: every round's solution
satisfies the true constraints of the model, the previous solution stays
feasible, and the time decreases monotonically until the rounds agree
(sequential convex restriction). The quadratic term of the node relation, the
mean-speed correction and the jerk rows' speed factor are taken from the
previous round (linearised; with them the decrease is only nearly
monotone: a round slower than the one before ends the rounds, the fastest
kept); the first round drops the jerk constraints (the jerk-free optimum on the
grid: a lower bound). Where the first round with them has no solution (its
tangent planes taken at speeds far above any jerk-limited timing's), it is
solved again from a uniformly slower timing, or, with a moving boundary state
that such a slow-down cannot keep, approached through relaxed rounds whose
jerk limits are a multiple of the true ones (see :data:`RELAX_START`; so is
one whose first jerk round stalls, see :data:`STALL_FACTOR`).

A start or end at rest is exact: the first (last) interval is one jerk
phase from rest, ``x_1 = 1.5 D_0 u_1`` and path jerk ``sqrt(u_1^3 / (6 D_0))``.

Each round is solved by the banded interior-point method of :mod:`._ipm`
(compiled with numba; the time minimised directly, no cone), or as the cone
program by Clarabel where numba is missing or that method does not converge.

Pure math: arrays in, arrays out.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from . import _ipm, _jerk_jit
from ._hermite import time_to_reach, time_to_reach_one

__all__ = ["GridProblem", "GridSolution", "solve_grid"]

#: Stop when a round changes the time by less than this fraction.
ROUND_RTOL = 5e-4

#: A solve that starts from a solution of the grid (``settled`` or ``near``) stops
#: after its first round when that changed the time by less than this fraction.
SETTLED_RTOL = ROUND_RTOL

#: Most rounds (the first is jerk-free).
MAX_ROUNDS = 6

#: Solver tolerances (relative gap and feasibility).
SOLVER_TOL = 1e-8

#: A round the solver stopped early is still used when its primal residual is below this.
PRIMAL_RTOL = 1e-7

#: The cones are scaled by the previous round's x, but not below this fraction of its largest.
SCALE_FLOOR = 1e-9

#: Screening: an inequality (a limit, bound > 0) whose slack at the previous
#: round's solution (or at the starting point) is above this fraction of its
#: bound is left out of the next round (after the jerk-free round: only the velocity and
#: acceleration rows; the jerk rows are all kept) ...
SCREEN_SLACK = 0.25

#: Before the rounds have settled (SCREEN_SETTLED) only the rows whose slack, in
#: the units of the row normalised to coefficients <= 1, is above this are left out.
SCREEN_SLACK_LOOSE = 1.0

#: ... unless the new solution violates it by more than this; then the round is
#: solved again with more rows (see SCREEN_PASSES).
SCREEN_TOL = 1e-9

#: ... or comes within this fraction of its bound (it would be active: solved
#: again with it, so that the solver keeps it as accurately as the others).
SCREEN_MARGIN = 1e-6

#: Solves of one round at most: a round whose solution violates a row left out
#: is solved again with those rows and the rows near its solution added, the
#: last time with every row.
SCREEN_PASSES = 4

#: ... with every row of the nodes within this many nodes of a violated row.
SCREEN_AROUND = 2

#: Screening starts once a round changed the time by less than this fraction (the
#: rounds' solutions are then close, and so are their active limits); with a
#: starting point, the first round is compared with the starting point's time.
SCREEN_SETTLED = 0.02

#: The path's acceleration rows are left out at the nodes where the joints'
#: velocity and acceleration rows keep its square below this fraction of the
#: limit's (see ``_solve_scaled``).
BIND_RTOL = 0.999

#: Node speeds^2 below this fraction of the largest are treated as zero in the
#: tangent planes (guards a division near a stop in the path's interior).
TINY_X = 1e-12

#: A braking start whose recovery at the start's jerk comes to below this fraction
#: of its speed is followed node by node (see ``_braking_start``).
NEAR_STOP = 0.1

#: A new solution's jerk row (linearised at it, with its own legs) exceeded by
#: more than this (the rows are normalised) where the row that bounded it took
#: the looser leg: that interval takes the tighter leg from then on.
LEG_RTOL = 1e-6


@dataclass
class GridProblem:
    """Data of the grid problem, in the units of the caller.

    Attributes
    ----------
    s : ndarray, shape (n,)
        Grid of the path parameter, increasing.
    d1, d2, d3 : ndarray, shape (n, m)
        ``q'``, ``q''``, ``q'''`` of the m joints at the nodes.
    v_max, a_acc, a_dec : ndarray, shape (m,) or (n, m)
        Joint velocity and acceleration limits (leg: speeding up / slowing down).
    j_acc, j_dec : ndarray, shape (m,) or (n, m)
        Joint jerk limits of the two legs.
    x_cap : ndarray, shape (n,)
        Largest ``sdot^2`` at each node from the path's own speed limits.
    a_path, j_path : float
        Acceleration and jerk limits of the path (inf: none); with ``kappa``
        the acceleration limit bounds the norm of ``(sddot, kappa sdot^2)``.
    kappa : ndarray, shape (n,), optional
        Curvature of the tool path at the nodes [1/path unit] (normal acceleration).
    x_cap_mid : ndarray, shape (n - 1,), optional
        Largest ``sdot^2`` at the middle of every interval (the path's speed cap there).
    x0, u0, xN, uN : float
        Boundary states (``sdot^2`` and ``sddot``).
    j_path_scale : ndarray, shape (n - 1,), optional
        Factor (>= 1) on ``j_path`` in every interval (none: 1 everywhere).
    a_path_scale : ndarray, shape (n,), optional
        Factor (<= 1) on ``a_path`` at every node (none: 1 everywhere): the
        path's acceleration limit lowered locally.
    """

    s: np.ndarray
    d1: np.ndarray
    d2: np.ndarray
    d3: np.ndarray
    v_max: np.ndarray
    a_acc: np.ndarray
    a_dec: np.ndarray
    j_acc: np.ndarray
    j_dec: np.ndarray
    x_cap: np.ndarray
    a_path: float = math.inf
    j_path: float = math.inf
    x0: float = 0.0
    u0: float = 0.0
    xN: float = 0.0
    uN: float = 0.0
    kappa: np.ndarray | None = None
    x_cap_mid: np.ndarray | None = None
    j_path_scale: np.ndarray | None = None
    a_path_scale: np.ndarray | None = None


@dataclass
class GridSolution:
    """Node states of the solved grid problem.

    Attributes
    ----------
    x, u : ndarray, shape (n,)
        ``sdot^2`` and ``sddot`` at the nodes.
    time : float
        The model's duration [s].
    jerk_free_time : float
        Duration of the first (jerk-free) round: a lower bound of the model.
    rounds : int
    converged : bool
    status : str
        The solver's status of the last round.
    history : list of float
        The model's duration after every round [s].
    duals : ndarray
        The multipliers of the last round's inequalities (interior-point
        method only; NaN where a row was left out).
    """

    x: np.ndarray
    u: np.ndarray
    time: float
    jerk_free_time: float
    rounds: int
    converged: bool
    status: str
    history: list[float] = field(default_factory=list)  # time of every round [s]
    #: the multipliers of the last round's inequalities (NaN where a row was left
    #: out), for a warm start of a solve on the same grid
    duals: np.ndarray = field(default_factory=lambda: np.zeros(0))


class _StaticRows:
    """The inequalities that do not change between rounds, in interval form: every
    row ``coef[r] . (x_i, x_{i+1}, u_i, u_{i+1}) <= b[r]`` on its interval
    ``i = cell[r]``, normalised (divided by its largest coefficient or
    right-hand side: the set is unchanged), in the order they were added.
    """

    def __init__(self, n: int) -> None:
        self.n = n
        self._cell: list[np.ndarray] = []
        self._coef: list[np.ndarray] = []
        self._b: list[np.ndarray] = []
        self.size = 0

    def add(self, cell: np.ndarray, c0, c1, c2, c3, rhs: np.ndarray) -> None:
        """Rows on the intervals ``cell`` with the coefficients ``c0 .. c3`` (scalars
        or arrays of the rows) on ``x_i, x_{i+1}, u_i, u_{i+1}``."""
        k = rhs.size
        if k == 0:
            return
        C = np.empty((k, 4))
        for a, c in enumerate((c0, c1, c2, c3)):
            C[:, a] = c
        self._cell.append(np.asarray(cell, dtype=np.int64))
        self._coef.append(C)
        self._b.append(np.asarray(rhs, dtype=float))
        self.size += k

    def finish(self) -> None:
        """Stack and normalise the rows (each multiplied by the reciprocal of its
        largest magnitude, the right-hand side divided by it); ``node``: the
        first node a row involves, 0 for a row without a coefficient."""
        if self.size:
            cell = np.concatenate(self._cell)
            C = np.concatenate(self._coef)
            b = np.concatenate(self._b)
        else:
            cell, C, b = np.zeros(0, dtype=np.int64), np.zeros((0, 4)), np.zeros(0)
        # (an infinite right-hand side, a limit that is not there, stays infinite)
        bf = np.where(np.isfinite(b), np.abs(b), 0.0)
        A = np.abs(C)  # (the largest of the four columns: numpy's row maxima are slow here)
        big = np.maximum(np.maximum(np.maximum(A[:, 0], A[:, 1]), np.maximum(A[:, 2], A[:, 3])), bf)
        big = np.maximum(big, 1e-300)
        self.coef = C * (1.0 / big)[:, None]
        self.b = b / big
        self.cell = cell
        nz = self.coef != 0.0
        self.node = np.where(nz[:, 0] | nz[:, 2], cell, np.where(nz[:, 1] | nz[:, 3], cell + 1, 0))
        n = self.n
        self.cols = (cell, cell + 1, n + cell, n + cell + 1)

    def times(self, z: np.ndarray) -> np.ndarray:
        """``A z`` of the rows (in the order a sparse row product sums them)."""
        C = self.coef
        c0, c1, c2, c3 = self.cols
        return C[:, 0] * z[c0] + C[:, 1] * z[c1] + C[:, 2] * z[c2] + C[:, 3] * z[c3]

    def entries(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(row, column, value) of every nonzero coefficient (the cone program's matrix)."""
        r, a = np.nonzero(self.coef)
        cols = np.stack(self.cols, axis=1)
        return r, cols[r, a], self.coef[r, a]


def _near(Az: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The rows ``A z <= b`` (``Az`` = ``A z``) whose slack is below SCREEN_SLACK of
    their bound (and every row whose bound is not positive)."""
    return ((b - Az) < SCREEN_SLACK * b) | (b <= 0.0)


def _around(node: np.ndarray, rows: np.ndarray, n: int) -> np.ndarray:
    """The rows (of nodes ``node``, one per row, of ``n``) whose nodes lie within
    SCREEN_AROUND nodes of a node of one of ``rows`` (a boolean mask)."""
    mark = np.zeros(n + 2 * SCREEN_AROUND + 1, dtype=bool)
    for k in range(2 * SCREEN_AROUND + 1):
        mark[node[rows] + k] = True
    return mark[node + SCREEN_AROUND]


class _Layout:
    """The constraint matrix of the cone program in CSC, its sparsity pattern fixed for
    the grid: blocks of rows stacked in order, each with fixed (row, column) entries;
    one block (the inequalities) has rows that a solve may leave out. Built once;
    per solve only the values and the rows kept change (the CSC order of the entries
    is computed once).

    Parameters
    ----------
    nv : int
        Unknowns.
    blocks : list of (int, ndarray, ndarray)
        Rows of the block, and the row (within the block) and column of every entry.
    select : int
        Index of the block whose rows can be left out.
    """

    def __init__(self, nv: int, blocks: list[tuple[int, np.ndarray, np.ndarray]], select: int) -> None:
        self.nv = nv
        sizes = [b[0] for b in blocks]
        self.offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        self.n_rows = int(self.offsets[-1])
        self.select = select
        rows = np.concatenate([np.asarray(r, dtype=np.int64) + self.offsets[k]
                               for k, (_n, r, _c) in enumerate(blocks)])
        cols = np.concatenate([np.asarray(c, dtype=np.int64) for _n, _r, c in blocks])
        self.order = np.lexsort((rows, cols))  # column by column, rows increasing
        self.rows = rows[self.order]
        self.cols = cols[self.order]
        lo, hi = self.offsets[select], self.offsets[select + 1]
        self.in_select = (self.rows >= lo) & (self.rows < hi)
        self.local = self.rows[self.in_select] - lo
        self.indptr = np.concatenate([[0], np.cumsum(np.bincount(self.cols, minlength=nv))])

    def matrix(self, values: list[np.ndarray], keep: np.ndarray) -> sp.csc_matrix:
        """The matrix with the block values ``values`` (each in its block's entry order)
        and the rows ``keep`` (mask) of the selectable block."""
        data = np.concatenate(values)[self.order]
        if keep.all():
            return sp.csc_matrix((data, self.rows, self.indptr), shape=(self.n_rows, self.nv))
        lo = self.offsets[self.select]
        dropped = np.zeros(self.n_rows, dtype=np.int64)
        dropped[lo + np.nonzero(~keep)[0]] = 1
        shift = np.cumsum(dropped)
        entry = np.ones(self.rows.size, dtype=bool)
        entry[self.in_select] = keep[self.local]
        rows = self.rows[entry]
        cols = self.cols[entry]
        indptr = np.concatenate([[0], np.cumsum(np.bincount(cols, minlength=self.nv))])
        return sp.csc_matrix((data[entry], rows - shift[rows], indptr),
                             shape=(self.n_rows - int(shift[-1]), self.nv))


def _clarabel_solve(clarabel, P, q, A, b, cones):
    """Clarabel's solution of the cone program; without iterative refinement of the
    linear systems first (the stopping criteria are on the true residuals, so a
    solved status means the same accuracy), with it when that does not solve."""
    for refine in (False, True):
        settings = clarabel.DefaultSettings()
        settings.verbose = False
        settings.tol_gap_abs = SOLVER_TOL
        settings.tol_gap_rel = SOLVER_TOL
        settings.tol_feas = SOLVER_TOL
        settings.iterative_refinement_enable = refine
        sol = clarabel.DefaultSolver(P, q, A, b, cones, settings).solve()
        if str(sol.status).split(".")[-1] in ("Solved", "AlmostSolved"):
            break
    return sol


def _reversal_rows(static: _StaticRows, p: GridProblem, sig: np.ndarray, d1_mid: np.ndarray,
                   D: np.ndarray) -> None:
    """Joint accelerations in the middle of both intervals next to a reversal.

    A joint with separate acceleration legs reverses at a node (``q'`` zero
    there, see the engine's reversal nodes): its row there bounds ``q'' x``
    only, not ``u``, while on either side ``q' u`` counts. The middle of each
    neighbouring interval, on the leg of its other node's sign, with the
    interval's state there from the cubic Hermite interpolation of ``x``
    (slopes ``2 u``): ``x_mid = (x_i + x_{i+1})/2 + (u_i - u_{i+1}) D/4``,
    ``u_mid = 3 (x_{i+1} - x_i) / (4 D) - (u_i + u_{i+1})/4``; ``q'`` there as
    the velocity rows', ``q''`` the mean of the nodes'.
    """
    n, m = sig.shape
    acc = np.broadcast_to(p.a_acc, (n, m))
    dec = np.broadcast_to(p.a_dec, (n, m))
    node, joint = np.nonzero((sig == 0) & (acc != dec))
    inner = (node > 0) & (node < n - 1)
    node, joint = node[inner], joint[inner]
    if not node.size:
        return
    cell = np.concatenate([node - 1, node])
    joint = np.concatenate([joint, joint])
    other = np.concatenate([node - 1, node + 1])
    sg = sig[other, joint]
    keep = sg != 0
    cell, joint, sg = cell[keep], joint[keep], sg[keep]
    dd = D[cell]
    a1 = d1_mid[cell, joint]
    a2 = 0.5 * (p.d2[cell, joint] + p.d2[cell + 1, joint])
    c0, c1 = sg * (0.5 * a2 - 0.75 * a1 / dd), sg * (0.5 * a2 + 0.75 * a1 / dd)
    c2, c3 = sg * (0.25 * dd * a2 - 0.25 * a1), sg * (-0.25 * dd * a2 - 0.25 * a1)
    # speeding up within the accel leg, slowing down within the decel leg
    static.add(cell, c0, c1, c2, c3, np.minimum(acc[cell, joint], acc[cell + 1, joint]))
    static.add(cell, -c0, -c1, -c2, -c3, np.minimum(dec[cell, joint], dec[cell + 1, joint]))


def _legs(sig: np.ndarray, acc: np.ndarray, dec: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Upper and lower bound of ``sigma * q_ddot`` per node and joint (sigma = sign(q'))."""
    hi = np.where(sig != 0, acc, np.minimum(acc, dec))
    lo = np.where(sig != 0, dec, np.minimum(acc, dec))
    return hi, lo


def _speed_correction(x: np.ndarray, u: np.ndarray, D: np.ndarray,
                      tau: np.ndarray | None = None) -> np.ndarray:
    """The intervals' correction of the mean speed, ``(u_i - u_{i+1}) tau_i / 12``
    (``tau``: :func:`_interval_tau`, computed when not given)."""
    return (u[:-1] - u[1:]) * (_interval_tau(x, u, D) if tau is None else tau) / 12.0


def _interval_tau(x: np.ndarray, u: np.ndarray, D: np.ndarray) -> np.ndarray:
    """Durations of the constant-jerk intervals between node states (Hermite relation)."""
    v = np.sqrt(np.maximum(x, 0.0))
    qa = (u[:-1] - u[1:]) / 12.0
    qb = 0.5 * (v[:-1] + v[1:])
    disc = np.maximum(qb * qb + 4.0 * qa * D, 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        tau = 2.0 * D / (qb + np.sqrt(disc))
    return np.where(np.isfinite(tau), tau, 0.0)


def _time_scale(p: GridProblem) -> float:
    """A time unit [s] in which the problem's numbers are of order one."""
    L = float(p.s[-1] - p.s[0])
    n, m = p.d1.shape
    a1 = np.max(np.abs(p.d1), axis=0)

    def least(lim):  # every joint's limit (per joint or per node and joint): its least
        return np.broadcast_to(lim, (n, m)).min(axis=0)

    with np.errstate(divide="ignore"):
        v = np.min(np.where(a1 > 0, least(p.v_max) / a1, np.inf))
        a = np.min(np.where(a1 > 0, least(np.minimum(p.a_acc, p.a_dec)) / a1, np.inf))
        j = np.min(np.where(a1 > 0, least(np.minimum(p.j_acc, p.j_dec)) / a1, np.inf))
    v = min(v, float(np.max(np.sqrt(p.x_cap))))
    cands = [L / v if v > 0 and math.isfinite(v) else 0.0,
             math.sqrt(L / a) if a > 0 and math.isfinite(a) else 0.0,
             (L / j) ** (1.0 / 3.0) if j > 0 and math.isfinite(j) else 0.0,
             math.sqrt(L / p.a_path) if math.isfinite(p.a_path) else 0.0,
             (L / p.j_path) ** (1.0 / 3.0) if math.isfinite(p.j_path) else 0.0]
    T = max(cands)
    return T if T > 0 and math.isfinite(T) else 1.0


def _rest_jerk(qa: np.ndarray, jl: np.ndarray, j_path: float) -> float:
    """The largest path jerk of a jerk phase from or to rest: every joint's jerk
    limit ``jl`` over its ``|q'|`` ``qa`` (m,) (none where ``q'`` is 0), and the
    path's own limit ``j_path`` (inf: none)."""
    with np.errstate(divide="ignore"):
        return min(float(np.min(np.where(qa > 0, jl / qa, np.inf))), j_path)


def _rest_jerk_bounds(p: GridProblem, d1: np.ndarray, j_acc: np.ndarray, j_dec: np.ndarray,
                      D: np.ndarray, rest0: bool, restN: bool) -> list[tuple[int, float, float]]:
    """The rest intervals: one jerk phase, ``|q'| J <= j`` with ``J = sqrt(u^3 / (6 D))``,
    as a bound on the inner node's ``u``: (node, sign, bound) of each."""
    N = D.size
    out = []
    for flag, node, dd, sgn in ((rest0, 1, D[0], 1.0), (restN, N - 1, D[N - 1], -1.0)):
        if not flag:
            continue
        qa = np.maximum(np.abs(d1[node]), np.abs(d1[0 if node == 1 else N]))
        # from rest the joints speed up (accel leg), to rest they slow down
        J = _rest_jerk(qa, (j_acc if node == 1 else j_dec)[node], p.j_path)
        ub = (6.0 * dd) ** (1.0 / 3.0) * J ** (2.0 / 3.0)
        if math.isfinite(ub):
            out.append((node, sgn, ub))
    return out


def _braking_start(p: GridProblem, x: np.ndarray, d1: np.ndarray,
                   j_dec: np.ndarray) -> np.ndarray:
    """The jerk-free round's ``x`` lowered near a braking start to the speeds of its
    fastest recovery: the first jerk round's linearisation point.

    A start that slows down (``u0 < 0``) keeps slowing down until its
    acceleration is back at zero, at best at the jerk limit ``J`` of the leg
    (the joints' braking jerk over ``|q'|`` at the start, the path's jerk):
    its speed falls to ``v0 - u0^2 / (2 J)``. The jerk-free round turns the
    acceleration around at once and runs much faster there; the jerk rows'
    tangent planes (of ``j / v``, convex in the speed) taken at its speeds
    are then far below the limit at the speeds the braking start has to
    pass, and made the round infeasible (11 of 300 random moving starts).
    Below the end of that recovery, ``x`` is at most its speeds; after it,
    at most the speed regained at the start's deceleration.

    Where that recovery comes to a near-stop (below :data:`NEAR_STOP` of the
    start's speed), it runs node by node instead (:func:`_node_recovery`):
    the jerk the joints allow changes along it (a palletizer start at 0.033
    m/s braking at -1.2 m/s^2 came to 0.00015 m/s at the start's jerk, where
    its joints recover at 0.018 m/s, and no round had a solution).

    Parameters
    ----------
    p : GridProblem
        The (scaled) grid problem; ``x0 > 0``, ``u0 < 0``.
    x : ndarray, shape (n,)
        The jerk-free round's ``sdot^2`` at the nodes.
    d1 : ndarray, shape (n, m)
        ``dq/ds`` at the nodes.
    j_dec : ndarray, shape (n, m)
        The joints' jerk limits while slowing down.

    Returns
    -------
    ndarray, shape (n,)
    """
    v0, u0 = math.sqrt(p.x0), p.u0
    J = _rest_jerk(np.abs(d1[0]), j_dec[0], p.j_path)
    if not (math.isfinite(J) and J > 0.0):
        return x
    t1 = -u0 / J  # the recovery's duration, its length and the lowest speed
    s1 = t1 * (v0 + t1 * (0.5 * u0 + t1 * J / 6.0))
    v_low = v0 + t1 * (u0 + 0.5 * t1 * J)
    ds = p.s - p.s[0]
    if v_low < NEAR_STOP * v0 and (nodes := _node_recovery(p, d1, j_dec)) is not None:
        k, v, s1, v_low = nodes
        inside = np.arange(ds.size) <= k
    else:
        tt = time_to_reach(0.0, v0, u0, J, ds, t1)  # (every node inside the recovery)
        v = v0 + tt * (u0 + 0.5 * tt * J)
        inside = ds <= s1
    return np.minimum(x, np.where(inside, v * v, v_low * v_low - 2.0 * u0 * (ds - s1)))


def _node_recovery(p: GridProblem, d1: np.ndarray,
                   j_dec: np.ndarray) -> tuple[int, np.ndarray, float, float] | None:
    """A braking start's recovery (its acceleration back at zero) node by node, each
    cell at the jerk of :func:`_recovery_jerk` at its first node: ``(k, speed, s1,
    v_low)``, the last node inside it, the speeds at the nodes up to it (n,), its
    length and its lowest speed; None where a node's jerk is not positive or the
    speed would reach zero first."""
    ds = p.s - p.s[0]
    n = ds.size
    speed = np.empty(n)
    v, u, k = math.sqrt(p.x0), p.u0, 0
    while True:
        speed[k] = v
        J = _recovery_jerk(p, k, v, u, d1, j_dec)
        if not (math.isfinite(J) and J > 0.0):
            return None
        t1 = -u / J
        v_low = v + t1 * (u + 0.5 * t1 * J)
        if not v_low > 0.0:
            return None
        s1 = ds[k] + t1 * (v + t1 * (0.5 * u + t1 * J / 6.0))
        if k == n - 1 or s1 < ds[k + 1]:
            return k, speed, s1, v_low
        t = time_to_reach_one(v, u, J, ds[k + 1] - ds[k], t1)
        v, u, k = v + t * (u + 0.5 * t * J), u + t * J, k + 1


def _recovery_jerk(p: GridProblem, k: int, v: float, u: float, d1: np.ndarray,
                   j_dec: np.ndarray) -> float:
    """The largest path jerk at node ``k`` in the state ``v``, ``u``: every joint's
    jerk ``q''' v^3 + 3 q'' v u + q' j`` within its braking limit, and the path's
    jerk limit."""
    c = p.d3[k] * v**3 + 3.0 * p.d2[k] * v * u
    q1, jl = d1[k], j_dec[k]
    with np.errstate(divide="ignore", invalid="ignore"):
        bound = np.where(q1 > 0.0, (jl - c) / q1, np.where(q1 < 0.0, (jl + c) / -q1, np.inf))
    return min(float(np.min(bound)), p.j_path)


def _leg_limits(sig: np.ndarray, d1: np.ndarray, d2: np.ndarray, x: np.ndarray, u: np.ndarray,
                j_acc: np.ndarray, j_dec: np.ndarray, j_both: np.ndarray,
                mixed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The joints' jerk limit of every interval at its left and right end, each
    (n - 1, m), with the legs at the node states ``x``, ``u``: where the joint
    speeds up (slows down) at both ends of the interval, else (a leg change
    inside, or ``mixed``) the tighter of both."""
    sp = sig * (d2 * x[:, None] + d1 * u[:, None])
    up = (sp[:-1] > 0) & (sp[1:] > 0) & ~mixed
    down = (sp[:-1] < 0) & (sp[1:] < 0) & ~mixed
    left, right = (np.where(up, j_acc[e], np.where(down, j_dec[e], j_both[e]))
                   for e in (slice(None, -1), slice(1, None)))
    return left, right


def _leg_flips(p: GridProblem, used: tuple[np.ndarray, np.ndarray],
               new: tuple[np.ndarray, np.ndarray], g: np.ndarray,
               ends: tuple[np.ndarray, np.ndarray], sig: np.ndarray, d1: np.ndarray,
               d2: np.ndarray, d3: np.ndarray, j_acc: np.ndarray, j_dec: np.ndarray,
               j_both: np.ndarray, mixed: np.ndarray, D: np.ndarray) -> np.ndarray:
    """The free intervals whose jerk rows took a looser leg than the new solution
    runs on, where that solution's jerk exceeds the leg's limit.

    A round's jerk rows take an interval's leg from the states they are
    linearised at (``used``: ``x``, ``u`` of the nodes; the sign of
    ``qdot * qddot`` at both ends of the interval). Where the new solution
    (``new``: ``x``, ``u``) moves a leg
    change into or across the interval, its pieces there run on the other leg;
    if that leg's limit is the smaller (separate jerk limits while speeding up
    and slowing down), the rows did not bound them, and the next round, with
    the other leg, would move the change back. Returns a bool array (n - 1, m):
    the intervals ``g`` and joints where the new solution's jerk, as its own
    rows (linearised at it, with its legs) measure it, exceeds that limit, less
    those already ``mixed`` (which take the smaller limit whatever their leg).
    """
    x, u = new
    before = _leg_limits(sig, d1, d2, *used, j_acc, j_dec, j_both, mixed)
    after = _leg_limits(sig, d1, d2, x, u, j_acc, j_dec, j_both, mixed)
    out = np.zeros(mixed.shape, dtype=bool)
    out[g] = ((before[0] > after[0]) | (before[1] > after[1]))[g]
    if not out.any():
        return out
    n, m = x.size, d1.shape[1]
    rows = _jerk_rows(p, x, u, _speed_correction(x, u, D), g, ends, sig, d1, d2, d3, j_acc, j_dec,
                      j_both, mixed, D, n, [])
    z = np.concatenate([x, u])
    over = (rows.times(z) - rows.b)[:4 * g.size * m] > LEG_RTOL
    hit = np.zeros(mixed.shape, dtype=bool)
    hit[g] = over.reshape(4, g.size, m).any(axis=0)
    return out & hit


def _jerk_cells(g: np.ndarray, m: int, path_jerk: bool) -> np.ndarray:
    """The interval of every jerk row of :func:`_jerk_rows` (in its order)."""
    cells = [np.repeat(g, m)] * 4 + ([g, g] if path_jerk else [])
    return np.concatenate(cells) if cells else np.zeros(0, dtype=int)


class _JerkRows:
    """The jerk rows of one round (see :func:`_jerk_rows`): ``coef`` (r, 4) on the
    columns ``x_i, x_{i+1}, u_i, u_{i+1}`` of the row's interval ``i`` (``cell``),
    then the rest intervals' bounds (one coefficient ``rest`` on ``u`` of ``node``);
    ``b`` the right-hand side of all."""

    def __init__(self, coef: np.ndarray, cell: np.ndarray, rest: np.ndarray, node: np.ndarray,
                 b: np.ndarray, n: int) -> None:
        self.coef = coef
        self.cols = (cell, cell + 1, n + cell, n + cell + 1)
        self.rest = rest
        self.rest_col = n + node
        self.b = b

    def values(self) -> np.ndarray:
        """The coefficients in the entry order of :meth:`pattern`."""
        return np.concatenate([self.coef.ravel(), self.rest])

    @staticmethod
    def pattern(cell: np.ndarray, node: np.ndarray, n: int) -> tuple[int, np.ndarray, np.ndarray]:
        """Rows, and row and column of every entry."""
        nr = cell.size
        rows = np.concatenate([np.repeat(np.arange(nr), 4), nr + np.arange(node.size)])
        cols = np.concatenate([np.column_stack([cell, cell + 1, n + cell, n + cell + 1]).ravel(),
                               n + node])
        return nr + node.size, rows, cols

    def times(self, z: np.ndarray) -> np.ndarray:
        """``A z`` of the rows (summed as a CSR product does: entry by entry)."""
        C = self.coef
        c0, c1, c2, c3 = self.cols
        return np.concatenate([C[:, 0] * z[c0] + C[:, 1] * z[c1] + C[:, 2] * z[c2] + C[:, 3] * z[c3],
                               self.rest * z[self.rest_col]])


def _jerk_rows(p: GridProblem, x_bar: np.ndarray, u_bar: np.ndarray, ecorr: np.ndarray,
               g: np.ndarray, ends: tuple[np.ndarray, np.ndarray], sig: np.ndarray,
               d1: np.ndarray, d2: np.ndarray, d3: np.ndarray, j_acc: np.ndarray,
               j_dec: np.ndarray, j_both: np.ndarray, mixed: np.ndarray, D: np.ndarray, n: int,
               rest_rows: list[tuple[int, float, float]], relax: float = 1.0) -> _JerkRows:
    """The jerk rows linearised at ``(x_bar, u_bar)`` (see the module notes), normalised.

    Every row of a free interval ``i`` has its coefficients on ``x_i, x_{i+1}, u_i,
    u_{i+1}`` (columns ``i, i + 1, n + i, n + i + 1``): the joints' jerk at both ends
    of the interval, both signs, then the path's jerk, then the rest intervals' bounds.
    ``mixed`` (n - 1, m): the intervals whose joint takes the tighter leg (see
    :func:`_leg_flips`).
    ``relax``: a factor on every jerk limit (a relaxed round, see RELAX_START).
    Compiled (:mod:`._jerk_jit`) where numba is available, else in numpy.
    """
    m = d1.shape[1]
    j_path = p.j_path
    if relax != 1.0:
        j_acc, j_dec, j_both, j_path = j_acc * relax, j_dec * relax, j_both * relax, j_path * relax
        rest_rows = [(nd, sgn, ub * relax) for nd, sgn, ub in rest_rows]
    if _jerk_jit.AVAILABLE:
        C, b = _jerk_jit.jerk_rows(x_bar, u_bar, ecorr, np.ascontiguousarray(g, dtype=np.int64),
                                   *(np.ascontiguousarray(a, dtype=float) for a in
                                     (sig, d1, d2, d3, j_acc, j_dec, j_both)),
                                   np.ascontiguousarray(mixed, dtype=np.bool_),
                                   np.ascontiguousarray(D, dtype=float),
                                   float(j_path), TINY_X)
    else:
        C, b = _jerk_coefs_numpy(j_path, x_bar, u_bar, ecorr, g, ends, sig, d1, d2, d3,
                                 j_acc, j_dec, j_both, mixed, D)
    if p.j_path_scale is not None and math.isfinite(p.j_path):
        # the path's jerk limit times its factor in each interval: the rows' terms
        # in x and their bound scale with it (then normalised again)
        G = g.size
        rows = 4 * G * m + np.arange(2 * G)
        f = np.tile(np.asarray(p.j_path_scale, dtype=float)[g], 2)
        C[rows, :2] *= f[:, None]
        b[rows] *= f
        big = np.maximum(np.max(np.abs(C[rows]), axis=1), np.abs(b[rows]))
        C[rows] /= big[:, None]
        b[rows] /= big
    rest = np.array([sgn / max(1.0, ub) for _node, sgn, ub in rest_rows], dtype=float)
    extra = np.array([ub / max(1.0, ub) for _node, _sgn, ub in rest_rows], dtype=float)
    node = np.array([nd for nd, _sgn, _ub in rest_rows], dtype=int)
    return _JerkRows(C, _jerk_cells(g, m, math.isfinite(p.j_path)), rest, node,
                     np.concatenate([b, extra]), n)


def _jerk_coefs_numpy(j_path: float, x_bar: np.ndarray, u_bar: np.ndarray, ecorr: np.ndarray,
                      g: np.ndarray, ends: tuple[np.ndarray, np.ndarray], sig: np.ndarray,
                      d1: np.ndarray, d2: np.ndarray, d3: np.ndarray, j_acc: np.ndarray,
                      j_dec: np.ndarray, j_both: np.ndarray, mixed: np.ndarray,
                      D: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The coefficients and right-hand sides of the joints' and the path's jerk rows
    (normalised) of :func:`_jerk_rows`, in numpy (:func:`._jerk_jit.jerk_rows` is
    the compiled twin)."""
    sq = np.sqrt(np.maximum(x_bar, TINY_X * max(float(x_bar.max()), TINY_X)))
    S = sq[g] + sq[g + 1] + 2.0 * ecorr[g]
    S = np.maximum(S, 0.5 * (sq[g] + sq[g + 1]))
    S2 = (S * S)[:, None]
    Dg = D[g][:, None]
    xi, xj = x_bar[g][:, None], x_bar[g + 1][:, None]
    si, sj = sq[g][:, None], sq[g + 1][:, None]
    coef: list[np.ndarray] = []  # (r, 4) each
    rhs: list[np.ndarray] = []
    # the leg of each interval from the previous round's states
    legs = _leg_limits(sig, d1, d2, x_bar, u_bar, j_acc, j_dec, j_both, mixed)
    for e, nd in enumerate(ends):
        jl = legs[e][g]
        f = 2.0 * jl / S[:, None]
        gi = -jl / (S2 * si)
        gj = -jl / (S2 * sj)
        r = (f - gi * xi - gj * xj).ravel()
        rs = 2.0 * (si if e == 0 else sj) / S[:, None]  # the node's speed over the mean
        half = 0.5 * (1.0 + rs)
        nt = d3[nd] * x_bar[nd][:, None] + 3.0 * d2[nd] * u_bar[nd][:, None]
        for sgn in (1.0, -1.0):
            fac = np.where(sgn * nt > 0.0, np.maximum(rs, half), np.minimum(rs, half))
            w = sgn * d1[nd] / Dg
            c3, c2 = sgn * fac * d3[nd], sgn * fac * 3.0 * d2[nd]
            if e == 0:
                c = (c3 - gi, -gj, c2 - w, w)
            else:
                c = (-gi, c3 - gj, -w, c2 + w)
            coef.append(np.stack(c, axis=-1).reshape(-1, 4))
            rhs.append(r)
    if math.isfinite(j_path):
        f1 = 2.0 * j_path / S
        gi1 = -j_path / (S * S * sq[g])
        gj1 = -j_path / (S * S * sq[g + 1])
        r1 = f1 - gi1 * x_bar[g] - gj1 * x_bar[g + 1]
        for sgn in (1.0, -1.0):
            w1 = sgn / D[g]
            coef.append(np.column_stack([-gi1, -gj1, -w1, w1]))
            rhs.append(r1)
    C = np.concatenate(coef) if coef else np.zeros((0, 4))
    b = np.concatenate(rhs) if rhs else np.zeros(0)
    big = np.maximum(np.maximum(np.abs(C).max(axis=1, initial=0.0), np.abs(b)), 1e-300)
    return C / big[:, None], b / big


def _ipm_solve(s_cell, s_coef, b_in_all, keep, jerk, g, eq_values, b_eq, rest0, restN, D, wts, p,
               x_bar, u_bar, xv, nv, n, quad=None, duals=None):
    """One round by the banded interior-point method (:mod:`._ipm`) on the
    inequalities ``keep`` (of the static rows, then the jerk rows, as in
    ``b_in_all``): ``(z, time, multipliers)`` with ``z`` the cone program's
    unknowns (only ``x`` and ``u`` filled) and the multipliers of the rows (NaN
    for those left out), or ``(None, nan, None)`` when it did not solve.
    ``duals``: the previous round's multipliers of the same rows, to start
    this round's from (a warm start)."""
    N = n - 1
    cells = [s_cell]
    coefs = [s_coef]
    if jerk is not None:
        cells.append(jerk.cols[0])
        coefs.append(jerk.coef)
        if jerk.rest.size:
            node = jerk.rest_col - n
            rc = np.zeros((node.size, 4))
            rc[:, 2] = jerk.rest
            cells.append(np.minimum(node, N - 1))
            coefs.append(rc)
    cell = np.concatenate(cells).astype(np.int64)
    C = np.concatenate(coefs)
    rows = keep[:cell.size] & np.isfinite(b_in_all[:cell.size])
    cell, C, h = cell[rows], C[rows], b_in_all[:cell.size][rows]
    # equalities: the rest intervals' relations, then the node relations of the intervals g
    ecells, ecoefs = [], []
    k = 0
    if rest0:
        ecells.append(np.array([0]))
        ecoefs.append(np.array([[0.0, eq_values[0][0], 0.0, eq_values[0][1]]]))
        k += 1
    if restN:
        ecells.append(np.array([N - 1]))
        ecoefs.append(np.array([[eq_values[k][0], 0.0, eq_values[k][1], 0.0]]))
        k += 1
    one, mone, cu0, cu1 = eq_values[k:k + 4]
    ecells.append(g)
    ecoefs.append(np.column_stack([mone * np.ones(g.size), one * np.ones(g.size), cu0, cu1]))
    ecell = np.concatenate(ecells).astype(np.int64)
    E = np.concatenate(ecoefs)
    e = np.asarray(b_eq, dtype=float)
    if x_bar is None:  # the jerk-free round: from half the speeds the ends allow
        inner = xv[1:-1]
        level = float(np.min(inner[np.isfinite(inner)], initial=1.0))
        top = float(np.max(inner[np.isfinite(inner)], initial=level))
        x0 = np.clip(START_REACH * _reachable(xv, D, p), START_FLOOR * level, top)
        x0 = np.where(np.isfinite(x0), x0, START_LEVEL * level)
        u0 = np.zeros(n)
    else:
        x0, u0 = x_bar.copy(), u_bar.copy()
    x0[0], u0[0], x0[N], u0[N] = p.x0, p.u0, p.xN, p.uN
    warm = duals is not None and duals.size == rows.size
    lam_out = np.empty(int(rows.sum()))
    X, U, status, _its, f = _ipm.solve_round(wts, cell, C, h, ecell, E, e, x0, u0, quad,
                                             lam0=duals[rows] if warm else None, lam_out=lam_out)
    if status != _ipm.ST_SOLVED:
        return None, math.nan, None
    lam = np.full(rows.size, math.nan)
    lam[rows] = lam_out
    z = np.zeros(nv)
    z[:n] = X
    z[n:2 * n] = U
    return z, f, lam


#: The jerk-free round starts from this fraction of the squared speeds the ends
#: allow (:func:`_reachable`), at least START_FLOOR of the slowest node's cap
#: (where nothing bounds them: START_LEVEL of it); 8.7 % fewer iterations over
#: the benchmark's arm motions than from a flat START_LEVEL.
START_REACH = 0.5
START_FLOOR = 1e-3
START_LEVEL = 0.1


def _reachable(xv: np.ndarray, D: np.ndarray, p: GridProblem) -> np.ndarray:
    """Squared path speeds (n,) reachable from both end states under the velocity
    caps ``xv`` (n,) with the path acceleration each node's joints allow at rest
    (``min_j a_j / |q_j'|``, the smaller of two neighbours over an interval of
    length ``D``): ``x_(i+1) <= x_i + 2 D_i a_i``, forward and backward, as
    min-plus scans. A starting point only (no limit is decided by it)."""
    d1 = np.abs(p.d1)
    with np.errstate(divide="ignore", invalid="ignore"):
        um = np.min(np.where(d1 > 0, np.minimum(p.a_acc, p.a_dec) / d1, np.inf), axis=1)
    step = 2.0 * D * np.minimum(um[:-1], um[1:])
    cap = np.asarray(xv, dtype=float).copy()
    cap[0], cap[-1] = p.x0, p.xN
    # an unbounded step (no joint moves): one larger than any bound the scan can
    # carry past it, so that nothing before it bounds what comes after
    fin = np.isfinite(step)
    big = 4.0 * (float(np.max(cap[np.isfinite(cap)], initial=0.0)) + float(np.sum(step[fin]))) + 1.0
    step = np.where(fin, step, big)
    with np.errstate(invalid="ignore"):
        C = np.concatenate([[0.0], np.cumsum(step)])  # x_i <= cap_k + C_i - C_k, k <= i
        fwd = C + np.minimum.accumulate(cap - C)
        B = np.concatenate([np.cumsum(step[::-1])[::-1], [0.0]])  # ... k >= i, from the end
        bwd = B + np.minimum.accumulate((cap - B)[::-1])[::-1]
    return np.minimum(fwd, bwd)


#: Use the banded interior-point method (:mod:`._ipm`) where numba is installed;
#: the cone solver otherwise (and for a round the method does not solve).
USE_IPM = True


#: Nodes within this fraction of the path's speed cap are put on it (a cruise
#: at the programmed speed is exactly at that speed, not a solver tolerance below).
SNAP_RTOL = 1e-6

#: A node of a cruise at the cap has no path acceleration (the speed is at its
#: largest there, on both sides): a solver's remainder (about 1e-8 of it) is
#: set to zero where it is below this fraction of the cap over the path's length.
SNAP_U_RTOL = 1e-4


def _rest_relation(x: np.ndarray, u: np.ndarray, s: np.ndarray, start: bool, end: bool) -> None:
    """The rest intervals' relation, exactly, on their inner nodes (``start``: the
    first interval's, ``end``: the last's): one jerk phase from or to rest over
    the interval ``D`` reaches ``x = 1.5 D |u|`` (``u`` > 0 from rest, < 0 to
    rest); ``u`` (n,) set from ``x`` (n,) on the grid ``s`` (n,)."""
    N = x.size - 1
    if start:
        u[1] = x[1] / (1.5 * (s[1] - s[0]))
    if end:
        u[N - 1] = -x[N - 1] / (1.5 * (s[N] - s[N - 1]))


def _snap_to_caps(sol: GridSolution, p: GridProblem) -> None:
    """Put nodes at the path's own speed cap exactly on it; a run of such nodes with one
    cap is a cruise (no path acceleration). A rest interval's inner node keeps the
    relation of its jerk phase (``x = 1.5 D |u|``)."""
    x, u = sol.x, sol.u
    cap = p.x_cap
    on = np.isfinite(cap) & (x >= cap * (1.0 - 2.0 * SNAP_RTOL))
    on[0] = on[-1] = False
    x[on] = cap[on]
    same = on[:-1] & on[1:] & (cap[:-1] == cap[1:])
    flat = np.zeros(x.size, dtype=bool)
    flat[:-1] |= same
    flat[1:] |= same
    u[flat & (np.abs(u) * (p.s[-1] - p.s[0]) <= SNAP_U_RTOL * np.maximum(cap, 1e-300))] = 0.0
    N = x.size - 1
    if N >= 2:
        _rest_relation(x, u, p.s, p.x0 == 0.0 and p.u0 == 0.0 and bool(on[1] or flat[1]),
                       p.xN == 0.0 and p.uN == 0.0 and bool(on[N - 1] or flat[N - 1]))


#: A grid interval shorter than this fraction of its longer neighbour is short
#: (the twin node just before a path breakpoint): its node states are settled.
SHORT_INTERVAL = 1e-2


def _settle_short(sol: GridSolution, p: GridProblem) -> None:
    """Make every short interval's node speeds those of one constant-jerk piece.

    The node relation holds only to the solver's tolerance, and less where a
    node was put on its speed cap; the two pieces of an interval then differ
    in jerk by that error over the interval's duration squared, which a short
    interval turns into a jerk far above the limit. With the accelerations
    ``a0, a1`` kept, one jerk joins the states exactly when
    ``v1 - v0 = (a0 + a1) tau / 2``, with ``tau`` from
    ``D = v1 tau - (a0 + 2 a1) tau^2 / 6`` (from the end) or
    ``D = v0 tau + (2 a0 + a1) tau^2 / 6`` (from the start). The first node's
    speed is set from the second's; where that would pass the first node's
    speed cap, the second's from the first (within its cap), else nothing is
    changed. The change moves into the long neighbour interval, divided by its
    duration squared. The inner node of a rest interval keeps its speed (its
    jerk phase from or to rest ties it to the node's acceleration).
    """
    D = np.diff(p.s)
    N = D.size
    if N < 3:
        return
    longer = np.maximum(np.concatenate([[0.0], D[:-1]]), np.concatenate([D[1:], [0.0]]))
    x, u = sol.x, sol.u
    cap = p.x_cap
    rest0 = p.x0 == 0.0 and p.u0 == 0.0
    restN = p.xN == 0.0 and p.uN == 0.0
    for i in np.nonzero(D < SHORT_INTERVAL * longer)[0]:
        if i == 0 or i == N - 1:  # a given end state (or a rest interval)
            continue
        a0, a1, d = float(u[i]), float(u[i + 1]), float(D[i])
        v1 = math.sqrt(max(x[i + 1], 0.0))
        disc = v1 * v1 - 2.0 * (a0 + 2.0 * a1) * d / 3.0
        if v1 > 0.0 and disc >= 0.0 and not (i == 1 and rest0):
            tau = 2.0 * d / (v1 + math.sqrt(disc))
            v0 = v1 - 0.5 * (a0 + a1) * tau
            if v0 > 0.0 and v0 * v0 <= cap[i]:
                x[i] = v0 * v0
                continue
        v0 = math.sqrt(max(x[i], 0.0))
        disc = v0 * v0 + 2.0 * (2.0 * a0 + a1) * d / 3.0
        if v0 > 0.0 and disc >= 0.0 and not (i == N - 2 and restN):
            tau = 2.0 * d / (v0 + math.sqrt(disc))
            v1 = v0 + 0.5 * (a0 + a1) * tau
            if v1 > 0.0 and v1 * v1 <= cap[i + 1]:
                x[i + 1] = v1 * v1


#: Where the first jerk round has no solution (its rows linearised at the
#: jerk-free round's speeds, which can be twice those of any jerk-limited
#: timing), it is solved again from that round's timing slowed down uniformly,
#: its ``x`` times SLOWER_X (the time doubled), at most SLOWER_RETRIES times.
SLOWER_RETRIES = 2
SLOWER_X = 0.25

#: With a moving boundary state a uniform slow-down cannot keep that state: where
#: the first jerk round has no solution, it is approached in relaxed rounds
#: instead (a continuation), their jerk limits times a factor, each round
#: linearised at the one before: from RELAX_START, divided by RELAX_STEP after
#: every relaxed round that solves; a round that does not solve is tried again
#: with the factor between its own and that of its linearisation point (the
#: geometric mean; from the jerk-free round's point, or the caller's starting
#: point, a factor RELAX_STEP^2 larger), at most RELAX_FAILS times. A relaxed
#: round's solution is only the next round's linearisation point, never a result.
RELAX_START = 8.0
RELAX_STEP = 2.0
RELAX_FAILS = 6

#: ... the factors closer to 1 than this are 1 (the true limits), and a step
#: closer to its linearisation point's factor than this ends the continuation.
RELAX_RTOL = 0.05

#: With a moving boundary state, a first jerk round after the jerk-free round (not
#: a relaxed one) whose time is more than this many times the jerk-free time
#: counts as without a solution (the relaxed rounds take over): its tangent
#: planes, taken far from any jerk-feasible timing, held the speed near zero at
#: some node (a near-stop in the middle of the path; 2e8 times the jerk-free time
#: on one of the benchmark's re-plans), which no later round left. (A solve
#: started from a given point is not tested: compared with that point's time,
#: 3 of the benchmark's 98 re-plans failed that the later rounds repair.)
STALL_FACTOR = 1e3

#: :attr:`GridSolution.status` of a solve whose rounds ended in a relaxed round
#: (its ``x`` and ``u`` a relaxed solution: a starting point, not a timing).
RELAXED = "Relaxed"


def solve_grid(p: GridProblem, max_rounds: int = MAX_ROUNDS,
               init: tuple[np.ndarray, np.ndarray] | None = None,
               settled: bool = False, near: bool = False,
               duals: np.ndarray | None = None) -> GridSolution:
    """Solve the grid problem (see the module notes); raises RuntimeError if the solver fails.

    The problem is solved in scaled units (``s / L``, ``t / T0`` with ``T0``
    from :func:`_time_scale`) and the result returned in the caller's.
    ``init`` (node ``x`` and ``u``, e.g. a coarser grid's solution interpolated)
    is the first linearisation point: the jerk-free round is skipped
    (``jerk_free_time`` is then NaN). ``settled``: ``init`` is a solution of
    this grid with about the same limits, so its active limits are those of the
    first round (which then leaves out the rows far from them, see SCREEN_SLACK;
    the result is the same, only sooner). ``near``: ``init`` is a converged
    solution of this grid less a few nodes (cells split in two), interpolated:
    the solve stops after its first round when that changed the time by less
    than SETTLED_RTOL (its first round is screened loosely, SCREEN_SLACK_LOOSE).
    """
    L = float(p.s[-1] - p.s[0])
    T0 = _time_scale(p)
    vs, as_, js = T0, T0 * T0, T0**3
    scaled = GridProblem(
        s=(p.s - p.s[0]) / L, d1=p.d1 * L, d2=p.d2 * L**2, d3=p.d3 * L**3,
        v_max=np.asarray(p.v_max) * vs, a_acc=np.asarray(p.a_acc) * as_,
        a_dec=np.asarray(p.a_dec) * as_, j_acc=np.asarray(p.j_acc) * js,
        j_dec=np.asarray(p.j_dec) * js, x_cap=p.x_cap * (T0 / L) ** 2,
        a_path=p.a_path * as_ / L, j_path=p.j_path * js / L,
        x0=p.x0 * (T0 / L) ** 2, u0=p.u0 * as_ / L, xN=p.xN * (T0 / L) ** 2, uN=p.uN * as_ / L,
        kappa=None if p.kappa is None else np.asarray(p.kappa, dtype=float) * L,
        x_cap_mid=None if p.x_cap_mid is None else p.x_cap_mid * (T0 / L) ** 2,
        j_path_scale=p.j_path_scale, a_path_scale=p.a_path_scale)
    init_s = None if init is None else (init[0] * (T0 / L) ** 2, init[1] * as_ / L)
    sol = _solve_scaled(scaled, max_rounds, init_s, settled and init is not None,
                        near and init is not None, duals if settled and init is not None else None)
    sol.x = sol.x * (L / T0) ** 2
    sol.u = sol.u * L / as_
    sol.x[0], sol.u[0], sol.x[-1], sol.u[-1] = p.x0, p.u0, p.xN, p.uN
    _snap_to_caps(sol, p)
    _settle_short(sol, p)
    sol.time *= T0
    sol.jerk_free_time *= T0
    sol.history = [t * T0 for t in sol.history]
    return sol


def _solve_scaled(p: GridProblem, max_rounds: int,
                  init: tuple[np.ndarray, np.ndarray] | None = None,
                  settled: bool = False, near: bool = False,
                  duals0: np.ndarray | None = None) -> GridSolution:
    import clarabel

    s = p.s
    n = s.size
    N = n - 1
    D = np.diff(s)
    m = p.d1.shape[1]
    d1, d2, d3 = p.d1, p.d2, p.d3
    sig = np.sign(d1)
    vmax = np.broadcast_to(p.v_max, (n, m))
    a_hi, a_lo = _legs(sig, np.broadcast_to(p.a_acc, (n, m)), np.broadcast_to(p.a_dec, (n, m)))
    j_both = np.minimum(np.broadcast_to(p.j_acc, (n, m)), np.broadcast_to(p.j_dec, (n, m)))
    # (full arrays, once: every round's jerk rows read them)
    j_acc = np.ascontiguousarray(np.broadcast_to(p.j_acc, (n, m)), dtype=float)
    j_dec = np.ascontiguousarray(np.broadcast_to(p.j_dec, (n, m)), dtype=float)
    rest0 = p.x0 == 0.0 and p.u0 == 0.0
    restN = p.xN == 0.0 and p.uN == 0.0

    ix = np.arange(n)
    iu = n + ix
    ic = 2 * n + ix
    idd = 3 * n + np.arange(N)
    nv = 3 * n + N

    with np.errstate(divide="ignore"):
        xv = np.min(np.where(np.abs(d1) > 0, (vmax / np.abs(d1)) ** 2, np.inf), axis=1)
    xv = np.minimum(xv, p.x_cap)
    inner = np.arange(1, N)  # nodes whose state is free
    d1_mid = 0.5 * (d1[:-1] + d1[1:]) + 0.125 * D[:, None] * (d2[:-1] - d2[1:])
    with np.errstate(divide="ignore"):
        xv_mid = np.min(np.where(np.abs(d1_mid) > 0,
                                 (np.minimum(vmax[:-1], vmax[1:]) / np.abs(d1_mid)) ** 2, np.inf), axis=1)

    # objective: interval time D / mean speed (the rest intervals' constant-jerk phase: 1.5x)
    q = np.zeros(nv)
    wts = 2.0 * D.copy()
    if rest0:
        wts[0] *= 1.5
    if restN:
        wts[-1] *= 1.5
    q[idd] = wts

    # cones: c_i^2 <= x_i and d_i (c_i + c_{i+1}) >= 1, each scaled by the
    # previous round's values (sigma ~ x_i, rho ~ 1 / (c_i + c_{i+1})) so that
    # they stay accurate next to a stop where x is tiny. The end nodes' x is
    # given: their c is fixed by an equality, no cone, so that the problem
    # keeps a strictly feasible interior.
    free = np.arange(1, N)
    nf = free.size
    k3 = np.arange(nf)
    k4 = np.arange(N)
    base = 3 * nf
    cone_r = np.concatenate([3 * k3, 3 * k3 + 1, 3 * k3 + 2])
    cone_c = np.concatenate([ix[free], ix[free], ic[free]])
    r2 = np.concatenate([base + 3 * k4] * 3 + [base + 3 * k4 + 1] * 3)
    c2 = np.concatenate([idd, ic[:-1], ic[1:], idd, ic[:-1], ic[1:]])

    def cone_values(sigma: np.ndarray, rho: np.ndarray) -> np.ndarray:
        sf = sigma[free]
        return np.concatenate([-1.0 / sf, -1.0 / sf, -2.0 / np.sqrt(sf),
                               -1.0 / rho, -rho, -rho, -1.0 / rho, rho, rho])

    sigma = np.ones(n)
    rho = np.ones(N)

    # the path's acceleration vector: ||(u_i, kappa_i x_i)|| <= a_path, at the nodes
    # where it can bind: the joints' velocity and acceleration rows bound x and |u|
    # at every node (|q'| |u| <= a + |q''| x), and where those bounds keep the
    # vector inside its limit, its rows are left out (they could never be active)
    reach = np.zeros(n, dtype=bool)
    # (the limit at every node: lowered locally where a_path_scale says so)
    ap = np.full(n, p.a_path) if p.a_path_scale is None else p.a_path * np.asarray(p.a_path_scale)
    if math.isfinite(p.a_path):
        with np.errstate(divide="ignore", invalid="ignore"):
            u_top = np.min(np.where(np.abs(d1) > 0, (np.maximum(a_hi, a_lo) + np.abs(d2) * xv[:, None])
                                    / np.abs(d1), np.inf), axis=1)
            k_top = 0.0 if p.kappa is None else np.asarray(p.kappa) * xv
            reach = ~(k_top * k_top + u_top * u_top < BIND_RTOL * ap**2)
    if p.kappa is not None and math.isfinite(p.a_path):
        kn = free[(np.asarray(p.kappa)[free] > 0) & reach[free]]
    else:
        kn = np.zeros(0, dtype=int)
    kr = np.arange(kn.size)
    acc_block = (3 * kn.size, np.concatenate([3 * kr + 1, 3 * kr + 2]), np.concatenate([iu[kn], ix[kn]]))
    acc_values = np.concatenate([-np.ones(kn.size), -np.asarray(p.kappa)[kn]]) if kn.size else np.zeros(0)
    b_acc = np.column_stack([ap[kn], np.zeros((kn.size, 2))]).ravel()

    x_bar = None
    u_bar = np.zeros(n)
    tau2 = np.zeros(N)
    ecorr = np.zeros(N)
    times: list[float] = []
    times_status: list[str] = []
    status = ""
    x = np.zeros(n)
    u = np.zeros(n)
    converged = False
    jerk_free = math.nan

    def linearise_at(xx: np.ndarray, uu: np.ndarray):
        floor = SCALE_FLOOR * max(float(xx.max()), TINY_X)
        sg = np.maximum(xx, floor)
        rh = 1.0 / (np.sqrt(sg[:-1]) + np.sqrt(sg[1:]))
        ta = _interval_tau(xx, uu, D)
        return sg, rh, ta * ta, _speed_correction(xx, uu, D, ta)

    # the rows that do not change between rounds: the nodes' and the intervals'
    # velocity, the path's speed cap, the joint accelerations of both legs, the
    # path acceleration (normalised inequalities) and the signs of c and d
    static = _StaticRows(n)
    static.add(inner, 1.0, 0.0, 0.0, 0.0, xv[inner])
    # joint velocities in the middle of every interval too (x_mid as for the cap below;
    # q' there from its cubic Hermite interpolation)
    im = np.nonzero(np.isfinite(xv_mid))[0]
    static.add(im, 0.5, 0.5, 0.25 * D[im], -0.25 * D[im], xv_mid[im])
    # the path's speed cap also in the middle of every interval (the speed
    # between nodes, not only at them): x_mid = (x_i + x_{i+1})/2 + (u_i - u_{i+1}) D/4
    capm = np.minimum(p.x_cap[:-1], p.x_cap[1:])
    if p.x_cap_mid is not None:
        capm = np.minimum(capm, p.x_cap_mid)
    cm = np.nonzero(np.isfinite(capm))[0]
    static.add(cm, 0.5, 0.5, 0.25 * D[cm], -0.25 * D[cm], capm[cm])
    n_vel = static.size
    # joint accelerations at the free nodes, both legs
    nn = np.repeat(inner, m)
    kk = np.tile(np.arange(m), inner.size)
    sg = np.where(sig[nn, kk] != 0, sig[nn, kk], 1.0)
    static.add(nn, sg * d2[nn, kk], 0.0, sg * d1[nn, kk], 0.0, a_hi[nn, kk])
    static.add(nn, -sg * d2[nn, kk], 0.0, -sg * d1[nn, kk], 0.0, a_lo[nn, kk])
    _reversal_rows(static, p, sig, d1_mid, D)
    if math.isfinite(p.a_path):  # (where it can bind and the curvature's rows do not bound it)
        flat = np.setdiff1d(inner[reach[inner]], kn)
        static.add(flat, 0.0, 0.0, 1.0, 0.0, ap[flat])
        static.add(flat, 0.0, 0.0, -1.0, 0.0, ap[flat])
    static.finish()
    b_static = static.b
    use_ipm = USE_IPM and _ipm.AVAILABLE
    # the path's acceleration with the curvature, as the method's quadratic rows
    quad = None
    if kn.size:
        ka = np.asarray(p.kappa)[kn] / ap[kn]
        quad = (kn.astype(np.int64), ka * ka, 1.0 / ap[kn]**2)
    n_static = b_static.size
    # the node of every inequality (the first node it involves: screening around a node)
    node_static = static.node
    # the signs of c and d
    both = np.concatenate([ic[free], idd])
    b_nn = np.zeros(both.size)

    mid = np.arange(N)
    special = np.zeros(N, dtype=bool)
    special[0] = rest0
    special[N - 1] |= restN
    g = mid[~special]  # intervals with a free jerk (not the rest intervals)
    # the jerk rows' limit (leg) at both ends of every free interval, both signs
    ends = (g, g + 1)
    rest_rows = _rest_jerk_bounds(p, d1, j_acc, j_dec, D, rest0, restN)
    # the intervals held to the tighter leg (see _leg_flips; only with separate legs)
    mixed = np.zeros((N, m), dtype=bool)
    asym = bool(np.any(j_acc != j_dec))

    # the equalities: the boundary states, the rest intervals' relation and the node relations
    eq_cols = [ix[0:1], iu[0:1], ix[N:], iu[N:], ic[0:1], ic[N:]]
    eq_rows = [np.arange(1) + k for k in range(6)]
    n_eq = 6
    if rest0:
        eq_cols += [ix[1:2], iu[1:2]]
        eq_rows += [np.array([n_eq])] * 2
        n_eq += 1
    if restN:
        eq_cols += [ix[N - 1:N], iu[N - 1:N]]
        eq_rows += [np.array([n_eq])] * 2
        n_eq += 1
    rel = n_eq + np.arange(g.size)
    eq_cols += [ix[g + 1], ix[g], iu[g], iu[g + 1]]
    eq_rows += [rel] * 4
    n_eq += g.size
    eq_fixed = [np.ones(6)]
    b_eq_fixed = [np.array([p.x0, p.u0, p.xN, p.uN, math.sqrt(p.x0), math.sqrt(p.xN)])]
    if rest0:
        eq_fixed.append(np.array([1.0, -1.5 * D[0]]))
        b_eq_fixed.append(np.zeros(1))
    if restN:
        eq_fixed.append(np.array([1.0, 1.5 * D[N - 1]]))
        b_eq_fixed.append(np.zeros(1))
    ones_g = np.ones(g.size)

    # every inequality that a round may have: the static rows, then the jerk rows
    jcell = _jerk_cells(g, m, math.isfinite(p.j_path))
    jnode = np.array([nd for nd, _sgn, _ub in rest_rows], dtype=np.int64)
    n_jerk = jcell.size + jnode.size
    node_in = np.concatenate([node_static, jcell, jnode])

    @functools.cache
    def static_entries() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return static.entries()

    @functools.cache
    def layout() -> _Layout:
        """The cone program's sparsity pattern (made when the cone solver takes a round)."""
        st_row, st_col, _ = static_entries()
        _, j_rows, j_cols = _JerkRows.pattern(jcell, jnode, n)
        return _Layout(nv, [(n_eq, np.concatenate(eq_rows), np.concatenate(eq_cols)),
                            (n_static + n_jerk, np.concatenate([st_row, n_static + j_rows]),
                             np.concatenate([st_col, j_cols])),
                            (both.size, np.arange(both.size), both),
                            (3 * nf + 3 * N, np.concatenate([cone_r, r2]), np.concatenate([cone_c, c2])),
                            acc_block], select=1)
    nn_values = -np.ones(both.size)
    no_jerk = np.zeros(4 * jcell.size + jnode.size)  # (the jerk rows' entries)

    jerk_rounds = 0
    retries = 0  # (see SLOWER_RETRIES)
    moving = not (rest0 and restN)
    relax = 1.0  # the jerk limits' factor of the round (> 1: a relaxed round, see RELAX_START)
    relax_from = math.inf  # ... that of the linearisation point (inf: not a relaxed round's)
    relax_fails = 0
    rounds_left = max_rounds  # (relaxed rounds, and those that fail in between, do not count)
    relaxed_xu = False  # x, u are a relaxed round's solution
    best = None
    z_prev = None
    # the last round's multipliers of the inequalities (a warm start of a settled round)
    duals = duals0 if duals0 is not None else np.zeros(0)
    t_init = math.nan
    if init is not None:
        x_bar, u_bar = np.maximum(init[0], 0.0), init[1]
        sigma, rho, tau2, ecorr = linearise_at(x_bar, u_bar)
        z_prev = np.zeros(nv)  # the inequalities only involve x and u
        z_prev[ix], z_prev[iu] = x_bar, u_bar
        sqi = np.sqrt(x_bar)
        with np.errstate(divide="ignore"):
            t_init = float(np.sum(wts / (sqi[:-1] + sqi[1:])))
    while rounds_left > 0:
        rounds_left -= 1
        eq_values = eq_fixed + [ones_g, -ones_g, -(D[g] - u_bar[g] * tau2[g] / 6.0),
                                -(D[g] + u_bar[g + 1] * tau2[g] / 6.0)]
        b_eq = np.concatenate(b_eq_fixed + [-(u_bar[g + 1] ** 2 - u_bar[g] ** 2) * tau2[g] / 12.0])

        if x_bar is not None:
            jerk = _jerk_rows(p, x_bar, u_bar, ecorr, g, ends, sig, d1, d2, d3,
                              j_acc, j_dec, j_both, mixed, D, n, rest_rows, relax)
            b_in_all = np.concatenate([b_static, jerk.b])
        else:  # the jerk-free round: no jerk rows
            jerk = None
            b_in_all = np.concatenate([b_static, np.full(n_jerk, np.inf)])

        def ineq_times(zz: np.ndarray, jerk: _JerkRows | None = jerk) -> np.ndarray:
            """``A z`` of every inequality of the round."""
            az = static.times(zz)
            return np.concatenate([az, jerk.times(zz) if jerk is not None else np.zeros(n_jerk)])

        # screening: the rows with a wide margin at the previous round's solution are
        # left out (a narrower one once the rounds have settled); if the new solution violates one of
        # them, the round is solved again with more rows (the result is the same either
        # way: the solution of fewer rows that keeps all of them is the optimum). The
        # first round with the jerk rows after the jerk-free round keeps every row: the
        # jerk limits move the solution far from the one without them, and solving
        # again for the rows it then violates took longer than all rows at once
        # (2.7 % of the benchmark's arm planning time)
        t_prev = times[-2] if jerk_rounds >= 2 else (t_init if jerk_rounds == 1 else math.nan)
        # (a settled round also starts from the previous multipliers; a solution of
        # the grid before a split, interpolated, is screened loosely: narrowly, its
        # first round left out rows of the new nodes and took 45-100 iterations)
        warm = z_prev is not None and ((settled and not times)
                                       or bool(times and abs(times[-1] - t_prev) <= SCREEN_SETTLED * times[-1]))
        if warm and z_prev is not None:
            az_prev = ineq_times(z_prev)
            keep = _near(az_prev, b_in_all)
            # the velocity and speed-cap rows only loosely (a cruise at the cap stays exact)
            keep[:n_vel] |= (b_static[:n_vel] - az_prev[:n_vel]) < SCREEN_SLACK_LOOSE
        elif z_prev is not None and (jerk_rounds or init is not None):
            keep = (b_in_all - ineq_times(z_prev)) < SCREEN_SLACK_LOOSE
        else:
            keep = np.ones(b_in_all.size, dtype=bool)
        if jerk is None:
            keep[n_static:] = False
        ipm_round = use_ipm  # (the cone solver takes the round if the method fails)
        for screen in range(SCREEN_PASSES):
            if ipm_round:
                z_new, t_new, lam = _ipm_solve(static.cell, static.coef, b_in_all, keep, jerk, g,
                                               eq_values[1:], b_eq[6:], rest0, restN, D, wts, p, x_bar,
                                               u_bar, xv, nv, n, quad,
                                               duals if warm and screen == 0 else None)
                ipm_round = z_new is not None
                duals = lam if lam is not None else np.zeros(0)
            if not ipm_round:
                # (the cone program's parts: made only when it takes a round)
                jerk_values = jerk.values() if jerk is not None else no_jerk
                values = [np.concatenate(eq_values), np.concatenate([static_entries()[2], jerk_values]),
                          nn_values, cone_values(sigma, rho), acc_values]
                A = layout().matrix(values, keep)
                b_in = b_in_all[keep]
                b_cone = np.concatenate([np.tile([1.0, -1.0, 0.0], nf), np.tile([0.0, 0.0, 2.0], N)])
                b = np.concatenate([b_eq, b_in, b_nn, b_cone, b_acc])
                cones = [clarabel.ZeroConeT(n_eq),
                         clarabel.NonnegativeConeT(b_in.size + b_nn.size)]
                cones += [clarabel.SecondOrderConeT(3)] * (nf + N + kn.size)
                sol = _clarabel_solve(clarabel, sp.csc_matrix((nv, nv)), q, A, b, cones)
                z_new = np.asarray(sol.x)
            if keep.all() or (jerk is None and keep[:n_static].all()):
                break
            # a row left out must not be violated, nor come close to its bound
            az_new = ineq_times(z_new)
            viol = (b_in_all - az_new) < SCREEN_MARGIN * b_in_all - SCREEN_TOL
            if jerk is None:
                viol[n_static:] = False
            if not (viol & ~keep).any():
                break
            if screen + 2 >= SCREEN_PASSES:
                keep[:] = True
            else:  # every row around those, and the rows near the new solution, then again
                keep |= _around(node_in, viol & ~keep, n) | _near(az_new, b_in_all)
            if jerk is None:
                keep[n_static:] = False
        if ipm_round:
            status = "Solved"
            usable = True
        else:
            status = str(sol.status).split(".")[-1]
            usable = status in ("Solved", "AlmostSolved") or (
                status == "InsufficientProgress" and float(getattr(sol, "r_prim", 1.0)) < PRIMAL_RTOL)
        t_round = (t_new if ipm_round else float(q @ z_new)) if usable else math.nan
        if (usable and moving and jerk_rounds == 0 and times and relax == 1.0
                and t_round > STALL_FACTOR * times[-1]):
            usable, status = False, "Stalled"
        times_status.append(status)
        if not usable:
            if x_bar is None:
                raise RuntimeError(f"path timing: the jerk-free grid problem failed ({status})")
            if jerk_rounds == 0 and moving and relax_fails < RELAX_FAILS:
                # the first jerk round, linearised too far from any jerk-feasible
                # timing, with a moving boundary state: approached in relaxed rounds
                relax_fails += 1
                if math.isinf(relax_from):
                    relax = RELAX_START if relax == 1.0 else relax * RELAX_STEP**2
                else:
                    relax = math.sqrt(relax_from * relax)
                    if relax_from < relax * (1.0 + RELAX_RTOL):
                        break
                rounds_left += 1
                continue
            if jerk_rounds == 0 and not moving and retries < SLOWER_RETRIES:
                # the first jerk round, linearised too far from any jerk-feasible timing
                # (the jerk-free round's speeds): again from a uniformly slower one
                retries += 1
                x_bar, u_bar = x_bar * SLOWER_X, u_bar * SLOWER_X
                sigma, rho, tau2, ecorr = linearise_at(x_bar, u_bar)
                continue
            break  # keep the previous round's solution
        z = z_new
        z_prev = z
        x = np.maximum(z[ix], 0.0)
        u = z[iu].copy()
        x[0], u[0], x[N], u[N] = p.x0, p.u0, p.xN, p.uN
        # the rest intervals' relation exactly (the solver meets it only to its tolerance,
        # which is large relative to the tiny states next to a stop)
        _rest_relation(x, u, s, rest0, restN)
        relaxed_xu = relax > 1.0
        if relaxed_xu:  # (a relaxed round: the next one's linearisation point only)
            relax_from = relax
            relax = relax / RELAX_STEP
            if relax < 1.0 + RELAX_RTOL:
                relax = 1.0
            rounds_left += 1
            x_bar, u_bar = x, u
            sigma, rho, tau2, ecorr = linearise_at(x_bar, u_bar)
            continue
        t = t_round
        times.append(t)
        if x_bar is None:
            jerk_free = t
        elif asym and (flips := _leg_flips(p, (x_bar, u_bar), (x, u), g, ends, sig, d1, d2, d3,
                                           j_acc, j_dec, j_both, mixed, D)).any():
            # the rows missed a leg change: this solution may exceed the tighter leg's
            # limit there; again with that leg in those intervals
            jerk_rounds += 1
            mixed |= flips
        else:
            jerk_rounds += 1
            if best is None or t < best[0]:
                best = (t, x.copy(), u.copy())
            if jerk_rounds >= 2 and abs(times[-2] - t) <= ROUND_RTOL * t:
                converged = True
                break
            if jerk_rounds == 1 and (settled or near) and abs(t_init - t) <= SETTLED_RTOL * t:
                converged = True  # the starting point was a solution: it was the round before
                break
            if jerk_rounds >= 2 and t > times[-2] * (1.0 + ROUND_RTOL):
                break  # the rounds got slower (the linearised terms moved): keep the best
        x_bar, u_bar = x, u
        if jerk_rounds == 0 and p.u0 < 0.0 and p.x0 > 0.0:
            # (after the jerk-free round: see _braking_start)
            x_bar = _braking_start(p, x, d1, j_dec)
        sigma, rho, tau2, ecorr = linearise_at(x_bar, u_bar)
    if best is not None:  # every round's solution keeps the constraints: the fastest
        t, x, u = best
    elif relaxed_xu:
        status = RELAXED  # (no round after the relaxed ones solved)
    return GridSolution(x=x, u=u, time=t if times else math.nan,
                        jerk_free_time=jerk_free, rounds=len(times), converged=converged,
                        status=status, history=times, duals=duals)
