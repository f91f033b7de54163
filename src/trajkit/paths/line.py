"""Straight line segment (continuous-path control along a line, Jiang 1987)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import InvalidInputError
from ._tolerances import COINCIDENT_DIST
from .base import Path, check_point, check_size

__all__ = ["Line"]


class Line(Path):
    """Straight segment from ``p0`` to ``p1``.

    Parameters
    ----------
    p0, p1 : array_like, shape (3,)
        End points [m].

    Raises
    ------
    InvalidInputError
        For coordinates that are not finite or outside +-1e6 m, or a line
        shorter than 1 nm (see :mod:`trajkit.paths._tolerances`).

    Notes
    -----
    Exact: ``point(s) = p0 + s * u`` with ``u = (p1 - p0) / |p1 - p0|``,
    curvature 0.
    """

    def __init__(self, p0: Any, p1: Any) -> None:
        a = check_point(p0, "line start p0")
        b = check_point(p1, "line end p1")
        d = b - a
        length = float(np.linalg.norm(d))
        if length <= COINCIDENT_DIST:
            raise InvalidInputError(
                f"line has zero length: p0={a.tolist()} and p1={b.tolist()} coincide "
                f"(distance {length!r} m <= {COINCIDENT_DIST})"
            )
        check_size(length, "line length", a, b)
        self.p0 = a
        self.p1 = b
        self.length = length
        self.direction = d / length

    def _point(self, s):
        return self.p0 + s[:, None] * self.direction

    def _tangent(self, s):
        return np.broadcast_to(self.direction, (s.size, 3)).copy()

    def _curvature(self, s):
        return np.zeros(s.size)

    @property
    def end_point(self) -> np.ndarray:
        return self.p1.copy()

    def to_dict(self) -> dict:
        return {"type": "Line", "length": self.length, "p0": self.p0.tolist(), "p1": self.p1.tolist()}

    def __repr__(self) -> str:
        return f"Line(p0={self.p0.tolist()}, p1={self.p1.tolist()})"
