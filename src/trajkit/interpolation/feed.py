"""Feed along a path: jerk-limited S-curve in arc length, below a speed-limit curve.

Without a speed limit the feed profile is exactly the core rest-to-rest
profile ``plan_move(0, L, AxisLimits(v_max=feed, a_max, j_max))``. With a
speed-limit curve ``v_lim(s)`` (from machine axes, or from the chord error
between setpoints) the planner builds *plateaus*: constant speed (the feed
where ``v_lim >= feed``, the lowest ``v_lim`` over each region where it is
below the feed), joined by jerk-limited S-curve speed changes that always
happen on the faster side of a junction, so the speed never exceeds
``v_lim``. A plateau too short for its speed changes is lowered (bisection)
or merged with its neighbour. Composite paths stop at corners.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._sampling import MAX_SAMPLES, period_times
from .._validate import check_positive
from ..errors import InvalidInputError
from ..limits import AxisLimits
from ..paths.base import Path
from ..paths.chords import arc_step_for_tolerance
from ..profiles import plan_move
from ._pieces import JerkPieces

__all__ = ["Slowdown", "FeedSample", "FeedPlan", "plan_feed", "MIN_PERIOD", "MAX_PERIOD", "setpoint_times"]

#: Shortest and longest control period accepted [s] (0.1 ms ... the 100 ms step of Jiang, 1987).
MIN_PERIOD = 1e-4
MAX_PERIOD = 0.1

#: Grid points per path for the speed-limit curve.
LIMIT_GRID = 4097

#: Relative round-off slack on speeds and plateau lengths.
SPEED_RTOL = 1e-12

#: Bisection of a plateau speed stops at this relative width.
BISECT_RTOL = 1e-15

#: Golden-section steps refining the lowest speed limit of a slowdown.
REFINE_ITER = 60

#: Bisection steps when lowering a plateau that is too short.
PLATEAU_BISECT = 100

#: A stretch runs below the feed (a slow-down) when a speed limit is below
#: this fraction of it.
SLOWDOWN_RTOL = 1e-3

#: Slow-down stretches are split where their limiting speed changes by this factor.
SLOWDOWN_BAND = 1.25

#: Reason given for a slowdown caused by the chord error between setpoints.
CHORD_REASON = "chord error at the period"

#: A speed-limit function: arc lengths (n,) -> (speed limits (n,) [m/s], reason index (n,) int).
SpeedLimitFn = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class Slowdown:
    """A stretch of the path where the feed is lowered below the commanded feed.

    Attributes
    ----------
    s_start, s_end : float
        Arc-length range [m] where the speed limit is below the feed.
    speed : float
        Planned tool speed there [m/s].
    limit : float
        Lowest value of the speed-limit curve there [m/s]. For a velocity (or
        chord-error) reason a bound of the speed; for an acceleration or jerk
        reason the speed at which that axis quantity reaches its limit at
        constant tool speed (the path's own acceleration can offset the part
        from the curvature, so the planned speed may pass it while the axis
        keeps its limit).
    reason : str
        Which axis and quantity sets that lowest limit (e.g. ``"theta velocity"``).
    """

    s_start: float
    s_end: float
    speed: float
    limit: float
    reason: str

    def to_dict(self) -> dict:
        return {"s_start": self.s_start, "s_end": self.s_end, "speed": self.speed,
                "limit": self.limit, "reason": self.reason}


@dataclass(frozen=True)
class FeedSample:
    """Feed state at sample times; arrays of shape (n,), points (n, 3).

    Attributes
    ----------
    t : ndarray [s]
    s, v, a, j : ndarray
        Arc length [m], tool speed [m/s], tangential acceleration [m/s^2]
        and jerk [m/s^3].
    points : ndarray, shape (n, 3)
        Tool points on the exact path at ``s`` [m].
    """

    t: np.ndarray
    s: np.ndarray
    v: np.ndarray
    a: np.ndarray
    j: np.ndarray
    points: np.ndarray


def setpoint_times(duration: float, period: float,
                   max_samples: int | None = MAX_SAMPLES) -> np.ndarray:
    """Fixed-period sample times ``k * period``, k = 0 .. ceil(duration / period).

    The last sample is at or after the end (where the motion holds the goal
    at rest), so consecutive samples are always exactly one period apart.
    More than ``max_samples`` setpoints are refused before anything is
    allocated (:data:`trajkit._sampling.MAX_SAMPLES` by default).

    Returns
    -------
    ndarray, shape (n,) [s]
    """
    dt = _check_period(period)
    return period_times(duration, dt, end="after", max_samples=max_samples, what="setpoints")


def _check_period(period: float) -> float:
    dt = check_positive(period, "period")
    if not MIN_PERIOD <= dt <= MAX_PERIOD:
        raise InvalidInputError(
            f"period {dt!r} s is outside the supported range [{MIN_PERIOD}, {MAX_PERIOD}] s"
        )
    return dt


class FeedPlan:
    """The planned motion along a path: s(t) with exact derivatives.

    Build it with :func:`plan_feed`.

    Attributes
    ----------
    path : Path
    feed : float
        Commanded tool speed [m/s].
    a_max, j_max : float
        Tangential acceleration [m/s^2] and jerk [m/s^3] used.
    motion : JerkPieces
        s(t) as constant-jerk pieces.
    duration : float [s]
    slowdowns : tuple of Slowdown
    stops : ndarray
        Arc lengths [m] where the tool stops (start, corners, end).
    profiles : tuple
        The core :class:`~trajkit.Profile` of each rest-to-rest stretch that
        needed no slowdown (``None`` for stretches planned with plateaus).
    """

    def __init__(self, path, feed, a_max, j_max, motion, slowdowns, stops, profiles, reasons):
        self.path = path
        self.feed = feed
        self.a_max = a_max
        self.j_max = j_max
        self.motion = motion
        self.duration = motion.duration
        self.slowdowns = tuple(slowdowns)
        self.stops = np.asarray(stops, dtype=float)
        self.profiles = tuple(profiles)
        self.reasons = tuple(reasons)

    def sample(self, t: Any, points: bool = True) -> FeedSample:
        """Exact state at times ``t`` [s] (array (n,)); ``points`` evaluates the path too."""
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        s, v, a, j = self.motion.sample(tt)
        s = np.clip(s, 0.0, self.path.length)
        pts = self.path.point(s) if points else np.empty((tt.size, 0))
        return FeedSample(tt, s, v, a, j, pts)

    def setpoints(self, period: float, max_samples: int | None = MAX_SAMPLES) -> FeedSample:
        """Samples at a fixed control period (see :func:`setpoint_times`)."""
        return self.sample(setpoint_times(self.duration, period, max_samples))

    @property
    def peak_speed(self) -> float:
        """Largest tool speed [m/s] (at a piece boundary, exact)."""
        return float(np.max(self.motion.state[:, 1]))

    def cruise_mask(self, t: Any) -> np.ndarray:
        """True where the times ``t`` lie in a constant-speed piece at the commanded feed."""
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        m = self.motion
        i = np.clip(np.searchsorted(m.t, tt, side="right") - 1, 0, max(m.jerk.size - 1, 0))
        if m.jerk.size == 0:
            return np.zeros(tt.size, bool)
        const = (m.jerk[i] == 0.0) & (np.abs(m.state[i, 2]) == 0.0)
        at_feed = np.abs(m.state[i, 1] - self.feed) <= SPEED_RTOL * self.feed
        return const & at_feed & (tt >= 0) & (tt <= self.duration)

    def to_dict(self) -> dict:
        return {
            "path": self.path.to_dict(), "feed": self.feed, "a_max": self.a_max, "j_max": self.j_max,
            "duration": self.duration, "peak_speed": self.peak_speed,
            "slowdowns": [z.to_dict() for z in self.slowdowns], "stops": self.stops.tolist(),
        }


# ---------------------------------------------------------------- planning
def chord_speed_limit(path: Path, tolerance: float, period: float) -> SpeedLimitFn:
    """Speed limit so that the straight line between consecutive setpoints
    stays within ``tolerance`` of the path (Jiang, 1987: too high a speed for
    the period leaves the path).

    ``v_lim(s) = arc(K, E) / period`` where ``arc`` is the arc length whose
    chord has sagitta E on a circle of radius K (Chen et al., 2013, eq. 11) and K the
    smallest radius of curvature within one grid cell either side.
    """
    E = check_positive(tolerance, "tolerance")
    dt = _check_period(period)
    sg, kg = path.curvature_grid()
    kpad = np.maximum(kg, np.maximum(np.concatenate([kg[1:], kg[-1:]]), np.concatenate([kg[:1], kg[:-1]])))

    def fn(s):
        k = np.interp(s, sg, kpad)
        # the max over the neighbouring cells bounds the curvature between grid points
        i = np.clip(np.searchsorted(sg, s), 0, sg.size - 1)
        k = np.maximum(k, kpad[i])
        with np.errstate(divide="ignore"):
            v = arc_step_for_tolerance(np.where(k > 0, 1.0 / k, np.inf), E) / dt
        return v, np.zeros(np.size(s), dtype=int)

    return fn


def plan_feed(
    path: Path,
    feed: float,
    a_max: float,
    j_max: float,
    *,
    speed_limit: SpeedLimitFn | None = None,
    reasons: Sequence[str] = (),
    tolerance: float | None = None,
    period: float | None = None,
    axes: Any = None,
) -> FeedPlan:
    """Plan the tool's motion along ``path`` at the commanded ``feed``.

    Where no limit is below the feed, a stretch between two stops is the
    closed-form rest-to-rest profile (``plan_move`` of its length, exactly
    time-optimal). Otherwise it is timed by the path-timing engine
    (:func:`trajkit.timing.plan_path_timing`) under the feed, the speed-limit
    curve, the tangential acceleration and jerk and, with ``axes``, the
    machine axes' own velocity, acceleration and jerk limits.

    Parameters
    ----------
    path : Path
    feed : float
        Commanded tool speed [m/s], > 0.
    a_max, j_max : float
        Tangential acceleration [m/s^2] and jerk [m/s^3] limits, > 0.
    speed_limit : callable, optional
        ``fn(s) -> (v_lim, reason_index)`` for arc lengths ``s`` (n,): the
        highest allowed tool speed [m/s] and an index into ``reasons``.
    reasons : sequence of str
        Names of the speed-limit causes (e.g. ``"theta velocity"``).
    tolerance, period : float, optional
        When both are given, the speed is also limited so that the chord
        between two consecutive setpoints deviates from the path by at most
        ``tolerance`` [m] (see :func:`chord_speed_limit`).
    axes : tuple (joint_path, limits, names), optional
        Machine axes driven along the path: a :class:`trajkit.timing.JointPath`
        over the whole path's arc length, their :class:`~trajkit.AxisLimits`,
        and their names (for the slow-down reasons).

    Returns
    -------
    FeedPlan
        Starts and ends at rest; stops at the corners of a composite path;
        runs at ``feed`` exactly wherever no limit is below it.

    Raises
    ------
    InvalidInputError
        For a non-positive or non-finite feed, acceleration, jerk,
        tolerance or period, or a period outside [0.1 ms, 100 ms].
    """
    F = check_positive(feed, "feed")
    A = check_positive(a_max, "tangential acceleration a_max")
    J = check_positive(j_max, "tangential jerk j_max")
    if (tolerance is None) != (period is None):
        raise InvalidInputError("tolerance and period must be given together (or neither)")
    names = list(reasons)
    fns: list[tuple[SpeedLimitFn, int]] = []
    if speed_limit is not None:
        fns.append((speed_limit, 0))
    if tolerance is not None and period is not None:  # both or neither (checked above)
        fns.append((chord_speed_limit(path, tolerance, period), len(names)))
        names.append(CHORD_REASON)

    def cap(s):
        v = np.full(s.size, np.inf)
        why = np.zeros(s.size, dtype=int)
        for fn, base in fns:
            vi, ri = fn(s)
            lower = vi < v
            v = np.where(lower, vi, v)
            why = np.where(lower, ri + base, why)
        return v, why

    L = path.length
    stops = np.unique(np.concatenate([[0.0], path.corners(), [L]]))
    pieces: list[tuple[float, float]] = []
    slowdowns: list[Slowdown] = []
    profiles = []
    for s0, s1 in zip(stops[:-1], stops[1:]):
        grid = np.linspace(s0, s1, LIMIT_GRID)
        if fns:
            vg, _ = cap(grid)
            if np.any(~(vg > 0)):
                i = int(np.argmin(np.where(vg > 0, np.inf, 0.0)))
                raise InvalidInputError(f"speed limit is not positive at s={grid[i]!r} m: {vg[i]!r}")
        if axes is None and (not fns or bool(np.all(cap(grid)[0] >= F))):
            prof = plan_move(0.0, s1 - s0, AxisLimits(v_max=F, a_max=A, j_max=J, name="path"))
            pieces += [(d, j) for d, j in zip(prof.phase_durations, prof.jerks) if d > 0.0]
            profiles.append(prof)
            continue
        timing = _engine_stretch(path, s0, s1, F, A, J, cap, axes)
        profiles.append(timing)
        pieces += [(d, j) for d, j in zip(np.diff(timing.t), timing.jerk) if d > 0.0]
        slowdowns += _stretch_slowdowns(timing, s0, F, cap, names, axes)
    motion = JerkPieces(pieces, 0.0, L)
    return FeedPlan(path, F, A, J, motion, slowdowns, stops, profiles, names)


class _ArcLength:
    """The path parameter itself as the one joint (``q = s``): the tangential limits."""

    #: Exact derivatives are cheap: the timing engine checks its limits with them.
    cheap_derivatives = True

    def __init__(self, length: float) -> None:
        self.length = length
        self.n_joints = 1
        self.breakpoints = np.zeros(0)

    def derivatives(self, s: np.ndarray):
        s = np.asarray(s, dtype=float)
        one = np.ones((s.size, 1))
        zero = np.zeros((s.size, 1))
        return s[:, None], one, zero, zero.copy()


def _engine_stretch(path: Path, s0: float, s1: float, F: float, A: float, J: float, cap, axes):
    """The stretch [s0, s1] (rest to rest) timed by the path-timing engine."""
    from ..timing import PathRest, plan_path_timing

    def speed(s):
        return np.minimum(F, cap(s0 + np.asarray(s))[0]) if cap is not None else np.full(np.size(s), F)

    if axes is None:
        jp, lims = _ArcLength(s1 - s0), [AxisLimits(math.inf, A, J, name="path")]
        return plan_path_timing(jp, lims, speed=speed)
    base, lims, _names = axes
    return plan_path_timing(PathRest(base, s0, s1), list(lims), speed=speed, accel=A, jerk=J)


def ramp_mask(v: np.ndarray) -> np.ndarray:
    """Nodes on the ramps from and to rest: before the first and after the last local
    maximum of the planned speed ``v`` (their low speed is the start or the stop)."""
    n = v.size
    out = np.zeros(n, dtype=bool)
    if n < 3:
        return np.ones(n, dtype=bool)
    up = np.nonzero(np.diff(v) < 0.0)[0]
    first = int(up[0]) if up.size else n - 1
    down = np.nonzero(np.diff(v) > 0.0)[0]
    last = int(down[-1]) + 1 if down.size else 0
    out[:first] = True
    out[last + 1:] = True
    return out


def stretch_speed(v: np.ndarray, ramp: np.ndarray) -> float:
    """The slowest planned speed of a slow-down stretch off the ramps from and to rest
    (the fastest one when the stretch lies on a ramp)."""
    off = ~ramp
    return float(v[off].min()) if off.any() else float(v.max())


def _stretch_slowdowns(timing: Any, s0: float, F: float, cap, names: list[str], axes) -> list[Slowdown]:
    """Stretches where a speed limit is below the feed, split where the limit's level changes."""
    s = timing.grid
    v = timing.grid_speed
    vlim, why = cap(s0 + s)
    label = [names[w] if w < len(names) else "limit" for w in why]
    if axes is not None:
        _, d1, d2, d3 = timing.grid_derivatives
        lims = axes[1]
        ax_names = axes[2]
        qty = []
        for k, lm in enumerate(lims):
            with np.errstate(divide="ignore"):
                qty += [(lm.v_max / np.abs(d1[:, k]), f"{ax_names[k]} velocity"),
                        (np.sqrt(min(lm.a_max, lm.a_max_decel) / np.abs(d2[:, k])),
                         f"{ax_names[k]} acceleration"),
                        (np.cbrt(min(lm.j_max, lm.j_max_decel) / np.abs(d3[:, k])), f"{ax_names[k]} jerk")]
        for arr, nm in qty:
            lower = arr < vlim
            vlim = np.where(lower, arr, vlim)
            label = [nm if lw else lb for lw, lb in zip(lower, label)]
    limited = vlim < F * (1.0 - SLOWDOWN_RTOL)
    ramp = ramp_mask(v)
    band = np.floor(np.log(np.maximum(vlim, 1e-300) / F) / math.log(SLOWDOWN_BAND))
    out = []
    i = 0
    while i < s.size:
        if not limited[i]:
            i += 1
            continue
        j = i
        while j + 1 < s.size and limited[j + 1] and band[j + 1] == band[i]:
            j += 1
        seg = slice(i, j + 1)
        # the binding limit off the ramps from and to rest (where the speed is the
        # start or the stop, not the limit's), like the speed reported
        # (a stretch all on a ramp reports its fastest speed and the limit there)
        off = ~ramp[seg]
        k = i + (int(np.argmin(np.where(off, vlim[seg], np.inf))) if off.any()
                 else int(np.argmax(v[seg])))
        spd = stretch_speed(v[seg], ramp[seg])
        out.append(Slowdown(s0 + float(s[i]), s0 + float(s[j]), spd, float(vlim[k]), label[k]))
        i = j + 1
    return out
