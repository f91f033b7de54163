"""The ``cell`` palletizing planner: every trip planned around the cell's geometry.

The clearance heights of Cao et al. (2012) (``Z1``, ``Z2``) stand in for geometry;
this planner uses the geometry itself (:mod:`trajkit.palletizing.cell`): the
conveyor, guides and end stop, the pallet, the stack as it grows, and the
gripper with the box hanging below it.

One trip
--------
The horizontal joints A, C, D make one *block*: a synchronised rest-to-rest
move of duration ``tH`` (their common minimum time) from the trip's start
pose to its goal pose, starting at ``t_s``. Along the block the footprint of
the moving volume is known, so the lowest height B may have at each instant
is a function of the block's time, the *floor* ``F(tau)``
(:func:`~trajkit.palletizing.cell.volume_floors`: the height at which every
obstacle is ``clearance`` away; at the block's ends also the settle height
above the start and goal). B is one jerk-limited rest-to-rest motion
``Z0 -> Z3`` that must stay above ``F(t - t_s)`` while the block runs; it
never stops in between.

With ``U(t)`` B's full-throttle rise from rest at ``Z0`` and ``D(t)`` the
time reverse of its full-throttle arrival at rest at ``Z3`` (so ``t_up(z)``
is the earliest B can be at ``z``, ``t_dn(z)`` the least time from ``z`` to
rest at ``Z3``), every floor point ``(tau, F)`` demands

    t_s >= t_up(F) - tau        and        T >= t_s + tau + t_dn(F),

so no B motion beats the *window bound*
``max_tau (t_up(F) - tau)^+ + max(tH, max_tau (tau + t_dn(F)))`` (only the
record points of the floor matter: its prefix maxima for the first term, its
suffix maxima for the second). Neither does it beat ``t_B``, B alone from
rest over ``max F`` to rest (the ``optimal`` planner's search over the
turning acceleration). Candidates, the fastest that clears the floor wins:

``"window"``
    The block at the earliest ``t_s``; B rises at full throttle (``U``) to
    the binding rising floor point, a state-to-state middle of the remaining
    time joins the full-throttle descent (``D``) where it passes the binding
    falling point (or a minimum-time turn from ``U`` onto ``D``): the trip
    takes exactly the window bound.
``"peak"``
    B alone to a peak ``(zp, 0, ap)`` and down, minimum time each way, with
    the lowest ``zp`` whose motion clears the floor for some block start
    (for a motion that rises, then falls, those starts form one interval,
    exact from the record points).
``"stretched"``
    As ``"window"``, the trip lengthened (bisection on ``T``) until the
    middle clears the floor.
``"hold"``
    B rests at the top of the floor while the block runs (a fallback that
    always clears it).

The floor is evaluated on a grid of the block's time (finer within
:data:`FINE_SPAN` of its ends, where the volume leaves or reaches obstacles
it nearly touches). Between two grid points no footprint distance can fall
more than the footprint's speed bound times the gap, a cone from each end;
the planner's *envelope* keeps the clearance at the cones' low point, and B
is checked on the grid with the sag a motion within B's acceleration limit
can have between two points. So a trip that passes the planner's check keeps
the clearance over the continuous motion (to :data:`CLEARANCE_ATOL`);
:func:`~trajkit.palletizing.verify.verify_plan` checks the result again,
independently.

The whole job
-------------
Within a layer the order of the boxes, the wrist direction of each box (the
box looks the same turned by 180 degrees) and the synchronisation of the
block (``"time"``: each joint its own S-curve of the common duration;
``"phase"``: one shared profile, a straight line in joint space) are chosen
by dynamic programming over the subsets of the layer's boxes, with the
window bound of each trip on a coarse grid as its cost. The floor of a trip
is the maximum of per-obstacle floors, so each is computed once per box,
wrist and synchronisation, and combined for every subset of placed
neighbours.

The value of that programme is a lower bound on the job over every
in-layer order, wrist choice, synchronisation and B motion (the floor
sampled on the coarse grid leaves constraints out, so it stays a bound):
``plan.info["lower_bound_s"]``. ``plan.info["cell_floor_s"]`` is weaker but
holds for any motion at all, whatever the horizontal joints do: per trip the
window bound of the two floor points every motion has (the start pose just
before the horizontal joints leave it, the goal pose when they arrive).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from ..errors import InfeasibleError, InvalidInputError, TrajkitError
from ..limits import AxisLimits
from ..profiles import plan_move
from ..profiles.state import min_state_duration, plan_state_to_state
from ..trajectory import plan_ptp
from ._crossing import _solve_phase, clearance_crossings, position_peak
from .cell import Cell, Prisms, footprint_distances, required_height, stack_prisms, volume_floors
from .optimal import _best_turn, _phases_of, _reverse, _trip_profile, full_throttle_phases
from .planners import HORIZONTAL_JOINTS, CyclePlan, TripPlan, _assemble, register_planner
from .scenario import PalletScenario, TripSpec
from .timeline import Piece

__all__ = [
    "CellTrip",
    "SYNC_MODES",
    "plan_cycle_cell",
    "wrist_options",
    "PLANNER_NAME",
]

#: Name of the planner in :data:`~trajkit.palletizing.PLANNERS`.
PLANNER_NAME = "cell"

#: Synchronisations of the horizontal block the planner tries.
SYNC_MODES = ("time", "phase")

#: Grid step of the block's time for the order search [s].
SEARCH_STEP = 4e-3

#: Grid step of the block's time for the final plan of each trip [s].
PLAN_STEP = 5e-4

#: Finer grid step [s] within :data:`FINE_SPAN` of the block's ends, where
#: the volume leaves or reaches obstacles it touches (or nearly touches).
FINE_STEP = 1e-4

#: Length [s] of the finely gridded stretches at the block's ends.
FINE_SPAN = 0.06

#: Extra height [m] B keeps over the floor in the final plan (round-off
#: margin of the exact checks; a micrometre).
FLOOR_MARGIN = 1e-6

#: A B motion placed at the earliest start its binding floor point allows
#: touches the envelope by construction: its margin there is 0 up to round-off
#: of the profile's phases [m]. Within FLOOR_MARGIN, so the clearance holds.
TOUCH_TOL = 1e-12

#: Distances within this of the clearance count as keeping it [m]: the
#: resolution of the certified check between grid points (the verifier
#: uses the same tolerance).
CLEARANCE_ATOL = 1e-7

#: Absolute tolerance [s] of the search over the trip time when the
#: window bound cannot be reached.
T_XTOL = 5e-4

#: The lengthened turn is searched only when the best other candidate is
#: more than this fraction above the window bound.
STRETCH_MIN = 0.01

#: Offsets [s] of the turn's start before the crossing of U and D.
TURN_OFFSETS = (0.01, 0.035, 0.075, 0.14, 0.28, 0.55)

_B = 1
_H = list(HORIZONTAL_JOINTS)


@dataclass(frozen=True)
class CellTrip:
    """How the ``cell`` planner planned one trip.

    Attributes
    ----------
    candidate : str
        ``"window"`` (the trip takes its window bound), ``"peak"`` (B alone
        to the lowest feasible peak and down), ``"stretched"`` (B turns at
        speed, the trip lengthened until the turn clears the floor) or
        ``"hold"`` (B rests at the top of the floor).
    duration : float
        Trip duration [s].
    lower_bound : float
        ``max(window bound, t_B)`` of this trip's block [s] (fine grid).
    window_bound : float
        The window bound alone [s].
    cell_floor : float
        The bound any motion obeys (floor points at the start and goal
        poses only) [s].
    t_h : float
        Duration of the horizontal block [s].
    t_start : float
        When the block starts [s from the trip start].
    sync : str
        Synchronisation of the block.
    wrist : int
        Which wrist angle of the place (0: nearest to the pick's).
    z_peak : float
        B's highest point [m].
    floor_max : float
        Highest point of the floor [m].
    margin : float
        Smallest height of B above the planner's floor envelope [m].
    """

    candidate: str
    duration: float
    lower_bound: float
    window_bound: float
    cell_floor: float
    t_h: float
    t_start: float
    sync: str
    wrist: int
    z_peak: float
    floor_max: float
    margin: float

    @property
    def gap_s(self) -> float:
        """How much longer than its lower bound the trip is [s]."""
        return self.duration - self.lower_bound


# ------------------------------------------------------------ full throttle
class _Rise:
    """A rise from rest at ``z0`` made of constant-jerk phases (velocity >= 0):
    vectorised evaluation and inverse (the time at which a height is reached)."""

    def __init__(self, phases: list, z0: float) -> None:
        self.phases = list(phases)
        if not self.phases or not math.isinf(self.phases[-1][0]):
            # hold the end state for ever (a finite rise ends at its top)
            self.phases.append((math.inf, 0.0, 0.0))
        self.z0 = float(z0)
        tb, P, V, A, J = [0.0], [self.z0], [0.0], [], []
        for dt, j, a in self.phases:
            A.append(a)
            J.append(j)
            if math.isinf(dt):
                break
            p, v = P[-1], V[-1]
            P.append(p + dt * (v + dt * (0.5 * a + dt * j / 6.0)))
            V.append(v + dt * (a + 0.5 * dt * j))
            tb.append(tb[-1] + dt)
        self.tb = np.array(tb)
        self.P = np.array(P)
        self.V = np.array(V)
        self.A = np.array(A)
        self.J = np.array(J)
        self.dur = np.array([dt for dt, _, _ in self.phases])
        self._table: tuple[np.ndarray, np.ndarray] | None = None  # (z, t) of the rise, for guesses

    def state(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(z, v, a)`` at times ``t`` >= 0 [s] after the start."""
        t = np.asarray(t, dtype=float)
        i = np.clip(np.searchsorted(self.tb, t, side="right") - 1, 0, len(self.tb) - 1)
        dt = t - self.tb[i]
        P, V, A, J = self.P[i], self.V[i], self.A[i], self.J[i]
        return (P + dt * (V + dt * (0.5 * A + dt * J / 6.0)), V + dt * (A + 0.5 * dt * J),
                A + J * dt)

    def time_at(self, z) -> np.ndarray:
        """Earliest time [s] at which the rise reaches height ``z`` (0 at or below ``z0``)."""
        z = np.atleast_1d(np.asarray(z, dtype=float))
        out = np.zeros(z.shape)
        up = z > self.z0
        if not up.any():
            return out
        zz = z[up]
        i = np.clip(np.searchsorted(self.P, zz, side="right") - 1, 0, len(self.tb) - 1)
        P, V, A, J = self.P[i], self.V[i], self.A[i], self.J[i]
        d = zz - P
        last = i == len(self.tb) - 1
        hi = np.where(last, np.inf, self.dur[np.minimum(i, len(self.dur) - 1)])
        # last (unbounded) phase: constant jerk 0: p = V t + A t^2 / 2
        with np.errstate(divide="ignore", invalid="ignore"):
            tl = np.where(A > 0.0, (-V + np.sqrt(V * V + 2.0 * A * d)) / A, d / V)
        hi_f = np.where(last, 1.0, hi)
        t = np.where(last, tl, 0.5 * hi_f)
        fin = ~last
        if fin.any() and np.count_nonzero(fin) <= _SCALAR_MAX:
            # few heights: the scalar safeguarded Newton solve is cheaper
            for k in np.flatnonzero(fin):
                t[k] = _solve_phase(0.0, float(V[k]), float(A[k]), float(J[k]), float(d[k]),
                                    float(hi_f[k]), 1.0)
        elif fin.any():
            tab = self._table
            if tab is None:
                ts = np.linspace(0.0, float(self.tb[-1]), _TABLE_SIZE)
                tab = self._table = (self.state(ts)[0], ts)
            guess = np.interp(zz[fin], tab[0], tab[1]) - self.tb[i[fin]]
            t[fin] = _solve_cubic(P[fin] * 0.0, V[fin], A[fin], J[fin], d[fin], hi_f[fin],
                                  np.clip(guess, 0.0, hi_f[fin]))
        out[up] = self.tb[i] + t
        return out

    def phases_until(self, t: float) -> list:
        """The rise's phases ``(dt, jerk, a0)`` cut at time ``t``."""
        out, acc = [], 0.0
        for dt, j, a in self.phases:
            if acc + dt >= t:
                if t - acc > 0.0:
                    out.append((t - acc, j, a))
                return out
            if dt > 0.0:
                out.append((dt, j, a))
            acc += dt
        return out  # pragma: no cover - the last phase is unbounded


def _solve_cubic(p0, v0, a0, j, x, dt, t0=None):
    """Solve ``p0 + t v0 + t^2 a0/2 + t^3 j/6 = x`` for ``t`` in ``[0, dt]`` (vectorised).

    The cubic rises monotonically on ``[0, dt]`` and ``x`` lies between its
    values at the ends. Newton's method safeguarded by bisection from the
    guess ``t0`` (default: the middle); stops when the step is a few ulps of
    ``dt`` or the residual a few ulps of ``x``.
    """
    lo = np.zeros_like(x)
    hi = dt.copy()
    t = 0.5 * hi if t0 is None else t0
    for _ in range(_NEWTON_ITER):
        f = p0 + t * (v0 + t * (0.5 * a0 + t * j / 6.0)) - x
        lo = np.where(f < 0.0, t, lo)
        hi = np.where(f > 0.0, t, hi)
        df = v0 + t * (a0 + 0.5 * t * j)
        with np.errstate(divide="ignore", invalid="ignore"):
            tn = t - f / df
        tn = np.where((tn > lo) & (tn < hi), tn, 0.5 * (lo + hi))
        eps = np.finfo(float).eps
        small = np.abs(f) <= 4.0 * eps * np.maximum(1.0, np.abs(x))
        tn = np.where(small, t, tn)
        if np.all(small | (np.abs(tn - t) <= 8.0 * eps * np.maximum(dt, 1e-300))):
            return tn
        t = tn
    return t


#: Iterations of the vectorised safeguarded Newton solve (each step at
#: least halves the bracket when Newton leaves it).
_NEWTON_ITER = 60

#: Points of the table that gives Newton its first guess.
_TABLE_SIZE = 1025

#: Up to this many heights are solved one by one (no table, no array passes).
_SCALAR_MAX = 48


def _throttle(limits: AxisLimits, leg: str, z0: float) -> _Rise:
    """B's full-throttle rise from rest at ``z0`` (see :func:`full_throttle_phases`)."""
    return _Rise(full_throttle_phases(limits, leg), z0)


# --------------------------------------------------------------- the block
def wrist_options(scenario: PalletScenario, place_pose, n: int = 2) -> list[np.ndarray]:
    """Joint vectors that put the box at ``place_pose``, nearest wrist turn first.

    The box looks the same turned by 180 degrees, so the wrist angle is
    ``yaw - theta + k pi``; the (up to) ``n`` values inside D's range
    nearest to the pick's wrist angle are returned.
    """
    rob = scenario.robot
    q0 = rob.joints_from_pose(np.asarray(place_pose, dtype=float), scenario.pick_joints()[3],
                              yaw_period=math.pi, check=False)
    lo, hi = rob.limits[3].position_min, rob.limits[3].position_max
    d_pick = scenario.pick_joints()[3]
    cands = []
    for k in range(-3, 4):
        d = q0[3] + k * math.pi
        if lo - 1e-12 <= d <= hi + 1e-12:
            cands.append((abs(d - d_pick), k, min(max(d, lo), hi)))
    cands.sort()
    out = []
    for _, _, d in cands[:n]:
        q = q0.copy()
        q[3] = d
        out.append(q)
    return out


def _grid(t_h: float, step: float, fine: bool) -> np.ndarray:
    """Times of the block's grid [s]: ``step`` apart, and :data:`FINE_STEP`
    apart within :data:`FINE_SPAN` of both ends when ``fine`` (where the
    volume starts and stops next to obstacles it touches)."""
    if not fine:
        return np.linspace(0.0, t_h, max(2, int(math.ceil(t_h / step)) + 1))
    if t_h <= 2.0 * FINE_SPAN:
        return np.linspace(0.0, t_h, max(2, int(math.ceil(t_h / FINE_STEP)) + 1))
    nf = int(math.ceil(FINE_SPAN / FINE_STEP))
    head = np.linspace(0.0, FINE_SPAN, nf + 1)
    mid = np.linspace(FINE_SPAN, t_h - FINE_SPAN,
                      max(2, int(math.ceil((t_h - 2.0 * FINE_SPAN) / step)) + 1))
    tail = np.linspace(t_h - FINE_SPAN, t_h, nf + 1)
    return np.concatenate([head, mid[1:-1], tail])


class _Block:
    """A horizontal block of one trip on a grid of its time, with its floors.

    ``mode="search"``: one floor per obstacle group at the grid points
    (exact heights for the clearance itself: lower bounds).
    ``mode="plan"``: one group; the exact floor at the points (``floor``)
    and the *cell envelope* (``envelope``, one value per grid cell): the
    height B must keep at both ends of the cell so that the true clearance
    holds all over it.
    """

    def __init__(self, scenario: PalletScenario, q_start, q_goal, sync: str, carrying: bool,
                 groups: list[Prisms], mode: str = "search") -> None:
        lims = scenario.robot.limits
        self.traj = plan_ptp(q_start[_H], q_goal[_H], [lims[k] for k in _H], sync=sync)
        self.t_h = float(self.traj.duration)
        self.sync = sync
        self.tau = _grid(self.t_h, SEARCH_STEP if mode == "search" else PLAN_STEP,
                         fine=mode != "search")
        n = self.tau.size
        s = self.traj.sample(self.tau)
        q = np.zeros((n, 4))
        q[:, _H] = s.position
        self.q = q
        cell = scenario.cell
        assert cell is not None  # the cell planner runs on scenarios with a cell (plan_cycle_cell)
        c = cell.clearance
        box = (scenario.box.length, scenario.box.width, scenario.box.height)
        grip = cell.gripper_size(box[0], box[1])
        if mode == "search":
            # one pass over every obstacle, then the maximum per group
            sizes = [len(g) for g in groups]
            allg = groups[0]
            for g in groups[1:]:
                allg = allg.concat(g)
            F = volume_floors(q, box, grip, carrying, allg, c - CLEARANCE_ATOL)
            cuts = np.cumsum([0] + sizes)
            self.floors = [F[:, a:b].max(axis=1) if b > a else np.full(n, -np.inf)
                           for a, b in zip(cuts[:-1], cuts[1:])]
            return
        obst = groups[0]
        h = np.diff(self.tau)
        L = _speed_bound(s.position, s.velocity, s.acceleration, [lims[k] for k in _H],
                         box, grip, h)
        reach = c + float(np.max(L * h)) if n > 1 else c
        top = np.asarray(obst.z1, dtype=float)[None, :]
        F = np.full(n, -np.inf)
        E = np.full(n - 1, -np.inf)
        self.min_distance = math.inf
        for d, lo in footprint_distances(q, box, grip, carrying, obst, reach):
            if d.size == 0:
                continue
            # exact at the points, for the clearance less the tolerance (bounds)
            F = np.maximum(F, np.max(required_height(d, top, c - CLEARANCE_ATOL), axis=1) - lo)
            # smallest distance anywhere in the cell: the two ends' cones meet
            dlb = 0.5 * (d[:-1] + d[1:] - (L * h)[:, None]) + CLEARANCE_ATOL
            E = np.maximum(E, np.max(required_height(dlb, top, c), axis=1) - lo)
        self.floor = F
        self.envelope = E


def _speed_bound(pos, vel, acc, lims, box, grip, h) -> np.ndarray:
    """Bound on the horizontal speed [m/s] of any point of the moving footprint
    within each grid cell (width ``h``, shape (n - 1,)).

    Each joint's speed within half a cell of an end is at most
    ``|v| + |a| h/2 + j_max h^2/8`` there; a footprint point moves at most
    ``|dR/dt| + R |dtheta/dt| + rho |dyaw/dt|`` (``rho``: half the
    footprint diagonal, ``yaw = theta + D``).
    """
    rho = max(math.hypot(box[0], box[1]), math.hypot(grip[0], grip[1])) * 0.5
    half = 0.5 * h

    def joint(i, lim):
        jm = max(lim.j_max, lim.j_max_decel)
        e = [np.abs(vel[k, i]) + np.abs(acc[k, i]) * half + jm * half * half / 2.0
             for k in (slice(None, -1), slice(1, None))]
        return np.maximum(e[0], e[1])

    wt, vr, wd = (joint(i, l) for i, l in enumerate(lims))
    r = np.maximum(np.abs(pos[:-1, 1]), np.abs(pos[1:, 1])) + vr * half
    return vr + r * wt + rho * (wt + wd)


# ---------------------------------------------------------------- B search
def _window_bound(up: _Rise, dn: _Rise, tau, F, t_h) -> tuple[float, float, float]:
    """``(t_s*, e*, bound)``: earliest block start, block start to trip end, their sum."""
    m = np.isfinite(F)
    if not m.any():
        return 0.0, t_h, t_h
    ts = float(max(0.0, np.max(up.time_at(F[m]) - tau[m])))
    e = float(max(t_h, np.max(tau[m] + dn.time_at(F[m]))))
    return ts, e, ts + e


def _cell_envelope(env, a_b, h) -> np.ndarray:
    """Per grid cell: the envelope plus the sag a motion of B with acceleration
    at most ``a_b`` can have below the chord of the cell's ends (``a_b h^2/8``)."""
    return env + a_b * h * h / 8.0 + FLOOR_MARGIN


def _check(prof, t_s, tau, E) -> float:
    """Smallest margin of B over the cell envelope ``E`` with the block at ``t_s``."""
    z = prof.sample(t_s + tau).position
    m = np.isfinite(E)
    if not m.any():
        return math.inf
    return float(np.min(np.minimum(z[:-1], z[1:])[m] - E[m]))


def _range_ok(prof, lb: AxisLimits) -> bool:
    zp, _, _ = position_peak(prof)
    zmin = float(np.min(prof.boundary_states()[:, 0]))
    return zp <= lb.position_max + 1e-12 and zmin >= lb.position_min - 1e-12


def _settle_ok(prof, t_s, t_h, z1, z2) -> bool:
    r = clearance_crossings([(0.0, prof)], z1, z2, 0.0, float(prof.duration), float(prof.start))
    if r is None:
        return False
    t_up, t_dn, _ = r
    return t_up <= t_s + 1e-12 and t_s + t_h <= t_dn + 1e-12


def _turn(up: _Rise, dn: _Rise, lb: AxisLimits, T: float, t1: float, z3: float):
    """B: ``U`` until ``t1``, a minimum-time turn onto ``D`` (arriving at ``T``)."""
    z, v, a = (float(x) for x in up.state(t1))
    if z > lb.position_max:
        return None
    s1 = (z, v, a)

    def s2_at(t2):
        w = T - t2
        zz, vv, aa = (float(x) for x in dn.state(w))
        return (zz, -vv, aa)

    def g(t2):
        try:
            return min_state_duration(s1, s2_at(t2), lb) - (t2 - t1)
        except TrajkitError:
            return math.nan

    g_end = g(T)
    if not (g_end <= 0.0):
        return None
    lo = t1
    g_lo = g(lo)
    if not (g_lo > 0.0):
        return None
    def g_safe(x):
        v = g(x)
        return 1.0 if math.isnan(v) else v

    try:
        t2 = brentq(g_safe, lo, T, xtol=1e-12)
    except (ValueError, RuntimeError):
        return None
    s2 = s2_at(t2)
    if s2[0] > lb.position_max:
        return None
    try:
        mid = plan_state_to_state(s1, s2, lb)
    except TrajkitError:
        return None
    tail = _reverse(dn.phases_until(T - t2))
    phases = up.phases_until(t1) + _phases_of(mid) + tail
    return _trip_profile(phases, up.z0, z3, lb, "cell:turn")


def _crossing_time(up: _Rise, dn: _Rise, T: float) -> float:
    """When the rise ``U`` meets the arrival ``D`` (ending at ``T``)."""
    def f(t):
        return float(up.state(t)[0]) - float(dn.state(T - t)[0])
    try:
        return brentq(f, 0.0, T, xtol=1e-9)
    except ValueError:
        return 0.5 * T


def _hold(z0, z3, zh, t_h, lb, tau, E, zs):
    """B rests at ``zh`` (rest-to-rest up and down) long enough for the block."""
    up = plan_move(z0, zh, lb)
    down = plan_move(zh, z3, lb)
    phases = []
    for p in (up,):
        phases += [(d, j, a) for d, j, a in zip(np.diff(p.phase_times), p.jerks,
                                                  p.boundary_states()[:-1, 2]) if d > 0]
    # the block runs while B rests at zh (between the two moves)
    phases.append((t_h, 0.0, 0.0))
    phases += [(d, j, a) for d, j, a in zip(np.diff(down.phase_times), down.jerks,
                                              down.boundary_states()[:-1, 2]) if d > 0]
    prof = _trip_profile(phases, z0, z3, lb, "cell:hold")
    t_s = up.duration
    m = _check(prof, t_s, tau, E)
    if m < -TOUCH_TOL or not _settle_ok(prof, t_s, t_h, *zs):
        return None
    return prof, t_s, m


def _fixed_middle(up: _Rise, dn: _Rise, lb: AxisLimits, T: float, t1: float, t2: float,
                  z3: float):
    """B: ``U`` until ``t1``, a state-to-state piece of duration ``t2 - t1`` onto ``D``."""
    if not 0.0 <= t1 < t2 <= T:
        return None
    s1 = tuple(float(x) for x in up.state(t1))
    zz, vv, aa = (float(x) for x in dn.state(T - t2))
    s2 = (zz, -vv, aa)
    if max(s1[0], s2[0]) > lb.position_max:
        return None
    try:
        mid = plan_state_to_state(s1, s2, lb, duration=t2 - t1)
    except TrajkitError:
        return None
    phases = up.phases_until(t1) + _phases_of(mid) + _reverse(dn.phases_until(T - t2))
    return _trip_profile(phases, up.z0, z3, lb, "cell:window")


#: Fractions of the time between the two binding floor points by which the
#: rise is followed longer / the arrival started earlier (fixed middles).
MIDDLE_SHIFTS = (0.0, 0.15, 0.4)


class _BSearch:
    """B motions for one block and its floor envelope (see :func:`_plan_b`)."""

    def __init__(self, lb, z0, z3, tau, E, t_h, zs):
        self.lb, self.z0, self.z3, self.tau, self.E, self.t_h, self.zs = lb, z0, z3, tau, E, t_h, zs
        self.up, self.dn = _throttle(lb, "accel", z0), _throttle(lb, "decel", z3)
        m = np.isfinite(E)
        self.m = m
        # Only the record cells matter for "latest t_up(E_i) - tau_i" (a cell
        # with a higher floor no later dominates) and for "latest tau_i+1 +
        # t_dn(E_i)" (a higher floor no earlier dominates): prefix and suffix
        # maxima of the floor, exact and few.
        Ef = np.where(m, E, -np.inf)
        pre = np.maximum.accumulate(Ef)
        self.i_up = np.flatnonzero(m & (Ef >= pre) & (Ef > np.concatenate([[-np.inf], pre[:-1]])))
        suf = np.maximum.accumulate(Ef[::-1])[::-1]
        nxt = np.concatenate([suf[1:], [-np.inf]])
        self.i_dn = np.flatnonzero(m & (Ef >= suf) & (Ef > nxt))
        if m.any():
            iu_, id_ = self.i_up, self.i_dn
            a = self.up.time_at(E[iu_]) - tau[:-1][iu_]
            k = int(np.argmax(a))
            self.t_s = float(max(0.0, a[k]))
            self.tau_u = float(tau[iu_[k]]) if a[k] > 0.0 else 0.0
            e = tau[1:][id_] + self.dn.time_at(E[id_])
            k = int(np.argmax(e))
            self.e = float(max(t_h, e[k]))
            self.tau_d = float(tau[id_[k] + 1]) if e[k] >= t_h else t_h
        else:
            self.t_s, self.tau_u, self.e, self.tau_d = 0.0, 0.0, t_h, t_h
        self.T0 = self.t_s + self.e

    def accept(self, prof, t_s=None):
        t_s = self.t_s if t_s is None else t_s
        if prof is None or not _range_ok(prof, self.lb):
            return None
        if t_s + self.t_h > prof.duration + 1e-12:
            return None
        mg = _check(prof, t_s, self.tau, self.E)
        if mg >= -TOUCH_TOL and _settle_ok(prof, t_s, self.t_h, *self.zs):
            return prof, mg
        return None

    def at(self, T: float):
        """A B motion of duration ``T`` that clears the floor, or None.

        Fixed middles first: B follows ``U`` to the binding rising floor
        point (or a little longer) and joins ``D`` where ``D`` passes the
        binding falling floor point's height (or a little earlier); then
        minimum-time turns around the crossing of ``U`` and ``D``.
        """
        g1 = self.t_s + self.tau_u
        g2 = T - (self.e - self.tau_d)
        if g2 > g1:
            span = g2 - g1
            for f1 in MIDDLE_SHIFTS:
                for f2 in MIDDLE_SHIFTS:
                    if f1 + f2 >= 0.9:
                        continue
                    r = self.accept(_fixed_middle(self.up, self.dn, self.lb, T, g1 + f1 * span,
                                                  g2 - f2 * span, self.z3))
                    if r is not None:
                        return r
        tc = _crossing_time(self.up, self.dn, T)
        best = None
        for off in TURN_OFFSETS:
            t1 = tc - off
            if t1 <= 0.0:
                break
            prof = _turn(self.up, self.dn, self.lb, T, t1, self.z3)
            if prof is not None and abs(prof.duration - T) > 1e-6:
                continue
            r = self.accept(prof)
            if r is not None and (best is None or r[1] > best[1]):
                best = r
        return best


#: Turning accelerations of the ``peak`` candidates, as fractions of B's
#: acceleration limit (the motion turns at its top with ``-f * a_max``).
PEAK_TURNS = (1.0, 0.5)

#: Absolute tolerance [m] of the search for the lowest feasible peak.
PEAK_XTOL = 1e-4


def _peak(srch: _BSearch, zp: float, ap: float, check: bool = True):
    """B alone to a peak ``(zp, 0, ap)`` and down, minimum time each way; the
    block placed at the earliest start its floor allows (or None).

    For a motion that rises, then falls, the starts that keep every cell of
    the floor form one interval, exact from the record cells; ``check`` also
    samples the motion against the whole floor (and the settle rule).
    """
    lb, z0, z3 = srch.lb, srch.z0, srch.z3
    try:
        u = plan_state_to_state((z0, 0.0, 0.0), (zp, 0.0, ap), lb)
        d = plan_state_to_state((zp, 0.0, ap), (z3, 0.0, 0.0), lb)
    except TrajkitError:
        return None
    pu, pd = _phases_of(u), _phases_of(d)
    prof = _trip_profile(pu + pd, z0, z3, lb, "cell:peak")
    T = prof.duration
    E, tau, m = srch.E, srch.tau, srch.m
    if m.any():
        if np.max(E[m]) > zp:
            return None
        rise, fall = _Rise(pu, z0), _Rise(_reverse(pd), z3)
        iu_, id_ = srch.i_up, srch.i_dn
        lo = max(0.0, float(np.max(rise.time_at(E[iu_]) - tau[:-1][iu_])))
        hi = min(T - srch.t_h, float(np.min(T - fall.time_at(E[id_]) - tau[1:][id_])))
    else:
        lo, hi = 0.0, T - srch.t_h
    if lo > hi:
        return None
    if not check:
        return prof, lo, math.nan
    got = srch.accept(prof, lo)
    return None if got is None else (prof, lo, got[1])


def _best_peak(srch: _BSearch):
    """The ``peak`` candidate with the lowest feasible peak, over :data:`PEAK_TURNS`."""
    lb = srch.lb
    zlo = max(float(np.max(srch.E[srch.m])) if srch.m.any() else -math.inf, *srch.zs)
    zhi = lb.position_max
    A = min(lb.a_max, lb.a_max_decel)
    best = None
    for f in PEAK_TURNS:
        ap = -f * A
        if _peak(srch, zhi, ap, check=False) is None:
            continue
        lo, hi = zlo, zhi
        if _peak(srch, lo, ap, check=False) is not None:
            hi = lo
        while hi - lo > PEAK_XTOL:
            mid = 0.5 * (lo + hi)
            if _peak(srch, mid, ap, check=False) is None:
                lo = mid
            else:
                hi = mid
        # the full check on the result; where it says no (a motion that is not
        # up-then-down, the settle rule), search again above with it
        found = _peak(srch, hi, ap)
        if found is None and _peak(srch, zhi, ap) is not None:
            lo, hi2 = hi, zhi
            found = _peak(srch, zhi, ap)
            while hi2 - lo > PEAK_XTOL:
                mid = 0.5 * (lo + hi2)
                r = _peak(srch, mid, ap)
                if r is None:
                    lo = mid
                else:
                    hi2, found = mid, r
        if found is not None and (best is None or found[0].duration < best[0].duration):
            best = found
    return best


def _plan_b(scenario: PalletScenario, spec_levels, block: _Block):
    """B's motion for one block: the fastest candidate that clears the floor.

    Returns ``(candidate, profile, t_s, margin)`` or None when no motion
    within B's range clears the floor.
    """
    lb = scenario.robot.limits[_B]
    z0, z3 = spec_levels
    assert scenario.cell is not None  # the cell planner runs on scenarios with a cell (plan_cycle_cell)
    settle = scenario.cell.settle
    zs = (z0 + settle, z3 + settle)
    tau, t_h = block.tau, block.t_h
    E = _cell_envelope(block.envelope, max(lb.a_max, lb.a_max_decel), np.diff(tau))
    E[0] = max(E[0], zs[0] + FLOOR_MARGIN)
    E[-1] = max(E[-1], zs[1] + FLOOR_MARGIN)
    fin = np.isfinite(E)
    top = float(np.max(E[fin])) if fin.any() else -math.inf
    if top > lb.position_max:
        return None
    srch = _BSearch(lb, z0, z3, tau, E, t_h, zs)
    r = srch.at(srch.T0)
    if r is not None:
        return ("window", r[0], srch.t_s, r[1], srch.T0)
    cands = []
    pk = _best_peak(srch)
    if pk is not None:
        cands.append(("peak", pk[0], pk[1], pk[2], srch.T0))
    # a B motion that turns at speed, lengthened until it clears the floor
    # (searched only where it can still beat the peak by a useful margin)
    T_hi = pk[0].duration if pk is not None else None
    if T_hi is None:
        zh = min(max(top, *zs) + FLOOR_MARGIN, lb.position_max)
        fb = _hold(z0, z3, zh, t_h, lb, tau, E, zs)
        if fb is not None:
            cands.append(("hold", fb[0], fb[1], fb[2], srch.T0))
            T_hi = fb[0].duration
    if T_hi is not None and T_hi - srch.T0 > STRETCH_MIN * srch.T0:
        found = None
        lo, hi = srch.T0, T_hi
        while hi - lo > T_XTOL:
            mid = 0.5 * (lo + hi)
            r = srch.at(mid)
            if r is None:
                lo = mid
            else:
                hi, found = mid, r
        if found is not None:
            cands.append(("stretched", found[0], srch.t_s, found[1], srch.T0))
    if not cands:
        return None
    return min(cands, key=lambda c: c[1].duration)


# ------------------------------------------------------------------- cycle
class _Ctx:
    """What the cycle planner shares between trips (geometry, caches)."""

    def __init__(self, scenario: PalletScenario, cell: Cell) -> None:
        self.sc = scenario
        self.cell = cell
        self.lb = scenario.robot.limits[_B]
        b = scenario.box
        self.dims = (b.length, b.width, b.height)
        self.poses = scenario.place_poses()
        self.static = self.cell.static_prisms()
        self.pick_box = (stack_prisms(scenario.pick[None, :], *self.dims, names=("box at the pick",))
                         if self.cell.box_at_pick else Prisms.empty())
        self.q_pick = scenario.pick_joints()
        #: Joint vectors per box that place it (wrist_options), set by the planner.
        self.wrists: list[list[np.ndarray]] = []
        self.throttles: dict = {}
        self.turn_cache: dict = {}

    def throttle(self, leg: str, z: float) -> _Rise:
        key = (leg, z)
        if key not in self.throttles:
            self.throttles[key] = _throttle(self.lb, leg, z)
        return self.throttles[key]

    def boxes(self, idx, names=True) -> Prisms:
        idx = list(idx)
        return stack_prisms(self.poses[idx], *self.dims,
                            names=tuple(f"box {i}" for i in idx) if names else ())


def _trip_q(ctx: _Ctx, kind: str, q_place):
    return (ctx.q_pick, q_place) if kind == "load" else (q_place, ctx.q_pick)


def _search_layer(ctx: _Ctx, idx: list[int], below: Prisms):
    """Order, wrists and DP value of one layer (window bounds on the coarse grid)."""
    n = len(idx)
    base_load = ctx.static.concat(below)
    base_ret = base_load.concat(ctx.pick_box)
    singles = [ctx.boxes([b]) for b in idx]
    # per block and obstacle group: the two scalars of the window bound
    # (a: latest "t_up(F) - tau", b: latest "tau + t_dn(F)"); the bound of a
    # set of groups is max(0, max a) + max(tH, max b)
    terms = {}
    for i, b in enumerate(idx):
        for w, qp in enumerate(ctx.wrists[b]):
            for kind, base, carrying in (("load", base_load, True), ("return", base_ret, False)):
                qs, qg = _trip_q(ctx, kind, qp)
                z0, z3 = float(qs[_B]), float(qg[_B])
                up, dn = ctx.throttle("accel", z0), ctx.throttle("decel", z3)
                s_ = ctx.cell.settle
                for m in SYNC_MODES:
                    blk = _Block(ctx.sc, qs, qg, m, carrying, [base] + singles, mode="search")
                    ab = []
                    for F in blk.floors:
                        f = np.isfinite(F)
                        if f.any():
                            ab.append((float(np.max(up.time_at(F[f]) - blk.tau[f])),
                                       float(np.max(blk.tau[f] + dn.time_at(F[f])))))
                        else:
                            ab.append((-math.inf, -math.inf))
                    a0 = max(0.0, float(up.time_at(z0 + s_)[0]), ab[0][0])
                    b0 = max(blk.t_h, blk.t_h + float(dn.time_at(z3 + s_)[0]), ab[0][1])
                    terms[(i, w, kind, m)] = (a0, b0, ab[1:])

    def trip_cost(i, w, kind, S):
        best = (math.inf, SYNC_MODES[0])
        for m in SYNC_MODES:
            a0, b0, ab = terms[(i, w, kind, m)]
            for j in range(n):
                if S >> j & 1:
                    a0, b0 = max(a0, ab[j][0]), max(b0, ab[j][1])
            best = min(best, (a0 + b0, m))
        return best

    full = (1 << n) - 1
    exact = n <= MAX_DP_BOXES
    cost_cache: dict = {}

    def cost(i, S):
        key = (i, S)
        if key not in cost_cache:
            opts = []
            for w in range(len(ctx.wrists[idx[i]])):
                lv, lm = trip_cost(i, w, "load", S)
                rv, rm = trip_cost(i, w, "return", S | 1 << i)
                opts.append((lv + rv, w, lm, rm))
            cost_cache[key] = min(opts)
        return cost_cache[key]

    if exact:
        dp: dict[int, tuple[float, tuple[int, int] | None]] = {0: (0.0, None)}
        for S in range(full + 1):
            if S not in dp:
                continue
            base_v = dp[S][0]
            for i in range(n):
                if S >> i & 1:
                    continue
                v = base_v + cost(i, S)[0]
                T = S | 1 << i
                if T not in dp or v < dp[T][0]:
                    dp[T] = (v, (S, i))
        seq = []
        S = full
        while S:
            prev = dp[S][1]
            assert prev is not None  # every set but the empty one was reached from a smaller one
            P, i = prev
            seq.append(i)
            S = P
        seq.reverse()
        value = dp[full][0]
    else:
        seq, S = [], 0
        while S != full:
            i = min((j for j in range(n) if not S >> j & 1), key=lambda j: cost(j, S)[0])
            seq.append(i)
            S |= 1 << i
        # every order places each box after some subset: the bound uses none
        value = sum(cost(i, 0)[0] for i in range(n))
    out, S = [], 0
    for i in seq:
        out.append((idx[i],) + tuple(cost(i, S)[1:]))
        S |= 1 << i
    return out, value


def _plan_trip(ctx: _Ctx, kind: str, box: int, q_place, obstacles: Prisms, prefer: str):
    """Final plan of one trip on the fine grid.

    The synchronisation ``prefer`` (the order search's choice) first; the
    other one too when the first trip is more than :data:`RETRY_GAP` above
    its window bound.
    """
    qs, qg = _trip_q(ctx, kind, q_place)
    z0, z3 = float(qs[_B]), float(qg[_B])
    carrying = kind == "load"
    best = None
    for m in (prefer,) + tuple(x for x in SYNC_MODES if x != prefer):
        if best is not None and best[1][1].duration <= best[3] * (1.0 + RETRY_GAP):
            break
        blk = _Block(ctx.sc, qs, qg, m, carrying, [obstacles], mode="plan")
        r = _plan_b(ctx.sc, (z0, z3), blk)
        if r is None:
            continue
        if best is None or r[1].duration < best[1][1].duration:
            best = (m, r, blk, r[4])
    if best is None:
        raise InfeasibleError(
            f"{kind} trip of box {box}: no B motion within joint B's range "
            f"[{ctx.lb.position_min * 1000:g}, {ctx.lb.position_max * 1000:g}] mm keeps the "
            f"cell's clearance {ctx.cell.clearance * 1000:g} mm along the horizontal move"
        )
    m, r, blk, _ = best
    cand, prof, t_s, margin = r[:4]
    # bounds from the exact floor at the grid points (the clearance itself)
    s = ctx.cell.settle
    up, dn = ctx.throttle("accel", z0), ctx.throttle("decel", z3)
    F = blk.floor.copy()
    F[0] = max(F[0], z0 + s)
    F[-1] = max(F[-1], z3 + s)
    _, _, wb = _window_bound(up, dn, blk.tau, F, blk.t_h)
    fmax = float(np.max(F))
    t_b, _ = _best_turn(z0, fmax, z3, ctx.lb, ctx.turn_cache)
    t_b = t_b if math.isfinite(t_b) else 0.0
    t_h_min = min(_h_min_time(ctx, qs, qg, kind))
    cf = float(up.time_at(F[0])[0] + t_h_min + dn.time_at(F[-1])[0])
    zp, _, _ = position_peak(prof)
    info = CellTrip(cand, float(prof.duration), max(wb, t_b), wb, cf, blk.t_h, t_s, m, 0,
                    float(zp), fmax, margin)
    spec = TripSpec(kind, box, np.array(qs, dtype=float), np.array(qg, dtype=float), z0 + s, z3 + s)
    pieces: list[list[Piece]] = [[] for _ in range(4)]
    pieces[_B] = [Piece(0.0, prof)]
    for i, k in enumerate(_H):
        pieces[k] = [Piece(t_s, blk.traj.axes[i])]
    trip = TripPlan(spec, float(prof.duration), tuple(tuple(p) for p in pieces),
                    (t_s, t_s + blk.t_h), float(zp))
    return trip, info


def _h_min_time(ctx: _Ctx, qs, qg, kind: str):
    """Minimum time of the horizontal joints over every wrist choice of the place."""
    from ..profiles import min_duration

    lims = ctx.sc.robot.limits
    place = qg if kind == "load" else qs
    pose = ctx.sc.robot.pose_from_joints(place)
    out = []
    for q in wrist_options(ctx.sc, pose, n=8):
        a, b = (ctx.q_pick, q) if kind == "load" else (q, ctx.q_pick)
        out.append(max(min_duration(b[k] - a[k], lims[k]) for k in _H))
    return out


#: A trip more than this fraction above its window bound is also planned
#: with the other synchronisation.
RETRY_GAP = 0.003

#: Largest layer (boxes) whose order is found by dynamic programming over
#: its subsets; larger layers are ordered greedily.
MAX_DP_BOXES = 8


def plan_cycle_cell(scenario: PalletScenario) -> CyclePlan:
    """Plan the whole job around the cell's geometry (see the module docstring).

    ``plan.info`` holds ``"trips"`` (one :class:`CellTrip` per trip),
    ``"order"`` (the placing order, indices into the pattern's boxes),
    ``"lower_bound_s"`` (over every in-layer order, wrist, synchronisation
    and B motion), ``"order_bound_s"`` (this order, the fine floor and
    ``t_B``) and ``"cell_floor_s"`` (any motion in this order); all include
    the grip and release dwells.

    Raises
    ------
    InvalidInputError
        The scenario has no cell.
    InfeasibleError
        A trip whose floor is above joint B's range.
    """
    if scenario.cell is None:
        raise InvalidInputError(
            f"the {PLANNER_NAME!r} planner needs a cell (obstacles, gripper, clearance): the "
            f"scenario {scenario.name!r} has none (add a `cell` section to the job file)"
        )
    ctx = _Ctx(scenario, scenario.cell)
    ctx.wrists = [wrist_options(scenario, p) for p in ctx.poses]
    n = scenario.pattern.layer.n_boxes
    order, dp_total = [], 0.0
    for k in range(scenario.layers):
        idx = list(range(k * n, (k + 1) * n))
        seq, value = _search_layer(ctx, idx, ctx.boxes(range(k * n), names=True))
        order += seq
        dp_total += value
    trips, infos = [], []
    placed: list[int] = []
    base = ctx.static
    for b, w, m_load, m_ret in order:
        qp = ctx.wrists[b][w]
        obst = base.concat(ctx.boxes(placed))
        tp, info = _plan_trip(ctx, "load", b, qp, obst, m_load)
        trips.append(tp)
        infos.append(_with_wrist(info, w))
        placed.append(b)
        obst = base.concat(ctx.boxes(placed)).concat(ctx.pick_box)
        tp, info = _plan_trip(ctx, "return", b, qp, obst, m_ret)
        trips.append(tp)
        infos.append(_with_wrist(info, w))
    plan = _assemble(PLANNER_NAME, scenario, trips)
    plan.rule = "cell"
    dwell = plan.total_s - sum(t.duration for t in trips)
    plan.info["trips"] = infos
    plan.info["order"] = [o[0] for o in order]
    plan.info["lower_bound_s"] = float(dwell + dp_total)
    plan.info["order_bound_s"] = float(dwell + sum(i.lower_bound for i in infos))
    plan.info["cell_floor_s"] = float(dwell + sum(i.cell_floor for i in infos))
    return plan


def _with_wrist(info: CellTrip, w: int) -> CellTrip:
    from dataclasses import replace

    return replace(info, wrist=int(w))


register_planner(PLANNER_NAME, plan_cycle_cell)
