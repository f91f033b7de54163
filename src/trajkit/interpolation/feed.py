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
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from .._sampling import MAX_SAMPLES, period_times
from .._validate import check_positive
from ..errors import InvalidInputError
from ..limits import AxisLimits
from ..paths.base import Path
from ..paths.chords import arc_step_for_tolerance
from ..profiles import plan_move
from ._pieces import JerkPieces, velocity_change

__all__ = ["Slowdown", "FeedSample", "FeedPlan", "plan_feed", "MIN_PERIOD", "MAX_PERIOD", "setpoint_times"]

#: Shortest and longest control period accepted [s] (0.1 ms ... seed 003's 100 ms).
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
        Lowest value of the speed-limit curve there [m/s].
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
    stays within ``tolerance`` of the path (seed 002: too high a speed for the
    period leaves the path).

    ``v_lim(s) = arc(K, E) / period`` where ``arc`` is the arc length whose
    chord has sagitta E on a circle of radius K (seed 003, eq. 11) and K the
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
) -> FeedPlan:
    """Plan the tool's motion along ``path`` at the commanded ``feed``.

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
    if tolerance is not None:
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
        zones = _zones(cap, s0, s1, F) if fns else []
        if not zones:
            prof = plan_move(0.0, s1 - s0, AxisLimits(v_max=F, a_max=A, j_max=J, name="path"))
            pieces += [(d, j) for d, j in zip(prof.phase_durations, prof.jerks) if d > 0.0]
            profiles.append(prof)
            continue
        profiles.append(None)
        plateaus = _plateaus(zones, s0, s1, F)
        _make_feasible(plateaus, A, J)
        pieces += _build(plateaus, A, J)
        for z0, z1, vmin, why in zones:
            spd = min(p[2] for p in plateaus if p[0] < z1 and p[1] > z0)
            slowdowns.append(Slowdown(z0, z1, spd, vmin, names[why] if why < len(names) else "limit"))
    motion = JerkPieces(pieces, 0.0, L)
    return FeedPlan(path, F, A, J, motion, slowdowns, stops, profiles, names)


def _zones(cap, s0: float, s1: float, F: float):
    """Regions of [s0, s1] where the speed limit is below the feed: (start, end, min, reason)."""
    s = np.linspace(s0, s1, LIMIT_GRID)
    v, why = cap(s)
    if np.any(~(v > 0)):
        i = int(np.argmin(np.where(v > 0, np.inf, 0.0)))
        raise InvalidInputError(f"speed limit is not positive at s={s[i]!r} m: {v[i]!r}")
    low = v < F
    out = []
    i = 0
    n = s.size
    while i < n:
        if not low[i]:
            i += 1
            continue
        k = i
        while k < n and low[k]:
            k += 1
        a, b = max(i - 1, 0), min(k, n - 1)  # the neighbouring grid points bound the region
        seg = slice(a, b + 1)
        m = a + int(np.argmin(v[seg]))
        vm, wm = _refine_min(cap, s[max(m - 1, 0)], s[min(m + 1, n - 1)], float(v[m]), int(why[m]))
        out.append((float(s[a]), float(s[b]), vm, wm))
        i = k
    # merge touching zones
    merged = []
    for z in out:
        if merged and z[0] <= merged[-1][1]:
            p = merged[-1]
            merged[-1] = (p[0], max(p[1], z[1]), min(p[2], z[2]), p[3] if p[2] <= z[2] else z[3])
        else:
            merged.append(z)
    return merged


def _refine_min(cap, lo: float, hi: float, vbest: float, wbest: int) -> tuple[float, int]:
    """Lowest speed limit in [lo, hi] by golden-section search (never above the grid value)."""
    g = (math.sqrt(5.0) - 1.0) / 2.0
    x1, x2 = hi - g * (hi - lo), lo + g * (hi - lo)
    (f1,), (w1,) = cap(np.array([x1]))
    (f2,), (w2,) = cap(np.array([x2]))
    for _ in range(REFINE_ITER):
        if f1 < f2:
            hi, x2, f2, w2 = x2, x1, f1, w1
            x1 = hi - g * (hi - lo)
            (f1,), (w1,) = cap(np.array([x1]))
        else:
            lo, x1, f1, w1 = x1, x2, f2, w2
            x2 = lo + g * (hi - lo)
            (f2,), (w2,) = cap(np.array([x2]))
    for f, w in ((f1, w1), (f2, w2)):
        if f < vbest:
            vbest, wbest = float(f), int(w)
    return vbest, wbest


def _plateaus(zones, s0, s1, F):
    """[start, end, level] list covering [s0, s1], with zero-length rests at both ends."""
    pl = [[s0, s0, 0.0]]
    cur = s0
    for z0, z1, vmin, _ in zones:
        if z0 > cur:
            pl.append([cur, z0, F])
        pl.append([max(z0, cur), z1, vmin])
        cur = z1
    if s1 > cur:
        pl.append([cur, s1, F])
    pl.append([s1, s1, 0.0])
    return pl


def _dist(v1, v2, A, J):
    return velocity_change(v1, v2, A, J)[1]


def _need(pl, i, level, A, J):
    need = 0.0
    for k in (i - 1, i + 1):
        lk = pl[k][2]
        if lk < level:
            need += _dist(lk, level, A, J)
    return need


def _make_feasible(pl, A, J) -> None:
    """Lower or merge plateaus until each is long enough for its speed changes."""
    for _ in range(100 * len(pl) + 100):
        changed = False
        # merge equal neighbours
        i = 1
        while i < len(pl) - 1:
            if i + 1 < len(pl) - 1 and pl[i][2] == pl[i + 1][2]:
                pl[i][1] = pl[i + 1][1]
                del pl[i + 1]
                continue
            i += 1
        for i in range(1, len(pl) - 1):
            length = pl[i][1] - pl[i][0]
            level = pl[i][2]
            if _need(pl, i, level, A, J) <= length * (1 + SPEED_RTOL):
                continue
            changed = True
            vn = max(pl[i - 1][2], pl[i + 1][2])
            if vn < level and _need(pl, i, vn, A, J) <= length:
                lo, hi = vn, level
                for _ in range(PLATEAU_BISECT):
                    mid = 0.5 * (lo + hi)
                    if _need(pl, i, mid, A, J) <= length:
                        lo = mid
                    else:
                        hi = mid
                    if hi - lo <= BISECT_RTOL * hi:
                        break
                pl[i][2] = lo
            else:
                # too short even at the faster neighbour's level: merge with it. That
                # neighbour is never a rest end (a rest end has level 0, and a plateau
                # between two zero levels always fits its own speed changes).
                j = i - 1 if pl[i - 1][2] >= pl[i + 1][2] else i + 1
                a, b = min(i, j), max(i, j)
                pl[a] = [pl[a][0], pl[b][1], min(pl[a][2], pl[b][2])]
                del pl[b]
            break
        if not changed:
            return
    raise InvalidInputError("feed planner did not converge (plateau lengths)")  # pragma: no cover


def _build(pl, A, J):
    """Constant-jerk pieces for a feasible plateau list."""
    out: list[tuple[float, float]] = []
    for i in range(1, len(pl) - 1):
        s_a, s_b, lv = pl[i]
        prev, nxt = pl[i - 1][2], pl[i + 1][2]
        up, d_up = velocity_change(prev, lv, A, J) if prev < lv else ([], 0.0)
        dn, d_dn = velocity_change(lv, nxt, A, J) if nxt < lv else ([], 0.0)
        cruise = max((s_b - s_a) - d_up - d_dn, 0.0)
        out += up
        if cruise > 0.0 and lv > 0.0:
            out.append((cruise / lv, 0.0))
        out += dn
    return out
