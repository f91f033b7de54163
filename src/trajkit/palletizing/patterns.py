"""Layer patterns for palletizing: column, interlock, pinwheel and the ``seed`` preset.

A *layer pattern* lists the boxes of one layer as centre offsets from the
pallet centre [m] and yaw angles [rad]; a :class:`StackPattern` adds the
rule for alternate layers (none, turned 180 degrees about the pallet centre,
or mirrored about the pallet's x axis). Every function works in SI units and
checks that each box lies on the pallet and that no two boxes overlap.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._validate import check_array, check_positive
from ..errors import InvalidInputError

__all__ = [
    "BoxSize",
    "LayerPattern",
    "StackPattern",
    "ALTERNATE_MODES",
    "PATTERN_NAMES",
    "seed_layer",
    "column_layer",
    "interlock_layer",
    "pinwheel_layer",
    "make_pattern",
    "check_layer_fit",
]

#: Rules for the alternate (2nd, 4th, ...) layers.
ALTERNATE_MODES = ("none", "rotate180", "mirror")

#: Pattern generators by name (see :func:`make_pattern`).
PATTERN_NAMES = ("seed", "column", "interlock", "pinwheel")

#: Geometric tolerance [m] for fit and overlap checks (a micrometre: boxes
#: that touch are fine, float round-off must not flag them).
FIT_ATOL = 1e-6


@dataclass(frozen=True)
class BoxSize:
    """Size of a box [m]: ``length`` along its own x axis (yaw 0 = along the world x)."""

    length: float
    width: float
    height: float

    def __post_init__(self) -> None:
        for f in ("length", "width", "height"):
            object.__setattr__(self, f, check_positive(getattr(self, f), f"box {f}"))


@dataclass(frozen=True)
class LayerPattern:
    """One layer of boxes.

    Attributes
    ----------
    offsets : ndarray, shape (n, 2)
        Box centre offsets from the pallet centre [m].
    yaw : ndarray, shape (n,)
        Box yaw [rad] (0: the box's long side along the pallet x axis).
    box : BoxSize
    name : str
    """

    offsets: np.ndarray
    yaw: np.ndarray
    box: BoxSize
    name: str = "custom"

    def __post_init__(self) -> None:
        off = check_array(self.offsets, "offsets", ndim=2)
        if off.shape[1] != 2 or off.shape[0] == 0:
            raise InvalidInputError(f"offsets must have shape (n, 2) with n >= 1, got {off.shape}")
        yaw = check_array(self.yaw, "yaw", ndim=1, size=off.shape[0])
        off.setflags(write=False)
        yaw.setflags(write=False)
        object.__setattr__(self, "offsets", off)
        object.__setattr__(self, "yaw", yaw)

    @property
    def n_boxes(self) -> int:
        return int(self.offsets.shape[0])

    def rotated180(self) -> LayerPattern:
        """The layer turned 180 degrees about the pallet centre."""
        return LayerPattern(-self.offsets, self.yaw + math.pi, self.box, self.name + " (rot 180)")

    def mirrored(self) -> LayerPattern:
        """The layer mirrored about the pallet's x axis (y -> -y, yaw -> -yaw)."""
        return LayerPattern(self.offsets * np.array([1.0, -1.0]), -self.yaw, self.box,
                            self.name + " (mirror)")

    def footprints(self) -> np.ndarray:
        """Corners of every box, shape (n, 4, 2) [m], relative to the pallet centre."""
        hl, hw = 0.5 * self.box.length, 0.5 * self.box.width
        local = np.array([[hl, hw], [-hl, hw], [-hl, -hw], [hl, -hw]])
        c, s = np.cos(self.yaw), np.sin(self.yaw)
        rot = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)  # (n,2,2)
        return self.offsets[:, None, :] + np.einsum("nij,kj->nki", rot, local)


