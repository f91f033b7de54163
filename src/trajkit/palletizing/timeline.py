"""Piecewise joint trajectories: timed sequences of per-joint :class:`Profile` pieces."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._sampling import MAX_SAMPLES, period_times
from ..errors import InvalidInputError
from ..profiles import Profile

__all__ = ["Piece", "Timeline", "TimelineSample", "CHAIN_RTOL"]

#: Relative tolerance for pieces that chain (start where the previous one
#: ended, in time and position): float round-off of absolute start times.
CHAIN_RTOL = 1e-12


@dataclass(frozen=True)
class Piece:
    """One rest-to-rest move of one joint, starting at absolute time ``t0`` [s]."""

    t0: float
    profile: Profile

    @property
    def t1(self) -> float:
        """End time [s]."""
        return self.t0 + self.profile.duration


@dataclass(frozen=True)
class TimelineSample:
    """Joint states at sampled times.

    Attributes
    ----------
    t : ndarray, shape (n,)
    position, velocity, acceleration, jerk : ndarray, shape (n, n_joints)
    """

    t: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray


class Timeline:
    """A multi-joint trajectory made of timed rest-to-rest pieces per joint.

    Between (and before / after) its pieces a joint rests. Pieces of one
    joint must not overlap and must chain (each starts where the previous
    one ended).

    Parameters
    ----------
    pieces : sequence of sequences of Piece
        ``pieces[k]`` is joint ``k``'s pieces in time order.
    start : array_like, shape (n_joints,)
        Joint positions before the first piece of each joint.
    duration : float
        Total duration [s] (>= the end of every piece).
    names : sequence of str, optional
    atol : float
        Relative tolerance for the chaining checks (:data:`CHAIN_RTOL`).

    Raises
    ------
    InvalidInputError
        Overlapping or non-chaining pieces, or a piece past ``duration``.
    """

    def __init__(self, pieces: Sequence[Sequence[Piece]], start: Any, duration: float,
                 names: Sequence[str] | None = None, atol: float = CHAIN_RTOL) -> None:
        self.pieces = tuple(tuple(p) for p in pieces)
        self.start = np.asarray(start, dtype=float).copy()
        self.duration = float(duration)
        n = len(self.pieces)
        self.names = tuple(names) if names is not None else tuple(f"q{k}" for k in range(n))
        if self.start.shape != (n,):
            raise InvalidInputError(f"start must have shape ({n},), got {self.start.shape}")
        for k, ps in enumerate(self.pieces):
            pos, tend = self.start[k], -np.inf
            for i, pc in enumerate(ps):
                scale = max(1.0, abs(pos))
                if pc.t0 < tend - atol * max(1.0, abs(tend)):
                    raise InvalidInputError(
                        f"piece {i} of joint {self.names[k]} starts at {pc.t0!r} s before the "
                        f"previous one ends at {tend!r} s"
                    )
                if abs(pc.profile.start - pos) > atol * scale:
                    raise InvalidInputError(
                        f"piece {i} of joint {self.names[k]} starts at {pc.profile.start!r}, "
                        f"not where the joint is ({pos!r})"
                    )
                pos, tend = pc.profile.goal, pc.t1
            if ps and tend > self.duration * (1 + atol) + atol:
                raise InvalidInputError(
                    f"joint {self.names[k]} moves until {tend!r} s, past the duration "
                    f"{self.duration!r} s"
                )
        self._starts = [np.array([pc.t0 for pc in ps]) for ps in self.pieces]

    @property
    def n_joints(self) -> int:
        return len(self.pieces)

    @property
    def goal(self) -> np.ndarray:
        """Joint positions at the end, shape (n_joints,)."""
        return np.array([ps[-1].profile.goal if ps else s for ps, s in zip(self.pieces, self.start)])

    def segment_boundaries(self) -> np.ndarray:
        """Sorted unique start and end times of every piece, plus 0 and ``duration`` [s]."""
        ts = [0.0, self.duration]
        for ps in self.pieces:
            for pc in ps:
                ts += [pc.t0, pc.t1]
        return np.unique(np.array(ts))

    def phase_boundary_states(self, joint: int) -> np.ndarray:
        """Exact states at every phase boundary of every piece of ``joint``.

        Returns
        -------
        ndarray, shape (8 * n_pieces, 4)
            Columns: absolute time [s], position, velocity, acceleration
            (from :meth:`Profile.boundary_states`).
        """
        rows = []
        for pc in self.pieces[joint]:
            bs = pc.profile.boundary_states()
            rows.append(np.column_stack([pc.t0 + pc.profile.phase_times, bs]))
        return np.vstack(rows) if rows else np.empty((0, 4))

    def sample(self, t: Any) -> TimelineSample:
        """Sample every joint at times ``t`` [s] (exact piecewise-cubic evaluation).

        Parameters
        ----------
        t : float or array_like, shape (n,)

        Returns
        -------
        TimelineSample
            Arrays of shape (n, n_joints).
        """
        tt = np.atleast_1d(np.asarray(t, dtype=np.float64))
        n = tt.shape[0]
        out = np.zeros((4, n, self.n_joints))
        for k, ps in enumerate(self.pieces):
            if not ps:
                out[0, :, k] = self.start[k]
                continue
            idx = np.searchsorted(self._starts[k], tt, side="right") - 1
            idx = np.clip(idx, 0, len(ps) - 1)
            for i in np.unique(idx):
                m = idx == i
                pc = ps[i]
                s = pc.profile.sample(tt[m] - pc.t0)
                out[0, m, k] = s.position
                out[1, m, k] = s.velocity
                out[2, m, k] = s.acceleration
                out[3, m, k] = s.jerk
        return TimelineSample(tt, out[0], out[1], out[2], out[3])

    def times(self, period: float, max_samples: int | None = MAX_SAMPLES) -> np.ndarray:
        """Times 0, dt, 2 dt, ... ending exactly at ``duration`` [s]; at most
        ``max_samples`` (see :func:`trajkit._sampling.period_times`)."""
        return period_times(self.duration, period, end="exact", max_samples=max_samples)

    def __repr__(self) -> str:
        return f"Timeline(n_joints={self.n_joints}, duration={self.duration!r})"
