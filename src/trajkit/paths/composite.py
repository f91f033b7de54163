"""A path made of segments joined end to end."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..errors import InvalidInputError
from ._tolerances import CORNER_ANGLE, JOIN_DIST
from .base import Path

__all__ = ["CompositePath"]


class CompositePath(Path):
    """Segments traversed one after the other.

    Parameters
    ----------
    segments : sequence of Path
        At least one; each must start where the previous one ends (within
        :data:`~trajkit.paths._tolerances.JOIN_DIST` [m]).
    corner_angle : float
        Tangent jump [rad] above which a junction is a corner (where the feed
        stops); smaller jumps (e.g. rounded taught points) are passed through,
        with a velocity direction step of ``feed * jump``.

    Attributes
    ----------
    segments : tuple of Path
    offsets : ndarray, shape (n_segments + 1,)
        Arc length [m] at the start of each segment, then the total length.

    Notes
    -----
    At a junction the point, tangent and curvature of the *following*
    segment are returned (the end of the path belongs to the last one).
    Junctions where the tangent turns by more than ``corner_angle`` are
    :meth:`corners`.
    """

    def __init__(self, segments: Sequence[Path], corner_angle: float = CORNER_ANGLE) -> None:
        segs = tuple(segments)
        if not segs:
            raise InvalidInputError("composite path needs at least one segment, got 0")
        for i, sg in enumerate(segs):
            if not isinstance(sg, Path):
                raise InvalidInputError(f"segment {i} must be a Path, got {type(sg).__name__}")
        for i in range(1, len(segs)):
            gap = float(np.linalg.norm(segs[i].start_point - segs[i - 1].end_point))
            if gap > JOIN_DIST:
                raise InvalidInputError(
                    f"segment {i} starts {gap:.6g} m away from the end of segment {i - 1} "
                    f"(joins must be within {JOIN_DIST} m)"
                )
        ca = float(corner_angle)
        if not (0.0 <= ca < math.pi):
            raise InvalidInputError(f"corner_angle must lie in [0, pi) rad, got {corner_angle!r}")
        self.corner_angle = ca
        self.segments = segs
        self.offsets = np.concatenate([[0.0], np.cumsum([sg.length for sg in segs])])
        self.length = float(self.offsets[-1])
        self.closed = bool(np.linalg.norm(segs[-1].end_point - segs[0].start_point) <= JOIN_DIST)
        corners = []
        for i in range(1, len(segs)):
            t0 = segs[i - 1].tangent(segs[i - 1].length)
            t1 = segs[i].tangent(0.0)
            ang = math.atan2(float(np.linalg.norm(np.cross(t0, t1))), float(np.dot(t0, t1)))
            if ang > ca:
                corners.append(self.offsets[i])
        self._corners = np.array(corners, dtype=float)

    def corners(self) -> np.ndarray:
        return self._corners.copy()

    def _split(self, s):
        k = np.searchsorted(self.offsets[1:-1], s, side="right")
        local = np.clip(s - self.offsets[k], 0.0, None)
        return k, local

    def _eval(self, s, name, width):
        k, local = self._split(s)
        out = np.empty((s.size, 3)) if width else np.empty(s.size)
        for i, sg in enumerate(self.segments):
            m = k == i
            if np.any(m):
                loc = np.minimum(local[m], sg.length)
                out[m] = getattr(sg, name)(loc)
        return out

    def _point(self, s):
        return self._eval(s, "_point", True)

    def _tangent(self, s):
        return self._eval(s, "_tangent", True)

    def _curvature(self, s):
        return self._eval(s, "_curvature", False)

    def uniform_nodes(self, n: int) -> np.ndarray:
        return np.linspace(0.0, self.length, int(n) + 1)

    def to_dict(self) -> dict:
        return {"type": "CompositePath", "length": self.length,
                "segments": [sg.to_dict() for sg in self.segments]}

    def __repr__(self) -> str:
        return f"CompositePath({len(self.segments)} segments, length={self.length!r})"
