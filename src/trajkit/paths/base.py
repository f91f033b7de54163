"""The common interface of geometric paths, parameterised by arc length."""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any

import numpy as np

from .._validate import check_array
from ..errors import InvalidInputError
from ._tolerances import MAX_COORDINATE, MIN_FEATURE, MIN_RELATIVE_FEATURE, S_RANGE_RTOL

__all__ = ["Path", "check_point", "check_size"]


def check_point(p: Any, field: str) -> np.ndarray:
    """A point (3,) [m] with finite coordinates within +-``MAX_COORDINATE``."""
    a = check_array(p, field, ndim=1, size=3)
    big = np.abs(a) > MAX_COORDINATE
    if big.any():
        k = int(np.argmax(big))
        raise InvalidInputError(
            f"{field}: coordinate {'xyz'[k]} = {a[k]:.6g} m is outside the supported range "
            f"+-{MAX_COORDINATE:g} m")
    return a


def check_size(value: float, field: str, *points: np.ndarray) -> float:
    """A length or radius [m] in [``MIN_FEATURE``, 2 ``MAX_COORDINATE``], and at least
    ``MIN_RELATIVE_FEATURE`` times the largest coordinate of ``points``."""
    if not MIN_FEATURE <= value <= 2.0 * MAX_COORDINATE:
        raise InvalidInputError(
            f"{field} {value:.6g} m is outside the supported range "
            f"[{MIN_FEATURE:g}, {2.0 * MAX_COORDINATE:g}] m")
    far = max((float(np.abs(p).max()) for p in points), default=0.0)
    if value < MIN_RELATIVE_FEATURE * far:
        raise InvalidInputError(
            f"{field} {value:.6g} m is too small for points {far:.6g} m from the origin "
            f"(at least {MIN_RELATIVE_FEATURE:g} of it: move the origin closer)")
    return value


class Path(ABC):
    """A curve in space parameterised by its arc length ``s`` [m].

    Every method takes ``s`` as a float or an array of shape (n,) and is
    vectorised: a scalar gives a (3,) vector (or a float), an array gives
    (n, 3) (or (n,)). ``s`` must lie in ``[0, length]``; a value outside
    (beyond round-off) is an :class:`~trajkit.InvalidInputError`.

    Attributes
    ----------
    length : float
        Arc length [m].
    closed : bool
        True when the end point is the start point (full circle, saddle seam).
    """

    length: float
    closed: bool = False

    # ------------------------------------------------------------ interface
    @abstractmethod
    def _point(self, s: np.ndarray) -> np.ndarray: ...

    @abstractmethod
    def _tangent(self, s: np.ndarray) -> np.ndarray: ...

    @abstractmethod
    def _curvature(self, s: np.ndarray) -> np.ndarray: ...

    def point(self, s: Any) -> np.ndarray:
        """Point at arc length ``s``: shape (3,) or (n, 3) [m]."""
        ss, scalar = self._prep(s)
        out = self._point(ss)
        return out[0] if scalar else out

    def tangent(self, s: Any) -> np.ndarray:
        """Unit tangent (direction of increasing ``s``): shape (3,) or (n, 3)."""
        ss, scalar = self._prep(s)
        out = self._tangent(ss)
        return out[0] if scalar else out

    def curvature(self, s: Any) -> np.ndarray | float:
        """Curvature [1/m] (1 / radius of curvature): float or shape (n,)."""
        ss, scalar = self._prep(s)
        out = self._curvature(ss)
        return float(out[0]) if scalar else out

    @property
    def start_point(self) -> np.ndarray:
        """First point, shape (3,) [m]."""
        return self.point(0.0)

    @property
    def end_point(self) -> np.ndarray:
        """Last point, shape (3,) [m]."""
        return self.point(self.length)

    def corners(self) -> np.ndarray:
        """Arc lengths [m] where the tangent jumps (the feed must stop there).

        Returns
        -------
        ndarray, shape (k,)
            Empty for a smooth path.
        """
        return np.empty(0)

    def uniform_nodes(self, n: int) -> np.ndarray:
        """Arc lengths of ``n`` equal steps of the path's natural parameter.

        For lines and arcs the natural parameter is the arc length (equal
        steps = equal angles on an arc); curves with another parameter
        (the saddle angle theta) override it.

        Returns
        -------
        ndarray, shape (n + 1,)
            Increasing, from 0 to ``length``.
        """
        return np.linspace(0.0, self.length, int(n) + 1)

    def curvature_grid(self, n: int = 4097) -> tuple[np.ndarray, np.ndarray]:
        """Curvature sampled on ``n`` equally spaced arc lengths.

        Returns
        -------
        s : ndarray, shape (n,)
        kappa : ndarray, shape (n,) [1/m]
        """
        s = np.linspace(0.0, self.length, n)
        return s, self._curvature(s)

    # -------------------------------------------------------------- helpers
    def _prep(self, s: Any) -> tuple[np.ndarray, bool]:
        arr = np.asarray(s, dtype=np.float64)
        scalar = arr.ndim == 0
        arr = np.atleast_1d(arr)
        if arr.ndim != 1:
            raise InvalidInputError(f"arc length s must be a number or a 1-D array, got shape {arr.shape}")
        if arr.size:
            slack = S_RANGE_RTOL * max(self.length, 1.0)
            lo, hi = float(np.min(arr)), float(np.max(arr))
            if not (np.isfinite(lo) and np.isfinite(hi)):
                raise InvalidInputError("arc length s must be finite")
            if lo < -slack or hi > self.length + slack:
                bad = lo if lo < -slack else hi
                raise InvalidInputError(
                    f"arc length s={bad!r} is outside the path [0, {self.length!r}] m"
                )
            arr = np.clip(arr, 0.0, self.length)
        return arr, scalar

    def to_dict(self) -> dict:
        """Plain description (type, length [m], geometry)."""
        return {"type": type(self).__name__, "length": self.length}
