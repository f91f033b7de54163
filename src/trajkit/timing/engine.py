"""The path-timing engine: minimum-time, jerk-limited motion along a geometric path.

Given a joint path ``q(s)`` (:class:`~trajkit.timing.paths.JointPath`), the
joints' velocity, acceleration and jerk limits (accel and decel legs) and the
path's own limits (speed cap along the path, tangential acceleration and
jerk), :func:`plan_path_timing` returns the fastest ``s(t)`` it finds as
exact pieces of constant path jerk (:class:`PathTiming`).

Steps:

0. the minimum-time S-curve of ``s`` under the path's own limits alone (a
   lower bound of every timing): where the check (step 4) finds it within
   every joint's limits too, it is the timing (``info["status"]`` "path
   limits") and the steps below are skipped;
1. a grid of ``s`` (refined at the path's ends, at its breakpoints and
   wherever the joint-path derivatives change faster than their cubic
   interpolation follows, to :data:`FIRST_GRID_RTOL`);
2. the grid problem (:mod:`trajkit.timing._socp`): the jerk-free optimum
   first (a lower bound), then rounds of convex restriction of the jerk
   constraints; the grid is then split where the path acceleration swings
   (the jerk phases) and refined to :data:`GRID_RTOL`, and the rounds go on
   there until the time settles;
3. exact constant-jerk pieces through the node states
   (:mod:`trajkit.timing._hermite`);
4. a dense check of every limit on the pieces (every piece boundary plus
   :data:`CHECK_PER_PIECE` points inside, path derivatives exact where the
   path makes them cheap, otherwise by their cubic interpolation on the grid,
   towards the values from below in a cell that ends at a breakpoint); where
   a limit is exceeded the limit of that joint is lowered at the nearby nodes
   and the problem solved again (:data:`MAX_TIGHTEN` times). The final check
   is denser (:data:`FINAL_CHECK_PER_PIECE`, then a zoom on the pieces close
   to a limit); on a path without cheap derivatives it evaluates the true
   derivatives at the middle of every cell where it comes within
   :data:`VERIFY_ABOVE` of a limit, at every point of :data:`VERIFY_POINTS`
   where it then comes within :data:`VERIFY_FULL_ABOVE`, and corrects the
   interpolation there (``_Corrected``). The checks run compiled (:mod:`trajkit.timing._checks`)
   when numba is installed. Any excess left is removed by slowing the whole
   motion down uniformly (time scaled by ``k``: velocities / k, accelerations
   / k^2, jerks / k^3), which always succeeds.

Optimality: the result is a stationary point of the grid problem (the rounds
stop when the time changes by less than :data:`ROUND_RTOL`); the
jerk-free optimum on the same grid is reported beside it as a lower bound
(``PathTiming.jerk_free_time``).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._validate import check_positive
from ..errors import InfeasibleError, InvalidInputError
from ..limits import AxisLimits
from ..profiles import plan_move
from ..profiles._pieces import eval_pieces
from ..profiles._range import check_limits_range
from ..profiles.state import plan_state_to_state
from . import _checks
from ._hermite import UnjoinableError, hermite_pieces, time_to_reach
from ._socp import MAX_ROUNDS, RELAXED, ROUND_RTOL, STALL_FACTOR, GridProblem, GridSolution, _rest_jerk, solve_grid
from .paths import JointPath

__all__ = ["PathTiming", "plan_path_timing", "CHECK_PER_PIECE", "MAX_TIGHTEN", "LimitUse"]

#: Longest motion the engine plans [s] (about 116 days); a longer one is refused
#: before any work.
MAX_DURATION = 1e7

#: Grid nodes to start from (before refinement).
GRID_START = 48

#: Most grid nodes.
GRID_MAX = 1200

#: Refinement: a cell is split while the interpolated derivative at its middle
#: misses the true one by more than this fraction of the limit it feeds.
GRID_RTOL = 2e-3

#: The same for a path whose derivatives are cheap to evaluate exactly
#: (``cheap_derivatives``): the limit check uses the exact ones.
GRID_RTOL_CHEAP = 2e-2

#: The first solve's grid is refined to this tolerance only (its solution
#: places the nodes of the jerk phases and starts the second solve); the
#: second grid, with those nodes, is refined to GRID_RTOL. 10 % less planning
#: time over the benchmark's arm motions (its blends 9-27 %) than with the
#: first grid refined to GRID_RTOL, durations within 1.6e-4 (the rounds'
#: tolerance is 5e-4).
FIRST_GRID_RTOL = 2e-2

#: Samples of a speed-cap function searched for its steps.
CAP_GRID = 4097

#: A change of the speed cap between two samples that counts as a step (fraction).
CAP_STEP = 0.01

#: A point of that sampling within this fraction of its spacing of a grid node is
#: not added as a node (the node is there already, to round-off).
CAP_MERGE = 1e-3

#: Refinement passes at most (each halves the cells still over GRID_RTOL: a
#: corner blend of 0.05 mm radius on a 0.2 m line needs 9). Cells still over it
#: after the last pass, or left whole at GRID_MAX, are checked with the true
#: derivatives at every point of the final check.
GRID_PASSES = 12

#: Nodes added near each end of the path at geometrically growing spacing
#: (the motion from rest goes like s ~ t^3 there).
END_NODES = 6

#: Distance of a breakpoint's twin node before it, as a fraction of the regular spacing.
BREAK_TWIN = 1e-3

#: The first of them, as a fraction of the regular spacing.
END_FIRST = 0.02

#: A piece of the path shorter than this fraction of its length at its start or
#: end is planned as the extension of the piece next to it (see ``_ShortEnds``):
#: the grid's regular spacing refined 12 times is 5e-6 of the length, and such a
#: piece (a re-plan's start state just before a breakpoint) made cells of
#: round-off length there, or a first node whose third derivative the rest of
#: its cell does not have (up to 8 % slower, the fallback, within 1e-7 of the
#: length).
END_PIECE = 1e-6

#: The same at an end in rest: a piece shorter than two of the grid's finest
#: cells. A breakpoint between END_PIECE and this before a rest end made the
#: timing from rest up to 1.2 % slower, and re-plans from states braking into
#: such an end raised (5 of 900 re-plans; 1 with this); next to a rest end the
#: path speed is close to zero, and with it the joints' jerk from the step of
#: the third derivative.
END_PIECE_REST = 1e-5

#: The timing's motion ends within this fraction of the path's length of its end
#: (round-off; checked before a timing is returned).
END_RTOL = 1e-9

#: Rounds of the first solve (it only finds where the jerk phases are and
#: where the second solve starts from).
FIRST_ROUNDS = 3

#: After the first solve, an interval whose path acceleration changes by more
#: than this fraction of the acceleration's range is split (in 2 to 4).
SWING_SPLIT = 0.02

#: After the first solve, a rest interval (the constant-jerk phase from or to
#: rest) whose jerk stays below REST_SPLIT_BELOW of its limit while its inner
#: node's acceleration is at REST_SPLIT_ACCEL of its limit or more ends too
#: far from the rest: the ramp at the jerk limit to that acceleration ends
#: sooner, and a node is put there, REST_SPLIT_MIN of the interval from the
#: rest or more (see ``_rest_splits``).
REST_SPLIT_BELOW = 0.9
REST_SPLIT_ACCEL = 0.9
REST_SPLIT_MIN = 1e-3

#: The grid problem plans with this fraction of every jerk limit: its pieces'
#: jerks differ from the model's by a fraction of a per cent (two pieces per
#: interval), which this absorbs instead of a slow-down of the whole motion.
JERK_MARGIN = 0.998

#: (From and to rest only: with a moving boundary state the grid problem plans with
#: the full jerk limits. A state taken from a time-optimal timing, an online
#: re-plan, can be on its way to a limit at the full jerk limit, where a lower
#: one would carry it past that limit: no timing. Its pieces' excesses are
#: lowered locally, see :data:`MAX_TIGHTEN_MOVING`.)

#: Points checked inside every piece (besides its ends) by the rounds' checks,
#: which lower the limits locally where they find an excess (the final check is
#: denser). With 8 instead of 16, the 94 arm motions of the robust set (the
#: benchmark's and random lines and arcs) came out the same to 5.4e-7 of their
#: durations, with 6 % less planning time over the benchmark's.
CHECK_PER_PIECE = 8

#: A joint whose |velocity| is below this fraction of its limit is at rest for the
#: choice of the leg (speeding up or slowing down) in the limit check.
REST_RTOL = 1e-9

#: Samples the limit check evaluates at once (whole pieces; the numbers of a chunk
#: stay in the processor's cache).
CHECK_CHUNK = 4096

#: Points checked inside every piece by the final check of the chosen timing
#: (then ZOOM_LEVELS brackets around the largest values of the pieces close to a
#: limit). With 16, 32 or 64 points, the check found the same largest ratios, to
#: 1e-9, on 94 arm motions (the benchmark's and random lines and arcs) and on the
#: 200 speed-dip lines of the feed sweep (one of them to 3e-12).
FINAL_CHECK_PER_PIECE = 32

#: A compiled check of at least this many samples, in pieces of increasing index,
#: runs in two halves at once where a second core is free (the kernel releases
#: the GIL; the halves hold different pieces, the results are the same).
PARALLEL_SAMPLES = 4000


_POOLS: dict[int, Any] = {}


def _second_core():
    """A one-thread pool for the other half of a large check, or None (one core).
    One per process: a process forked from one that had the pool gets its own
    (the forked copy has no thread behind it)."""
    import os
    from concurrent.futures import ThreadPoolExecutor

    pid = os.getpid()
    if pid not in _POOLS:
        try:
            cores = len(os.sched_getaffinity(0))
        except AttributeError:  # (not on Linux)
            cores = os.cpu_count() or 1
        _POOLS.clear()
        _POOLS[pid] = (ThreadPoolExecutor(max_workers=1, thread_name_prefix="trajkit-check")
                       if cores > 1 else None)
    return _POOLS[pid]


def _sample_ratios(t, st, jerk, s_grid, piece, dt, F, cap_s, args, mid, have):
    """:func:`._checks.sample_ratios` of the samples, in two halves on two threads
    where :data:`PARALLEL_SAMPLES` and :func:`_second_core` allow it and the
    pieces increase (a piece's samples in one half only: its row of ``mid`` is
    filled by one thread). ``F``: ``(F1, F2, F3)``; ``args``: the kernel's
    arguments from ``d1`` to ``xs``, then from ``vlim`` to ``cap``."""
    n = piece.size
    pool = _second_core() if n >= PARALLEL_SAMPLES else None
    h = n // 2
    while pool is not None and 0 < h < n and piece[h] == piece[h - 1]:
        h += 1
    if pool is None or not 0 < h < n or not bool(np.all(piece[1:] >= piece[:-1])):
        return _checks.sample_ratios(t, st, jerk, s_grid, piece, dt, *args[:9], *F, *args[9:],
                                     cap_s, mid, have)

    m = args[9].size
    out = (np.empty(n, dtype=np.int64), np.empty((n, m)), np.empty((n, m)), np.empty((n, m)),
           np.empty(n), np.empty(n))

    def half(lo, hi):  # (each half writes its rows of the results)
        return _checks.sample_ratios_into(t, st, jerk, s_grid, piece[lo:hi], dt[lo:hi], *args[:9],
                                          *(f[lo:hi] if f.shape[0] else f for f in F), *args[9:],
                                          cap_s[lo:hi] if cap_s.size else cap_s, mid, have,
                                          *(x[lo:hi] for x in out))

    other = pool.submit(half, h, n)
    a = half(0, h)
    b = other.result()
    return (*out, np.maximum(a[0], b[0]), np.maximum(a[1], b[1]))


#: The final check looks again at every piece that comes within ZOOM_ABOVE of a
#: limit: ZOOM_LEVELS times ZOOM_POINTS points in a bracket narrowing around its
#: largest values (see ``_zoom``).
ZOOM_ABOVE = 1e-3
ZOOM_POINTS = 17
ZOOM_LEVELS = 4

#: The final check of a path whose derivatives are not cheap (inverse
#: kinematics) evaluates the true derivatives at the middle of every grid
#: cell where a check point comes within VERIFY_ABOVE of a limit (the
#: interpolation error of ``q'''`` is a fraction of a per cent where the grid is
#: refined), and corrects the interpolation there (see ``_Corrected``).
VERIFY_ABOVE = 1e-2

#: Points (fractions of a cell) where the true derivatives are evaluated (each
#: costs an inverse kinematics and the derivatives of the path at that point):
#: first the middle of every cell within VERIFY_ABOVE of a limit, then all
#: three in the cells still within VERIFY_FULL_ABOVE. With the middle alone
#: the corrected interpolation missed a joint's largest jerk in a corner blend
#: by 4e-5 of its limit; with all three, by 1e-7.
VERIFY_POINTS = (0.25, 0.5, 0.75)
VERIFY_FULL_ABOVE = 1e-3

#: The largest values the final check's zoom finds within this fraction of a limit
#: are evaluated again with the path's true derivatives.
EXACT_PEAK_ABOVE = 1e-5

#: Rounds of lowering a limit locally after the check found an excess.
MAX_TIGHTEN = 2

#: ... up to this many while the best timing so far would still need a uniform
#: slow-down by more than SLOW_SCALE (a uniform slow-down costs its factor over the
#: whole motion; the local lowering only where the excess is).
MAX_TIGHTEN_SLOW = 6
SLOW_SCALE = 1.005

#: An excess above this fraction means the grid is too coarse where it happens:
#: the cells around it are split in two and the problem solved again (at most
#: MAX_SPLITS times) before any limit is lowered.
SPLIT_ABOVE = 1e-2
MAX_SPLITS = 3

#: The check's largest excess above which a limit is lowered locally and the
#: problem solved again (below it the uniform slow-down is cheaper).
TIGHTEN_ABOVE = 1e-6

#: With a moving boundary state no uniform slow-down is possible (it would
#: change that state): every excess above CHECK_RTOL is lowered locally, in up
#: to this many rounds, and the rounds' check is as dense as the final one.
MAX_TIGHTEN_MOVING = 8

#: With a moving state, a cell whose excess after a local lowering is still at
#: least this fraction of the one before is split (the lowering did not reach it).
STUBBORN_EXCESS = 0.5

#: With a moving boundary state an attempt further above a limit than the least
#: excess of the attempts before it has that limit lowered by at most that least
#: excess (at least SPLIT_ABOVE), times this factor for every attempt in a row
#: before it that was above it too (an excess that persists is the motion's
#: own, not rounds gone astray).
CLIP_GROWTH = 1.5

#: A timing that had to be slowed down uniformly counts this fraction longer
#: when the attempts are compared.
SCALED_PENALTY = 2e-3

#: A best attempt that needs a uniform slow-down by more than this factor is
#: compared with the always-feasible fallback, and the shorter one kept (a
#: safeguard: on the benchmark's motions every attempt needs less than 1 %).
FALLBACK_ABOVE = 1.1

#: Rounds of a solve after a limit was lowered locally (it starts from the previous one).
TIGHTEN_ROUNDS = 3

#: The score of an attempt above a limit with a moving boundary state, per unit of
#: its largest ratio: above that of any timing within the limits (which is its
#: duration, at most MAX_DURATION).
MOVING_EXCESS_SCORE = 1e30

#: Margin kept under a limit that was lowered locally (fraction) ...
TIGHTEN_MARGIN = 1e-4

#: ... but a joint's limit with a moving start at most this many times the excess:
#: the start cannot move, and a start at a joint's limit (cruising at its velocity
#: limit) could not keep a small excess next to it lowered by the whole margin
#: (no later attempt found a timing).
JOINT_MARGIN_RATIO = 10.0

#: With a moving boundary state, an excess of at most this fraction of a limit
#: left after a round (the round-off of the linearised rows: lowered locally, it
#: turns up in another piece in the next round) lowers that limit everywhere by
#: ROUNDOFF_LOWER times the excess.
ROUNDOFF_EXCESS = 1e-6
ROUNDOFF_LOWER = 10.0

#: Attempts past MAX_TIGHTEN_MOVING for an excess at the round-off (the last
#: attempt's, lowered everywhere as above): a moving state cannot be slowed down
#: uniformly, and without them a timing 4e-8 over a limit is refused.
ROUNDOFF_ROUNDS = 2

#: Relative slack of the final check (round-off).
CHECK_RTOL = 1e-9

#: Final checks at most: each one that finds an excess slows the timing down
#: uniformly (from and to rest) or, with a moving boundary state, goes on to the
#: fallback; a timing still above a limit after them is refused.
FINAL_ATTEMPTS = 5


@dataclass
class LimitUse:
    """Largest |value| / limit of each joint over the checked samples.

    Attributes
    ----------
    velocity, acceleration, jerk : ndarray, shape (m,)
    path_acceleration, path_jerk : float
        Largest |s''| / a_path and |s'''| / j_path (0 when unlimited).
    path_speed : float
        Largest sdot / speed cap.
    """

    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray
    path_acceleration: float = 0.0
    path_jerk: float = 0.0
    path_speed: float = 0.0

    @property
    def worst(self) -> float:
        return float(max(self.velocity.max(initial=0.0), self.acceleration.max(initial=0.0),
                         self.jerk.max(initial=0.0), self.path_acceleration, self.path_jerk,
                         self.path_speed))


@dataclass
class PathTiming:
    """The planned motion ``s(t)`` along a path: exact pieces of constant path jerk.

    Attributes
    ----------
    path : JointPath
    limits : list of AxisLimits
    duration : float
        [s].
    t : ndarray, shape (k + 1,)
        Piece boundaries [s].
    state : ndarray, shape (k + 1, 3)
        ``s``, ``sdot``, ``sddot`` at every boundary (exact integration).
    jerk : ndarray, shape (k,)
        Path jerk of every piece [path unit / s^3].
    grid : ndarray, shape (n,)
        The grid of ``s`` the timing was planned on.
    grid_speed : ndarray, shape (n,)
        Planned ``sdot`` at the grid nodes.
    speed_cap : ndarray, shape (n,)
        The largest ``sdot`` the velocity limits and the path's speed cap allow
        at each node (the jerk-free speed limit curve's velocity part).
    jerk_free_time : float
        Minimum time on the same grid without the jerk limits (a lower bound) [s].
    time_scale : float
        Uniform slow-down applied after the check (1 when none was needed).
    limit_use : LimitUse
        Largest use of every limit over the dense check.
    rounds : int
        Rounds of the grid problem (last solve).
    grid_derivatives : tuple of 4 ndarray, shape (n, m)
        ``q``, ``q'``, ``q''``, ``q'''`` at the grid nodes.
    info : dict
        Grid size, tightening rounds and ``"status"``: the grid problem's solver
        status, ``"path limits"`` (the minimum-time S-curve of ``s`` under the
        path's own limits, which keeps every joint's too: the optimum) or
        ``"fallback"`` (the S-curve within every limit on the whole path).
    """

    path: Any
    limits: list
    duration: float
    t: np.ndarray
    state: np.ndarray
    jerk: np.ndarray
    grid: np.ndarray
    grid_speed: np.ndarray
    speed_cap: np.ndarray
    jerk_free_time: float
    time_scale: float
    limit_use: LimitUse
    rounds: int
    grid_derivatives: tuple = ()
    info: dict = field(default_factory=dict)

    @property
    def length(self) -> float:
        return float(self.path.length)

    def sample(self, time: Any) -> np.ndarray:
        """Path state at ``time`` [s]: array (4, n) of ``s``, ``sdot``, ``sddot``, ``sdddot``.

        Before 0 the start state holds (position only, moving states are
        extrapolated by the first piece), after the end the end state.
        """
        tt = np.atleast_1d(np.asarray(time, dtype=np.float64))
        out = np.empty((4, tt.size))
        if self.jerk.size == 0:
            out[0] = self.state[0, 0]
            out[1:] = 0.0
            return out
        tc = np.clip(tt, 0.0, self.duration)
        st = self.state[:-1]
        out[0], out[1], out[2], out[3] = eval_pieces(tc, self.t, st[:, 0], st[:, 1], st[:, 2],
                                                     self.jerk)
        end = tt >= self.duration
        out[0] = np.clip(out[0], 0.0, self.length)
        out[0, end] = self.state[-1, 0]
        out[1, end] = self.state[-1, 1]
        out[2, end] = self.state[-1, 2]
        out[3, end] = 0.0
        return out

    def grid_interpolated(self, s: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """First, second and third joint-path derivatives at ``s`` (n,), interpolated from
        the grid nodes (each (n, m)): cubic Hermite for the first two (the next
        derivative as the slope), linear for the third. The engine's limit check uses
        the same interpolation."""
        ss = np.clip(np.atleast_1d(np.asarray(s, dtype=np.float64)), self.grid[0], self.grid[-1])
        return _interp_derivatives(self.grid, self.grid_derivatives, ss)

    def joint_states(self, time: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Joint position, velocity, acceleration and jerk at ``time`` (each (n, m)), from
        the path's derivatives at ``s(t)`` and the chain rule.

        A time inside a piece that ends at one of the path's breakpoints takes the
        derivatives from before the breakpoint, where ``s(t)`` rounds onto it (or
        past it): the path's higher derivatives may step there, and the piece's
        own path jerk belongs to the side before it."""
        s, v, a, j = self.sample(time)
        bp = np.asarray(getattr(self.path, "breakpoints", np.zeros(0)), dtype=float)
        if bp.size and self.jerk.size:
            tt = np.atleast_1d(np.asarray(time, dtype=np.float64))
            k = np.searchsorted(self.t[1:-1], tt, side="right")  # (the piece of every time)
            end = self.state[k + 1, 0]
            before = np.isin(end, bp) & (tt < self.t[k + 1]) & (s >= end)
            s = np.where(before, np.nextafter(end, -np.inf), s)
        q, d1, d2, d3 = self.path.derivatives(s)
        qd = d1 * v[:, None]
        qdd = d2 * (v * v)[:, None] + d1 * a[:, None]
        qddd = d3 * (v ** 3)[:, None] + 3.0 * d2 * (v * a)[:, None] + d1 * j[:, None]
        return q, qd, qdd, qddd

    def __repr__(self) -> str:
        return (f"PathTiming(length={self.length!r}, duration={self.duration!r}, "
                f"pieces={self.jerk.size}, jerk_free_time={self.jerk_free_time!r})")


