"""A path through joint-space waypoints shaped for the joints' limits (linear programs).

The shape of a path through waypoints decides how fast it can be timed: a
natural cubic spline bends least, but spreads its curvature over every joint
alike, whatever each joint's room. :func:`shaped_path` builds instead, per
joint, a C2 cubic spline ``p(tau)`` in a time-like parameter ``tau`` with
:data:`PIECES` pieces between consecutive waypoints, passing each waypoint at
``tau_i``, and chooses it by a linear program so that the motion ``p(tau)``,
run at ``tau = t``, needs the least time once every stretch between two
waypoints is slowed down or sped up uniformly to its limits:

- the B-spline's derivatives are B-splines of the differences of its control
  points, and a B-spline lies in the convex hull of its control points: the
  bounds ``|p'| <= v (M_i)``, ``|p''| <= a (2 M_i - 1)``, ``|p'''| <= j (3 M_i
  - 2)`` on those control points hold everywhere on stretch i (``M_i`` is the
  stretch's time scale, linearised around 1: ``v / k``, ``a / k^2``, ``j /
  k^3`` for a slow-down by ``k``);
- the objective is the linearised time ``sum_i h_i M_i`` (``h_i`` the
  stretch's length in ``tau``), plus a small weight on every joint's own
  largest scale (a joint with room to spare takes its least demanding shape);
- the stretches are then rescaled (``h_i M_i``) and the program solved again,
  :data:`ROUNDS` times.

With a tolerance (a blend), the point where the path passes each inner
waypoint is free within a ball of that radius around it: a second-order cone
in the program (which is then a cone program), so the path cuts each corner
where its joints gain most.

The first ``tau`` of every stretch is the longest one-axis rest-to-rest
time of its joints. The path has zero second derivative at both ends
(``p'`` free there: the path is regular, the timing starts it from rest).
The timing engine times the result exactly under the real limits; the
program only shapes the path.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import clarabel
import numpy as np
import scipy.sparse as sp
from scipy.interpolate import BSpline, PPoly, make_interp_spline

from ..limits import AxisLimits
from ..profiles.batch import plan_moves

__all__ = ["ShapedJointPath", "shaped_path", "within_tolerance", "PIECES", "ROUNDS", "MAX_SHAPED_WAYPOINTS"]

#: Cubic pieces of the path between two consecutive waypoints.
PIECES = 8

#: Linear programs solved (each after rescaling the stretches by the last one's scales).
ROUNDS = 3

#: The first parameter of every stretch: this fraction of its longest one-axis
#: rest-to-rest time (passing a waypoint is faster than stopping there).
FIRST_SCALE = 0.7

#: Weight of every joint's own largest time scale, relative to the total time.
JOINT_WEIGHT = 1e-3

#: Most waypoints of one shaped stretch (the program grows with them); a longer
#: stretch gets the natural cubic spline.
MAX_SHAPED_WAYPOINTS = 64

#: Derivatives (0: velocity, 1: acceleration, 2: jerk) bounded by every joint's own scale.
JOINT_ORDERS = (1,)

#: Tolerances of the linear programs (duality gap, absolute and relative, and
#: feasibility): the programs only shape the path (the timing engine times it
#: exactly); at the cone solver's default 1e-8 they stall (up to 200 iterations,
#: most ending "almost solved"), at 1e-6 they solve in 18-29.
LP_TOL = 1e-6

_DEG = 3


class ShapedJointPath:
    """A C2 piecewise-cubic path through waypoints (a :class:`JointPath`).

    The parameter ``s`` is the time-like parameter the path was shaped in
    (``knots[i]`` at waypoint i); the path passes every waypoint exactly, has
    continuous first and second derivatives, a piecewise constant third
    derivative (:attr:`breakpoints` where its pieces meet) and zero second
    derivative at both ends.

    Parameters
    ----------
    points : ndarray, shape (k, m)
        The points the path passes: the waypoints, or points within the
        tolerance of them.
    knots : ndarray, shape (k,)
        Strictly increasing parameter of every waypoint, ``knots[0] = 0``.
    coeffs : ndarray, shape (4, p, m)
        Cubic coefficients of every piece (highest power first, in ``s - x[i]``).
    x : ndarray, shape (p + 1,)
        Piece boundaries (every knot is one).
    """

    #: Exact derivatives are cheap: the timing engine checks its limits with them.
    cheap_derivatives = True

    def __init__(self, points: np.ndarray, knots: np.ndarray, coeffs: np.ndarray, x: np.ndarray) -> None:
        self.points = points
        self.knots = knots
        self.n_joints = points.shape[1]
        self.length = float(knots[-1])
        self._pp = PPoly(coeffs, x, extrapolate=True)
        self._der = [self._pp] + [self._pp.derivative(k) for k in (1, 2, 3)]
        self.breakpoints = x[1:-1].copy()
        #: Another path through the same waypoints, timed beside this one (set by the caller).
        self.alternative: Any = None

    def derivatives(self, s: np.ndarray):
        s = np.clip(np.atleast_1d(np.asarray(s, dtype=float)), 0.0, self.length)
        q = self._pp(s)
        # exactly the waypoints at their knots (the pieces start there)
        hit = np.searchsorted(self.knots, s)
        on = (hit < self.knots.size) & (self.knots[np.minimum(hit, self.knots.size - 1)] == s)
        q[on] = self.points[hit[on]]
        return (q,) + tuple(d(s) for d in self._der[1:])

    def joint_range(self) -> tuple[np.ndarray, np.ndarray]:
        """Lowest and highest position of every joint between consecutive waypoints, each (k - 1, m)."""
        c = self._pp.c  # (4, p, m)
        x = self._pp.x
        h = np.diff(x)[:, None]
        a, b, cc = 3.0 * c[0], 2.0 * c[1], c[2]
        root = np.sqrt(np.maximum(b * b - 4.0 * a * cc, 0.0))
        with np.errstate(divide="ignore", invalid="ignore"):
            x1 = np.where(a != 0.0, (-b - root) / (2.0 * a), np.where(b != 0.0, -cc / b, 0.0))
            x2 = np.where(a != 0.0, (-b + root) / (2.0 * a), 0.0)
        cand = [np.zeros_like(h + a), np.broadcast_to(h, a.shape)]
        cand += [np.clip(np.nan_to_num(z), 0.0, h) for z in (x1, x2)]
        vals = np.stack([((c[0] * z + c[1]) * z + c[2]) * z + c[3] for z in cand])
        lo, hi = vals.min(axis=0), vals.max(axis=0)  # per piece
        seg = np.clip(np.searchsorted(self.knots, x[:-1], side="right") - 1, 0, self.knots.size - 2)
        k = self.knots.size - 1
        out_lo = np.full((k, self.n_joints), np.inf)
        out_hi = np.full((k, self.n_joints), -np.inf)
        np.minimum.at(out_lo, seg, lo)
        np.maximum.at(out_hi, seg, hi)
        return out_lo, out_hi


def _diff_matrix(t: np.ndarray, k: int) -> sp.csr_matrix:
    """Control points of the derivative of a degree-k B-spline on knots t (from its own)."""
    n = t.size - k - 1
    w = k / (t[k + 1:k + n] - t[1:n])
    return sp.diags([-w, w], [0, 1], shape=(n - 1, n), format="csr")


def _first_knots(points: np.ndarray, lims: Sequence[AxisLimits]) -> np.ndarray:
    """Parameter of every waypoint: the cumulated longest one-axis rest-to-rest time [s]."""
    step = np.abs(np.diff(points, axis=0))
    times = np.zeros_like(step)
    for j, lm in enumerate(lims):
        moving = step[:, j] > 0.0
        if moving.any():
            batch = plan_moves(np.zeros(int(moving.sum())), step[moving, j], lm.v_max, lm.a_max, lm.j_max,
                               lm.a_max_decel, lm.j_max_decel)
            times[moving, j] = batch.duration
    return np.concatenate([[0.0], np.cumsum(times.max(axis=1))])


def _solve(points, knots, vlim, alim, jlim, lo, hi, tol=0.0):
    """One linear program (a cone program with ``tol`` > 0: every inner waypoint passed
    within ``tol``); (control points (n, m), B-spline knots, stretch scales) or None."""
    k, m = points.shape
    nseg = k - 1
    inner = np.concatenate([np.linspace(knots[i], knots[i + 1], PIECES + 1)[:-1] for i in range(nseg)]
                           + [knots[-1:]])
    t = np.concatenate([[knots[0]] * _DEG, inner, [knots[-1]] * _DEG])
    n = t.size - _DEG - 1
    d1 = _diff_matrix(t, 3)
    t1 = t[1:-1]
    d2 = _diff_matrix(t1, 2) @ d1
    t2 = t1[1:-1]
    d3 = _diff_matrix(t2, 1) @ d2
    t3 = t2[1:-1]
    # where every derivative control point acts: the stretch(es) of its support's middle
    where = [0.5 * (t1[1:d1.shape[0] + 1] + t1[2:d1.shape[0] + 2]), t2[1:d2.shape[0] + 1],
             0.5 * (t3[:d3.shape[0]] + t3[1:d3.shape[0] + 1])]
    n_p = n * m
    i_seg = n_p
    i_joint = n_p + nseg
    nv = n_p + nseg + m
    rows_, cols_, vals_, rhs = [], [], [], []
    r0 = 0  # rows so far (of the inequalities)

    def add(d: sp.csr_matrix, rr: np.ndarray, col0: int, sgn: float, extra_col: np.ndarray,
            extra_val: float) -> None:
        """Rows ``rr`` of ``sgn * d`` at columns ``col0 + ...``, each with one more entry
        ``extra_val`` at its column of ``extra_col``, as the next rows."""
        nonlocal r0
        starts, counts = d.indptr[rr], d.indptr[rr + 1] - d.indptr[rr]
        k = np.repeat(starts - np.concatenate([[0], np.cumsum(counts)[:-1]]), counts) \
            + np.arange(int(counts.sum()))
        rows_.append(np.repeat(r0 + np.arange(rr.size), counts))
        cols_.append(d.indices[k] + col0)
        vals_.append(sgn * d.data[k])
        rows_.append(r0 + np.arange(rr.size))
        cols_.append(extra_col)
        vals_.append(np.full(rr.size, extra_val))
        r0 += rr.size

    for order, (d, at, lim) in enumerate(zip((d1, d2, d3), where, (vlim, alim, jlim))):
        w = order + 1.0
        s_lo = np.clip(np.searchsorted(knots, at, side="left") - 1, 0, nseg - 1)
        s_hi = np.clip(np.searchsorted(knots, at, side="right") - 1, 0, nseg - 1)
        d = d.tocsr()
        d.sum_duplicates()
        d.eliminate_zeros()
        r = d.shape[0]
        rows = np.arange(r)
        two = np.nonzero(s_hi != s_lo)[0]
        for j in range(m):
            if not np.isfinite(lim[j]):
                continue
            ll = float(lim[j])
            for sgn in (1.0, -1.0):
                # every control point of the derivative within the limit of its
                # stretch's scale (of both stretches where its support's middle is
                # a waypoint), and of the joint's own scale
                sel = [(rows, i_seg + s_lo)]
                if order in JOINT_ORDERS:
                    sel.append((rows, i_joint + j + np.zeros(r, dtype=int)))
                if two.size:
                    sel.append((two, i_seg + s_hi[two]))
                for rr, cc in sel:
                    add(d, rr, j * n, sgn, cc, -w * ll)
                    rhs.append(np.full(rr.size, -(w - 1.0) * ll))
    # position range: the control points inside it keep the whole path inside
    for j in range(m):
        for bound, sgn in ((lo[j], -1.0), (hi[j], 1.0)):
            if np.isfinite(bound):
                rows_.append(r0 + np.arange(n))
                cols_.append(j * n + np.arange(n))
                vals_.append(np.full(n, sgn))
                r0 += n
                rhs.append(np.full(n, sgn * float(bound)))
    ineq = sp.csr_matrix((np.concatenate(vals_), (np.concatenate(rows_), np.concatenate(cols_))),
                         shape=(r0, nv))
    interp = BSpline.design_matrix(knots, t, _DEG).tocsr()
    ends = d2[[0, d2.shape[0] - 1]]
    # the waypoints passed exactly (with tol > 0 the ends only, the inner ones in cones)
    passed = np.arange(k) if tol == 0.0 else np.array([0, k - 1])
    e = sp.vstack([interp[passed], ends]).tocsr()
    eqs = [sp.hstack([sp.csr_matrix((e.shape[0], j * n)), e, sp.csr_matrix((e.shape[0], nv - (j + 1) * n))])
           for j in range(m)]
    b_eq = np.concatenate([np.concatenate([points[passed, j], np.zeros(2)]) for j in range(m)])
    # (tol, waypoint - p(tau_i)) in a second-order cone for every inner waypoint: its
    # rows (0; joint j's interpolation row at tau_i for every j)
    cones = 0 if tol == 0.0 else k - 2
    a_cone = sp.csr_matrix((0, nv))
    if cones:
        row = interp[1:k - 1].tocoo()
        joints = np.arange(m)[None, :]
        a_cone = sp.csr_matrix((np.repeat(row.data, m),
                                ((row.row[:, None] * (m + 1) + 1 + joints).ravel(),
                                 (row.col[:, None] + n * joints).ravel())),
                               shape=(cones * (m + 1), nv))
    b_cone = np.column_stack([np.full(cones, tol), points[1:1 + cones]]).ravel()
    h = np.diff(knots)
    c = np.zeros(nv)
    c[i_seg:i_joint] = h
    c[i_joint:] = JOINT_WEIGHT * h.sum()
    a_eq = sp.vstack(eqs)
    a_all = sp.vstack([a_eq, ineq, a_cone]).tocsc()
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = LP_TOL
    sol = clarabel.DefaultSolver(sp.csc_matrix((nv, nv)), c, a_all, np.concatenate([b_eq] + rhs + [b_cone]),
                                 [clarabel.ZeroConeT(a_eq.shape[0]), clarabel.NonnegativeConeT(ineq.shape[0])]
                                 + [clarabel.SecondOrderConeT(m + 1)] * cones,
                                 settings).solve()
    if str(sol.status).split(".")[-1] not in ("Solved", "AlmostSolved"):
        return None
    xx = np.asarray(sol.x)
    ctrl = xx[:n_p].reshape(m, n).T
    scales = xx[i_seg:i_joint]
    if not (np.isfinite(ctrl).all() and np.isfinite(scales).all()):
        return None
    return ctrl, t, scales


def within_tolerance(points: np.ndarray, moved: np.ndarray, tol: float) -> np.ndarray:
    """``moved`` (k, m) with every inner point brought to at most ``tol`` from its point
    of ``points`` (the solvers meet their cones to their tolerance) and both ends on
    theirs."""
    d = moved - points
    d[0] = d[-1] = 0.0
    dist = np.linalg.norm(d, axis=1)
    over = dist > tol
    d[over] *= (tol / dist[over])[:, None]
    out = points + d
    out[0], out[-1] = points[0], points[-1]
    return out


def shaped_path(points: np.ndarray, lims: Sequence[AxisLimits], tol: float = 0.0) -> ShapedJointPath | None:
    """The path through ``points`` (k, m) shaped for the joints' limits (see the module
    notes), passing every inner point within ``tol`` (joint-space distance, >= 0); None
    where a program fails (the caller then uses another shape)."""
    k, m = points.shape
    if k < 3 or k > MAX_SHAPED_WAYPOINTS:
        return None
    vlim = np.array([lm.v_max for lm in lims], dtype=float)
    alim = np.array([min(lm.a_max, lm.a_max_decel) for lm in lims], dtype=float)
    jlim = np.array([min(lm.j_max, lm.j_max_decel) for lm in lims], dtype=float)
    lo = np.array([lm.position_min for lm in lims], dtype=float)
    hi = np.array([lm.position_max for lm in lims], dtype=float)
    knots = _first_knots(points, lims) * FIRST_SCALE
    if not (np.all(np.diff(knots) > 0.0) and np.isfinite(knots).all()):
        return None
    best = None
    for _ in range(ROUNDS):
        out = _solve(points, knots, vlim, alim, jlim, lo, hi, tol)
        if out is None:
            break
        best = (out, knots)
        scales = np.clip(out[2], 0.05, 20.0)
        knots = np.concatenate([[0.0], np.cumsum(np.diff(knots) * scales)])
    if best is None:
        return None
    (ctrl, t, _), knots = best
    pps = [PPoly.from_spline(BSpline(t, ctrl[:, j], _DEG)) for j in range(m)]
    keep = np.diff(pps[0].x) > 0.0
    x = np.concatenate([pps[0].x[:-1][keep], pps[0].x[-1:]])
    coeffs = np.stack([pq.c[:, keep] for pq in pps], axis=2)
    pp = PPoly(coeffs, x)
    # where the path passes: the waypoints, or with a tolerance where the program's
    # path passes them (within it)
    passing = points if tol == 0.0 else within_tolerance(points, pp(knots), tol)
    # the program meets them to its tolerance: a natural cubic spline through the
    # residuals (C2, as small as they are) makes the passage exact
    resid = passing - pp(knots)
    corr = make_interp_spline(knots, resid, k=3, bc_type="natural")
    x0 = x[:-1]
    for order in range(4):
        coeffs[3 - order] += corr(x0, order) / [1.0, 1.0, 2.0, 6.0][order]
    start = np.searchsorted(x0, knots[:-1])
    coeffs[3, start] = passing[:-1]
    return ShapedJointPath(passing, knots, coeffs, x)