@dataclass(frozen=True)
class StackPattern:
    """A layer pattern plus the rule for alternate layers.

    Parameters
    ----------
    layer : LayerPattern
        Pattern of the 1st, 3rd, 5th, ... layer.
    alternate : {"none", "rotate180", "mirror"}
        Pattern of the 2nd, 4th, ... layer.
    """

    layer: LayerPattern
    alternate: str = "rotate180"

    def __post_init__(self) -> None:
        if self.alternate not in ALTERNATE_MODES:
            raise InvalidInputError(
                f"alternate must be one of {ALTERNATE_MODES}, got {self.alternate!r}"
            )

    def layer_at(self, k: int) -> LayerPattern:
        """Pattern of layer ``k`` (0-based)."""
        if k % 2 == 0 or self.alternate == "none":
            return self.layer
        return self.layer.rotated180() if self.alternate == "rotate180" else self.layer.mirrored()

    def box_poses(self, n_layers: int, centre: Any, box_height: float | None = None) -> np.ndarray:
        """Gripper poses of every box of the stack, in placing order.

        Parameters
        ----------
        n_layers : int
            Number of layers (>= 1).
        centre : array_like, shape (3,)
            Pallet centre on its top face ``(x, y, z)`` [m] in the robot base frame.
        box_height : float, optional
            Box height [m]; defaults to ``layer.box.height``.

        Returns
        -------
        ndarray, shape (n_layers * n_boxes, 4)
            ``(x, y, z, yaw)`` [m, rad]: the centre of each box's top face
            (``z = centre_z + height * (k + 1)`` for layer ``k``) and its yaw.
        """
        if int(n_layers) != n_layers or n_layers < 1:
            raise InvalidInputError(f"layers must be an integer >= 1, got {n_layers!r}")
        c = check_array(centre, "pallet centre", ndim=1, size=3)
        h = self.layer.box.height if box_height is None else check_positive(box_height, "box height")
        out = []
        for k in range(int(n_layers)):
            lay = self.layer_at(k)
            z = c[2] + h * (k + 1)
            for (dx, dy), yw in zip(lay.offsets, lay.yaw):
                out.append((c[0] + dx, c[1] + dy, z, yw))
        return np.array(out)


def check_layer_fit(layer: LayerPattern, pallet_length: float, pallet_width: float,
                    overhang: float = 0.0) -> None:
    """Raise unless every box lies on the pallet and no two boxes overlap.

    Parameters
    ----------
    layer : LayerPattern
    pallet_length, pallet_width : float
        Pallet size along its x and y axes [m].
    overhang : float
        Allowed overhang past the pallet edge [m] (>= 0).

    Raises
    ------
    InvalidInputError
        A box over the pallet edge (the message names the box, the side, the
        coordinate and the bound) or two overlapping boxes.
    """
    L = check_positive(pallet_length, "pallet length")
    W = check_positive(pallet_width, "pallet width")
    if not (math.isfinite(overhang) and overhang >= 0.0):
        raise InvalidInputError(f"overhang must be finite and >= 0 m, got {overhang!r}")
    fp = layer.footprints()
    hx, hy = 0.5 * L + overhang + FIT_ATOL, 0.5 * W + overhang + FIT_ATOL
    for i in range(fp.shape[0]):
        xs, ys = fp[i, :, 0], fp[i, :, 1]
        for val, bound, side in ((xs.max(), hx, "+x"), (-xs.min(), hx, "-x"),
                                 (ys.max(), hy, "+y"), (-ys.min(), hy, "-y")):
            if val > bound:
                raise InvalidInputError(
                    f"box {i} of layer pattern {layer.name!r} is over the pallet edge on the "
                    f"{side} side: it reaches {val * 1000:.1f} mm from the centre, the pallet "
                    f"edge is at {(bound - FIT_ATOL) * 1000:.1f} mm"
                )
    # pairs whose bounding boxes overlap; exact for boxes turned by multiples of 90 deg
    lo, hi = fp.min(axis=1), fp.max(axis=1)
    sep = ((lo[:, None, :] >= hi[None, :, :] - FIT_ATOL)
           | (lo[None, :, :] >= hi[:, None, :] - FIT_ATOL)).any(axis=2)
    quarter = np.abs(np.sin(2.0 * layer.yaw)) <= FIT_ATOL
    ii, jj = np.nonzero(np.triu(~sep, 1))
    for i, j in zip(ii.tolist(), jj.tolist()):
        if (quarter[i] and quarter[j]) or _overlap(fp[i], fp[j]):
            raise InvalidInputError(
                f"boxes {i} and {j} of layer pattern {layer.name!r} overlap "
                f"(centres {tuple(np.round(layer.offsets[i] * 1000, 1))} and "
                f"{tuple(np.round(layer.offsets[j] * 1000, 1))} mm)"
            )


