"""The palletizing cell: static obstacles, the gripper volume, the growing stack.

Every solid here is a *prism*: a convex rectangle in the horizontal plane
(centre, half sizes, yaw) extruded over a height interval ``[z0, z1]``. The
conveyor, guides, end stop and pallet of a cell are axis-aligned prisms, the
placed boxes are prisms turned by their yaw, and the moving volume (the
vacuum gripper, with the box hanging below it while carrying) is one or two
prisms that follow the robot's joints.

Distances are exact: for two prisms the set of differences of their points
is the product of a convex polygon (the Minkowski difference of the
footprints) and an interval, so the Euclidean distance splits into

    d = sqrt(d_xy^2 + d_z^2)

with ``d_xy`` the distance between the two footprints and ``d_z`` the gap
between the height intervals (each 0 when they overlap). Two separated
convex polygons are closest at a vertex of one of them, so ``d_xy`` is the
smallest of eight point-to-rectangle distances. Overlapping prisms get a
negative *signed* distance: minus the smallest translation that separates
them (along a footprint edge normal or along z). The same numbers come from
``coal`` (tests cross-check them); these vectorised numpy formulas are much
faster for the thousands of poses a cycle needs.

The height a moving prism must keep over an obstacle follows from the same
split: with a horizontal distance ``d_xy`` below the clearance ``c`` its
bottom must be at least ``sqrt(c^2 - d_xy^2)`` above the obstacle's top
(:func:`required_height`).

All quantities in SI (m, rad).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._validate import check_finite, check_positive
from ..errors import InvalidInputError

__all__ = [
    "Obstacle",
    "GripperVolume",
    "Cell",
    "Prisms",
    "PRISM_FIELDS",
    "prism_signed_distance",
    "footprint_signed_distance",
    "moving_prisms",
    "required_height",
    "volume_floors",
    "footprint_distances",
    "stack_prisms",
    "DEFAULT_CLEARANCE",
    "DEFAULT_SETTLE",
]

#: Default clearance between the moving volume and every obstacle [m].
DEFAULT_CLEARANCE = 0.010

#: Default settle height above each pick and place [m]: only B moves there.
DEFAULT_SETTLE = 0.020


@dataclass(frozen=True)
class Obstacle:
    """A static obstacle: an axis-aligned box ``[x0, x1] x [y0, y1] x [z0, z1]`` [m]."""

    x: tuple[float, float]
    y: tuple[float, float]
    z: tuple[float, float]
    name: str = "obstacle"

    def __post_init__(self) -> None:
        for f in ("x", "y", "z"):
            iv = tuple(getattr(self, f))
            if len(iv) != 2:
                raise InvalidInputError(
                    f"obstacle {self.name!r}: {f} must be an interval [min, max], got {iv!r}"
                )
            lo = check_finite(iv[0], f"obstacle {self.name!r} {f} min")
            hi = check_finite(iv[1], f"obstacle {self.name!r} {f} max")
            if not hi > lo:
                raise InvalidInputError(
                    f"obstacle {self.name!r}: {f} max {hi!r} m must be above {f} min {lo!r} m"
                )
            object.__setattr__(self, f, (lo, hi))


@dataclass(frozen=True)
class GripperVolume:
    """The vacuum gripper: a box of ``length x width`` footprint and ``height`` [m].

    It sits on the gripper point (the top face of a carried box) and turns
    with the box (yaw ``theta + D``); ``None`` for length or width means
    "the box's footprint".
    """

    height: float = 0.1
    length: float | None = None
    width: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "height", check_positive(self.height, "gripper height"))
        for f in ("length", "width"):
            if getattr(self, f) is not None:
                object.__setattr__(self, f, check_positive(getattr(self, f), f"gripper {f}"))


@dataclass(frozen=True)
class Cell:
    """The geometry of a palletizing cell.

    Parameters
    ----------
    obstacles : sequence of Obstacle
        Static obstacles (conveyor, guides, end stop, pallet, fences).
    gripper : GripperVolume
        The gripper volume above the gripper point.
    clearance : float
        Smallest distance [m] between the moving volume and any obstacle
        while a horizontal joint moves (default 10 mm).
    settle : float
        Settle height [m] above each pick and place: the horizontal joints
        rest while B is closer than this to the trip's start or goal height
        (default 20 mm).
    box_at_pick : bool
        The next box waits at the pick during every return trip (an
        obstacle for the empty gripper).

    Notes
    -----
    Placed boxes are obstacles from their release on. While only B moves
    (at the start or goal pose of a trip), the moving volume may touch the
    obstacles it touches resting at that pose (its support, the placed
    neighbours it slides past) but never pierce them; every other obstacle
    keeps the clearance.
    """

    obstacles: tuple[Obstacle, ...] = ()
    gripper: GripperVolume = field(default_factory=GripperVolume)
    clearance: float = DEFAULT_CLEARANCE
    settle: float = DEFAULT_SETTLE
    box_at_pick: bool = True

    def __post_init__(self) -> None:
        obs = tuple(self.obstacles)
        for o in obs:
            if not isinstance(o, Obstacle):
                raise InvalidInputError(f"cell obstacles must be Obstacle objects, got {o!r}")
        object.__setattr__(self, "obstacles", obs)
        if not isinstance(self.gripper, GripperVolume):
            raise InvalidInputError(f"cell gripper must be a GripperVolume, got {self.gripper!r}")
        c = check_finite(self.clearance, "cell clearance")
        if c < 0.0:
            raise InvalidInputError(f"cell clearance must be >= 0 m, got {c!r}")
        s = check_finite(self.settle, "cell settle")
        if s < 0.0:
            raise InvalidInputError(f"cell settle must be >= 0 m, got {s!r}")
        object.__setattr__(self, "clearance", c)
        object.__setattr__(self, "settle", s)
        object.__setattr__(self, "box_at_pick", bool(self.box_at_pick))

    def static_prisms(self) -> Prisms:
        """The static obstacles as :class:`Prisms` (yaw 0)."""
        if not self.obstacles:
            return Prisms.empty()
        a = np.array([[*o.x, *o.y, *o.z] for o in self.obstacles], dtype=float)
        return Prisms(
            cx=0.5 * (a[:, 0] + a[:, 1]), cy=0.5 * (a[:, 2] + a[:, 3]),
            hx=0.5 * (a[:, 1] - a[:, 0]), hy=0.5 * (a[:, 3] - a[:, 2]),
            yaw=np.zeros(len(a)), z0=a[:, 4], z1=a[:, 5],
            names=tuple(o.name for o in self.obstacles),
        )

    def gripper_size(self, box_length: float, box_width: float) -> tuple[float, float, float]:
        """``(length, width, height)`` [m] of the gripper for a box footprint."""
        g = self.gripper
        return (g.length if g.length is not None else box_length,
                g.width if g.width is not None else box_width, g.height)

    def to_dict(self) -> dict:
        """JSON-ready description in mm."""
        g = self.gripper
        return {
            "clearance_mm": self.clearance * 1000,
            "settle_mm": self.settle * 1000,
            "box_at_pick": self.box_at_pick,
            "gripper_mm": {"height": g.height * 1000,
                           "length": None if g.length is None else g.length * 1000,
                           "width": None if g.width is None else g.width * 1000},
            "obstacles": [{"name": o.name, "x_mm": [v * 1000 for v in o.x],
                           "y_mm": [v * 1000 for v in o.y], "z_mm": [v * 1000 for v in o.z]}
                          for o in self.obstacles],
        }


# ------------------------------------------------------------------ prisms
#: The array fields of :class:`Prisms`, in constructor order.
PRISM_FIELDS = ("cx", "cy", "hx", "hy", "yaw", "z0", "z1")


@dataclass(frozen=True)
class Prisms:
    """A batch of prisms (arrays of equal shape, SI units).

    Attributes
    ----------
    cx, cy : ndarray
        Footprint centre [m].
    hx, hy : ndarray
        Half sizes along the prism's own x and y axes [m].
    yaw : ndarray
        Turn of the footprint about z [rad].
    z0, z1 : ndarray
        Bottom and top [m].
    names : tuple of str
        Labels (for reports); may be empty.
    """

    cx: np.ndarray
    cy: np.ndarray
    hx: np.ndarray
    hy: np.ndarray
    yaw: np.ndarray
    z0: np.ndarray
    z1: np.ndarray
    names: tuple[str, ...] = ()

    @staticmethod
    def empty() -> Prisms:
        z = np.zeros(0)
        return Prisms(z, z, z, z, z, z, z, ())

    @staticmethod
    def from_fields(arrays: Iterable[np.ndarray], names: tuple[str, ...] = ()) -> Prisms:
        """Prisms from the arrays of :data:`PRISM_FIELDS`, in that order."""
        cx, cy, hx, hy, yaw, z0, z1 = arrays
        return Prisms(cx, cy, hx, hy, yaw, z0, z1, names)

    def __len__(self) -> int:
        return int(np.shape(self.cx)[0]) if np.ndim(self.cx) else 1

    def concat(self, other: Prisms) -> Prisms:
        """Both batches in one (1-D batches)."""
        return Prisms.from_fields((np.concatenate([getattr(self, k), getattr(other, k)])
                                   for k in PRISM_FIELDS),
                                  names=tuple(self.names) + tuple(other.names))

    def take(self, idx: Any) -> Prisms:
        """A sub-batch (1-D batches)."""
        idx = np.asarray(idx, dtype=int)
        names = tuple(self.names[i] for i in idx) if self.names else ()
        return Prisms.from_fields((np.asarray(getattr(self, k))[idx] for k in PRISM_FIELDS), names=names)

    def corners(self) -> np.ndarray:
        """Footprint corners, shape (..., 4, 2) [m]."""
        c, s = np.cos(self.yaw), np.sin(self.yaw)
        out = []
        for sx, sy in ((1, 1), (-1, 1), (-1, -1), (1, -1)):
            dx, dy = sx * self.hx, sy * self.hy
            out.append(np.stack([self.cx + c * dx - s * dy, self.cy + s * dx + c * dy], -1))
        return np.stack(out, -2)


def stack_prisms(poses: Any, length: float, width: float, height: float,
                 names: Sequence[str] = ()) -> Prisms:
    """Placed boxes as prisms.

    Parameters
    ----------
    poses : array_like, shape (n, 4)
        Top-face centre and yaw of each box ``(x, y, z, yaw)`` [m, rad].
    length, width, height : float
        Box size [m].
    """
    p = np.asarray(poses, dtype=float).reshape(-1, 4)
    n = p.shape[0]
    return Prisms(p[:, 0].copy(), p[:, 1].copy(), np.full(n, 0.5 * length),
                  np.full(n, 0.5 * width), p[:, 3].copy(), p[:, 2] - height, p[:, 2].copy(),
                  tuple(names))


def moving_prisms(joints: Any, box: tuple[float, float, float],
                  gripper: tuple[float, float, float], carrying: bool) -> list[tuple[Prisms, float, float]]:
    """The moving volume at joint states as prisms.

    Parameters
    ----------
    joints : array_like, shape (n, 4)
        ``(theta, z, r, d)`` [rad, m, m, rad].
    box, gripper : (float, float, float)
        ``(length, width, height)`` [m] of the box and of the gripper.
    carrying : bool
        With the box hanging below the gripper point.

    Returns
    -------
    list of (Prisms, float, float)
        One entry per part (gripper, then the box when carrying): prisms of
        shape (n,), and the part's bottom and top relative to the gripper
        point [m].
    """
    q = np.asarray(joints, dtype=float).reshape(-1, 4)
    th, z, r, d = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    cx, cy, yaw = r * np.cos(th), r * np.sin(th), th + d
    parts = [(gripper, 0.0, gripper[2])]
    if carrying:
        parts.append((box, -box[2], 0.0))
    out = []
    for (L, W, _), lo, hi in parts:
        n = q.shape[0]
        out.append((Prisms(cx, cy, np.full(n, 0.5 * L), np.full(n, 0.5 * W), yaw, z + lo, z + hi),
                    lo, hi))
    return out


# -------------------------------------------------------------- distances
def _point_rect_distance(px, py, cx, cy, c, s, hx, hy):
    """Distance from points to rectangles (0 inside), broadcast."""
    dx, dy = px - cx, py - cy
    u = np.abs(c * dx + s * dy) - hx
    v = np.abs(-s * dx + c * dy) - hy
    return np.hypot(np.maximum(u, 0.0), np.maximum(v, 0.0))


def _proj_radius(hx, hy, c, s, ux, uy):
    """Half extent of a rectangle (axes (c, s), (-s, c)) along the unit axis (ux, uy)."""
    return hx * np.abs(c * ux + s * uy) + hy * np.abs(-s * ux + c * uy)


def footprint_signed_distance(a: Prisms, b: Prisms) -> np.ndarray:
    """Signed distance between the footprints of two prism batches (broadcast).

    Returns
    -------
    ndarray
        The distance between the two rectangles [m] when they are apart;
        minus the penetration depth (smallest separating translation) when
        they overlap; 0 when they touch.
    """
    ca, sa = np.cos(a.yaw), np.sin(a.yaw)
    cb, sb = np.cos(b.yaw), np.sin(b.yaw)
    dx, dy = b.cx - a.cx, b.cy - a.cy
    # separating-axis test on the four edge normals: overlap along each axis
    overlap: np.ndarray | None = None
    for ux, uy in ((ca, sa), (-sa, ca), (cb, sb), (-sb, cb)):
        ra = _proj_radius(a.hx, a.hy, ca, sa, ux, uy)
        rb = _proj_radius(b.hx, b.hy, cb, sb, ux, uy)
        o = ra + rb - np.abs(dx * ux + dy * uy)
        overlap = o if overlap is None else np.minimum(overlap, o)
    # apart: the closest points include a vertex of one of the rectangles
    dist: np.ndarray | None = None
    for (p, q, cq, sq) in ((a, b, cb, sb), (b, a, ca, sa)):
        cp, sp = np.cos(p.yaw), np.sin(p.yaw)
        for sx, sy in ((1, 1), (-1, 1), (-1, -1), (1, -1)):
            ex, ey = sx * p.hx, sy * p.hy
            px, py = p.cx + cp * ex - sp * ey, p.cy + sp * ex + cp * ey
            dd = _point_rect_distance(px, py, q.cx, q.cy, cq, sq, q.hx, q.hy)
            dist = dd if dist is None else np.minimum(dist, dd)
    assert overlap is not None and dist is not None  # the loops above are not empty
    return np.where(overlap > 0.0, -overlap, dist)


def prism_signed_distance(a: Prisms, b: Prisms) -> np.ndarray:
    """Exact signed distance between prisms (broadcast over the batches).

    ``sqrt(d_xy^2 + d_z^2)`` when both the footprints and the height
    intervals are apart, the larger of the two separations when only one
    is, and minus the smaller penetration (footprint or height) when both
    overlap.

    Returns
    -------
    ndarray
        Signed distance [m] (negative: penetration depth).
    """
    dxy = footprint_signed_distance(a, b)
    dz = np.maximum(b.z0 - a.z1, a.z0 - b.z1)
    both = (dxy > 0.0) & (dz > 0.0)
    return np.where(both, np.hypot(np.maximum(dxy, 0.0), np.maximum(dz, 0.0)),
                    np.maximum(dxy, dz))


def required_height(dxy: np.ndarray, top: np.ndarray, clearance: float) -> np.ndarray:
    """Lowest bottom height [m] of a moving prism that keeps ``clearance`` over an obstacle.

    Parameters
    ----------
    dxy : ndarray
        Signed footprint distance to the obstacle [m]
        (:func:`footprint_signed_distance`).
    top : ndarray
        Obstacle top [m] (broadcast with ``dxy``).
    clearance : float
        [m].

    Returns
    -------
    ndarray
        ``top + sqrt(c^2 - dxy^2)`` where ``0 <= dxy < c``, ``top + c``
        where the footprints overlap, ``-inf`` where ``dxy >= c`` (no
        constraint).
    """
    c = float(clearance)
    gap = np.where(dxy > 0.0, np.sqrt(np.maximum(c * c - dxy * dxy, 0.0)), c)
    return np.where(dxy >= c, -np.inf, top + gap)


def footprint_distances(joints: Any, box: tuple[float, float, float],
                        gripper: tuple[float, float, float], carrying: bool,
                        obstacles: Prisms, reach: float) -> list[tuple[np.ndarray, float]]:
    """Signed footprint distances of each moving part to each obstacle.

    Pairs whose bounding circles are more than ``reach`` apart are not
    computed (their distance is reported as ``+inf``).

    Parameters
    ----------
    joints : array_like, shape (n, 4)
    box, gripper : (float, float, float)
        ``(length, width, height)`` [m].
    carrying : bool
    obstacles : Prisms
        Batch of shape (m,).
    reach : float
        Distances above this are not needed [m].

    Returns
    -------
    list of (ndarray, float)
        Per moving part: the distances, shape (n, m) [m], and the part's
        bottom relative to the gripper point [m].
    """
    q = np.asarray(joints, dtype=float).reshape(-1, 4)
    n, m = q.shape[0], len(obstacles)
    keys = PRISM_FIELDS
    ob = {k: np.asarray(getattr(obstacles, k), dtype=float) for k in keys}
    r_ob = np.hypot(ob["hx"], ob["hy"])
    out = []
    for part, lo, _ in moving_prisms(q, box, gripper, carrying):
        d = np.full((n, m), np.inf)
        if m and n:
            r_mv = np.hypot(part.hx, part.hy)
            cd = np.hypot(part.cx[:, None] - ob["cx"][None, :], part.cy[:, None] - ob["cy"][None, :])
            near = cd <= r_mv[:, None] + r_ob[None, :] + reach
            ii, jj = np.nonzero(near)
            if ii.size:
                a = Prisms.from_fields(np.asarray(getattr(part, k))[ii] for k in keys)
                b = Prisms.from_fields(ob[k][jj] for k in keys)
                d[ii, jj] = footprint_signed_distance(a, b)
        out.append((d, lo))
    return out


def volume_floors(joints: Any, box: tuple[float, float, float],
                  gripper: tuple[float, float, float], carrying: bool, obstacles: Prisms,
                  clearance: float) -> np.ndarray:
    """Lowest B height that keeps the moving volume ``clearance`` above each obstacle.

    Parameters
    ----------
    joints : array_like, shape (n, 4)
        Joint states; only A, C and D (the footprint) matter.
    box, gripper : (float, float, float)
        ``(length, width, height)`` [m].
    carrying : bool
        With the box below the gripper point.
    obstacles : Prisms
        Batch of shape (m,).
    clearance : float
        [m].

    Returns
    -------
    ndarray, shape (n, m)
        Height [m] of the gripper point (joint B) at or above which the
        volume keeps the clearance over obstacle ``k``; ``-inf`` where the
        footprints are at least the clearance apart.
    """
    q = np.asarray(joints, dtype=float).reshape(-1, 4)
    out = np.full((q.shape[0], len(obstacles)), -np.inf)
    top = np.asarray(obstacles.z1, dtype=float).reshape(1, -1)
    for d, lo in footprint_distances(q, box, gripper, carrying, obstacles, clearance):
        np.maximum(out, required_height(d, top, clearance) - lo, out=out)
    return out