# --------------------------------------------------------------------------- input
def _limit_arrays(limits: Sequence[AxisLimits], m: int):
    if len(limits) != m:
        raise InvalidInputError(f"limits has {len(limits)} entries but the path has {m} joints")
    lims = []
    for k, lm in enumerate(limits):
        if not isinstance(lm, AxisLimits):
            raise InvalidInputError(f"limits[{k}] must be an AxisLimits, got {type(lm).__name__}")
        check_limits_range(lm, states=True)
        lims.append(lm)
    v = np.array([lm.v_max for lm in lims])
    aa = np.array([lm.a_max for lm in lims])
    ad = np.array([lm.a_max_decel for lm in lims])
    ja = np.array([lm.j_max for lm in lims])
    jd = np.array([lm.j_max_decel for lm in lims])
    for name, arr in (("a_max", aa), ("a_max_decel", ad), ("j_max", ja), ("j_max_decel", jd)):
        bad = ~np.isfinite(arr)
        if bad.any():
            k = int(np.argmax(bad))
            raise InvalidInputError(f"path timing needs finite {name} on every joint; "
                                    f"axis {lims[k].name if lims[k].name is not None else k} has inf")
    return lims, v, aa, ad, ja, jd


def _speed_cap(speed: Any, s: np.ndarray) -> np.ndarray:
    if callable(speed):
        cap = np.asarray(speed(s), dtype=float)
        if cap.shape != s.shape or np.any(~(cap > 0)):
            raise InvalidInputError("speed(s) must return positive caps of the shape of s")
        return cap
    return np.full(s.shape, check_positive(speed, "speed", allow_inf=True))


# --------------------------------------------------------------------------- grid
def _twins(L: float, breaks: np.ndarray) -> np.ndarray:
    """The twin node of every breakpoint: :data:`BREAK_TWIN` of a starting cell
    before it, and inside the piece that ends there (at most a quarter of it)."""
    h = L / GRID_START
    prev = np.concatenate([[0.0], breaks[:-1]])
    return breaks - np.minimum(BREAK_TWIN * h, 0.25 * (breaks - prev))


def _initial_grid(L: float, breaks: np.ndarray) -> np.ndarray:
    base = np.linspace(0.0, L, GRID_START + 1)
    h = L / GRID_START
    ends = h * np.geomspace(END_FIRST, 0.5, END_NODES)
    # a breakpoint gets a twin just before it: the joint path's third derivative
    # may step there, and the twin carries the incoming piece's values
    twins = _twins(L, breaks)
    pts = np.concatenate([base, ends, L - ends, breaks, twins])
    pts = np.unique(np.clip(pts, 0.0, L))
    # nodes of the regular grid too close to a breakpoint or its twin are dropped
    special = np.unique(np.concatenate([breaks, twins]))
    if not special.size:
        return pts
    at = np.searchsorted(special, pts)
    gap = np.minimum(np.abs(pts - special[np.maximum(at - 1, 0)]),
                     np.abs(pts - special[np.minimum(at, special.size - 1)]))
    # (the path's ends are nodes whatever lies near them)
    near = (gap < 0.25 * h) & ~np.isin(pts, special) & (pts > 0.0) & (pts < L)
    return pts[~near]


def _mid_caps(s: np.ndarray, cap_fn, speed) -> np.ndarray:
    """Squared speed cap at the middle of every grid interval (inf when the cap is a number)."""
    if not callable(speed):
        return np.full(s.size - 1, np.inf)
    return cap_fn(0.5 * (s[:-1] + s[1:])) ** 2


def _cap_edges(cap_fn, L: float) -> np.ndarray:
    """Parameter values on both sides of every place where the speed cap changes by more
    than CAP_STEP between neighbours of a CAP_GRID-point sampling (a dip of the cap then
    always has nodes inside it)."""
    g = np.linspace(0.0, L, CAP_GRID)
    c = cap_fn(g)
    fin = np.isfinite(c)
    a, b = c[:-1], c[1:]
    with np.errstate(invalid="ignore", divide="ignore"):
        jump = (fin[:-1] != fin[1:]) | (fin[:-1] & fin[1:] & (np.abs(b - a) > CAP_STEP * np.minimum(a, b)))
    k = np.nonzero(jump)[0]
    return np.unique(np.concatenate([g[k], g[k + 1]]))


def _add_nodes(s: np.ndarray, pts: np.ndarray, gap: float) -> np.ndarray:
    """The grid ``s`` (increasing) with the points ``pts`` added, except those within
    ``gap`` of one of its nodes or of a point added before them: two nodes a few
    ulps apart (the same parameter value reached by two roundings) would make an
    interval whose duration is round-off, and its pieces' jerk the solver's error
    over that duration squared."""
    pts = np.unique(pts)
    if not pts.size:
        return s
    at = np.searchsorted(s, pts)
    left = s[np.maximum(at - 1, 0)]
    right = s[np.minimum(at, s.size - 1)]
    pts = pts[(np.abs(pts - left) > gap) & (np.abs(right - pts) > gap)]
    if pts.size > 1:
        pts = pts[np.concatenate([[True], np.diff(pts) > gap])]
    return np.unique(np.concatenate([s, pts]))


def _finite_derivatives(der: tuple) -> None:
    """Raise where the joint path's derivatives on the grid are not finite."""
    if not all(np.isfinite(d).all() for d in der[1:]):
        raise InfeasibleError("the joint path has no finite derivative somewhere (a singularity)")


def _hermite_interp(s0, s1, f0, f1, g0, g1, sm):
    """Cubic Hermite value at ``sm`` from values f and slopes g at s0, s1 (broadcast over joints)."""
    h = (s1 - s0)[:, None]
    t = ((sm - s0) / (s1 - s0))[:, None]
    h00 = 2 * t**3 - 3 * t**2 + 1
    h10 = t**3 - 2 * t**2 + t
    h01 = -2 * t**3 + 3 * t**2
    h11 = t**3 - t**2
    return h00 * f0 + h10 * h * g0 + h01 * f1 + h11 * h * g1


class _ShortEnds:
    """The path with its pieces within ``short`` of its start and ``short_end``
    of its end (those that end before ``short``, begin after ``length -
    short_end``) replaced by the cubic extension of the piece next to them: its
    position and first three derivatives at the first breakpoint kept (from
    after it) and just before the last one kept. ``breaks``: the path's
    breakpoints inside it (sorted); :attr:`breakpoints` are those kept.

    For pieces shorter than :data:`END_PIECE` of the path's length only
    (:data:`END_PIECE_REST` at an end in rest): there the second derivative
    differs from the original's by the jump of the third times the piece's
    length, and the third by that jump, which the joints' jerk sees times the
    path speed cubed (next to a rest end close to zero)."""

    def __init__(self, path: JointPath, breaks: np.ndarray, short: float, short_end: float) -> None:
        self.path = path
        self.length = L = float(path.length)
        self.n_joints = path.n_joints
        self.cheap_derivatives = bool(getattr(path, "cheap_derivatives", False))
        head, tail = breaks[breaks < short], breaks[breaks > L - short_end]
        # (where, which side is replaced, the Taylor coefficients of the piece next to it)
        self.ends: list[tuple[float, int, tuple]] = []
        if head.size:
            lo = float(head[-1])
            self.ends.append((lo, -1, tuple(d[0] for d in path.derivatives(np.array([lo])))))
        if tail.size:
            hi = float(tail[0])
            below = np.nextafter(hi, -np.inf)
            self.ends.append((hi, 1, tuple(d[0] for d in path.derivatives(np.array([below])))))
        self.breakpoints = breaks[(breaks >= short) & (breaks <= L - short_end)]

    def derivatives(self, s: np.ndarray):
        s = np.atleast_1d(np.asarray(s, dtype=float))
        q, d1, d2, d3 = (np.array(v, dtype=float) for v in self.path.derivatives(s))
        for at, side, (q0, a1, a2, a3) in self.ends:
            out = s < at if side < 0 else s >= at
            if out.any():
                h = (s[out] - at)[:, None]
                q[out] = q0 + h * (a1 + h * (0.5 * a2 + h * a3 / 6.0))
                d1[out] = a1 + h * (a2 + 0.5 * h * a3)
                d2[out] = a2 + h * a3
                d3[out] = a3
        return q, d1, d2, d3