def _overlap(p: np.ndarray, q: np.ndarray) -> bool:
    """Separating-axis test for two convex quadrilaterals, shape (4, 2) each."""
    for poly in (p, q):
        edges = np.roll(poly, -1, axis=0) - poly
        normals = np.stack([-edges[:, 1], edges[:, 0]], axis=1)
        for nrm in normals:
            nrm = nrm / np.hypot(*nrm)
            a, b = p @ nrm, q @ nrm
            if a.max() <= b.min() + FIT_ATOL or b.max() <= a.min() + FIT_ATOL:
                return False
    return True


# ---------------------------------------------------------------- generators
def seed_layer(box: BoxSize | None = None) -> LayerPattern:
    """The ``seed`` preset: the layer of the shipped job on a 1200 x 1000 mm pallet.

    Cao et al. (2012) give no picture of their layer; this is trajkit's
    choice for their 600 x 400 mm boxes (see docs/palletizing.md).

    Two boxes long side along x at (-300, -300) and (300, -300) mm, three
    boxes turned 90 degrees at (-400, 200), (0, 200), (400, 200) mm from the
    pallet centre; boxes 600 x 400 x 200 mm unless ``box`` is given.
    """
    box = box or BoxSize(0.6, 0.4, 0.2)
    off = np.array([[-0.3, -0.3], [0.3, -0.3], [-0.4, 0.2], [0.0, 0.2], [0.4, 0.2]])
    yaw = np.array([0.0, 0.0, 0.5 * math.pi, 0.5 * math.pi, 0.5 * math.pi])
    return LayerPattern(off, yaw, box, "seed")


def _row(n: int, pitch: float) -> np.ndarray:
    return (np.arange(n) - 0.5 * (n - 1)) * pitch


def column_layer(pallet_length: float, pallet_width: float, box: BoxSize) -> LayerPattern:
    """A grid of boxes all turned the same way, centred on the pallet.

    The orientation (long side along x or along y) that holds more boxes is
    used (along x on a tie).

    Raises
    ------
    InvalidInputError
        Not even one box fits on the pallet.
    """
    L = check_positive(pallet_length, "pallet length")
    W = check_positive(pallet_width, "pallet width")
    best = None
    for yaw, bx, by in ((0.0, box.length, box.width), (0.5 * math.pi, box.width, box.length)):
        nx, ny = int(math.floor(L / bx + FIT_ATOL)), int(math.floor(W / by + FIT_ATOL))
        if nx * ny > (best[0] * best[1] if best else 0):
            best = (nx, ny, yaw, bx, by)
    if best is None:
        raise InvalidInputError(
            f"box {box.length * 1000:g} x {box.width * 1000:g} mm does not fit on the pallet "
            f"{L * 1000:g} x {W * 1000:g} mm"
        )
    nx, ny, yaw, bx, by = best
    xs, ys = np.meshgrid(_row(nx, bx), _row(ny, by))
    off = np.column_stack([xs.ravel(), ys.ravel()])
    return LayerPattern(off, np.full(off.shape[0], yaw), box, "column")


def interlock_layer(pallet_length: float, pallet_width: float, box: BoxSize) -> LayerPattern:
    """Rows of boxes along x, then rows of boxes turned 90 degrees, centred on the pallet.

    ``m`` rows of boxes with the long side along x (depth = box width each)
    and ``k`` rows of turned boxes (depth = box length) are chosen to hold
    the most boxes, preferring mixed layers (which interlock when alternate
    layers are turned or mirrored). On a 1200 x 1000 pallet with 600 x 400
    boxes this gives the ``seed`` layer.
    """
    L = check_positive(pallet_length, "pallet length")
    W = check_positive(pallet_width, "pallet width")
    n_a = int(math.floor(L / box.length + FIT_ATOL))   # boxes per row, long side along x
    n_b = int(math.floor(L / box.width + FIT_ATOL))    # boxes per row, turned
    best = None
    for m in range(int(math.floor(W / box.width + FIT_ATOL)) + 1):
        rest = W - m * box.width
        k = int(math.floor(rest / box.length + FIT_ATOL)) if rest > 0 else 0
        count = m * n_a + k * n_b
        key = (count, m > 0 and k > 0)
        if count > 0 and (best is None or key > best[0]):
            best = (key, m, k)
    if best is None:
        raise InvalidInputError(
            f"box {box.length * 1000:g} x {box.width * 1000:g} mm does not fit on the pallet "
            f"{L * 1000:g} x {W * 1000:g} mm"
        )
    _, m, k = best
    depth = m * box.width + k * box.length
    y = -0.5 * depth
    off, yaw = [], []
    for _ in range(m):
        yc = y + 0.5 * box.width
        off += [(x, yc) for x in _row(n_a, box.length)]
        yaw += [0.0] * n_a
        y += box.width
    for _ in range(k):
        yc = y + 0.5 * box.length
        off += [(x, yc) for x in _row(n_b, box.width)]
        yaw += [0.5 * math.pi] * n_b
        y += box.length
    return LayerPattern(np.array(off), np.array(yaw), box, "interlock")


