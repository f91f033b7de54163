"""Exact evaluation of piecewise-constant-jerk motion (shared by every profile type)."""

from __future__ import annotations

import numpy as np

__all__ = ["eval_pieces"]


def eval_pieces(tc: np.ndarray, tb: np.ndarray, P: np.ndarray, V: np.ndarray,
                A: np.ndarray, J: np.ndarray):
    """Position, velocity, acceleration and jerk at times ``tc`` inside the pieces.

    Parameters
    ----------
    tc : ndarray
        Times [s], already clipped to ``[tb[0], tb[n]]``.
    tb : ndarray, shape (n + 1,)
        Piece start times, then the end time.
    P, V, A, J : ndarray, shape (n,)
        State at each piece start and the piece's constant jerk.

    Returns
    -------
    tuple of 4 ndarray shaped like ``tc``
        ``p0 + dt (v0 + dt (a0/2 + dt j/6))`` and its derivatives.
    """
    n = J.size
    idx = np.searchsorted(tb[1:n], tc, side="right")
    dt = tc - tb[idx]
    a = A[idx]
    j = J[idx]
    v = V[idx]
    pos = P[idx] + dt * (v + dt * (0.5 * a + dt * j / 6.0))
    vel = v + dt * (a + 0.5 * dt * j)
    acc = a + dt * j
    return pos, vel, acc, j
