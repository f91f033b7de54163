"""Jerk-limited feed along a path with a speed cap that varies along it.

The path is cut into *runs*: intervals of arc length with a speed cap and
their own path acceleration/jerk limits. The feed cruises at a constant speed
in each run and changes speed with jerk-limited S-curves (acceleration zero at
both ends), each placed inside the run with the higher speed, so the speed
never exceeds a cap. Where a run is too short for its transitions, its speed
is lowered (bisection) until they fit.

Pure math: numbers in, numbers out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Run", "Feed", "speed_change", "plan_feed"]

#: Relative tolerance of the run-speed fitting (bisection and convergence).
FIT_RTOL = 1e-9

#: Largest number of fitting sweeps over the runs.
FIT_MAX_SWEEPS = 500

#: Bisection steps when lowering a run speed.
FIT_BISECT_STEPS = 60


def speed_change(dv: float, a: float, j: float) -> tuple[float, float]:
    """Time-optimal jerk-limited speed change of ``dv`` >= 0, zero acceleration at both ends.

    Returns
    -------
    tj : float
        Duration of each of the two jerk phases [s].
    ta : float
        Duration of the constant-acceleration phase [s].
    """
    if dv <= 0.0:
        return 0.0, 0.0
    if dv >= a * a / j:
        return a / j, dv / a - a / j
    return math.sqrt(dv / j), 0.0


def _change_length(v0: float, v1: float, a: float, j: float) -> float:
    tj, ta = speed_change(abs(v1 - v0), a, j)
    return 0.5 * (v0 + v1) * (2.0 * tj + ta)


@dataclass
class Run:
    """An interval of the path with a speed cap.

    Attributes
    ----------
    s0, s1 : float
        Arc-length interval [m] (or path units).
    cap : float
        Speed cap [m/s], > 0.
    accel, jerk : float
        Path acceleration [m/s^2] and jerk [m/s^3] for speed changes inside it.
    speed : float
        The planned cruise speed (<= cap), set by :func:`plan_feed`.
    """

    s0: float
    s1: float
    cap: float
    accel: float
    jerk: float
    speed: float = 0.0

    @property
    def length(self) -> float:
        return self.s1 - self.s0


class Feed:
    """Piecewise-constant-jerk motion s(t) from rest to rest.

    Attributes
    ----------
    duration : float [s]
    length : float [m]
    """

    def __init__(self, pieces: list[tuple[float, float]], length: float) -> None:
        # pieces: (duration, jerk), integrated exactly from rest
        t, s, v, a = 0.0, 0.0, 0.0, 0.0
        rows = []
        for dur, jk in pieces:
            if dur <= 0.0:
                continue
            rows.append((t, s, v, a, jk))
            s = s + dur * (v + dur * (a / 2.0 + dur * jk / 6.0))
            v = v + dur * (a + dur * jk / 2.0)
            a = a + dur * jk
            t += dur
        self._t0 = np.array([r[0] for r in rows] + [t])
        self._st = np.array(rows).reshape(-1, 5)
        self.duration = t
        self.length = length
        self.end_error = s - length

    def sample(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Arc length, speed and acceleration at times ``t`` (n,) [s]."""
        tt = np.clip(np.asarray(t, dtype=np.float64), 0.0, self.duration)
        if self._st.shape[0] == 0:
            z = np.zeros_like(tt)
            return z, z.copy(), z.copy()
        k = np.clip(np.searchsorted(self._t0, tt, side="right") - 1, 0, self._st.shape[0] - 1)
        row = self._st[k]
        d = tt - row[:, 0]
        s0, v0, a0, jk = row[:, 1], row[:, 2], row[:, 3], row[:, 4]
        s = s0 + d * (v0 + d * (a0 / 2.0 + d * jk / 6.0))
        v = v0 + d * (a0 + d * jk / 2.0)
        a = a0 + d * jk
        s = np.minimum(s, self.length)
        s[tt >= self.duration] = self.length
        v[tt >= self.duration] = 0.0
        a[tt >= self.duration] = 0.0
        return s, np.maximum(v, 0.0), a


def _fit(run: Run, c_max: float, prev: float, nxt: float) -> float:
    def need(c: float) -> float:
        d = 0.0
        if c > prev:
            d += _change_length(prev, c, run.accel, run.jerk)
        if c > nxt:
            d += _change_length(c, nxt, run.accel, run.jerk)
        return d

    if need(c_max) <= run.length:
        return c_max
    lo = min(c_max, prev, nxt)
    hi = c_max
    for _ in range(FIT_BISECT_STEPS):
        mid = 0.5 * (lo + hi)
        if need(mid) <= run.length:
            lo = mid
        else:
            hi = mid
        if hi - lo <= FIT_RTOL * hi:
            break
    return lo


def plan_feed(runs: list[Run]) -> Feed:
    """Set each run's speed and return the rest-to-rest feed over all runs.

    Parameters
    ----------
    runs : list of Run
        Contiguous, increasing, each of positive length.

    Returns
    -------
    Feed
    """
    n = len(runs)
    for r in runs:
        r.speed = r.cap
    for _ in range(FIT_MAX_SWEEPS):
        changed = False
        for i, r in enumerate(runs):
            prev = runs[i - 1].speed if i > 0 else 0.0
            nxt = runs[i + 1].speed if i + 1 < n else 0.0
            c = _fit(r, r.speed, prev, nxt)
            if c < r.speed * (1.0 - FIT_RTOL):
                changed = True
            r.speed = min(c, r.speed)
        if not changed:
            break
    pieces: list[tuple[float, float]] = []
    for i, r in enumerate(runs):
        prev = runs[i - 1].speed if i > 0 else 0.0
        nxt = runs[i + 1].speed if i + 1 < n else 0.0
        c = r.speed
        used = 0.0
        if c > prev:
            tj, ta = speed_change(c - prev, r.accel, r.jerk)
            pieces += [(tj, r.jerk), (ta, 0.0), (tj, -r.jerk)]
            used += _change_length(prev, c, r.accel, r.jerk)
        down = []
        if c > nxt:
            tj, ta = speed_change(c - nxt, r.accel, r.jerk)
            down = [(tj, -r.jerk), (ta, 0.0), (tj, r.jerk)]
            used += _change_length(c, nxt, r.accel, r.jerk)
        cruise = max(r.length - used, 0.0)
        if c > 0.0:
            pieces.append((cruise / c, 0.0))
        pieces += down
    return Feed(pieces, runs[-1].s1 - runs[0].s0 if runs else 0.0)