def pinwheel_layer(pallet_length: float, pallet_width: float, box: BoxSize,
                   per_arm: int | None = None) -> LayerPattern:
    """Four arms of boxes turning about the pallet centre (a pinwheel).

    Each arm is a block of ``per_arm`` boxes side by side (block
    ``length x per_arm*width``); the four blocks are turned by 90 degrees
    each around a central gap, within a square of side
    ``length + per_arm*width``.

    Parameters
    ----------
    per_arm : int, optional
        Boxes per arm; default: the most that fit in the smaller pallet side.

    Raises
    ------
    InvalidInputError
        The pinwheel does not fit, or the block is square (use a column).
    """
    L = check_positive(pallet_length, "pallet length")
    W = check_positive(pallet_width, "pallet width")
    side = min(L, W)
    if per_arm is None:
        per_arm = int(math.floor((side - box.length) / box.width + FIT_ATOL))
    if int(per_arm) != per_arm or per_arm < 1:
        raise InvalidInputError(
            f"pinwheel per_arm must be an integer >= 1 and fit on the pallet, got {per_arm!r} "
            f"(pallet side {side * 1000:g} mm, box {box.length * 1000:g} x {box.width * 1000:g} mm)"
        )
    per_arm = int(per_arm)
    a, b = box.length, per_arm * box.width  # block size
    if abs(a - b) <= FIT_ATOL:
        raise InvalidInputError(
            f"pinwheel blocks are square ({a * 1000:g} mm): use the column pattern"
        )
    # block 0: long side a along x, at the bottom-left of the (a+b) square
    cx, cy = -0.5 * b, -0.5 * a
    rel = _row(per_arm, box.width)  # boxes of a block, along its b side
    off, yaw = [], []
    for q in range(4):
        ang = 0.5 * math.pi * q
        c, s = math.cos(ang), math.sin(ang)
        for r in rel:
            # boxes of block 0 lie side by side along y (the block's b side)
            px, py = cx, cy + r
            off.append((c * px - s * py, s * px + c * py))
            yaw.append(ang)
    lay = LayerPattern(np.array(off), np.array(yaw), box, "pinwheel")
    return lay


def make_pattern(name: str, pallet_length: float, pallet_width: float, box: BoxSize,
                 alternate: str = "rotate180", overhang: float = 0.0) -> StackPattern:
    """Build a named pattern and check that it fits on the pallet.

    Parameters
    ----------
    name : {"seed", "column", "interlock", "pinwheel"}
    pallet_length, pallet_width : float
        Pallet size [m].
    box : BoxSize
    alternate : {"none", "rotate180", "mirror"}
    overhang : float
        Allowed overhang past the pallet edge [m].

    Returns
    -------
    StackPattern

    Raises
    ------
    InvalidInputError
        Unknown name, or a layer (or its alternate) that does not fit.
    """
    if name == "seed":
        layer = seed_layer(box)
    elif name == "column":
        layer = column_layer(pallet_length, pallet_width, box)
    elif name == "interlock":
        layer = interlock_layer(pallet_length, pallet_width, box)
    elif name == "pinwheel":
        layer = pinwheel_layer(pallet_length, pallet_width, box)
    else:
        raise InvalidInputError(f"pattern must be one of {PATTERN_NAMES}, got {name!r}")
    stack = StackPattern(layer, alternate)
    check_layer_fit(stack.layer_at(0), pallet_length, pallet_width, overhang)
    check_layer_fit(stack.layer_at(1), pallet_length, pallet_width, overhang)
    return stack
