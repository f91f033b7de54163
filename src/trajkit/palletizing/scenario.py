"""A palletizing scenario: robot, pick point, pallet, pattern, and its trips.

All quantities in SI (m, rad, s). :func:`seed_scenario` is the palletizing
experiment of Cao et al. (2012) with the default palletizer.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._validate import check_array, check_finite
from ..errors import InvalidInputError, UnreachableError
from ..kinematics.palletizer import CylindricalPalletizer, default_palletizer
from .cell import Cell, Prisms, prism_signed_distance, stack_prisms
from .patterns import BoxSize, StackPattern, check_layer_fit, make_pattern

__all__ = ["PalletScenario", "TripSpec", "seed_scenario", "CELL_OVERLAP_ATOL"]

#: Overlap [m] between a cell obstacle and a resting box that still counts as
#: touching (round-off of mm inputs).
CELL_OVERLAP_ATOL = 1e-9


@dataclass(frozen=True)
class TripSpec:
    """One trip of the cycle: from a rest pose to another, over a clearance.

    Attributes
    ----------
    kind : {"load", "return"}
        ``"load"``: pick -> place with a box; ``"return"``: place -> pick, empty.
    box : int
        Index of the box (placing order).
    q_start, q_goal : ndarray, shape (4,)
        Joints ``(theta, z, r, d)`` [rad, m, m, rad] at the start and goal.
    z_clear_start : float
        Height ``Z1`` [m] that B must reach before A, C, D may move.
    z_clear_goal : float
        Height ``Z2`` [m] above which A, C, D must have finished before B
        goes below it at the goal.
    """

    kind: str
    box: int
    q_start: np.ndarray
    q_goal: np.ndarray
    z_clear_start: float
    z_clear_goal: float

    @property
    def z_levels(self) -> tuple[float, float, float, float]:
        """``(Z0, Z1, Z2, Z3)`` as named by Cao et al. (2012) [m]."""
        return (float(self.q_start[1]), self.z_clear_start, self.z_clear_goal,
                float(self.q_goal[1]))


@dataclass(frozen=True)
class PalletScenario:
    """Everything needed to plan a palletizing job.

    Parameters
    ----------
    robot : CylindricalPalletizer
    pick : array_like, shape (4,)
        Gripper pose at the pick ``(x, y, z, yaw)`` [m, rad]: top-face centre
        of the waiting box.
    pallet_centre : array_like, shape (3,)
        Centre of the pallet's top face [m].
    pallet_size : (float, float)
        Pallet length (x) and width (y) [m].
    pattern : StackPattern
        Layer pattern and alternate-layer rule (the box size comes with it).
    layers : int
        Number of layers.
    lift : float
        Clearance height above the pick [m] (P1 = pick + lift).
    approach : float
        Clearance height above each place [m] (P2 = place + approach).
    grip_s, release_s : float
        Gripper dwell at the pick and at the place [s] (nothing moves).
    overhang : float
        Allowed overhang past the pallet edge [m].
    name : str
    cell : Cell, optional
        The cell's geometry (obstacles, gripper volume, clearance, settle
        height); ``None`` for a job planned under the clearance heights
        alone. The ``cell`` planner needs one, and :func:`verify_plan`
        checks every plan against it.

    Raises
    ------
    InvalidInputError
        Bad numbers; a pattern over the pallet edge.
    UnreachableError
        A place (or its approach height, or the pick lift) outside a joint
        range, or the stack top above the robot's reach (B range).
    """

    robot: CylindricalPalletizer
    pick: np.ndarray
    pallet_centre: np.ndarray
    pallet_size: tuple[float, float]
    pattern: StackPattern
    layers: int
    lift: float = 0.4
    approach: float = 0.2
    grip_s: float = 0.0
    release_s: float = 0.0
    overhang: float = 0.0
    name: str = "scenario"
    cell: Cell | None = None
    _cache: dict = field(default_factory=dict, compare=False, repr=False)

    def __post_init__(self) -> None:
        pick = check_array(self.pick, "pick", ndim=1, size=4)
        centre = check_array(self.pallet_centre, "pallet_centre", ndim=1, size=3)
        object.__setattr__(self, "pick", pick)
        object.__setattr__(self, "pallet_centre", centre)
        if int(self.layers) != self.layers or self.layers < 1:
            raise InvalidInputError(f"layers must be an integer >= 1, got {self.layers!r}")
        object.__setattr__(self, "layers", int(self.layers))
        for f in ("lift", "approach", "grip_s", "release_s", "overhang"):
            v = check_finite(getattr(self, f), f)
            if v < 0.0:
                raise InvalidInputError(f"{f} must be >= 0, got {v!r}")
            object.__setattr__(self, f, v)
        L, W = (check_finite(x, "pallet_size") for x in self.pallet_size)
        object.__setattr__(self, "pallet_size", (L, W))
        if self.cell is not None and not isinstance(self.cell, Cell):
            raise InvalidInputError(f"cell must be a Cell or None, got {self.cell!r}")
        check_layer_fit(self.pattern.layer_at(0), L, W, self.overhang)
        check_layer_fit(self.pattern.layer_at(1), L, W, self.overhang)
        self._validate_reach()
        if self.cell is not None:
            self._validate_cell(self.cell)

    # ------------------------------------------------------------- geometry
    @property
    def box(self) -> BoxSize:
        return self.pattern.layer.box

    @property
    def n_boxes(self) -> int:
        return self.layers * self.pattern.layer.n_boxes

    def place_poses(self) -> np.ndarray:
        """Gripper poses at every place, shape (n_boxes, 4) [m, rad], placing order."""
        return self.pattern.box_poses(self.layers, self.pallet_centre, self.box.height)

    def pick_joints(self) -> np.ndarray:
        """Joints at the pick, shape (4,), wrist nearest to 0."""
        return self.robot.joints_from_pose(self.pick, 0.0, yaw_period=math.pi, check=False)

    def place_joints(self) -> np.ndarray:
        """Joints at every place, shape (n_boxes, 4).

        The wrist takes the smaller motion from the pick's wrist angle (a
        rectangular box looks the same turned 180 degrees).
        """
        return self.robot.joints_from_pose(
            self.place_poses(), self.pick_joints()[3], yaw_period=math.pi, check=False
        )

    def _validate_reach(self) -> None:
        rob = self.robot
        qp = self.pick_joints()
        rob.check_joints(qp, "pick")
        top = qp[1] + self.lift
        if top > rob.z_top:
            raise UnreachableError(
                f"pick lift height {top * 1000:.1f} mm (pick z + lift) is above the robot's reach: "
                f"joint B range ends at {rob.z_top * 1000:g} mm"
            )
        poses = self.place_poses()
        ztop = float(poses[:, 2].max()) + self.approach
        if ztop > rob.z_top:
            raise UnreachableError(
                f"stack top {poses[:, 2].max() * 1000:.1f} mm + approach "
                f"{self.approach * 1000:g} mm = {ztop * 1000:.1f} mm is above the robot's reach: "
                f"joint B range ends at {rob.z_top * 1000:g} mm "
                f"({self.layers} layers of {self.box.height * 1000:g} mm)"
            )
        q = rob.joints_from_pose(poses, qp[3], yaw_period=math.pi, check=False)
        rob.check_joints(q, "place")

    def _validate_cell(self, cell: Cell) -> None:
        """No static obstacle of ``cell`` may pierce a box at its place or the box at the pick."""
        static = cell.static_prisms()
        if not len(static):
            return
        b = self.box
        poses = np.vstack([self.place_poses(), self.pick[None, :]])
        boxes = stack_prisms(poses, b.length, b.width, b.height)
        keys = ("cx", "cy", "hx", "hy", "yaw", "z0", "z1")
        d = prism_signed_distance(Prisms(*(getattr(boxes, k)[:, None] for k in keys)),
                                  Prisms(*(getattr(static, k)[None, :] for k in keys)))
        i, k = np.unravel_index(int(np.argmin(d)), d.shape)
        if d[i, k] < -CELL_OVERLAP_ATOL:
            what = "the box at the pick" if i == poses.shape[0] - 1 else f"box {i} at its place"
            raise InvalidInputError(
                f"cell obstacle {static.names[k]!r} overlaps {what} by {-d[i, k] * 1000:.3f} mm"
            )

    # ---------------------------------------------------------------- trips
    def trips(self) -> list[TripSpec]:
        """The trips of the whole job, in order: load 0, return 0, load 1, ...

        Returns
        -------
        list of TripSpec, length 2 * n_boxes
        """
        if "trips" in self._cache:
            return self._cache["trips"]
        qp = self.pick_joints()
        z_pick_clear = qp[1] + self.lift
        out = []
        for i, q in enumerate(self.place_joints()):
            z_place_clear = q[1] + self.approach
            out.append(TripSpec("load", i, qp.copy(), q.copy(), z_pick_clear, z_place_clear))
            out.append(TripSpec("return", i, q.copy(), qp.copy(), z_place_clear, z_pick_clear))
        self._cache["trips"] = out
        return out

    def to_dict(self) -> dict:
        """JSON-ready description in job-file units (mm, deg)."""
        return {
            "name": self.name,
            "robot": self.robot.to_dict(),
            "pick_mm_deg": [*(self.pick[:3] * 1000).tolist(), math.degrees(self.pick[3])],
            "pallet_centre_mm": (self.pallet_centre * 1000).tolist(),
            "pallet_size_mm": [self.pallet_size[0] * 1000, self.pallet_size[1] * 1000],
            "box_mm": [self.box.length * 1000, self.box.width * 1000, self.box.height * 1000],
            "pattern": self.pattern.layer.name,
            "alternate": self.pattern.alternate,
            "layers": self.layers,
            "lift_mm": self.lift * 1000,
            "approach_mm": self.approach * 1000,
            "grip_s": self.grip_s,
            "release_s": self.release_s,
            "boxes": self.n_boxes,
            **({"cell": self.cell.to_dict()} if self.cell is not None else {}),
        }


def seed_scenario(robot: CylindricalPalletizer | None = None, **overrides: Any) -> PalletScenario:
    """The palletizing experiment of Cao et al. (2012): 25 boxes, 5 layers, 180-degree interlock.

    Pick (1200, 0, 400) mm, yaw 0; pallet centre (0, 1400, 400) mm on a
    1200 x 1000 mm pallet; boxes 600 x 400 x 200 mm in the ``seed`` layer, the
    2nd and 4th layers turned 180 degrees; lift 400 mm, approach 200 mm;
    gripper times zero. The paper gives no joint limits: the robot is
    :func:`~trajkit.kinematics.default_palletizer` unless given. Keyword
    arguments override fields of :class:`PalletScenario`.
    """
    box = BoxSize(0.6, 0.4, 0.2)
    kw: dict[str, Any] = dict(
        robot=robot or default_palletizer(),
        pick=np.array([1.2, 0.0, 0.4, 0.0]),
        pallet_centre=np.array([0.0, 1.4, 0.4]),
        pallet_size=(1.2, 1.0),
        pattern=make_pattern("seed", 1.2, 1.0, box, "rotate180"),
        layers=5,
        lift=0.4,
        approach=0.2,
        name="Cao et al. (2012) job",
    )
    kw.update(overrides)
    return PalletScenario(**kw)
