"""Moving through joint-space waypoints without stopping.

:func:`plan_waypoints` joins N waypoints by a smooth path (``"spline"``: a
path shaped for the joints' limits or a natural cubic spline, through them
or within the blend tolerance of them, whichever is faster; see
:mod:`trajkit.timing._shaped`), or (``"lines"``) by straight lines in joint
space, rounding every inner corner with a quintic blend that leaves and enters the
lines with the same direction and zero curvature, so the path ``q(s)`` has
continuous first and second derivatives (the joint velocities and
accelerations stay continuous) and passes each inner waypoint within the
blend tolerance. The path-timing engine (:func:`plan_path_timing`) then times
it in minimum time under every joint's velocity, acceleration and jerk
limits. The motion stops only where the path reverses (a corner of nearly
180 degrees cannot be rounded) and at the ends.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.interpolate import CubicSpline

from .._validate import check_array, check_finite, check_positive
from ..errors import InvalidInputError
from ..limits import AxisLimits
from ..profiles._range import DISTANCE_ABS_MIN, POSITION_MAX, check_limits_range
from ..sync import plan_ptp
from ._shaped import ShapedJointPath, shaped_path, within_tolerance
from .engine import PathTiming, plan_path_timing
from .paths import JointPath

__all__ = ["BlendedJointPath", "SplineJointPath", "ShapedJointPath", "SHAPES", "WaypointTrajectory",
           "WaypointSample", "plan_waypoints",
           "MAX_WAYPOINTS", "REVERSAL_ANGLE"]

#: Most waypoints of one call.
MAX_WAYPOINTS = 10_000

#: Smallest step between consecutive distinct waypoints, as a fraction of the
#: path's chord length (the splines' parameter must resolve every step); at
#: least ``DISTANCE_ABS_MIN`` too.
STEP_RTOL_MIN = 1e-12

#: The engine times a straight joint line from rest to rest within this
#: fraction of the phase-synchronised PTP optimum (tested): a stretch is run
#: with a stop at every waypoint when that is faster by more than this.
STOP_ALL_MARGIN = 0.005

#: Path shapes of :func:`plan_waypoints`.
SHAPES = ("spline", "lines")

#: A corner turning by more than this [rad] is a reversal: the motion stops there.
REVERSAL_ANGLE = math.pi - 1e-3

#: A corner turning by less than this [rad] is no corner (collinear waypoints).
STRAIGHT_ANGLE = 1e-9

#: Handle of the quintic blend as a fraction of its radius (control points
#: ``A, A + h d_in, A + 2 h d_in, B - 2 h d_out, B - h d_out, B``).
HANDLE = 0.3


def _bezier(ctrl: np.ndarray, u: np.ndarray, order: int) -> np.ndarray:
    c = ctrl
    for _ in range(order):
        c = (c.shape[0] - 1) * np.diff(c, axis=0)
    n = c.shape[0] - 1
    u = u[:, None]
    m = 1.0 - u
    out = np.zeros((u.shape[0], ctrl.shape[1]))
    for i in range(n + 1):
        out += math.comb(n, i) * m ** (n - i) * u**i * c[i]
    return out


def _corner_ctrl(p: np.ndarray, d_in: np.ndarray, d_out: np.ndarray, r: float) -> np.ndarray:
    h = HANDLE * r
    a = p - r * d_in
    b = p + r * d_out
    return np.array([a, a + h * d_in, a + 2 * h * d_in, b - 2 * h * d_out, b - h * d_out, b])


class BlendedJointPath:
    """Straight lines between waypoints with quintic corner blends (a :class:`JointPath`).

    The parameter ``s`` is the joint-space arc length on the lines; on a blend
    of radius r it runs over ``5 h = 5 HANDLE r`` with the Bezier parameter
    ``u = (s - s_start) / (5 h)``, which makes ``dq/ds`` a unit vector and
    ``d2q/ds2`` zero at both ends of the blend, like on the lines.

    Parameters
    ----------
    points : ndarray, shape (k, m)
        Waypoints (no two consecutive equal, no reversal inside).
    radii : ndarray, shape (k - 2,)
        Blend radius of every inner corner (0: no blend, the lines are collinear).
    """

    #: Exact derivatives are cheap: the timing engine checks its limits with them.
    cheap_derivatives = True

    def __init__(self, points: np.ndarray, radii: np.ndarray) -> None:
        self.points = points
        self.n_joints = points.shape[1]
        seg = np.diff(points, axis=0)
        seglen = np.linalg.norm(seg, axis=1)
        dirs = seg / seglen[:, None]
        self.kind: list[str] = []
        self.start: list[float] = []
        self.data: list[Any] = []
        s = 0.0
        trim0 = np.zeros(len(seg))
        trim1 = np.zeros(len(seg))
        trim0[1:] = radii
        trim1[:-1] = radii
        for i in range(len(seg)):
            a = points[i] + trim0[i] * dirs[i]
            ln = seglen[i] - trim0[i] - trim1[i]
            if ln > 0.0:
                self.kind.append("line")
                self.start.append(s)
                self.data.append((a, dirs[i], ln))
                s += ln
            if i + 1 < len(seg) and radii[i] > 0.0:
                ctrl = _corner_ctrl(points[i + 1], dirs[i], dirs[i + 1], radii[i])
                ell = 5.0 * HANDLE * radii[i]
                self.kind.append("blend")
                self.start.append(s)
                self.data.append((ctrl, ell))
                s += ell
        self.length = s
        self.starts = np.array(self.start + [s])
        self.breakpoints = self.starts[1:-1].copy()

    def derivatives(self, s: np.ndarray):
        s = np.clip(np.atleast_1d(np.asarray(s, dtype=float)), 0.0, self.length)
        k = np.clip(np.searchsorted(self.starts, s, side="right") - 1, 0, len(self.kind) - 1)
        m = self.n_joints
        out = [np.empty((s.size, m)) for _ in range(4)]
        for i in np.unique(k):
            sel = k == i
            loc = s[sel] - self.starts[i]
            if self.kind[i] == "line":
                a, d, _ = self.data[i]
                out[0][sel] = a + loc[:, None] * d
                out[1][sel] = d
                out[2][sel] = 0.0
                out[3][sel] = 0.0
            else:
                ctrl, ell = self.data[i]
                u = loc / ell
                for order in range(4):
                    out[order][sel] = _bezier(ctrl, u, order) / ell**order
        return tuple(out)


class SplineJointPath:
    """A natural cubic spline through points in joint space (a :class:`JointPath`).

    The parameter ``s`` is the chord length of the given knot points
    (``knots[i]`` at point i); the path has continuous first and second
    derivatives, a piecewise constant third derivative (its pieces meet at the
    inner knots, the :attr:`breakpoints`) and zero curvature at both ends.

    Parameters
    ----------
    points : ndarray, shape (k, m)
        Points the spline passes, k >= 2.
    knots : ndarray, shape (k,)
        Strictly increasing parameter values of the points, ``knots[0] = 0``.
    """

    #: Exact derivatives are cheap: the timing engine checks its limits with them.
    cheap_derivatives = True

    def __init__(self, points: np.ndarray, knots: np.ndarray) -> None:
        self.points = points
        self.knots = knots
        self.n_joints = points.shape[1]
        self.length = float(knots[-1])
        self.breakpoints = knots[1:-1].copy()
        self._spline = CubicSpline(knots, points, bc_type="natural")

    def derivatives(self, s: np.ndarray):
        s = np.clip(np.atleast_1d(np.asarray(s, dtype=float)), 0.0, self.length)
        return tuple(self._spline(s, order) for order in range(4))

    def joint_range(self) -> tuple[np.ndarray, np.ndarray]:
        """Lowest and highest position of every joint on every piece, each (k - 1, m)."""
        c = self._spline.c  # (4, k - 1, m): c0 x^3 + c1 x^2 + c2 x + c3 on [0, h]
        h = np.diff(self.knots)[:, None]
        a, b, cc = 3.0 * c[0], 2.0 * c[1], c[2]
        disc = np.maximum(b * b - 4.0 * a * cc, 0.0)
        root = np.sqrt(disc)
        with np.errstate(divide="ignore", invalid="ignore"):
            x1 = np.where(a != 0.0, (-b - root) / (2.0 * a), np.where(b != 0.0, -cc / b, 0.0))
            x2 = np.where(a != 0.0, (-b + root) / (2.0 * a), 0.0)
        cand = [np.zeros_like(h + a), np.broadcast_to(h, a.shape)]
        cand += [np.clip(np.nan_to_num(x), 0.0, h) for x in (x1, x2)]
        vals = np.stack([((c[0] * x + c[1]) * x + c[2]) * x + c[3] for x in cand])
        return vals.min(axis=0), vals.max(axis=0)


def _least_bending(points: np.ndarray, knots: np.ndarray, tol: float) -> np.ndarray:
    """Inner points moved by at most ``tol`` so that the natural spline through them
    bends least (minimum integral of ``|d2q/ds2|^2``; a second-order cone program).

    Returns the moved points (the ends stay); the given points where the solver
    does not succeed.
    """
    import clarabel

    k, m = points.shape
    if k < 3 or tol <= 0.0:
        return points.copy()
    h = np.diff(knots)
    nv = k * m
    pi = np.arange(nv).reshape(k, m)  # index of P[i, j]
    mi = nv + pi                      # index of M[i, j] (second derivative at knot i)
    # energy: sum_i h_i / 3 (M_i^2 + M_i M_i+1 + M_i+1^2) per joint, as 1/2 x^T Q x
    rows, cols, vals = [], [], []
    for j in range(m):
        for i in range(k - 1):
            a, b = mi[i, j], mi[i + 1, j]
            rows += [a, b, a]
            cols += [a, b, b]
            vals += [2.0 * h[i] / 3.0, 2.0 * h[i] / 3.0, h[i] / 3.0]
    Q = sp.csc_matrix((vals, (rows, cols)), shape=(2 * nv, 2 * nv))
    # equalities: fixed ends, natural ends, the spline's continuity relations
    er: list[int] = []  # row, column and value of every entry of A
    ec: list[int] = []
    ev: list[float] = []
    eb: list[float] = []  # right-hand side of every row

    def entry(row: int, col: int, val: float) -> None:
        er.append(row)
        ec.append(col)
        ev.append(val)

    r = 0
    for j in range(m):
        for i, want in ((0, points[0, j]), (k - 1, points[-1, j])):
            entry(r, pi[i, j], 1.0)
            eb.append(want)
            r += 1
            entry(r, mi[i, j], 1.0)
            eb.append(0.0)
            r += 1
        for i in range(1, k - 1):
            h0, h1 = h[i - 1], h[i]
            for col, val in ((mi[i - 1, j], h0), (mi[i, j], 2.0 * (h0 + h1)), (mi[i + 1, j], h1),
                             (pi[i + 1, j], -6.0 / h1), (pi[i, j], 6.0 / h1 + 6.0 / h0),
                             (pi[i - 1, j], -6.0 / h0)):
                entry(r, col, val)
            eb.append(0.0)
            r += 1
    n_eq = r
    # cones: (tol, P_i - W_i) for every inner point
    for i in range(1, k - 1):
        eb.append(tol)
        r += 1
        for j in range(m):
            entry(r, pi[i, j], -1.0)
            eb.append(-points[i, j])
            r += 1
    A = sp.csc_matrix((ev, (er, ec)), shape=(r, 2 * nv))
    cones = [clarabel.ZeroConeT(n_eq)] + [clarabel.SecondOrderConeT(m + 1)] * (k - 2)
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    sol = clarabel.DefaultSolver(Q, np.zeros(2 * nv), A, np.asarray(eb, dtype=float), cones,
                                 settings).solve()
    if str(sol.status).split(".")[-1] not in ("Solved", "AlmostSolved"):
        return points.copy()
    return within_tolerance(points, np.asarray(sol.x)[:nv].reshape(k, m), tol)


def _unit_deviation(d_in: np.ndarray, d_out: np.ndarray) -> float:
    """Distance of the corner from its blend for radius 1 (the blend's middle point)."""
    ctrl = _corner_ctrl(np.zeros(d_in.size), d_in, d_out, 1.0)
    mid = _bezier(ctrl, np.array([0.5]), 0)[0]
    return float(np.linalg.norm(mid))


@dataclass
class WaypointSample:
    """Joint states at sample times; arrays of shape (n, m)."""

    t: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray


class WaypointTrajectory:
    """A motion through joint-space waypoints (see :func:`plan_waypoints`).

    Attributes
    ----------
    duration : float
        [s].
    waypoints : ndarray, shape (N, m)
    blend : float
        The blend tolerance [joint units].
    deviation : ndarray, shape (N,)
        Distance of every waypoint from the path (0 at the ends and at stops).
    stops : list of int
        Indices of the waypoints where the motion stops (ends and reversals).
    segments : list of PathTiming
        The timed stretches between stops.
    offsets : ndarray, shape (len(segments) + 1,)
        Start time of every stretch, then the duration [s].
    """

    def __init__(self, waypoints, blend, deviation, stops, segments, limits) -> None:
        self.waypoints = waypoints
        self.blend = blend
        self.deviation = deviation
        self.stops = stops
        self.segments = segments
        self.limits = limits
        self.offsets = np.concatenate([[0.0], np.cumsum([sg.duration for sg in segments])])
        self.duration = float(self.offsets[-1])

    @property
    def n_axes(self) -> int:
        return int(self.waypoints.shape[1])

    def sample(self, t: Any) -> WaypointSample:
        """Joint position, velocity, acceleration and jerk at times ``t`` [s] (exact path
        derivatives and exact timing pieces)."""
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        m = self.n_axes
        out = [np.empty((tt.size, m)) for _ in range(4)]
        k = np.clip(np.searchsorted(self.offsets, tt, side="right") - 1, 0, len(self.segments) - 1)
        for i in np.unique(k):
            sel = k == i
            q, qd, qdd, qddd = self.segments[i].joint_states(tt[sel] - self.offsets[i])
            for arr, val in zip(out, (q, qd, qdd, qddd)):
                arr[sel] = val
        out[0][tt <= 0.0] = self.waypoints[0]
        out[0][tt >= self.duration] = self.waypoints[-1]
        return WaypointSample(tt, *out)

    def __repr__(self) -> str:
        return (f"WaypointTrajectory(n_axes={self.n_axes}, waypoints={len(self.waypoints)}, "
                f"duration={self.duration!r}, stops={len(self.stops)})")


def plan_waypoints(waypoints: Any, limits: AxisLimits | Sequence[AxisLimits], *,
                   blend: float = 0.0, shape: str = "spline") -> WaypointTrajectory:
    """Move through joint-space waypoints without stopping, in minimum time.

    Two path shapes join the waypoints; the path-timing engine
    (:func:`plan_path_timing`) then times the path in minimum time under every
    joint's velocity, acceleration and jerk limits. The motion stops at the
    ends and where the waypoints reverse (a corner within 1e-3 rad of 180
    degrees), and nowhere else, except that it is never slower than stopping
    at every waypoint: a stretch between stops that would take longer on its
    smooth path (tight blends, sharp corners) than on straight lines with a
    stop at each waypoint is run that way (then listed in ``stops``, passed
    exactly).

    ``"spline"`` (default)
        Through every waypoint (``blend = 0``): a C2 piecewise-cubic path
        shaped for the joints' limits by linear programs (per joint a cubic
        spline in a time-like parameter, bending where that joint has room;
        see docs/timing.md), and the
        natural cubic spline through the waypoints (parameterised by their
        chord length) beside it: both are timed and the faster is kept (the
        spline alone beyond 64 waypoints in a stretch, or where the shaped path would leave a
        joint's range). Both have continuous velocity and acceleration. With ``blend > 0``
        every inner waypoint may be passed up to ``blend`` away: the shaped
        path's program then chooses where it passes each (a cone of radius
        ``blend`` around the waypoint), and the spline beside it is the one of
        least bending (minimum integral of the squared second derivative)
        among all that pass within the tolerance. Where the path would leave a
        joint's position range between two waypoints, the motion stops at
        both (and runs straight between them if needed).
    ``"lines"``
        Straight lines between the waypoints, every inner corner rounded by a
        quintic blend that passes the waypoint at most ``blend`` away (``blend >
        0``; a blend spans at most half of each adjacent line). The path never
        leaves the straight lines outside the blends.

    Parameters
    ----------
    waypoints : array_like, shape (N, m)
        Joint positions [rad or m], N >= 2; the first is the start, the last
        the goal (both at rest). Consecutive duplicates are dropped.
    limits : AxisLimits or sequence of m AxisLimits
        Velocity, acceleration and jerk limits of every joint (finite
        acceleration and jerk; both legs) and its position range.
    blend : float, optional
        Tolerance [joint-space distance, rad or m; the Euclidean norm over the
        joints], >= 0 (``"spline"``) or > 0 (``"lines"``): how far from every
        inner waypoint the path may pass. Default 0: through every waypoint.
    shape : {"spline", "lines"}, optional

    Returns
    -------
    WaypointTrajectory

    Raises
    ------
    InvalidInputError
        Bad shapes, fewer than 2 distinct waypoints, more than
        :data:`MAX_WAYPOINTS`, a waypoint outside a joint's range, an unknown
        ``shape``, a bad ``blend`` or bad limits.
    """
    pts = check_array(waypoints, "waypoints", ndim=2)
    if pts.shape[0] > MAX_WAYPOINTS:
        raise InvalidInputError(f"waypoints has {pts.shape[0]} rows, more than {MAX_WAYPOINTS}")
    m = pts.shape[1]
    lims = [limits] * m if isinstance(limits, AxisLimits) else list(limits)
    if len(lims) != m:
        raise InvalidInputError(f"limits has {len(lims)} entries but the waypoints have {m} joints")
    for k, lm in enumerate(lims):
        if not isinstance(lm, AxisLimits):
            raise InvalidInputError(f"limits[{k}] must be an AxisLimits, got {type(lm).__name__}")
        check_limits_range(lm, states=True)
        for i in range(pts.shape[0]):
            lm.check_position(pts[i, k], f"waypoints[{i}]")
            if not (abs(pts[i, k]) <= POSITION_MAX):
                raise InvalidInputError(
                    f"waypoints[{i}] {float(pts[i, k])!r} on axis {lm.name if lm.name is not None else k} "
                    f"is outside the supported range: |position| must be at most {POSITION_MAX!r}")
    if shape not in SHAPES:
        raise InvalidInputError(f"shape must be one of {', '.join(map(repr, SHAPES))}, got {shape!r}")
    if shape == "lines":
        tol = check_positive(blend, "blend")
    else:
        tol = check_finite(blend, "blend")
        if tol < 0.0:
            raise InvalidInputError(f"blend must be >= 0, got {tol!r}")
    keep = np.concatenate([[True], np.any(np.diff(pts, axis=0) != 0.0, axis=1)])
    pts = pts[keep]
    if pts.shape[0] < 2:
        raise InvalidInputError("waypoints must hold at least two different joint positions")
    # stops: the ends and every reversal
    seg = np.diff(pts, axis=0)
    seglen = np.linalg.norm(seg, axis=1)
    # (the steps' lengths without underflow, for the check)
    big = np.max(np.abs(seg), axis=1)
    step = big * np.linalg.norm(seg / big[:, None], axis=1)
    step_min = max(DISTANCE_ABS_MIN, STEP_RTOL_MIN * float(np.sum(step)))
    short = ~(step >= step_min)
    if short.any():
        i = int(np.argmax(short))
        rows = np.nonzero(keep)[0]
        raise InvalidInputError(
            f"waypoints[{rows[i + 1]}] is {float(step[i])!r} from the waypoint before it, below "
            f"the supported step {step_min!r} (the larger of {DISTANCE_ABS_MIN!r} and "
            f"{STEP_RTOL_MIN!r} times the path's chord length): merge the two waypoints")
    dirs = seg / seglen[:, None]
    turn = np.arccos(np.clip(np.sum(dirs[:-1] * dirs[1:], axis=1), -1.0, 1.0))
    stops = [0] + [i + 1 for i, a in enumerate(turn) if a > REVERSAL_ANGLE] + [pts.shape[0] - 1]
    deviation = np.zeros(pts.shape[0])
    paths: list[JointPath] = []
    if shape == "spline":
        splines, stops = _spline_paths(pts, stops, tol, lims, deviation)
        paths.extend(splines)
    else:
        paths.extend(_line_paths(pts, stops, tol, turn, dirs, seglen, deviation))
    segments: list[PathTiming] = []
    out_stops = [stops[0]]
    for k, path in enumerate(paths):
        a, b = stops[k], stops[k + 1]
        timing = plan_path_timing(path, lims)
        if isinstance(path, ShapedJointPath) and path.alternative is not None:
            # the natural spline through the same waypoints is timed too, the faster kept
            other = plan_path_timing(path.alternative, lims)
            if other.duration < timing.duration:
                timing = other
                deviation[a:b + 1] = np.linalg.norm(path.alternative.points - pts[a:b + 1], axis=1)
        if b - a >= 2:
            # never slower than stopping at every waypoint of the stretch: a straight
            # joint line from rest to rest is the phase-synchronised PTP optimum, which
            # the engine meets to STOP_ALL_MARGIN
            stop_all = sum(plan_ptp(pts[i], pts[i + 1], lims, sync="phase").duration for i in range(a, b))
            if (1.0 + STOP_ALL_MARGIN) * stop_all < timing.duration:
                every = list(range(a, b + 1))
                flat = np.zeros(pts.shape[0])
                lines = _line_paths(pts, every, 0.0, turn, dirs, seglen, flat)
                segments.extend(plan_path_timing(line, lims) for line in lines)
                deviation[a:b + 1] = 0.0
                out_stops.extend(every[1:])
                continue
        segments.append(timing)
        out_stops.append(b)
    return WaypointTrajectory(pts, tol, deviation, out_stops, segments, lims)


def _line_paths(pts, stops, tol, turn, dirs, seglen, deviation) -> list[BlendedJointPath]:
    paths = []
    for a, b in zip(stops[:-1], stops[1:]):
        sub = pts[a:b + 1]
        radii = np.zeros(max(sub.shape[0] - 2, 0))
        for c in range(1, sub.shape[0] - 1):
            i = a + c - 1  # the segment into the corner
            if turn[i] < STRAIGHT_ANGLE:
                continue
            unit = _unit_deviation(dirs[i], dirs[i + 1])
            radii[c - 1] = min(tol / unit if unit > 0 else np.inf, 0.5 * seglen[i], 0.5 * seglen[i + 1])
            deviation[a + c] = radii[c - 1] * unit
        paths.append(BlendedJointPath(sub, radii))
    return paths


def _leaves_range(path, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Whether the path leaves a joint's position range between each two waypoints, (k - 1,)."""
    pmin, pmax = path.joint_range()
    return ((pmin < lo) | (pmax > hi)).any(axis=1)


def _spline_paths(pts, stops, tol, lims, deviation) -> tuple[list[JointPath], list[int]]:
    lo = np.array([lm.position_min for lm in lims])
    hi = np.array([lm.position_max for lm in lims])
    bounded = bool(np.isfinite(lo).any() or np.isfinite(hi).any())
    stops = list(stops)
    while True:
        paths: list[JointPath] = []
        added: set[int] = set()
        for a, b in zip(stops[:-1], stops[1:]):
            sub = pts[a:b + 1]
            knots = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(sub, axis=0), axis=1))])
            moved = _least_bending(sub, knots, tol)
            spline = SplineJointPath(moved, knots)
            path: ShapedJointPath | SplineJointPath = spline
            # the shaped path where it stays in the joints' ranges (the natural spline
            # beside it where that one does)
            shaped = shaped_path(sub, lims, tol)
            if shaped is not None and not (bounded and _leaves_range(shaped, lo, hi).any()):
                if not (bounded and _leaves_range(spline, lo, hi).any()):
                    shaped.alternative = spline
                path = shaped
            if bounded and sub.shape[0] > 2:
                for piece in np.nonzero(_leaves_range(path, lo, hi))[0]:
                    added.update({a + int(piece), a + int(piece) + 1} - {a, b})
            deviation[a:b + 1] = np.linalg.norm(path.points - sub, axis=1)
            paths.append(path)
        if not added:
            return paths, stops
        stops = sorted(set(stops) | added)
