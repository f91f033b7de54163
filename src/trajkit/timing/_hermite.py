"""Exact time pieces through the node states of the grid solution.

Between two nodes with states ``(v0, a0)`` and ``(v1, a1)`` a distance ``D``
apart, two pieces of constant jerk of equal duration ``h = tau / 2`` pass
through both states exactly when

    D = (v0 + v1) tau / 2 + (a0 - a1) tau^2 / 12,
    J1 = (v1 - v0 - (3 a0 + a1) h / 2) / h^2,    J2 = (a1 - a0) / h - J1

(the first line is a quadratic in tau with one positive root whenever the
states can be joined). An interval that starts or ends at rest is one jerk
phase: ``tau = sqrt(6 D / a)``, ``J = a / tau`` (``D = a tau^2 / 6``).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["hermite_pieces", "time_to_reach", "time_to_reach_one", "UnjoinableError"]


class UnjoinableError(ValueError):
    """Node states that pieces of constant jerk cannot join.

    Attributes
    ----------
    intervals : ndarray of int
        The grid intervals that cannot be joined.
    """

    def __init__(self, intervals: np.ndarray, what: str = "cannot be joined by constant-jerk pieces") -> None:
        self.intervals = np.asarray(intervals, dtype=int)
        super().__init__(f"grid interval {int(self.intervals[0])} {what}")


def hermite_pieces(s: np.ndarray, x: np.ndarray, u: np.ndarray, rest0: bool,
                   restN: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Durations and jerks of the pieces through the node states.

    Parameters
    ----------
    s : ndarray, shape (n,)
        Grid [path unit].
    x, u : ndarray, shape (n,)
        ``sdot^2`` and ``sddot`` at the nodes.
    rest0, restN : bool
        Whether the motion starts / ends at rest (one jerk phase there).

    Returns
    -------
    durations, jerks : ndarray, shape (k,)
    interval : ndarray of int, shape (k,)
        The grid interval of each piece.

    Raises
    ------
    UnjoinableError
        When node states cannot be joined (no positive duration), with every
        such interval.
    """
    D = np.diff(s)
    N = D.size
    v = np.sqrt(np.maximum(x, 0.0))
    v0, v1, a0, a1 = v[:-1], v[1:], u[:-1], u[1:]
    qa = (a0 - a1) / 12.0
    qb = 0.5 * (v0 + v1)
    disc = qb * qb + 4.0 * qa * D
    with np.errstate(divide="ignore", invalid="ignore"):
        tau = 2.0 * D / (qb + np.sqrt(np.maximum(disc, 0.0)))
        h = 0.5 * tau
        J1 = (v1 - v0 - (3.0 * a0 + a1) * h / 2.0) / (h * h)
        J2 = (a1 - a0) / h - J1
    special = np.zeros(N, dtype=bool)
    if rest0:
        special[0] = True
    if restN:
        special[-1] = True
    bad = ~special & ((disc < 0.0) | ~np.isfinite(tau) | (tau <= 0.0))
    if bad.any():
        raise UnjoinableError(np.nonzero(bad)[0])
    dur = np.column_stack([h, h]).ravel()
    jerk = np.column_stack([J1, J2]).ravel()
    keep = np.ones(2 * N, dtype=bool)
    for flag, i, a in ((rest0, 0, a1[0] if N else 0.0), (restN, N - 1, -a0[-1] if N else 0.0)):
        if not flag:
            continue
        a = max(float(a), 0.0)
        if a > 0.0:
            # one jerk phase from rest to acceleration a over the distance D:
            # D = a t^2 / 6 (the ratio first: no cube of a to under- or overflow)
            tr = math.sqrt(6.0 * (float(D[i]) / a))
            Jr = a / tr
        else:  # no acceleration at the neighbour node: constant speed is impossible from rest
            raise UnjoinableError(np.array([i]), "at rest has no acceleration")
        dur[2 * i], jerk[2 * i] = tr, Jr  # from rest up, or down to rest: jerk > 0 both
        keep[2 * i + 1] = False
    interval = np.repeat(np.arange(N), 2)
    return dur[keep], jerk[keep], interval[keep]


#: Bisection steps of :func:`time_to_reach` (each halves the bracket).
REACH_STEPS = 60

#: Newton steps of :func:`time_to_reach_one` (from 0 they approach the time from
#: below, 4-6 to round-off) and the relative step that ends them.
ONE_NEWTON = 30
ONE_NEWTON_RTOL = 1e-13


def time_to_reach(s0: np.ndarray | float, v0: np.ndarray | float, a0: np.ndarray | float,
                  jerk: np.ndarray | float, target: np.ndarray,
                  t_max: np.ndarray | float) -> np.ndarray:
    """The time at which pieces of constant jerk reach the positions ``target``.

    Parameters
    ----------
    s0, v0, a0, jerk : ndarray or float, broadcast to (n,)
        Every piece's start state and jerk [path unit, /s, /s^2, /s^3]; its
        speed must not fall below zero before ``t_max`` (``s`` increases).
    target : ndarray, shape (n,)
        The positions to reach [path unit].
    t_max : ndarray or float, broadcast to (n,)
        The end of every piece [s] (the bracket's upper end).

    Returns
    -------
    ndarray, shape (n,)
        The time inside ``[0, t_max]`` [s], by bisection (REACH_STEPS):
        ``t_max`` where the piece does not reach the target before its end.
    """
    lo = np.zeros(np.shape(target))
    hi = np.broadcast_to(np.asarray(t_max, dtype=float), lo.shape).copy()
    for _ in range(REACH_STEPS):
        h = 0.5 * (lo + hi)
        before = s0 + h * (v0 + h * (0.5 * a0 + h * jerk / 6.0)) < target
        lo, hi = np.where(before, h, lo), np.where(before, hi, h)
    return 0.5 * (lo + hi)


def time_to_reach_one(v: float, u: float, J: float, length: float, t_max: float) -> float:
    """:func:`time_to_reach` for one piece slowing down, in floats: the time a piece
    of jerk ``J`` from speed ``v`` and acceleration ``u < 0`` takes to run
    ``length``, reached before ``t_max = -u / J`` (where its speed, still
    positive, is lowest). Newton's method from 0, which approaches the root from
    below (the distance is concave in the time up to ``t_max``); a few
    microseconds where the bisection of arrays of one takes half a millisecond.
    """
    t = 0.0
    for _ in range(ONE_NEWTON):
        step = (length - t * (v + t * (0.5 * u + t * J / 6.0))) / (v + t * (u + 0.5 * t * J))
        t = min(t + step, t_max)
        if step <= ONE_NEWTON_RTOL * t:
            break
    return t
