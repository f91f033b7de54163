"""Spatial circular arc through three points (Jiang, 1987)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..errors import InvalidInputError
from ._tolerances import COINCIDENT_DIST, COLLINEAR_SIN, MAX_COORDINATE
from .base import Path, check_point, check_size

__all__ = ["Arc3", "circle_through"]


def circle_through(p1: Any, p2: Any, p3: Any) -> tuple[np.ndarray, float, np.ndarray]:
    """Centre, radius and unit normal of the circle through three points.

    The normal is oriented so that p1 -> p2 -> p3 runs counter-clockwise
    about it (right-hand rule).

    Parameters
    ----------
    p1, p2, p3 : array_like, shape (3,)
        Points [m].

    Returns
    -------
    centre : ndarray, shape (3,) [m]
    radius : float [m]
    normal : ndarray, shape (3,)

    Raises
    ------
    InvalidInputError
        When two points coincide or the three are collinear (no plane), a
        coordinate lies outside +-1e6 m, or the radius is outside
        [1e-9, 2e6] m.
    """
    a = check_point(p1, "arc point p1")
    b = check_point(p2, "arc point p2")
    c = check_point(p3, "arc point p3")
    pairs = ((("p1", a), ("p2", b)), (("p2", b), ("p3", c)), (("p1", a), ("p3", c)))
    for (n1, x), (n2, y) in pairs:
        if np.linalg.norm(y - x) <= COINCIDENT_DIST:
            raise InvalidInputError(
                f"arc points {n1}={x.tolist()} and {n2}={y.tolist()} coincide: no circle"
            )
    u = b - a
    v = c - a
    w = np.cross(u, v)
    nw = float(np.linalg.norm(w))
    sin_a = nw / (np.linalg.norm(u) * np.linalg.norm(v))
    if sin_a <= COLLINEAR_SIN:
        raise InvalidInputError(
            f"arc points p1={a.tolist()}, p2={b.tolist()}, p3={c.tolist()} are collinear "
            f"(sine of the angle at p1 {sin_a:.3g} <= {COLLINEAR_SIN}): no circle"
        )
    # centre = a + (|u|^2 (v x w) + |v|^2 (w x u)) / (2 |w|^2)
    centre = a + (np.dot(u, u) * np.cross(v, w) + np.dot(v, v) * np.cross(w, u)) / (2.0 * nw * nw)
    radius = float(np.mean([np.linalg.norm(p - centre) for p in (a, b, c)]))
    check_size(radius, "arc radius", a, b, c)
    if np.abs(centre).max() > 2.0 * MAX_COORDINATE:
        raise InvalidInputError(
            f"arc points p1={a.tolist()}, p2={b.tolist()}, p3={c.tolist()} are nearly collinear: "
            f"the centre lies {np.abs(centre).max():.3g} m away, outside the supported range")
    return centre, radius, w / nw


class Arc3(Path):
    """Circular arc from ``p1`` via ``p2`` to ``p3`` (Jiang, 1987), or the full circle.

    Parameters
    ----------
    p1, p2, p3 : array_like, shape (3,)
        Start point, a point on the way, end point [m].
    full_circle : bool
        When True, go all the way round: from ``p1`` via ``p2`` and ``p3``
        back to ``p1`` (sweep 2 pi).

    Attributes
    ----------
    centre : ndarray, shape (3,) [m]
    radius : float [m]
    normal : ndarray, shape (3,)
        Unit normal of the plane; the motion is counter-clockwise about it.
    sweep : float
        Swept angle [rad], in (0, 2 pi].
    u, w : ndarray, shape (3,)
        In-plane unit vectors: ``u`` from the centre to ``p1``, ``w = normal x u``.

    Notes
    -----
    Exact: ``point(s) = centre + radius (cos phi u + sin phi w)`` with
    ``phi = s / radius``; curvature ``1 / radius``.
    """

    def __init__(self, p1: Any, p2: Any, p3: Any, full_circle: bool = False) -> None:
        centre, radius, normal = circle_through(p1, p2, p3)
        a = np.asarray(p1, dtype=float)
        c = np.asarray(p3, dtype=float)
        u = (a - centre) / np.linalg.norm(a - centre)
        w = np.cross(normal, u)
        d3 = c - centre
        phi3 = math.atan2(float(np.dot(d3, w)), float(np.dot(d3, u))) % (2.0 * math.pi)
        self.p1 = a.copy()
        self.p2 = np.asarray(p2, dtype=float).copy()
        self.p3 = c.copy()
        self.centre = centre
        self.radius = radius
        self.normal = normal
        self.u = u
        self.w = w
        self.full_circle = bool(full_circle)
        self.closed = self.full_circle
        self.sweep = 2.0 * math.pi if self.full_circle else phi3
        self.length = self.radius * self.sweep

    def _phi(self, s):
        return s / self.radius

    def _point(self, s):
        phi = self._phi(s)
        return self.centre + self.radius * (np.cos(phi)[:, None] * self.u + np.sin(phi)[:, None] * self.w)

    def _tangent(self, s):
        phi = self._phi(s)
        return -np.sin(phi)[:, None] * self.u + np.cos(phi)[:, None] * self.w

    def _curvature(self, s):
        return np.full(s.size, 1.0 / self.radius)

    @property
    def end_point(self) -> np.ndarray:
        return (self.p1 if self.full_circle else self.p3).copy()

    def to_dict(self) -> dict:
        return {
            "type": "Arc3", "length": self.length, "p1": self.p1.tolist(), "p2": self.p2.tolist(),
            "p3": self.p3.tolist(), "centre": self.centre.tolist(), "radius": self.radius,
            "normal": self.normal.tolist(), "sweep": self.sweep, "full_circle": self.full_circle,
        }

    def __repr__(self) -> str:
        return (f"Arc3(centre={self.centre.tolist()}, radius={self.radius!r}, "
                f"sweep={self.sweep!r}, full_circle={self.full_circle})")