class _Cached:
    """The path's derivatives, each parameter value evaluated once: the grid nodes and
    the cells' middles recur from the refinement to the splits and the final check
    (a value comes out the same whichever batch it is evaluated in)."""

    def __init__(self, path: JointPath) -> None:
        self.path = path
        self.length = path.length
        self.n_joints = path.n_joints
        self.breakpoints = getattr(path, "breakpoints", np.zeros(0))
        self.s = np.zeros(0)
        self.values: tuple = ()

    def derivatives(self, S: np.ndarray) -> tuple:
        S = np.atleast_1d(np.asarray(S, dtype=np.float64))
        if self.s.size:
            at = np.minimum(np.searchsorted(self.s, S), self.s.size - 1)
            hit = self.s[at] == S
        else:
            at = np.zeros(S.size, dtype=int)
            hit = np.zeros(S.size, dtype=bool)
        if hit.all():
            return tuple(v[at] for v in self.values)
        miss = np.unique(S[~hit])
        new = self.path.derivatives(miss)
        if self.s.size:
            s_all = np.concatenate([self.s, miss])
            order = np.argsort(s_all, kind="stable")
            self.s = s_all[order]
            self.values = tuple(np.concatenate([v, w])[order] for v, w in zip(self.values, new))
        else:
            self.s = miss
            self.values = tuple(np.asarray(w) for w in new)
        at = np.searchsorted(self.s, S)
        return tuple(v[at] for v in self.values)

    def zero_slope(self, S: np.ndarray, joint: np.ndarray) -> None:
        """``dq/ds`` of ``joint`` (k,) set to exactly zero at ``S`` (k,), where that
        joint reverses: every later lookup of these grid nodes gets a node at rest
        for that joint (both legs' tighter limits there, see ``_socp._legs``)."""
        self.derivatives(S)
        self.values[1][np.searchsorted(self.s, S), joint] = 0.0


#: A joint reversal is found by REVERSAL_STEPS bisections on the interpolated
#: ``dq/ds``, then REVERSAL_NEWTON Newton steps on the true one.
REVERSAL_STEPS = 60
REVERSAL_NEWTON = 3

#: A joint reversal within this fraction of the path's length of a grid node is
#: put on that node (no interval of round-off length, see ``_add_nodes``).
REVERSAL_GAP = 1e-9


def _reversal_points(s_grid: np.ndarray, d1: np.ndarray, d2: np.ndarray, legs: np.ndarray,
                     slope: Callable[[np.ndarray], tuple]) -> tuple:
    """Where the joints ``legs`` (m,) reverse between the grid's nodes: ``dq/ds``
    changes sign in a cell. Found by bisection on the cubic Hermite interpolation
    of ``dq/ds`` (``d1``, ``d2`` (n, m) at the nodes), then by Newton steps on
    ``slope(S)``: ``(dq/ds, d2q/ds2)`` (n', m) at ``S`` (n',).

    A node where ``dq/ds`` is exactly zero between nodes of opposite signs is
    a reversal too.

    Returns the cells (k,) (the node for those), the joints (k,) and the
    reversals' ``s`` (k,).
    """
    cell, joint = np.nonzero((d1[:-1] * d1[1:] < 0.0) & legs[None, :])
    # (a node at a reversal, dq/ds exactly zero there: that node)
    node, on = np.nonzero((d1[1:-1] == 0.0) & (d1[:-2] * d1[2:] < 0.0) & legs[None, :])
    if not cell.size:
        return node + 1, on, s_grid[node + 1]
    rows = np.arange(cell.size)
    s0, s1 = s_grid[cell], s_grid[cell + 1]
    f0 = d1[cell, joint]
    lo, hi = s0.copy(), s1.copy()
    for _ in range(REVERSAL_STEPS):
        mid = 0.5 * (lo + hi)
        fm = _hermite_interp(s0, s1, f0[:, None], d1[cell + 1, joint][:, None],
                             d2[cell, joint][:, None], d2[cell + 1, joint][:, None], mid)[:, 0]
        same = np.sign(fm) == np.sign(f0)
        lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
    S = 0.5 * (lo + hi)
    for _ in range(REVERSAL_NEWTON):
        f1, f2 = (f[rows, joint] for f in slope(S))
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.where(f2 != 0.0, f1 / f2, 0.0)
        S = np.clip(S - step, s0, s1)
    return (np.concatenate([cell, node + 1]), np.concatenate([joint, on]),
            np.concatenate([S, s_grid[node + 1]]))


def _reversal_nodes(cached: _Cached, s: np.ndarray, der: tuple, cell_err: np.ndarray,
                    legs: np.ndarray) -> tuple:
    """The grid with a node where a joint with separate acceleration legs
    (``legs`` (m,)) reverses, its ``dq/ds`` exactly zero there
    (:meth:`_Cached.zero_slope`).

    Its leg changes there: between two nodes on either side the rows, which
    take every node's leg, do not see the change, and the timing ran the
    braking leg's acceleration up to the other's before the reversal (up to
    2.8 times its limit over whole cells, which no split of the cells
    resolved: a uniform slow-down of 3 % was left). At the node both legs'
    tighter limits hold, and on each side one leg (the grid problem bounds
    the joint's acceleration in the middle of both neighbouring cells too,
    see ``_socp._reversal_rows``). A reversal within
    REVERSAL_GAP of the path's length of a node is put on that node. The end
    cells are left alone (the rest intervals' one jerk phase; a joint that
    barely moves there "reverses" within 1e-7 of the path's length of its
    end, and a node there made that phase round-off). Returns the grid, its
    derivatives and every cell's error of the refinement (a new cell's: its
    parent's)."""
    cell, joint, S = _reversal_points(s, der[1], der[2], legs, lambda S: cached.derivatives(S)[1:3])
    inner = (cell > 0) & (cell < s.size - 2)
    joint, S = joint[inner], S[inner]
    if not S.size:
        return s, der, cell_err
    s_new = _add_nodes(s, S, REVERSAL_GAP * float(s[-1] - s[0]))
    near = np.clip(np.searchsorted(s_new, S), 1, s_new.size - 1)
    near = np.where(np.abs(s_new[near - 1] - S) < np.abs(s_new[near] - S), near - 1, near)
    cached.zero_slope(s_new[near], joint)
    parent = np.searchsorted(s, s_new[:-1], side="right") - 1
    return s_new, cached.derivatives(s_new), cell_err[parent]


def _refine(path: JointPath, s: np.ndarray, der, vlim, alim, jlim, cap_fn,
            breaks: np.ndarray | None = None, rtol: float = GRID_RTOL,
            todo: np.ndarray | None = None, left: tuple | None = None) -> tuple:
    """Split the grid's cells until the derivatives interpolated at every cell's
    middle are within ``rtol`` of the limits they feed (see GRID_RTOL).

    ``todo`` (cells,): the cells to check (default: all); the others count as
    within the tolerance (the sub-cells of cells checked before).

    ``left``: ``q'``, ``q''``, ``q'''`` (k, m) just before the breakpoints
    ``breaks`` (k,). A cell ending at a breakpoint interpolates towards them, the
    values of its own piece, as the checks do (:class:`_Interp`). (Towards the
    node's values, those after the breakpoint where ``q'''`` may step, the error
    does not shrink with the cell: such a cell was halved pass after pass down to
    round-off length, 6e-14 of a path of 0.34 m, over which two node states
    cannot be joined.)

    Returns the grid, its derivatives, the ranges ``(k, 2)`` of ``s`` where the
    passes or the node budget ran out before that (no cell is known to be
    resolved there), and every cell's error at its middle (the largest of the
    three, as a fraction of the limits; 0 for a cell not to check, NaN for one
    split last and not checked since).
    """
    breaks = np.zeros(0) if breaks is None else breaks
    twins = _twins(float(path.length), breaks)
    todo = np.ones(s.size - 1, dtype=bool) if todo is None else todo.copy()
    # the cells to check and not checked yet (then: those split last)
    pending = np.column_stack([s[:-1][todo], s[1:][todo]])
    err = np.where(todo, np.nan, 0.0)
    for _ in range(GRID_PASSES):
        if s.size >= GRID_MAX or not todo.any():
            break
        q, d1, d2, d3 = der
        c = np.nonzero(todo)[0]
        sm = 0.5 * (s[c] + s[c + 1])
        qm, m1, m2, m3 = path.derivatives(sm)
        r1, r2, r3 = d1[c + 1], d2[c + 1], d3[c + 1]
        if left is not None and breaks.size:
            at = np.minimum(np.searchsorted(breaks, s[c + 1]), breaks.size - 1)
            on = (s[c + 1] == breaks[at])[:, None]
            r1, r2, r3 = (np.where(on, lv[at], r) for lv, r in zip(left, (r1, r2, r3)))
        i1 = _hermite_interp(s[c], s[c + 1], d1[c], r1, d2[c], r2, sm)
        i2 = _hermite_interp(s[c], s[c + 1], d2[c], r2, d3[c], r3, sm)
        i3 = 0.5 * (d3[c] + r3)
        # the speed the cell could run at: the velocity limits, the path's cap, and
        # the speeds at which the curvature of the joint path alone uses the joints'
        # acceleration and jerk limits (a timing can run somewhat faster than
        # cbrt(j_max / |d3q/ds3|) where the path's acceleration and jerk cancel part
        # of d3q/ds3 v^3; the final check evaluates the true derivatives wherever
        # the interpolation's error could matter)
        with np.errstate(divide="ignore", invalid="ignore"):
            vcap = np.min(np.where(np.abs(m1) > 0, vlim / np.abs(m1), np.inf), axis=1)
            vcap = np.minimum(vcap, np.min(np.where(np.abs(m2) > 0, np.sqrt(alim / np.abs(m2)),
                                                    np.inf), axis=1))
            vcap = np.minimum(vcap, np.min(np.where(np.abs(m3) > 0, np.cbrt(jlim / np.abs(m3)),
                                                    np.inf), axis=1))
        vcap = np.minimum(vcap, cap_fn(sm))
        vcap = np.where(np.isfinite(vcap), vcap, 0.0)
        e1 = np.max(np.abs(i1 - m1) * vcap[:, None] / vlim, axis=1)
        e2 = np.max(np.abs(i2 - m2) * (vcap**2)[:, None] / alim, axis=1)
        e3 = np.max(np.abs(i3 - m3) * (vcap**3)[:, None] / jlim, axis=1)
        ec = np.maximum(np.maximum(e1, e2), e3)
        err[c] = ec
        split = np.zeros(s.size - 1, dtype=bool)
        split[c] = ec > rtol
        # the twin interval before a breakpoint stays whole (it interpolates towards
        # the values after the breakpoint; the checks take those from before it)
        if breaks.size:
            at = np.minimum(np.searchsorted(breaks, s[1:]), breaks.size - 1)
            split &= ~((s[1:] == breaks[at]) & (s[:-1] == twins[at]))
        if not split.any():
            pending = np.zeros((0, 2))
            break
        room = GRID_MAX - s.size
        idx = np.nonzero(split)[0]
        pending = np.column_stack([s[idx], s[idx + 1]])
        if idx.size > room:
            idx = idx[np.argsort(-err[idx])[:room]]
        # the new nodes are the middles of the cells split (all of them checked in
        # this pass), with the derivatives just evaluated there
        pos = np.searchsorted(c, idx)
        merged = np.concatenate([s, sm[pos]])
        order = np.argsort(merged, kind="stable")
        new = merged[order]
        der = tuple(np.concatenate([a, b[pos]])[order] for a, b in zip(der, (qm, m1, m2, m3)))
        # a split cell's halves are checked next, the others are done
        cell_old = np.concatenate([np.arange(s.size), idx])[order][:-1]
        halves = np.zeros(s.size - 1, dtype=bool)
        halves[idx] = True
        todo = halves[cell_old]
        err = np.where(todo, np.nan, err[cell_old])
        s = new
    return s, der, pending, err


# --------------------------------------------------------------------------- check
def _node_states(s: np.ndarray, x: np.ndarray, u: np.ndarray, dur: np.ndarray, jerk: np.ndarray,
                 interval: np.ndarray, k: float = 1.0):
    """Piece boundaries and start states: every interval's first piece starts exactly at
    its node state (no round-off carried along the path), the second from the first.

    ``k`` is the uniform time scale (durations already multiplied by it).
    """
    n_p = dur.size
    t = np.concatenate([[0.0], np.cumsum(dur)])
    st = np.zeros((n_p + 1, 3))
    v = np.sqrt(np.maximum(x, 0.0)) / k
    a = u / (k * k)
    first = np.ones(n_p, dtype=bool)
    first[1:] = interval[1:] != interval[:-1]
    st[:-1][first] = np.column_stack([s[interval[first]], v[interval[first]], a[interval[first]]])
    # the later pieces of an interval from the piece before, all at once (an interval
    # has two pieces at most, so this is one pass)
    done = first.copy()
    todo = np.nonzero(~first)[0]
    while todo.size:
        i = todo[done[todo - 1]]
        p0, v0, a0 = st[i - 1, 0], st[i - 1, 1], st[i - 1, 2]
        h = dur[i - 1]
        jk = jerk[i - 1]
        st[i, 0] = p0 + h * (v0 + h * (0.5 * a0 + h * jk / 6.0))
        st[i, 1] = v0 + h * (a0 + 0.5 * h * jk)
        st[i, 2] = a0 + h * jk
        done[i] = True
        todo = todo[~done[todo]]
    st[-1] = (s[-1], v[-1], a[-1])
    return t, st


def _pieces_state(dur: np.ndarray, jerk: np.ndarray, s0: float, v0: float, a0: float):
    k = dur.size
    t = np.zeros(k + 1)
    st = np.zeros((k + 1, 3))
    st[0] = (s0, v0, a0)
    for i in range(k):
        p, v, a = st[i]
        h = dur[i]
        jk = jerk[i]
        st[i + 1] = (p + h * (v + h * (0.5 * a + h * jk / 6.0)), v + h * (a + 0.5 * h * jk), a + h * jk)
        t[i + 1] = t[i] + h
    return t, st


