"""Piecewise-constant-jerk motion in one coordinate (the path parameter s)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..profiles._phase import phase_eval
from ..profiles._pieces import eval_pieces

__all__ = ["JerkPieces", "velocity_change"]


def velocity_change(v1: float, v2: float, a_max: float, j_max: float) -> tuple[list[tuple[float, float]], float]:
    """Jerk-limited change of speed from ``v1`` to ``v2`` (acceleration 0 at both ends).

    The acceleration rises with jerk ``j_max`` to ``a_max`` (or less for a
    small change), holds, and falls back: the S-curve velocity transition.

    Parameters
    ----------
    v1, v2 : float
        Speeds [m/s], >= 0.
    a_max, j_max : float
        Acceleration [m/s^2] and jerk [m/s^3] limits, > 0.

    Returns
    -------
    pieces : list of (duration [s], jerk [m/s^3])
        Up to three pieces (empty for v1 == v2).
    distance : float
        Distance travelled [m], exactly (v1 + v2) / 2 * total duration.
    """
    dv = v2 - v1
    if dv == 0.0:
        return [], 0.0
    sg = 1.0 if dv > 0 else -1.0
    D = abs(dv)
    if D * j_max >= a_max * a_max:
        tj = a_max / j_max
        ta = D / a_max - tj
    else:
        tj = math.sqrt(D / j_max)
        ta = 0.0
    pieces = [(tj, sg * j_max), (ta, 0.0), (tj, -sg * j_max)]
    return [p for p in pieces if p[0] > 0.0], 0.5 * (v1 + v2) * (2.0 * tj + ta)


class JerkPieces:
    """Motion s(t) made of pieces of constant jerk, starting at rest at ``s0``.

    Parameters
    ----------
    pieces : sequence of (duration [s], jerk [unit/s^3])
    s0 : float
        Start position [unit].
    s_end : float
        Exact end position [unit]: samples at or after the end return it
        (the integration's round-off at the end is removed).

    Attributes
    ----------
    t : ndarray, shape (k + 1,)
        Piece boundaries [s]; ``t[-1]`` is the duration.
    state : ndarray, shape (k + 1, 3)
        Exact position, velocity, acceleration at each boundary.
    jerk : ndarray, shape (k,)
    """

    def __init__(self, pieces: Sequence[tuple[float, float]], s0: float, s_end: float) -> None:
        d = np.array([p[0] for p in pieces], dtype=float)
        j = np.array([p[1] for p in pieces], dtype=float)
        k = d.size
        t = np.zeros(k + 1)
        st = np.zeros((k + 1, 3))
        st[0] = (s0, 0.0, 0.0)
        for i in range(k):
            p, v, a = st[i]
            h = d[i]
            st[i + 1] = phase_eval(p, v, a, j[i], h)
            t[i + 1] = t[i] + h
        self.t = t
        self.state = st
        self.jerk = j
        self.s0 = float(s0)
        self.s_end = float(s_end)
        self.duration = float(t[-1])

    def sample(self, time) -> np.ndarray:
        """Position, velocity, acceleration, jerk at ``time`` [s], exact.

        Returns
        -------
        ndarray, shape (4, n)
            Times before 0 hold the start at rest, after the duration the end.
        """
        tt = np.atleast_1d(np.asarray(time, dtype=float))
        out = np.empty((4, tt.size))
        if self.jerk.size == 0:
            out[0] = self.s0
            out[1:] = 0.0
            return out
        tc = np.clip(tt, 0.0, self.duration)
        st = self.state[:-1]
        out[0], out[1], out[2], out[3] = eval_pieces(
            tc, self.t, st[:, 0], st[:, 1], st[:, 2], self.jerk)
        after = tt >= self.duration
        before = tt < 0.0
        out[0] = np.clip(out[0], min(self.s0, self.s_end), max(self.s0, self.s_end))
        out[0] = np.where(after, self.s_end, np.where(before, self.s0, out[0]))
        rest = after | before
        out[1:, rest] = 0.0
        return out
