"""Exact evaluation of piecewise-constant-jerk motion (shared by every profile type)."""

from __future__ import annotations

import numpy as np

from ._phase import phase_eval

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
    j = J[idx]
    pos, vel, acc = phase_eval(P[idx], V[idx], A[idx], j, dt)
    return pos, vel, acc, j