def _solution_splits(s: np.ndarray, x: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Midpoints of the intervals where the path acceleration swings by more than
    :data:`SWING_SPLIT` of its range: the jerk phases get enough nodes to be rounded."""
    span = float(np.ptp(u))
    if span <= 0.0:
        return np.zeros(0)
    du = np.abs(np.diff(u)) / span
    out = []
    for parts in (2, 3, 4):
        sel = (du > SWING_SPLIT * (parts - 1)) & (du <= SWING_SPLIT * parts) if parts < 4 \
            else du > SWING_SPLIT * (parts - 1)
        k = np.nonzero(sel)[0]
        for f in range(1, parts):
            out.append(s[k] + (s[k + 1] - s[k]) * f / parts)
    pts = np.concatenate(out) if out else np.zeros(0)
    room = GRID_MAX - s.size
    return pts[:max(room, 0)]


def _rest_splits(s: np.ndarray, x: np.ndarray, u: np.ndarray, d1: np.ndarray, d2: np.ndarray,
                 legs: tuple, a_path: float, j_path: float, rest0: bool,
                 restN: bool) -> np.ndarray:
    """Nodes inside the rest intervals whose jerk is below REST_SPLIT_BELOW of its
    limit while they end at an acceleration limit (REST_SPLIT_ACCEL of it).

    A rest interval's motion is one jerk phase from rest (``s = J t^3 / 6``), so it
    reaches the acceleration ``u`` of its inner node at the end of the interval,
    whatever that interval's length ``D``: ``J = sqrt(u^3 / (6 D))``. When the
    grid's first node lies beyond the end of the fastest ramp to that
    acceleration (long motions with short jerk phases), ``J`` stays well below
    the limit ``J_max`` (the joints' jerk of the leg over ``|q'|``, the path's
    jerk) and the ramp takes longer than it needs to. Where ``u`` is at an
    acceleration limit (a joint's, of the leg, or the path's), the ramp at
    ``J_max`` to it ends at ``D (J / J_max)^2`` from the rest: a node there
    (REST_SPLIT_MIN of ``D`` at least) and at the middle of the rest of the
    interval let the next solve ramp at the limit. (Where the inner node's
    acceleration is below its limits, as after a ramp to a low velocity limit,
    the fastest ramp does not end there.)

    Parameters
    ----------
    s : ndarray, shape (N + 1,)
        The grid [path unit].
    x, u : ndarray, shape (N + 1,)
        The solution's ``sdot^2`` and ``sddot`` at the nodes.
    d1, d2 : ndarray, shape (N + 1, m)
        ``dq/ds``, ``d2q/ds2`` at the nodes.
    legs : tuple of 2 (a, j)
        The joints' acceleration and jerk limits, (m,) each, speeding up (from
        rest) and slowing down (to rest).
    a_path, j_path : float
        The path's acceleration and jerk limits (inf: none).
    rest0, restN : bool
        The motion starts, ends at rest.

    Returns
    -------
    ndarray
        The new nodes (none where the ramps already use their limit).
    """
    out = []
    N = s.size - 1
    for flag, rest, node, (al, jl) in ((rest0, 0, 1, legs[0]), (restN, N, N - 1, legs[1])):
        if not flag or N < 2:
            continue
        D = abs(float(s[node] - s[rest]))
        a = abs(float(u[node]))
        jmax = _rest_jerk(np.maximum(np.abs(d1[node]), np.abs(d1[rest])), jl, j_path)
        if not (D > 0.0 and a > 0.0 and math.isfinite(jmax)):
            continue
        ratio = math.sqrt(a**3 / (6.0 * D)) / jmax
        use = max(float(np.max(np.abs(d2[node] * x[node] + d1[node] * u[node]) / al)), a / a_path)
        if ratio >= REST_SPLIT_BELOW or use < REST_SPLIT_ACCEL:
            continue
        d = D * max(ratio * ratio, REST_SPLIT_MIN)
        for off in (d, 0.5 * (d + D)):
            out.append(s[rest] + off if rest == 0 else s[rest] - off)
    return np.asarray(out, dtype=float)


def _cell_interp(s0, s1, S, a0, a1, b0, b1, c0, c1):
    """The first three joint-path derivatives at ``S`` (n,) in the cells ``[s0, s1]``
    from their values at the cells' ends (each (n, m)): ``a`` the first, ``b`` the
    second, ``c`` the third. The first two by cubic Hermite interpolation (the next
    derivative as the slope, :func:`_hermite_interp` with the basis shared), the
    third linearly."""
    h = (s1 - s0)[:, None]
    t = ((S - s0) / (s1 - s0))[:, None]
    t2 = t**2
    t3 = t**3
    h00 = 2 * t3 - 3 * t2 + 1
    k10 = (t3 - 2 * t2 + t) * h
    h01 = -2 * t3 + 3 * t2
    k11 = (t3 - t2) * h
    f1 = h00 * a0 + k10 * b0 + h01 * a1 + k11 * b1
    f2 = h00 * b0 + k10 * c0 + h01 * b1 + k11 * c1
    f3 = (1 - t) * c0 + t * c1
    return f1, f2, f3


def _interp_derivatives(s_grid: np.ndarray, der: tuple, S: np.ndarray):
    """First three joint-path derivatives at ``S`` from the grid (see PathTiming.grid_interpolated)."""
    cell = np.clip(np.searchsorted(s_grid, S, side="right") - 1, 0, s_grid.size - 2)
    _, d1, d2, d3 = der
    nxt = cell + 1
    return _cell_interp(s_grid[cell], s_grid[nxt], S, d1[cell], d1[nxt], d2[cell], d2[nxt],
                        d3[cell], d3[nxt])


class _Interp:
    """Joint-path derivatives between the grid nodes for the checks of a path without
    cheap derivatives: ``_interp_derivatives``, except that a cell ending at a
    breakpoint of the path interpolates towards the derivatives there from below
    (``left``: ``q'``, ``q''``, ``q'''`` (k, m) at the breakpoints ``breaks`` (k,),
    evaluated just before them), the values of the piece the cell belongs to; the
    node itself carries those from above (``q'''`` may step there)."""

    def __init__(self, s_grid: np.ndarray, der: tuple, breaks: np.ndarray, left: tuple | None) -> None:
        self.s = s_grid
        self.der = der
        self.right = [d[1:] for d in der[1:]]
        if left is not None and breaks.size:
            node = np.searchsorted(s_grid, breaks)
            ok = (node > 0) & (node < s_grid.size)
            ok[ok] &= s_grid[node[ok]] == breaks[ok]
            if ok.any():
                self.right = [r.copy() for r in self.right]
                for r, lv in zip(self.right, left):
                    r[node[ok] - 1] = lv[ok]

    def _base(self, S: np.ndarray):
        s = self.s
        cell = np.clip(np.searchsorted(s, S, side="right") - 1, 0, s.size - 2)
        _, d1, d2, d3 = self.der
        r1, r2, r3 = self.right
        f1, f2, f3 = _cell_interp(s[cell], s[cell + 1], S, d1[cell], r1[cell], d2[cell], r2[cell],
                                  d3[cell], r3[cell])
        return cell, [f1, f2, f3]

    def derivatives(self, S: np.ndarray):
        _, f = self._base(np.atleast_1d(np.asarray(S, dtype=np.float64)))
        return None, f[0], f[1], f[2]


class _Corrected(_Interp):
    """Joint-path derivatives for the final check of a path without cheap derivatives:
    the grid interpolation (:class:`_Interp`), plus, in the cells where the true
    derivatives were evaluated (``add``), the polynomial in the cell's fraction ``w``
    that is 0 at both nodes (where the interpolation is exact) and equals the
    interpolation's error at :data:`VERIFY_POINTS` (a quartic for three points).
    At those points the check sees the true derivatives; between them the
    interpolation error left is of fifth order in the cell's length instead of
    second (linear ``q'''``). In the ranges ``exact`` ((k, 2) of ``s``: where the
    grid's refinement did not reach its tolerance) every point gets the true
    derivatives."""

    def __init__(self, path: JointPath, s_grid: np.ndarray, der: tuple, breaks: np.ndarray,
                 left: tuple | None, exact: np.ndarray | None = None) -> None:
        super().__init__(s_grid, der, breaks, left)
        self.path = path
        self.exact = np.zeros((0, 2)) if exact is None else np.asarray(exact, dtype=float)
        m = der[1].shape[1]
        self.err = np.zeros((s_grid.size - 1, len(VERIFY_POINTS), 3, m))
        self.done = np.zeros(s_grid.size - 1, dtype=bool)
        self.full = np.zeros(s_grid.size - 1, dtype=bool)
        self.evaluated = 0

    def add(self, cells: np.ndarray, full: bool = False) -> np.ndarray:
        """Evaluate the true derivatives in ``cells``: at the middle (those not done
        yet; the error at the other points of :data:`VERIFY_POINTS` set from the
        parabola through it, so that the correction is that parabola), or with
        ``full`` at every point (those not full yet). Returns the cells whose
        derivatives changed (sorted)."""
        none = np.zeros(0, dtype=int)
        return self.add_both(none, cells) if full else self.add_both(cells, none)

    def add_both(self, middle: np.ndarray, full: np.ndarray) -> np.ndarray:
        """:meth:`add` of the cells ``middle`` and, with ``full``, of the cells
        ``full`` (those take every point, not their middle first), with one
        evaluation of the path's derivatives. Returns the cells whose derivatives
        changed (sorted)."""
        full = np.unique(full)
        full = full[~self.full[full]]
        middle = np.setdiff1d(middle, full)
        middle = middle[~self.done[middle]]
        vp = np.asarray(VERIFY_POINTS)
        parts = [(middle, np.array([0.5])), (full, vp)]
        S = np.concatenate([(self.s[c][:, None] * (1.0 - w[None, :])
                             + self.s[c + 1][:, None] * w[None, :]).ravel() for c, w in parts])
        if not S.size:
            return np.union1d(middle, full)
        _, t1, t2, t3 = self.path.derivatives(S)
        _, (i1, i2, i3) = self._base(S)
        at = 0
        for (cells, w), is_full in zip(parts, (False, True)):
            k, npt = cells.size, w.size
            if not k:
                continue
            part = slice(at, at + k * npt)
            at += k * npt
            for order, (tv, iv) in enumerate(((t1, i1), (t2, i2), (t3, i3))):
                e = (tv[part] - iv[part]).reshape(k, npt, -1)
                if is_full:
                    self.err[cells, :, order, :] = e
                else:  # the parabola 4 e w (1 - w) through the middle's error
                    self.err[cells, :, order, :] = (4.0 * vp * (1.0 - vp))[None, :, None] * e
            self.done[cells] = True
            if is_full:
                self.full[cells] = True
        self.evaluated += S.size
        return np.union1d(middle, full)

    def derivatives(self, S: np.ndarray):
        S = np.atleast_1d(np.asarray(S, dtype=np.float64))
        cell, f = self._base(S)
        sel = self.done[cell]
        if sel.any():
            c = cell[sel]
            w = (S[sel] - self.s[c]) / (self.s[c + 1] - self.s[c])
            xs = np.concatenate([[0.0], VERIFY_POINTS, [1.0]])
            basis = np.ones((w.size, xs.size - 2))  # Lagrange basis of the inner points
            for k in range(1, xs.size - 1):
                for j in range(xs.size):
                    if j != k:
                        basis[:, k - 1] *= (w - xs[j]) / (xs[k] - xs[j])
            corr = np.einsum("nk,nkom->onm", basis, self.err[c])
            for order in range(3):
                f[order][sel] += corr[order]
        if self.exact.size:
            # (the ranges are sorted and do not overlap)
            rng = np.searchsorted(self.exact[:, 0], S, side="right") - 1
            inside = (rng >= 0) & (S <= self.exact[np.maximum(rng, 0), 1])
            if inside.any():
                _, t1, t2, t3 = self.path.derivatives(S[inside])
                self.evaluated += int(inside.sum())
                for order, tv in enumerate((t1, t2, t3)):
                    f[order][inside] = tv
        return None, f[0], f[1], f[2]


def _sample_pieces(t: np.ndarray, st: np.ndarray, jerk: np.ndarray, tt: np.ndarray) -> np.ndarray:
    """``s``, ``sdot`` at times ``tt`` of the pieces (2, n)."""
    tc = np.clip(tt, 0.0, t[-1])
    p, v, _, _ = eval_pieces(tc, t, st[:-1, 0], st[:-1, 1], st[:-1, 2], jerk)
    return np.vstack([p, v])


#: A moving state's fallback may not reverse along the path: its speed stays above
#: -FALLBACK_REVERSE_RTOL of its largest (the round-off of a stop at the end).
FALLBACK_REVERSE_RTOL = 1e-12


def _fallback(s: np.ndarray, der: tuple, L: float, vlim, aacc, adec, jacc, jdec, cap,
              a_path: float, j_path: float, kappa,
              boundary: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)):
    """An always-feasible timing: one S-curve of the path parameter whose speed,
    acceleration and jerk are small enough for every joint everywhere on the grid
    (the largest path derivatives with the smallest limits); what the final check
    still finds is removed by a uniform slow-down. Far from optimal on a curved
    path (on a joint-space line: the optimum of the tighter legs); used only when
    the optimisation fails.

    ``boundary``: the path's ``(start_speed, start_accel, end_speed, end_accel)``;
    rest to rest by default. With a moving state it is the minimum-time
    state-to-state profile under those limits, or None where there is none that
    moves forward only and keeps them from the start (a start or an end state
    outside them, or one that would have to reverse along the path).

    Returns ``(durations, jerks)`` of the pieces, or None.
    """
    _, d1, d2, d3 = der
    a1 = np.abs(d1).max(axis=0)
    a2 = np.abs(d2).max(axis=0)
    a3 = np.abs(d3).max(axis=0)
    A = np.minimum(aacc, adec)
    J = np.minimum(jacc, jdec)
    with np.errstate(divide="ignore", invalid="ignore"):
        v = float(np.min(np.where(a1 > 0, vlim / a1, np.inf)))
        v = min(v, float(np.min(cap)), float(np.min(np.where(a2 > 0, np.sqrt(0.5 * A / a2), np.inf))),
                float(np.min(np.where(a3 > 0, np.cbrt(0.25 * J / a3), np.inf))))
        if kappa is not None and math.isfinite(a_path) and kappa.max() > 0:
            v = min(v, math.sqrt(0.5 * a_path / float(kappa.max())))
        a = float(np.min(np.where(a1 > 0, (A - a2 * v * v) / a1, np.inf)))
        a = min(a, 0.5 * a_path) if math.isfinite(a_path) else a
        j = float(np.min(np.where(a1 > 0, (J - a3 * v**3 - 3.0 * a2 * v * a) / a1, np.inf)))
        j = min(j, j_path)
    if not (math.isfinite(v) and v > 0):
        v = 1.0
    a = a if (math.isfinite(a) and a > 0) else v
    j = j if (math.isfinite(j) and j > 0) else a
    return _path_s_curve(L, AxisLimits(v, a, j, name="path"), boundary)


def _path_s_curve(L: float, lim: AxisLimits, boundary: tuple[float, float, float, float]):
    """The minimum-time S-curve of the path parameter over ``[0, L]`` under ``lim``
    from and to the ``boundary`` states ``(start_speed, start_accel, end_speed,
    end_accel)``: ``(durations, jerks)`` of its pieces, or None where there is none
    that moves forward only and keeps ``lim`` from the start."""
    v0, a0, v1, a1 = boundary
    if not any(boundary):
        rest = plan_move(0.0, L, lim)
        durations, jerks = rest.phase_durations, rest.jerks
    else:
        try:
            moving = plan_state_to_state((0.0, v0, a0), (L, v1, a1), lim)
        except (InfeasibleError, InvalidInputError):
            return None
        vmin, vmax = moving.extrema().velocity
        if moving.brake_duration > 0.0 or vmin < -FALLBACK_REVERSE_RTOL * vmax:
            return None
        durations, jerks = moving.phase_durations, moving.jerks
    keep = np.asarray(durations) > 0.0
    return np.asarray(durations)[keep], np.asarray(jerks)[keep]


def _path_limits_profile(L: float, cap: np.ndarray, a_path: float, j_path: float,
                         boundary: tuple[float, float, float, float]):
    """The minimum-time S-curve of the path parameter under the path's own limits
    alone (its largest speed cap ``cap`` (n,), the path acceleration ``a_path`` as
    a tangential limit, the path jerk ``j_path``) between the ``boundary`` states:
    a relaxation of the path's timing problem (it drops the joints' limits, the
    cap's variation and the curvature's share of the acceleration), so where it
    keeps every limit it is the minimum-time timing itself (tried before the
    grid problem; e.g. a final stop in which the path's jerk binds, where
    :func:`_fallback`'s limits, the smallest over the whole path, cannot start).
    ``(durations, jerks)`` or None (a limit not finite, or no such S-curve, see
    :func:`_path_s_curve`)."""
    v = float(np.max(cap))
    if not (math.isfinite(v) and v > 0.0 and math.isfinite(a_path) and math.isfinite(j_path)):
        return None
    try:
        return _path_s_curve(L, AxisLimits(v, a_path, j_path, name="path"), boundary)
    except InvalidInputError:  # (limits outside the one-axis planners' range)
        return None


def _regrid(s_old: np.ndarray, s_new: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Node values on a refined grid: kept at the old nodes, the smaller neighbour's
    at a new node (lowered limits stay lowered around where they were)."""
    idx = np.clip(np.searchsorted(s_old, s_new, side="right") - 1, 0, s_old.size - 1)
    nxt = np.minimum(idx + 1, s_old.size - 1)
    on_old = s_old[idx] == s_new
    out = np.minimum(values[idx], values[nxt])
    out[on_old] = values[idx[on_old]]
    return out


#: Points per piece at which the path's acceleration is evaluated where it is
#: lowered locally (a moving boundary state, see ``plan_path_timing``).
PATH_ACC_POINTS = 17


def _piece_path_accel(t: np.ndarray, st: np.ndarray, jerk: np.ndarray, s_grid: np.ndarray,
                      kappa: np.ndarray | None) -> np.ndarray:
    """The largest norm of the path's acceleration vector ``(sddot, kappa sdot^2)``
    in every piece (times ``t`` (k + 1,), start states ``st`` (k + 1, 3), jerks
    (k,)), at :data:`PATH_ACC_POINTS` points of each, the curvature ``kappa``
    (n,) interpolated linearly between the nodes of ``s_grid`` (n,) (None: the
    tangential acceleration alone). Returns (k,) [path unit / s^2]."""
    tau = np.diff(t)[:, None] * np.linspace(0.0, 1.0, PATH_ACC_POINTS)[None, :]
    p0, v0, a0 = (st[:-1, i:i + 1] for i in range(3))
    j = jerk[:, None]
    sdd = a0 + tau * j
    if kappa is None:
        return np.abs(sdd).max(axis=1)
    sd = v0 + tau * (a0 + 0.5 * tau * j)
    pos = p0 + tau * (v0 + tau * (0.5 * a0 + tau * j / 6.0))
    return np.hypot(sdd, np.interp(pos, s_grid, kappa) * sd * sd).max(axis=1)


def _uniform_scale(use: LimitUse) -> float:
    """Time factor k >= 1 that brings every checked ratio to at most 1 (v / k, a / k^2, j / k^3).

    1 when no ratio exceeds 1 + CHECK_RTOL (the test is on the ratios, not on k:
    an acceleration 1.5e-9 over its limit needs k = 1 + 0.75e-9 only)."""
    if use.worst <= 1.0 + CHECK_RTOL:
        return 1.0
    k = max(1.0, float(use.velocity.max(initial=0.0)), use.path_speed,
            math.sqrt(max(float(use.acceleration.max(initial=0.0)), use.path_acceleration)),
            max(float(use.jerk.max(initial=0.0)), use.path_jerk) ** (1.0 / 3.0))
    return k * (1.0 + 4.0 * CHECK_RTOL)


@dataclass
class _Limits:
    """What the checks compare with: the joints' and the path's limits."""

    vlim: np.ndarray
    alim_acc: np.ndarray
    alim_dec: np.ndarray
    jacc: np.ndarray
    jdec: np.ndarray
    a_path: float
    j_path: float
    kappa: np.ndarray | None
    cap: np.ndarray | None
    cap_fn: Callable[[np.ndarray], np.ndarray] | None
    #: the joints' velocity scale of the rest test (REST_RTOL): the limit, or where
    #: there is none, the largest speed the joint reaches (None: the limit)
    vrest: np.ndarray | None = None


def _rest_scale(vlim: np.ndarray, d1: np.ndarray, st: np.ndarray) -> np.ndarray:
    """The joints' velocity scale of the rest test: ``vlim``, and where it is
    infinite, the largest ``|q'|`` times the largest path speed of the states ``st``."""
    reach = np.max(np.abs(d1), axis=0) * float(np.max(st[:, 1], initial=0.0))
    return np.where(np.isfinite(vlim), vlim, np.where(reach > 0.0, reach, 1.0))


def _evaluate(s_grid, der, t, st, jerk, lim: _Limits, path, piece, dt, mid=None):
    """Limit ratios at the times ``t[piece] + dt`` of the pieces.

    A sample at the end of its piece (``dt`` = the piece's duration) that lands on
    a grid node uses the path's derivatives from below: the end belongs to that
    piece, and at a breakpoint of the path (a grid node) the third derivative may
    step (the value from above is the next piece's start). ``mid``: the product
    ``qd * qdd`` at the middle of every piece (the leg where a joint is at rest);
    computed here when not given.

    Returns ``(rv, ra, rj)`` (n, m), the speed-cap ratio (n,), the path
    acceleration norm (n,), the path jerk (n,), the grid cell (n,), ``s`` (n,)
    and ``qd * qdd`` (n, m).

    The numpy formulation: the checks use it when numba is not installed
    (:func:`_evaluate_compiled` otherwise).
    """
    p0, v0, a0, jk = st[piece, 0], st[piece, 1], st[piece, 2], jerk[piece]
    S = p0 + dt * (v0 + dt * (0.5 * a0 + dt * jk / 6.0))
    V = v0 + dt * (a0 + 0.5 * dt * jk)
    A = a0 + dt * jk
    S = np.clip(S, s_grid[0], s_grid[-1])
    S_eval = S.copy()
    end = dt >= np.diff(t)[piece]
    if end.any():
        c0 = np.clip(np.searchsorted(s_grid, p0[end], side="right") - 1, 0, s_grid.size - 2)
        S_eval[end] = np.maximum(np.minimum(S[end], np.nextafter(s_grid[c0 + 1], -np.inf)),
                                 s_grid[0])
    cell = np.clip(np.searchsorted(s_grid, S_eval, side="right") - 1, 0, s_grid.size - 2)
    if path is not None:  # a path whose derivatives are cheap: the exact ones
        _, f1, f2, f3 = path.derivatives(S_eval)
    else:
        f1, f2, f3 = _interp_derivatives(s_grid, der, S_eval)
    qd = f1 * V[:, None]
    qdd = f2 * (V * V)[:, None] + f1 * A[:, None]
    qddd = f3 * (V**3)[:, None] + 3.0 * f2 * (V * A)[:, None] + f1 * jk[:, None]
    # the leg: speeding up (accel limits) or slowing down (decel limits); at rest,
    # where the product vanishes, the leg of the piece's middle (at rest there too:
    # the path's, a jerk phase that ends at rest is the end of a braking, one that
    # starts there speeds up)
    prod = qd * qdd
    aqd = np.abs(qd)
    at_rest = aqd <= REST_RTOL * (lim.vlim if lim.vrest is None else lim.vrest)
    if at_rest.any():
        rest_row = at_rest.any(axis=1)
        if mid is None:  # (only the pieces with a joint at rest)
            uniq = np.unique(piece[rest_row])
            mid = np.zeros((jerk.size, qd.shape[1]))
            a_mid = st[:jerk.size, 2] + 0.5 * np.diff(t) * jerk  # (the path's leg at the middles)
            mid[uniq] = _evaluate(s_grid, der, t, st, jerk, lim, path, uniq, 0.5 * np.diff(t)[uniq],
                                  mid=np.repeat(np.where(a_mid >= 0.0, 1.0, -1.0)[:, None],
                                                qd.shape[1], axis=1))[-1]
        prod[rest_row] = np.where(at_rest[rest_row], mid[piece[rest_row]], prod[rest_row])
    speeding = prod > 0
    slowing = prod < 0
    alim = np.where(speeding, lim.alim_acc, np.where(slowing, lim.alim_dec,
                                                      np.minimum(lim.alim_acc, lim.alim_dec)))
    jl = np.where(speeding, lim.jacc, np.where(slowing, lim.jdec, np.minimum(lim.jacc, lim.jdec)))
    rv = aqd / lim.vlim
    ra = np.abs(qdd) / alim
    rj = np.abs(qddd) / jl
    w = (S_eval - s_grid[cell]) / (s_grid[cell + 1] - s_grid[cell])
    if lim.kappa is not None:
        kap = (1 - w) * lim.kappa[cell] + w * lim.kappa[cell + 1]
        acc_norm = np.hypot(A, kap * V * V)
    else:
        acc_norm = np.abs(A)
    if lim.cap is not None:
        # the cap between two nodes: the smaller of the two (a cap may step at a node),
        # and the cap function itself at the sample when it is a function
        cp = np.minimum(lim.cap[cell], lim.cap[cell + 1])
        if lim.cap_fn is not None:
            cp = np.minimum(cp, lim.cap_fn(S))
        with np.errstate(divide="ignore", invalid="ignore"):
            rs = np.where(np.isfinite(cp), V / cp, 0.0)
    else:
        rs = np.zeros(S.size)
    return rv, ra, rj, rs, acc_norm, jk, cell, S, prod


def _use_of(lim: _Limits, rv, ra, rj, rs, acc_norm, jk) -> LimitUse:
    a_use = float(acc_norm.max(initial=0.0) / lim.a_path) if math.isfinite(lim.a_path) else 0.0
    j_use = float(np.abs(jk).max(initial=0.0) / lim.j_path) if math.isfinite(lim.j_path) else 0.0
    return LimitUse(rv.max(axis=0, initial=0.0), ra.max(axis=0, initial=0.0),
                    rj.max(axis=0, initial=0.0), a_use, j_use, float(rs.max(initial=0.0)))


def _evaluate_compiled(s_grid, der, t, st, jerk, lim: _Limits, path, piece, dt):
    """The limit ratios of :func:`_evaluate` at the times ``t[piece] + dt`` of the pieces,
    in one pass of the kernel :func:`._checks.sample_ratios` (the same results to a
    few ulps), with their :class:`LimitUse`.

    The derivatives come from the grid (``path`` None, an :class:`_Interp` on
    ``s_grid`` or a :class:`_Corrected`) inside the kernel, or from
    ``path.derivatives`` (a path with cheap derivatives) at the samples.

    Returns the LimitUse and, per sample (n,), the grid cell, ``rv, ra, rj``
    (n, m), the speed-cap ratio and the largest of the sample's ratios.
    """
    m = lim.vlim.size
    k = jerk.size
    f64 = np.float64
    s_grid = np.ascontiguousarray(s_grid, dtype=f64)
    t = np.ascontiguousarray(t, dtype=f64)
    st = np.ascontiguousarray(st, dtype=f64)
    jerk = np.ascontiguousarray(jerk, dtype=f64)
    piece = np.ascontiguousarray(piece, dtype=np.int64)
    dt = np.ascontiguousarray(dt, dtype=f64)
    tol = REST_RTOL * (lim.vlim if lim.vrest is None else lim.vrest)
    empty = np.zeros(0)
    none2 = np.zeros((0, m))
    mid = np.zeros((k, m))
    have = np.zeros(k, dtype=bool)
    done = np.zeros(0, dtype=bool)
    err = np.zeros((0, len(VERIFY_POINTS), 3, m))
    xs = np.concatenate([[0.0], VERIFY_POINTS, [1.0]])
    # (a corrected grid with ranges of exact derivatives: its own derivatives at the samples)
    grid_source = path is None or (isinstance(path, _Interp) and path.s is s_grid
                                   and not (isinstance(path, _Corrected) and path.exact.size))
    S = S_eval = empty
    if not grid_source:
        S, S_eval, _, _, _ = _checks.sample_states(t, st, jerk, s_grid, piece, dt)
    elif lim.cap is not None and lim.cap_fn is not None:
        S = _checks.sample_positions(t, st, jerk, s_grid, piece, dt)
    if grid_source:
        d = der[1:] if path is None else path.der[1:]
        r = [x[1:] for x in d] if path is None else path.right
        d1, d2, d3, r1, r2, r3 = (np.ascontiguousarray(x, dtype=f64) for x in (*d, *r))
        F1 = F2 = F3 = none2
        if isinstance(path, _Corrected):
            done, err = path.done, np.ascontiguousarray(path.err, dtype=f64)
    else:  # the path's own derivatives at the samples (and the pieces' middles)
        d1 = d2 = d3 = r1 = r2 = r3 = none2
        F1, F2, F3 = (np.ascontiguousarray(x, dtype=f64) for x in path.derivatives(S_eval)[1:])
        rest = np.nonzero(_checks.rest_pieces(F1, t, st, jerk, s_grid, piece, dt, tol, k))[0]
        if rest.size:
            _, Sm, Vm, Am, _ = _checks.sample_states(t, st, jerk, s_grid, rest, 0.5 * np.diff(t)[rest])
            _, g1, g2, _ = path.derivatives(Sm)
            mid[rest] = _checks.mid_products(np.ascontiguousarray(g1, dtype=f64),
                                             np.ascontiguousarray(g2, dtype=f64), Vm, Am, tol)
            have[rest] = True
    kappa = empty if lim.kappa is None else np.ascontiguousarray(lim.kappa, dtype=f64)
    cap = empty if lim.cap is None else np.ascontiguousarray(lim.cap, dtype=f64)
    cap_s = empty if (lim.cap is None or lim.cap_fn is None) else \
        np.ascontiguousarray(lim.cap_fn(S), dtype=f64)
    cell, rv, ra, rj, rs, worst, peak, path_peak = _sample_ratios(
        t, st, jerk, s_grid, piece, dt, (F1, F2, F3), cap_s,
        (d1, d2, d3, r1, r2, r3, done, err, xs,
         np.ascontiguousarray(lim.vlim, dtype=f64), np.ascontiguousarray(lim.alim_acc, dtype=f64),
         np.ascontiguousarray(lim.alim_dec, dtype=f64), np.ascontiguousarray(lim.jacc, dtype=f64),
         np.ascontiguousarray(lim.jdec, dtype=f64), tol, kappa, cap), mid, have)
    a_use = float(path_peak[0] / lim.a_path) if math.isfinite(lim.a_path) else 0.0
    j_use = float(path_peak[1] / lim.j_path) if math.isfinite(lim.j_path) else 0.0
    use = LimitUse(peak[0], peak[1], peak[2], a_use, j_use, float(path_peak[2]))
    return use, cell, rv, ra, rj, rs, worst


def _use_at(s_grid, der, t, st, jerk, lim: _Limits, path, piece, dt,
            compiled: bool = _checks.AVAILABLE) -> LimitUse:
    """The :class:`LimitUse` of the samples at the times ``t[piece] + dt`` of the
    pieces (derivatives from ``path`` as for :func:`_check`)."""
    if compiled:
        return _evaluate_compiled(s_grid, der, t, st, jerk, lim, path, piece, dt)[0]
    return _use_of(lim, *_evaluate(s_grid, der, t, st, jerk, lim, path, piece, dt)[:6])


def _reversals(s_grid, der, t, st, jerk, lim: _Limits, path,
               compiled: bool = _checks.AVAILABLE) -> LimitUse:
    """The limit ratios on both sides of every joint reversal inside the motion.

    Where a joint reverses (``dq/ds`` changes sign between two grid nodes, the
    path moving), its leg changes: its acceleration and jerk ratios jump from
    those of one leg to the other's, and the largest can be at the reversal
    itself, between the samples of :func:`_check` (a waypoint path's joint at
    its braking acceleration limit up to the moment it reversed: 1.4e-4 over
    it, the nearest sample 0.1 % below, too far for :func:`_zoom`). The
    reversal's ``s`` is found by bisection on the cubic Hermite interpolation
    of ``dq/ds`` between the nodes, then by Newton steps on the derivatives
    the check uses (``path``: its ``derivatives``; None: the interpolation);
    its time inside its piece by bisection on the piece's ``s(t)``. The
    ratios are evaluated just before and just after it, where the joint's
    speed is ten times the rest test's, so that each side takes its own leg.
    Only the joints with separate legs (their limits differ) are looked at.
    ``compiled`` as for :func:`_check`.
    """
    m = lim.vlim.size
    # (only the joints whose legs differ: elsewhere the ratios do not jump)
    legs = (lim.alim_acc != lim.alim_dec) | (lim.jacc != lim.jdec)

    def slope(S: np.ndarray) -> tuple:
        return path.derivatives(S)[1:3] if path is not None else _interp_derivatives(s_grid, der, S)[:2]

    _cell, joint, S = _reversal_points(s_grid, der[1], der[2], legs, slope)
    if not S.size:
        z = np.zeros((0, m))
        return _use_of(lim, z, z, z, np.zeros(0), np.zeros(0), np.zeros(0))
    # the piece and the time there
    k = jerk.size
    pc = np.clip(np.searchsorted(st[:k, 0], S, side="right") - 1, 0, k - 1)
    dur = np.diff(t)[pc]
    tc = time_to_reach(st[pc, 0], st[pc, 1], st[pc, 2], jerk[pc], S, dur)
    V = st[pc, 1] + tc * (st[pc, 2] + 0.5 * tc * jerk[pc])
    # (q' = 0 there: the joint's acceleration is q'' sdot^2)
    qdd = np.abs(slope(S)[1][np.arange(S.size), joint]) * V * V
    vrest = lim.vlim if lim.vrest is None else lim.vrest
    with np.errstate(divide="ignore"):
        eps = np.minimum(np.maximum(10.0 * REST_RTOL * vrest[joint] / qdd, 1e-9 * dur), 1e-3 * dur)
    pieces = np.concatenate([pc, pc])
    dt = np.concatenate([np.maximum(tc - eps, 0.0), np.minimum(tc + eps, dur)])
    if compiled:
        return _evaluate_compiled(s_grid, der, t, st, jerk, lim, path, pieces, dt)[0]
    out = _evaluate(s_grid, der, t, st, jerk, lim, path, pieces, dt)
    return _use_of(lim, out[0], out[1], out[2], out[3], out[4], out[5])


def _max_use(a: LimitUse, b: LimitUse) -> LimitUse:
    """The larger of two limit uses, ratio by ratio."""
    return LimitUse(np.maximum(a.velocity, b.velocity), np.maximum(a.acceleration, b.acceleration),
                    np.maximum(a.jerk, b.jerk), max(a.path_acceleration, b.path_acceleration),
                    max(a.path_jerk, b.path_jerk), max(a.path_speed, b.path_speed))


def _check(s_grid, der, t, st, jerk, lim: _Limits, path=None, per_piece=None,
           compiled: bool = _checks.AVAILABLE, select: np.ndarray | None = None):
    """Limit use at both ends of every piece and ``per_piece`` (default
    :data:`CHECK_PER_PIECE`) points inside it.

    Returns the LimitUse and, per sample, the grid cell, the joint ratios
    ``rv, ra, rj`` (n, m), the speed-cap ratio (n,) and the largest of the
    sample's ratios (n,); the samples run piece by piece, ``per_piece + 2``
    each. ``compiled``: by the kernel (:func:`_evaluate_compiled`), else by
    :func:`_evaluate` (numpy). ``select`` (indices into those samples): only
    these are evaluated (every sample is evaluated on its own, so each gets
    the values of the full check)."""
    k = jerk.size
    frac = np.linspace(0.0, 1.0, (per_piece or CHECK_PER_PIECE) + 2)
    npp = frac.size
    piece = np.repeat(np.arange(k), npp)
    dt = (np.diff(t)[:, None] * frac[None, :]).ravel()
    dt[npp - 1::npp] = np.diff(t)  # the piece's end exactly
    if select is not None:
        piece, dt = piece[select], dt[select]
    if compiled:
        return _evaluate_compiled(s_grid, der, t, st, jerk, lim, path, piece, dt)
    # in chunks of whole pieces (the arrays of a chunk stay in the cache)
    step = max(1, CHECK_CHUNK // npp) * npp
    parts = [_evaluate(s_grid, der, t, st, jerk, lim, path, piece[i:i + step], dt[i:i + step])[:7]
             for i in range(0, piece.size, step)]
    rv, ra, rj, rs, acc, jk, cell = (np.concatenate([pt[j] for pt in parts]) for j in range(7))
    worst = np.max(np.column_stack([rv, ra, rj, rs[:, None]]), axis=1)
    return _use_of(lim, rv, ra, rj, rs, acc, jk), cell, rv, ra, rj, rs, worst


def _recheck(prev: tuple, cells: np.ndarray, s_grid, der, t, st, jerk, lim: _Limits,
             path, per_piece: int) -> tuple:
    """:func:`_check` again after the derivatives changed in the grid ``cells``
    (:meth:`_Corrected.add`): the pieces with a sample in those cells are
    evaluated again, the other samples keep their values from ``prev`` (the
    full check's result, whose arrays are updated in place and returned with
    the new limit use). A sample's cell and the path's own ratios (acceleration,
    jerk, speed cap) do not depend on the joint derivatives."""
    use, cell, rv, ra, rj, rs, worst = prev
    if not cells.size:
        return prev
    npp = per_piece + 2
    changed = np.zeros(s_grid.size, dtype=bool)
    changed[cells] = True
    hit = changed[cell].reshape(-1, npp).any(axis=1)
    if not hit.any():
        return prev
    sel = (np.nonzero(hit)[0][:, None] * npp + np.arange(npp)[None, :]).ravel()
    _, _, rv2, ra2, rj2, _, worst2 = _check(s_grid, der, t, st, jerk, lim, path, per_piece,
                                             select=sel)
    if _checks.AVAILABLE:  # (one compiled pass; numpy's column maxima are slow here)
        peak = _checks.splice_ratios(sel, rv, ra, rj, worst, np.ascontiguousarray(rv2),
                                     np.ascontiguousarray(ra2), np.ascontiguousarray(rj2),
                                     np.ascontiguousarray(worst2))
    else:
        rv[sel], ra[sel], rj[sel], worst[sel] = rv2, ra2, rj2, worst2
        peak = np.stack([x.max(axis=0, initial=0.0) for x in (rv, ra, rj)])
    use = LimitUse(peak[0], peak[1], peak[2], use.path_acceleration, use.path_jerk,
                   use.path_speed)
    return use, cell, rv, ra, rj, rs, worst


def _zoom(s_grid, der, t, st, jerk, lim: _Limits, path, ratios: np.ndarray, npp: int,
          compiled: bool = _checks.AVAILABLE, samples: list | None = None,
          peaks: list | None = None) -> LimitUse:
    """The largest limit ratios inside the pieces that come close to a limit, found by
    repeated bracketing around their largest sampled values.

    ``ratios`` (k * npp,): the largest ratio of every sample of a :func:`_check`
    with ``npp`` samples per piece. Around the largest and the second largest
    sample of every piece above ``1 - ZOOM_ABOVE`` the bracket between the two
    neighbouring samples is sampled again with :data:`ZOOM_POINTS` points,
    :data:`ZOOM_LEVELS` times, each level narrowing the bracket by ``(ZOOM_POINTS
    - 1) / 2``: a smooth maximum inside a piece is found to within the square of a
    tiny fraction of the piece's duration. A bracket whose largest value is at an
    end of its piece stops there (the value at the end is exact). ``compiled`` as
    for :func:`_check`. ``samples``: a list that gets the grid cell and the
    ratios ``rv, ra, rj`` (n, m) and ``rs`` (n,) of every level's samples;
    ``peaks``: a list that gets, for the brackets that end at a level, their piece,
    the time in it of their largest value and that value (each (k,)).
    """
    k = jerk.size
    m = lim.vlim.size
    r = ratios.reshape(k, npp)
    close = np.nonzero(r.max(axis=1) > 1.0 - ZOOM_ABOVE)[0]
    if not close.size:
        z = np.zeros((0, m))
        return _use_of(lim, z, z, z, np.zeros(0), np.zeros(0), np.zeros(0))
    rc = r[close]
    first = np.argmax(rc, axis=1)
    masked = rc.copy()
    masked[np.abs(np.arange(npp)[None, :] - first[:, None]) <= 1] = -np.inf
    second = np.argmax(masked, axis=1)
    pieces = np.concatenate([close, close])
    centre = np.concatenate([first, second]).astype(float) / (npp - 1)
    half = np.full(pieces.size, 1.0 / (npp - 1))
    dur = np.diff(t)[pieces]
    u = np.linspace(-1.0, 1.0, ZOOM_POINTS)
    found = []
    uses = []
    rows = np.arange(pieces.size)
    for _level in range(ZOOM_LEVELS):
        frac = np.clip(centre[:, None] + half[:, None] * u[None, :], 0.0, 1.0)
        pc = np.repeat(pieces, ZOOM_POINTS)
        dt = (dur[:, None] * frac).ravel()
        at_end = frac.ravel() >= 1.0
        dt[at_end] = np.repeat(dur, ZOOM_POINTS)[at_end]
        if compiled:
            ev = _evaluate_compiled(s_grid, der, t, st, jerk, lim, path, pc, dt)
            uses.append(ev[0])
            worst = ev[6]
            if samples is not None:
                samples.append(ev[1:6])
        else:
            out = _evaluate(s_grid, der, t, st, jerk, lim, path, pc, dt)
            found.append(out[:6])
            worst = np.max(np.column_stack([out[0], out[1], out[2], out[3][:, None]]), axis=1)
            if samples is not None:
                samples.append((out[6], out[0], out[1], out[2], out[3]))
        best = np.argmax(worst.reshape(pieces.size, ZOOM_POINTS), axis=1)
        centre = frac[rows, best]
        half = half * 2.0 / (ZOOM_POINTS - 1)
        # a bracket whose largest value is at an end of its piece (evaluated
        # exactly there), the function rising towards it over the bracket's
        # points: done (the same largest ratios on 54 arm motions and the 200
        # speed-dip lines of the feed sweep as with every level)
        keep = (centre > 0.0) & (centre < 1.0)
        if peaks is not None:
            done = ~keep if _level < ZOOM_LEVELS - 1 else np.ones(keep.size, dtype=bool)
            top = worst.reshape(pieces.size, ZOOM_POINTS)[rows, best]
            peaks.append((pieces[done], (dur * centre)[done], top[done]))
        if not keep.any():
            break
        pieces, centre, half, dur = pieces[keep], centre[keep], half[keep], dur[keep]
        rows = np.arange(pieces.size)
    if compiled:
        return functools.reduce(_max_use, uses)
    cat = [np.concatenate([f[i] for f in found]) for i in range(6)]
    return _use_of(lim, *cat)


#: The best attempt of :func:`plan_path_timing` so far: (score, solution, piece
#: durations, piece jerks, limit use, uniform time scale, interval of every
#: piece, (grid, derivatives, speed cap, curvature, velocity cap), (the grid cell
#: and the largest ratio of every sample of its check: where the final check
#: corrects the derivatives first)).
_Best = tuple[float, GridSolution, np.ndarray, np.ndarray, LimitUse, float, np.ndarray,
              tuple[np.ndarray, tuple, np.ndarray, np.ndarray | None, np.ndarray],
              tuple[np.ndarray, np.ndarray]]


# --------------------------------------------------------------------------- public
def _speed_caps(d1: np.ndarray, vlim: np.ndarray, cap: np.ndarray) -> np.ndarray:
    """The largest path speed at every node (n,) that the joints' velocity limits
    ``vlim`` (m,) allow with ``q'`` = ``d1`` (n, m), and at most ``cap`` (n,)."""
    with np.errstate(divide="ignore"):
        return np.minimum(np.min(np.where(np.abs(d1) > 0, vlim / np.abs(d1), np.inf), axis=1), cap)


def plan_path_timing(path: JointPath, limits: Sequence[AxisLimits], *,
                     speed: float | Callable[[np.ndarray], np.ndarray] = math.inf,
                     accel: float = math.inf, jerk: float = math.inf,
                     curvature: Callable[[np.ndarray], np.ndarray] | None = None,
                     start_speed: float = 0.0, start_accel: float = 0.0,
                     end_speed: float = 0.0, end_accel: float = 0.0) -> PathTiming:
    """Minimum-time jerk-limited motion along a joint path (see the module notes).

    Parameters
    ----------
    path : JointPath
        ``q(s)`` with its derivatives, ``s`` in ``[0, path.length]``.
    limits : sequence of AxisLimits, length n_joints
        Joint limits (velocity, acceleration and jerk of both legs; finite
        acceleration and jerk).
    speed : float or callable
        Cap on ``sdot`` [path unit/s]: a number, or a function of ``s`` (n,)
        returning the cap at each ``s`` (the programmed tool speed, an
        orientation-rate cap...).
    accel, jerk : float
        Limits of the path's acceleration and jerk [path unit/s^2, /s^3]:
        ``|sddot| <= accel`` (with ``curvature``: the norm of the acceleration
        vector ``(sddot, curvature * sdot^2)``), ``|sdddot| <= jerk``.
    curvature : callable, optional
        Curvature of the tool path at ``s`` (n,) -> (n,) [1/path unit].
    start_speed, start_accel, end_speed, end_accel : float
        Path state at the ends (``sdot`` >= 0, ``sddot``); rest by default.

    Returns
    -------
    PathTiming

    Raises
    ------
    InvalidInputError
        Bad limits or boundary states.
    InfeasibleError
        The path cannot be passed (a joint would need infinite speed: a
        singularity), or the boundary states are outside the limits.
    """
    if not isinstance(path, JointPath):
        raise InvalidInputError(f"path must be a JointPath (length, n_joints, derivatives), "
                                f"got {type(path).__name__}")
    L = float(path.length)
    if not (math.isfinite(L) and L > 0.0):
        raise InvalidInputError(f"path length must be finite and > 0, got {L!r}")
    m = int(path.n_joints)
    lims, vlim, aacc, adec, jacc, jdec = _limit_arrays(limits, m)
    a_path = check_positive(accel, "accel", allow_inf=True)
    j_path = check_positive(jerk, "jerk", allow_inf=True)
    for nm, val in (("start_speed", start_speed), ("end_speed", end_speed)):
        if not (math.isfinite(val) and val >= 0.0):
            raise InvalidInputError(f"{nm} must be finite and >= 0, got {val!r}")
    for nm, val in (("start_accel", start_accel), ("end_accel", end_accel)):
        if not math.isfinite(val):
            raise InvalidInputError(f"{nm} must be finite, got {val!r}")

    rest0 = start_speed == 0.0 and start_accel == 0.0
    restN = end_speed == 0.0 and end_accel == 0.0
    moving = not (rest0 and restN)

    def cap_fn(ss):
        return _speed_cap(speed, ss)

    # the fraction of the joints' jerk limits the grid problem plans with (see
    # JERK_MARGIN); the path's jerk limit is JERK_MARGIN of it at a rest end (a jerk
    # phase from or to rest) and in the intervals times their factor (1 / JERK_MARGIN
    # with a moving boundary state, lowered where the pieces exceed it)
    margin = JERK_MARGIN if not moving else 1.0

    def path_jerk_scale(local: np.ndarray | None = None) -> np.ndarray | None:
        """The factor on the path's jerk limit (JERK_MARGIN of it) in every interval of
        the grid, times ``local`` (n - 1,) (the lowering where the check found an
        excess); None where it is 1 everywhere."""
        out = margin / JERK_MARGIN * (1.0 if local is None else local)
        if np.all(out == 1.0):
            return None
        return np.broadcast_to(out, (s.size - 1,)).astype(float)

    def on_grid(ss: np.ndarray, dd1: np.ndarray):
        """The speed cap, the joints' velocity cap and the tool path's curvature at
        the grid ``ss`` (with ``q'`` = ``dd1`` there)."""
        cc = cap_fn(ss)
        kk = None
        if curvature is not None:
            kk = np.abs(np.asarray(curvature(ss), dtype=float))
            if kk.shape != ss.shape or not np.isfinite(kk).all():
                raise InvalidInputError("curvature(s) must return finite values of the shape of s")
        return cc, _speed_caps(dd1, vlim, cc), kk

    breaks = np.asarray(getattr(path, "breakpoints", np.zeros(0)), dtype=float)
    breaks = np.unique(breaks[(breaks > 0.0) & (breaks < L)])
    # a piece shorter than END_PIECE at either end (END_PIECE_REST at a rest end):
    # planned as its neighbour's extension
    model = path
    short, short_end = ((END_PIECE_REST if rest else END_PIECE) * L for rest in (rest0, restN))
    if breaks.size and (breaks[0] < short or breaks[-1] > L - short_end):
        model = _ShortEnds(path, breaks, short, short_end)
        breaks = model.breakpoints
    s = _initial_grid(L, breaks)
    if callable(speed):  # nodes on both sides of every step of the speed cap
        s = _add_nodes(s, _cap_edges(cap_fn, L), CAP_MERGE * L / (CAP_GRID - 1))
    cached = _Cached(model)
    der = cached.derivatives(s)
    alim = np.minimum(aacc, adec)
    jlim = np.minimum(jacc, jdec)
    # a path with cheap exact derivatives is checked with them: its grid only
    # needs to resolve the motion, not to interpolate the derivatives exactly
    cheap = bool(getattr(path, "cheap_derivatives", False))
    exact = model if cheap else None
    # the derivatives just before every breakpoint: the refinement interpolates
    # towards them in the cell that ends there, as do the checks (those of a path
    # without cheap derivatives)
    below = model.derivatives(np.nextafter(breaks, -np.inf))[1:] if breaks.size else None
    left = None if cheap else below
    grid_rtol = GRID_RTOL_CHEAP if cheap else GRID_RTOL
    s, der, unresolved, cell_err = _refine(cached, s, der, vlim, alim, jlim, cap_fn, breaks,
                                           max(grid_rtol, FIRST_GRID_RTOL), left=below)
    _finite_derivatives(der)
    s, der, cell_err = _reversal_nodes(cached, s, der, cell_err, aacc != adec)
    q, d1, d2, d3 = der
    cap, vcap, kappa = on_grid(s, d1)
    n = s.size
    states = (f"from the start state (speed {start_speed:.6g}, acceleration {start_accel:.6g}) to "
              f"the end state (speed {end_speed:.6g}, acceleration {end_accel:.6g}) along this "
              f"path of length {L:.6g}")
    # the minimum-time S-curve under the path's own limits alone: a lower bound of every
    # timing (and the timing itself where it keeps every joint's limits, see below)
    boundary = (start_speed, start_accel, end_speed, end_accel)
    direct = _path_limits_profile(L, cap, a_path, j_path, boundary)
    # the work has to be worth it: a motion that cannot be shorter than MAX_DURATION
    with np.errstate(divide="ignore", over="ignore"):
        floor = float(np.sum(np.diff(s) / np.maximum(vcap[:-1], vcap[1:])))
        if rest0 and restN:
            # every joint moves its distance from rest to rest: at least the
            # time of its bang-bang acceleration and of its jerk alone
            dq = np.abs(q[-1] - q[0])
            floor = max(floor, float(np.max(2.0 * np.sqrt(dq / alim))),
                        float(np.max(np.cbrt(32.0 * dq / jlim))))
        if direct is not None:
            floor = max(floor, float(np.sum(direct[0])))
    if not floor <= MAX_DURATION:
        raise InvalidInputError(
            f"the motion along this path would take at least {floor:.3g} s, more than the "
            f"{MAX_DURATION:g} s the path timing supports (a speed cap or limit far too low "
            "for its length)")
    x_cap = cap ** 2  # lowered locally where the check finds the cap exceeded

    fallback = None  # (durations, jerks) of the fallback once made

    def fallback_on(ss, dd, cc, kk):
        """The fallback (see _fallback) on the grid ``ss``, its derivatives ``dd``, speed
        cap ``cc`` and curvature ``kk``, from and to the boundary states; or None."""
        return _fallback(ss, dd, L, vlim, aacc, adec, jacc, jdec, cc, a_path, j_path, kk, boundary)

    corrected: _Corrected | None = None

    def true_check(t, st, jk, lim: _Limits, close, per_piece: int):
        """:func:`_check` of the pieces (times ``t``, states ``st``, jerks ``jk``) on the
        grid ``s`` with ``per_piece`` points in each, with the true derivatives where
        the interpolation's error could matter (first where an earlier check came
        ``close``: its cells and ratios, or None); ``(result, derivative source)``."""
        nonlocal corrected
        if exact is None and (corrected is None or corrected.s is not s):
            corrected = _Corrected(cached, s, der, breaks, left, unresolved)
            if close is not None:  # the true derivatives where the rounds' check came close
                cell_b, near_b = close
                corrected.add_both(cell_b[near_b > 1.0 - VERIFY_ABOVE],
                                   cell_b[near_b > 1.0 - VERIFY_FULL_ABOVE])
        src = exact if exact is not None else corrected
        res = _check(s, der, t, st, jk, lim, src, per_piece)
        if corrected is not None:
            # the true derivatives in the cells that come close to a limit, then again
            res = _recheck(res, corrected.add(res[1][res[6] > 1.0 - VERIFY_ABOVE]),
                           s, der, t, st, jk, lim, src, per_piece)
            # ... and at every point of VERIFY_POINTS where that comes very close
            res = _recheck(res, corrected.add(res[1][res[6] > 1.0 - VERIFY_FULL_ABOVE], full=True),
                           s, der, t, st, jk, lim, src, per_piece)
        return res, src

    def limits_for(st: np.ndarray) -> _Limits:
        """What the checks of a timing with the node states ``st`` compare with, on the
        grid ``s``."""
        return _Limits(vlim, aacc, adec, jacc, jdec, a_path, j_path, kappa, cap,
                       cap_fn if callable(speed) else None, _rest_scale(vlim, der[1], st))

    def final_use(t, st, jk, close, per_piece: int) -> LimitUse:
        """The final check of the pieces: :func:`true_check`, then a zoom on those that
        come close to a limit and both sides of every joint reversal."""
        lim = limits_for(st)
        res, src = true_check(t, st, jk, lim, close, per_piece)
        use, worst = res[0], res[6]
        # the pieces that come close to a limit, again: the largest value inside a
        # piece, not only at the sampled points
        peaks: list = []
        use = _max_use(use, _zoom(s, der, t, st, jk, lim, src, worst, per_piece + 2, peaks=peaks))
        if exact is None and peaks:
            # ... there with the path's true derivatives (the corrected interpolation's
            # error left, about 1e-7 of a limit, could hide an excess)
            pc, dt, top = (np.concatenate(a) for a in zip(*peaks))
            near = top > 1.0 - EXACT_PEAK_ABOVE
            if near.any():
                use = _max_use(use, _use_at(s, der, t, st, jk, lim, cached, pc[near], dt[near]))
        # ... and both sides of every joint reversal (where the leg changes)
        return _max_use(use, _reversals(s, der, t, st, jk, lim, src))

    def s_curve_states(dur: np.ndarray, jk: np.ndarray):
        """Times and states ``(s, sdot, sddot)`` of an S-curve of ``s`` (its piece
        durations and jerks) from the start state; the end state exactly."""
        t, st = _pieces_state(dur, jk, 0.0, start_speed, start_accel)
        st[-1] = (L, end_speed, end_accel)
        return t, st

    # the path's own limits first: where their S-curve keeps the joints' limits too it
    # is the optimum itself (a motion held by its programmed feed, acceleration and
    # jerk everywhere); the rounds' check on this grid rules it out cheaply
    known = None  # (its final check's use, where it passes)
    if direct is not None:
        t, st = s_curve_states(*direct)
        screen = _check(s, der, t, st, direct[1], limits_for(st),
                        exact if cheap else _Interp(s, der, breaks, left), CHECK_PER_PIECE)[0]
        if screen.worst <= 1.0 + CHECK_RTOL:
            if grid_rtol < FIRST_GRID_RTOL:
                # the final check's grid: refined to the full tolerance (its true
                # derivatives are evaluated only where it comes within VERIFY_ABOVE)
                s, der, unresolved, cell_err = _refine(cached, s, der, vlim, alim, jlim, cap_fn,
                                                       breaks, grid_rtol, ~(cell_err <= grid_rtol),
                                                       left=below)
                _finite_derivatives(der)
                q, d1, d2, d3 = der
                cap, vcap, kappa = on_grid(s, d1)
                n = s.size
                x_cap = cap ** 2
            known = final_use(t, st, direct[1], None, max(FINAL_CHECK_PER_PIECE, CAP_GRID))
        if known is None or known.worst > 1.0 + CHECK_RTOL:
            direct = known = corrected = None
    best: _Best | None = None
    sol: GridSolution | None  # the solution kept; None for the fallback timing
    piv: np.ndarray | None  # the grid interval of every piece (with sol)
    if direct is None:
        try:
            # per-node limits, lowered where the check finds an excess
            scale_v = np.ones((n, m))
            scale_a = np.ones((n, m))
            scale_j = np.ones((n, m))
            # a first solve on the derivative-refined grid, then the grid refined where the
            # path acceleration swings (the jerk phases) and solved again from there
            first = solve_grid(GridProblem(s=s, d1=d1, d2=d2, d3=d3, v_max=vlim, a_acc=aacc, a_dec=adec,
                                           j_acc=jacc * margin, j_dec=jdec * margin,
                                           x_cap=x_cap, a_path=a_path, j_path=j_path * JERK_MARGIN,
                                           kappa=kappa, x_cap_mid=_mid_caps(s, cap_fn, speed),
                                           x0=start_speed**2, u0=start_accel,
                                           xN=end_speed**2, uN=end_accel,
                                           j_path_scale=path_jerk_scale()), max_rounds=FIRST_ROUNDS)
            jerk_free_time = first.jerk_free_time
            init = (first.x, first.u)
            # the second grid: the nodes of the jerk phases, refined to the full tolerance
            s_new = np.unique(np.concatenate([
                s, _solution_splits(s, first.x, first.u),
                _rest_splits(s, first.x, first.u, d1, d2, ((aacc, jacc * JERK_MARGIN),
                                                           (adec, jdec * JERK_MARGIN)),
                             a_path, j_path * JERK_MARGIN, rest0, restN)]))
            der_new = cached.derivatives(s_new)
            if grid_rtol < FIRST_GRID_RTOL:  # (the cells within it already: not again)
                parent = np.searchsorted(s, s_new[:-1], side="right") - 1
                s_new, der_new, unresolved, _ = _refine(cached, s_new, der_new, vlim, alim, jlim, cap_fn,
                                                        breaks, grid_rtol, ~(cell_err[parent] <= grid_rtol),
                                                        left=below)
                _finite_derivatives(der_new)
            regrid = s_new.size > s.size  # (the new grid holds the old one)
            if regrid:
                init = (np.interp(s_new, s, first.x), np.interp(s_new, s, first.u))
                s, der = s_new, der_new
                q, d1, d2, d3 = der
                cap, vcap, kappa = on_grid(s, d1)
                n = s.size
                x_cap = cap ** 2
                scale_v = np.ones((n, m))
                scale_a = np.ones((n, m))
                scale_j = np.ones((n, m))
            tightened = 0
            splits = 0
            best = None
            xmid_scale = np.ones(s.size - 1)
            jpath_scale = np.ones(s.size - 1)  # (lowered only with a moving state, see below)
            apath_scale = np.ones(s.size)  # (the same)
            attempt = 0
            least_worst = math.inf  # the least excess of the attempts so far
            above_least = 0  # attempts in a row above it
            init_settled = False  # init is a solution of the same grid
            init_near = False  # ... or of the grid before a split (interpolated)
            init_duals = None  # ... and its multipliers (on the same grid)
            prev_excess = None  # (moving state) every cell's excess in the attempt before
            roundoff_rounds = 0  # (moving state) attempts granted for a round-off excess
            while attempt <= (MAX_TIGHTEN_MOVING + roundoff_rounds if moving
                              else MAX_TIGHTEN_SLOW if best is not None and best[5] > SLOW_SCALE
                              else MAX_TIGHTEN):
                prob = GridProblem(s=s, d1=d1, d2=d2, d3=d3, v_max=vlim[None, :] * scale_v,
                                   a_acc=aacc[None, :] * scale_a, a_dec=adec[None, :] * scale_a,
                                   j_acc=jacc[None, :] * scale_j * margin,
                                   j_dec=jdec[None, :] * scale_j * margin,
                                   x_cap=x_cap, a_path=a_path, j_path=j_path * JERK_MARGIN, kappa=kappa,
                                   x_cap_mid=_mid_caps(s, cap_fn, speed) * xmid_scale,
                                   x0=start_speed**2, u0=start_accel, xN=end_speed**2, uN=end_accel,
                                   j_path_scale=path_jerk_scale(jpath_scale),
                                   a_path_scale=apath_scale if moving else None)
                reuse = attempt == 0 and not regrid and not splits and first.status != RELAXED
                sol = first if reuse else solve_grid(
                    prob, max_rounds=TIGHTEN_ROUNDS if attempt else MAX_ROUNDS, init=init,
                    settled=init_settled, near=init_near, duals=init_duals)
                # until an attempt comes within SPLIT_ABOVE of the limits (a timing
                # found), a moving state's solve from a given point that ends relaxed or
                # stalls (far slower than the first grid's) is solved again from the
                # jerk-free round, as the first grid was; where that ends relaxed, a
                # stalled solution is kept. A relaxed or stalled solution goes on to the
                # check: the grid is split where it exceeds a limit by more than
                # SPLIT_ABOVE, or where its node states cannot be joined by pieces, and
                # the problem solved again from it (it is returned only where the final
                # check finds it within every limit)
                found = best is not None and best[4].worst <= 1.0 + SPLIT_ABOVE
                split_left = moving and splits < MAX_SPLITS
                if not found and not reuse and (sol.status == RELAXED or (
                        moving and not sol.time <= STALL_FACTOR * first.time)):
                    cold = solve_grid(prob, max_rounds=MAX_ROUNDS)
                    if cold.status != RELAXED or sol.status == RELAXED:
                        sol = cold
                if sol.status == RELAXED and (found or not split_left):
                    if best is None:
                        raise RuntimeError("path timing: the grid problem ended in a relaxed round")
                    break
                init = (sol.x, sol.u)  # a tightened attempt starts from this one
                init_settled = True  # (on the same grid)
                init_duals = sol.duals
                try:
                    dur, jk, piv = hermite_pieces(s, sol.x, sol.u, rest0, restN)
                    unjoined = None
                except UnjoinableError as err:
                    if found or not (split_left and s.size < GRID_MAX):
                        if best is None:
                            raise
                        break
                    unjoined = err.intervals  # (split around them, as around an excess)
                    dur = jk = piv = np.zeros(0)  # (no pieces)
                if unjoined is None:
                    t, st = _node_states(s, sol.x, sol.u, dur, jk, piv)
                    lim = limits_for(st)
                    if moving:
                        # as the final check, which cannot slow it down: its zoom's samples
                        # too, where it finds an excess between the check points
                        (use, cell, rv, ra, rj, rs, near), src_t = true_check(t, st, jk, lim, None,
                                                                              FINAL_CHECK_PER_PIECE)
                        zoomed: list = []
                        use = _max_use(use, _zoom(s, der, t, st, jk, lim, src_t, near,
                                                  FINAL_CHECK_PER_PIECE + 2, samples=zoomed))
                        close = (cell, near)
                        cell, rv, ra, rj, rs = (np.concatenate([a, *(z[i] for z in zoomed)])
                                                for i, a in enumerate((cell, rv, ra, rj, rs)))
                    else:
                        use, cell, rv, ra, rj, rs, near = _check(s, der, t, st, jk, lim,
                                                                 exact if cheap else _Interp(s, der, breaks, left))
                        close = (cell, near)
                    k = _uniform_scale(use)
                    # with a moving state no limit is lowered by more than the least excess
                    # of the attempts before this one (at least SPLIT_ABOVE): an attempt
                    # further above a limit than an earlier one had its linearised rounds go
                    # astray, and its ratios overstate what that limit needs; that bound
                    # grows by CLIP_GROWTH with every attempt in a row above it
                    top = (max(least_worst, 1.0 + SPLIT_ABOVE) * CLIP_GROWTH**above_least
                           if moving else math.inf)
                    above_least = above_least + 1 if use.worst >= least_worst else 0
                    least_worst = min(least_worst, use.worst)
                    # a timing that needs no uniform slow-down keeps its exact cruise speeds:
                    # preferred unless a slowed one is clearly faster
                    score = t[-1] * k * (1.0 + SCALED_PENALTY if k > 1.0 else 1.0)
                    if moving and k > 1.0:
                        # (with a moving state no uniform slow-down: a timing within the
                        # limits before any other, then the one closest to them)
                        score = MOVING_EXCESS_SCORE * use.worst
                    if best is None or score < best[0]:
                        # (the cells close to a limit: the final check corrects them first)
                        best = (score, sol, dur, jk, use, k, piv, (s, der, cap, kappa, vcap), close)
                    if use.worst <= 1.0 + (CHECK_RTOL if moving else TIGHTEN_ABOVE):
                        break  # a small excess costs less as a uniform slow-down than as another round
                stubborn = None
                if moving and unjoined is None:
                    # a cell whose excess a local lowering did not halve: the lowering
                    # does not reach it (the grid is too coarse there), split it as
                    # around a large excess
                    excess = np.zeros(s.size - 1)
                    for ratio in (rv, ra, rj):
                        np.maximum.at(excess, cell, ratio.max(axis=1, initial=0.0) - 1.0)
                    if prev_excess is not None and prev_excess.size == excess.size:
                        stubborn = ((excess > CHECK_RTOL) & (prev_excess > CHECK_RTOL)
                                    & (excess >= STUBBORN_EXCESS * prev_excess))
                        stubborn = stubborn if stubborn.any() else None
                    prev_excess = excess
                if (unjoined is not None or stubborn is not None or use.worst > 1.0 + SPLIT_ABOVE) \
                        and splits < MAX_SPLITS and s.size < GRID_MAX:
                    # a large excess: the grid is too coarse for the motion there (the
                    # pieces' jerks differ from the interval's mean): split the cells
                    # around it and solve again from this solution
                    bad = np.zeros(s.size - 1, dtype=bool)
                    if unjoined is not None:
                        bad[unjoined] = True
                    else:
                        for ratio in (rv, ra, rj):
                            bad[cell[(ratio > 1.0 + SPLIT_ABOVE).any(axis=1)]] = True
                        bad[cell[rs > 1.0 + SPLIT_ABOVE]] = True
                        if stubborn is not None:
                            bad |= stubborn
                    prev_excess = None
                    bad[:-1] |= bad[1:].copy()
                    bad[1:] |= bad[:-1].copy()
                    cells = np.nonzero(bad)[0][:max(GRID_MAX - s.size, 0)]
                    s_new = np.unique(np.concatenate([s, 0.5 * (s[cells] + s[cells + 1])]))
                    init = (np.interp(s_new, s, sol.x), np.interp(s_new, s, sol.u))
                    init_settled = False
                    init_duals = None
                    init_near = sol.converged
                    scale_v, scale_a, scale_j, x_cap, apath_scale = (
                        _regrid(s, s_new, a) for a in (scale_v, scale_a, scale_j, x_cap, apath_scale))
                    xmid_scale = np.ones(s_new.size - 1)
                    jpath_scale = np.ones(s_new.size - 1)
                    s, der = s_new, cached.derivatives(s_new)
                    q, d1, d2, d3 = der
                    cap, vcap, kappa = on_grid(s, d1)
                    x_cap = np.minimum(x_cap, cap ** 2)
                    splits += 1
                    continue
                tightened += 1
                attempt += 1

                def lowered(ratio: np.ndarray, top: float = top, joint: bool = False) -> np.ndarray:
                    """The factor on a limit whose use is ``ratio`` (> 1), bounded by ``top``;
                    on a joint's limit (``joint``) with a moving start the margin below the
                    excess is at most JOINT_MARGIN_RATIO times the excess."""
                    margin = np.full(np.shape(ratio), TIGHTEN_MARGIN)
                    if joint and not rest0:
                        margin = np.minimum(margin, JOINT_MARGIN_RATIO * (ratio - 1.0))
                    return (1.0 - margin) / np.minimum(ratio, top)

                for ratio, scale in ((rv, scale_v), (ra, scale_a), (rj, scale_j)):
                    over = ratio > 1.0 + CHECK_RTOL
                    if not over.any():
                        continue
                    rows, cols = np.nonzero(over)
                    c = cell[rows]
                    f = lowered(ratio[rows, cols], joint=True)
                    for node in (c, c + 1):
                        np.minimum.at(scale, (node, cols), np.minimum(1.0, f * scale[node, cols]))
                over = rs > 1.0 + CHECK_RTOL
                if over.any():
                    c = cell[over]
                    f = lowered(rs[over]) ** 2
                    for node in (c, c + 1):
                        np.minimum.at(x_cap, node, f * x_cap[node])
                    np.minimum.at(xmid_scale, c, f * xmid_scale[c])
                if moving and math.isfinite(j_path):
                    # the path's jerk: with a moving state lowered in the intervals of the
                    # pieces above it (from rest, a small excess is a uniform slow-down)
                    over = np.abs(jk) > j_path * (1.0 + CHECK_RTOL)
                    if over.any():
                        c = piv[over]
                        f = lowered(np.abs(jk[over]) / j_path)
                        np.minimum.at(jpath_scale, c, f * jpath_scale[c])
                if moving and math.isfinite(a_path) and use.path_acceleration > 1.0 + CHECK_RTOL:
                    # ... and its acceleration, lowered at the nodes of the pieces above it
                    # (where none of their points is, the check's largest excess at the
                    # piece closest to it)
                    ratio = _piece_path_accel(t, st, jk, s, kappa) / a_path
                    over = ratio > 1.0 + CHECK_RTOL
                    if not over.any():
                        over = ratio == ratio.max()
                        ratio[over] = use.path_acceleration
                    c = piv[over]
                    f = lowered(ratio[over])
                    for node in (c, c + 1):
                        np.minimum.at(apath_scale, node, np.minimum(1.0, f * apath_scale[node]))
                if moving and use.worst <= 1.0 + ROUNDOFF_EXCESS:
                    # an excess at the round-off of the linearised rows moves from piece
                    # to piece between rounds: that limit lowered everywhere, by
                    # ROUNDOFF_LOWER times the excess (and solved again, past the
                    # attempts' budget up to ROUNDOFF_ROUNDS times)
                    if attempt > MAX_TIGHTEN_MOVING and roundoff_rounds < ROUNDOFF_ROUNDS:
                        roundoff_rounds += 1
                    for ratio_max, scale in ((use.velocity.max(initial=0.0), scale_v),
                                             (use.acceleration.max(initial=0.0), scale_a),
                                             (use.jerk.max(initial=0.0), scale_j),
                                             (use.path_acceleration, apath_scale),
                                             (use.path_jerk, jpath_scale)):
                        if ratio_max > 1.0 + CHECK_RTOL:
                            scale *= 1.0 - ROUNDOFF_LOWER * (float(ratio_max) - 1.0)
        except (RuntimeError, ValueError):  # the optimisation failed: the fallback below
            best = None

    if direct is not None:
        fallback = direct
    if best is not None and best[5] > (1.0 if moving else FALLBACK_ABOVE):
        # the best attempt needs a large uniform slow-down (its rounds went wrong),
        # or any with a moving state (which cannot be slowed down uniformly): the
        # always-feasible fallback instead where that is shorter (or exists)
        s_b, der_b, cap_b, kappa_b, vcap_b = best[7]
        fallback = fallback_on(s_b, der_b, cap_b, kappa_b)
        if fallback is not None and (moving or float(np.sum(fallback[0]))
                                     < float(np.sum(best[2])) * best[5]):
            s, der, cap, kappa, vcap = s_b, der_b, cap_b, kappa_b, vcap_b
            best = None
    if best is None:
        if fallback is None:
            fallback = fallback_on(s, der, cap, kappa)
        if fallback is None:  # (a moving state only)
            raise InfeasibleError(
                f"no timing found {states}: its grid problem has no solution within the limits, "
                "and the fallback (an S-curve of the path parameter within the limits everywhere "
                "on the path) cannot start or end in these states; a start that has to brake "
                "hard, or a path too short to reach the end state, makes it so")
        dur0, jk0 = fallback
        sol, piv, k_scale, tightened = None, None, 1.0, 0
        jerk_free_time = math.nan
    else:
        _, sol, dur0, jk0, use, k_scale, piv, (s, der, cap, kappa, vcap), close = best
    # the smallest excess of a timing checked (the message where none is left)
    least = use.worst if sol is not None and k_scale > 1.0 else math.inf
    # (the fallback's few long pieces: at least as many points each as the speed
    # cap's sampling for its steps has over the whole path)
    per_piece = FINAL_CHECK_PER_PIECE if sol is not None else max(FINAL_CHECK_PER_PIECE, CAP_GRID)
    for _final in range(FINAL_ATTEMPTS):
        if k_scale > 1.0 and moving:
            # no uniform slow-down with a moving state: the fallback, where it exists
            fallback = None if sol is None else fallback_on(s, der, cap, kappa)
            if fallback is None:
                raise InfeasibleError(
                    f"the timing {states} exceeds a limit by {100 * (least - 1):.3g} % after the "
                    "local lowering of the limits (the closest of the timings found), and with a "
                    "moving boundary state it cannot be slowed down uniformly (nor start or end the "
                    "fallback in these states)")
            (dur0, jk0), sol, piv, k_scale, tightened = fallback, None, None, 1.0, 0
            jerk_free_time = math.nan
            per_piece = max(FINAL_CHECK_PER_PIECE, CAP_GRID)
        dur = dur0 * k_scale
        jk = jk0 / k_scale**3
        if sol is None or piv is None:  # the fallback
            t, st = s_curve_states(dur, jk)
        else:
            t, st = _node_states(s, sol.x, sol.u, dur, jk, piv, k_scale)
        if known is not None:  # (the path-limits S-curve, checked before the grid problem)
            use, known = known, None
        else:  # the final check, denser than the rounds' (any excess left: a uniform slow-down)
            use = final_use(t, st, jk, None if sol is None else close, per_piece)
        least = min(least, use.worst)
        extra = _uniform_scale(use)
        if extra <= 1.0:
            break
        k_scale *= extra
    else:
        raise InfeasibleError(
            f"the timing {states} still exceeds a limit by {100 * (use.worst - 1):.3g} % after "
            f"{FINAL_ATTEMPTS} final checks")
    if not (st[0, 0] == 0.0 and abs(st[-1, 0] - L) <= END_RTOL * L):
        # (an invariant: the grid runs from the path's start to its end)
        raise RuntimeError(f"path timing: the motion runs from s = {float(st[0, 0])!r} to {float(st[-1, 0])!r}, "
                           f"not over the whole path [0, {L!r}]")
    if sol is None:
        tt = np.linspace(0.0, t[-1], 20 * s.size)
        sv = _sample_pieces(t, st, jk, tt)
        grid_speed = np.interp(s, sv[0], sv[1])
    else:
        grid_speed = np.sqrt(sol.x) / k_scale
    return PathTiming(path=path, limits=lims, duration=float(t[-1]), t=t, state=st, jerk=jk,
                      grid=s, grid_speed=grid_speed, speed_cap=vcap, jerk_free_time=jerk_free_time,
                      time_scale=k_scale, limit_use=use, rounds=0 if sol is None else sol.rounds,
                      grid_derivatives=der,
                      info={"nodes": int(s.size), "tightened": tightened,
                            "verified_points": 0 if corrected is None else corrected.evaluated,
                            "status": (("fallback" if direct is None else "path limits")
                                       if sol is None else sol.status),
                            "converged": sol is not None and sol.converged, "round_rtol": ROUND_RTOL})
