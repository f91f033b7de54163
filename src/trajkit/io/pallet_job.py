"""Palletizing job files (YAML), validated with pydantic.

A job file gives lengths in millimetres and angles in degrees (the names
say so: ``x_mm``, ``yaw_deg``); :func:`scenario_from_job` converts to SI and
builds a :class:`~trajkit.palletizing.PalletScenario`. Every error names the
field (``pallet.length_mm``) and the offending value. The palletizing job of
Cao et al. (2012) ships as ``trajkit/data/seed_pallet.yaml``
(:func:`seed_job_path`).

Example::

    name: my job
    pick: {x_mm: 1200, y_mm: 0, z_mm: 400, yaw_deg: 0}
    pallet: {centre_mm: [0, 1400, 400], length_mm: 1200, width_mm: 1000}
    box: {length_mm: 600, width_mm: 400, height_mm: 200}
    pattern: {name: interlock, alternate: rotate180}
    layers: 5
    cell:                        # optional: the cell's geometry (the ``cell`` planner)
      clearance_mm: 10
      settle_mm: 20
      gripper: {height_mm: 100}  # footprint: the box's unless length_mm/width_mm are given
      obstacles:
        - {name: conveyor belt, x_mm: [600, 1500], y_mm: [-300, 300], z_mm: [0, 200]}

The same job in its cell ships as ``trajkit/data/seed_cell.yaml``
(:func:`seed_cell_job_path`).
"""

from __future__ import annotations

import math
import os
from importlib import resources
from pathlib import Path
from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from ..errors import InvalidInputError
from ..kinematics.palletizer import DEFAULT_JOINT_TABLE, JOINT_NAMES, CylindricalPalletizer
from ..palletizing.cell import Cell, GripperVolume, Obstacle
from ..palletizing.patterns import BoxSize, LayerPattern, StackPattern, make_pattern
from ..palletizing.scenario import PalletScenario
from .document import plain, read_document
from .schema import (
    Angle_deg,
    Coordinate_mm,
    Count,
    Length_mm,
    LimitValue,
    PositiveLength_mm,
    Time_s,
    validation_message,
)

__all__ = ["PalletJob", "load_job", "scenario_from_job", "seed_job_path", "seed_cell_job_path",
           "parse_job"]

_MM = 1e-3
_DEG = math.pi / 180.0


#: Most layers in a job.
MAX_LAYERS = 1000

#: Most boxes in a custom layer.
MAX_BOXES_PER_LAYER = 10000


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class JointSpec(_Model):
    """One joint's limits in deg (A, D) or mm (B, C) units."""

    v_max: LimitValue
    a_max: LimitValue
    j_max: LimitValue
    min: Coordinate_mm
    max: Coordinate_mm
    a_max_decel: LimitValue | None = None
    j_max_decel: LimitValue | None = None


class RobotSpec(_Model):
    """Robot joint table; joints not given keep the default robot's values."""

    name: str = "cylindrical palletizer"
    joints: dict[Literal["A", "B", "C", "D"], JointSpec] = Field(default_factory=dict)


class PickSpec(_Model):
    x_mm: Coordinate_mm
    y_mm: Coordinate_mm
    z_mm: Coordinate_mm
    yaw_deg: Angle_deg = 0.0


class PalletSpec(_Model):
    centre_mm: tuple[Coordinate_mm, Coordinate_mm, Coordinate_mm]
    length_mm: PositiveLength_mm
    width_mm: PositiveLength_mm
    overhang_mm: Length_mm = 0.0


class BoxSpec(_Model):
    length_mm: PositiveLength_mm
    width_mm: PositiveLength_mm
    height_mm: PositiveLength_mm


class BoxPlace(_Model):
    """A box of a custom layer: centre offset from the pallet centre and yaw."""

    x_mm: Coordinate_mm
    y_mm: Coordinate_mm
    yaw_deg: Angle_deg = 0.0


class PatternSpec(_Model):
    name: Literal["seed", "column", "interlock", "pinwheel", "custom"] = "interlock"
    alternate: Literal["none", "rotate180", "mirror"] = "rotate180"
    boxes: list[BoxPlace] | None = Field(default=None, min_length=1, max_length=MAX_BOXES_PER_LAYER)


class GripperSpec(_Model):
    grip_s: Time_s = 0.0
    release_s: Time_s = 0.0


#: Most obstacles in a cell.
MAX_OBSTACLES = 1000


class ObstacleSpec(_Model):
    """A static obstacle: an axis-aligned box ``[x] x [y] x [z]`` in mm (robot base frame)."""

    name: str = "obstacle"
    x_mm: tuple[Coordinate_mm, Coordinate_mm]
    y_mm: tuple[Coordinate_mm, Coordinate_mm]
    z_mm: tuple[Coordinate_mm, Coordinate_mm]

    @field_validator("x_mm", "y_mm", "z_mm")
    @classmethod
    def _interval(cls, v):
        if not v[1] > v[0]:
            raise ValueError("an interval [min, max] needs max > min")
        return v


class GripperVolumeSpec(_Model):
    """The gripper above the gripper point; length/width default to the box's."""

    height_mm: PositiveLength_mm = 100.0
    length_mm: PositiveLength_mm | None = None
    width_mm: PositiveLength_mm | None = None


class CellSpec(_Model):
    """The cell around the robot (obstacles, gripper volume, clearance, settle height)."""

    clearance_mm: Length_mm = 10.0
    settle_mm: Length_mm = 20.0
    box_at_pick: bool = True
    gripper: GripperVolumeSpec = Field(default_factory=GripperVolumeSpec)
    obstacles: list[ObstacleSpec] = Field(default_factory=list, max_length=MAX_OBSTACLES)


class PalletJob(_Model):
    """A palletizing job (the schema of a job file; mm and deg)."""

    name: str = "pallet job"
    robot: RobotSpec = Field(default_factory=RobotSpec)
    pick: PickSpec
    pallet: PalletSpec
    box: BoxSpec
    pattern: PatternSpec = Field(default_factory=PatternSpec)
    layers: Count = Field(ge=1, le=MAX_LAYERS)
    lift_mm: Length_mm = 400.0
    approach_mm: Length_mm = 200.0
    gripper: GripperSpec = Field(default_factory=GripperSpec)
    cell: CellSpec | None = None


def _si_interval(iv_mm: tuple[float, float]) -> tuple[float, float]:
    """An interval ``[min, max]`` in mm, in m."""
    return (iv_mm[0] * _MM, iv_mm[1] * _MM)


def cell_from_spec(spec: CellSpec) -> Cell:
    """The SI :class:`~trajkit.palletizing.cell.Cell` of a job's ``cell`` section."""
    g = spec.gripper
    return Cell(
        obstacles=tuple(Obstacle(_si_interval(o.x_mm), _si_interval(o.y_mm), _si_interval(o.z_mm), o.name)
                        for o in spec.obstacles),
        gripper=GripperVolume(g.height_mm * _MM,
                              None if g.length_mm is None else g.length_mm * _MM,
                              None if g.width_mm is None else g.width_mm * _MM),
        clearance=spec.clearance_mm * _MM,
        settle=spec.settle_mm * _MM,
        box_at_pick=spec.box_at_pick,
    )


def parse_job(data: Any, source: str = "job") -> PalletJob:
    """Validate a mapping (e.g. loaded YAML) as a :class:`PalletJob`.

    Raises
    ------
    InvalidInputError
        The message names the source, the field path and the value.
    """
    if not isinstance(data, dict):
        raise InvalidInputError(f"{source}: expected a mapping of fields, got {type(data).__name__}")
    try:
        return PalletJob.model_validate(data)
    except ValidationError as exc:
        raise InvalidInputError(f"{source}: {validation_message(exc)}") from None


def scenario_from_job(job: PalletJob | dict, source: str = "job") -> PalletScenario:
    """Build the SI :class:`PalletScenario` of a job.

    Raises
    ------
    InvalidInputError
        Invalid fields, a pattern over the pallet edge, a custom pattern
        without boxes.
    UnreachableError
        A place or the stack top outside the robot's joint ranges.
    """
    if not isinstance(job, PalletJob):
        job = parse_job(job, source)
    table = {k: DEFAULT_JOINT_TABLE[k] for k in JOINT_NAMES}
    decel: dict[str, tuple[float | None, float | None]] = {}
    for jn, js in job.robot.joints.items():
        table[jn] = (js.v_max, js.a_max, js.j_max, js.min, js.max)
        if js.a_max_decel is not None or js.j_max_decel is not None:
            decel[jn] = (js.a_max_decel, js.j_max_decel)
    try:
        robot = CylindricalPalletizer.from_table(table, decel, name=job.robot.name)
    except InvalidInputError as exc:
        raise InvalidInputError(f"{source}: field robot.joints: {exc}") from None
    box = BoxSize(job.box.length_mm * _MM, job.box.width_mm * _MM, job.box.height_mm * _MM)
    L, W = job.pallet.length_mm * _MM, job.pallet.width_mm * _MM
    pat = job.pattern
    try:
        if pat.name == "custom":
            if not pat.boxes:
                raise InvalidInputError("field pattern.boxes: a custom pattern needs boxes")
            off = np.array([[b.x_mm * _MM, b.y_mm * _MM] for b in pat.boxes])
            yaw = np.array([b.yaw_deg * _DEG for b in pat.boxes])
            stack = StackPattern(LayerPattern(off, yaw, box, "custom"), pat.alternate)
        else:
            if pat.boxes:
                raise InvalidInputError(
                    f"field pattern.boxes: only a custom pattern takes boxes (pattern.name is "
                    f"{pat.name!r})"
                )
            stack = make_pattern(pat.name, L, W, box, pat.alternate, job.pallet.overhang_mm * _MM)
        return PalletScenario(
            robot=robot,
            pick=np.array([job.pick.x_mm * _MM, job.pick.y_mm * _MM, job.pick.z_mm * _MM,
                           job.pick.yaw_deg * _DEG]),
            pallet_centre=np.array(job.pallet.centre_mm) * _MM,
            pallet_size=(L, W),
            pattern=stack,
            layers=job.layers,
            lift=job.lift_mm * _MM,
            approach=job.approach_mm * _MM,
            grip_s=job.gripper.grip_s,
            release_s=job.gripper.release_s,
            overhang=job.pallet.overhang_mm * _MM,
            name=job.name,
            cell=None if job.cell is None else cell_from_spec(job.cell),
        )
    except InvalidInputError as exc:
        raise type(exc)(f"{source}: {exc}") from None


def load_job(path: str | os.PathLike) -> PalletScenario:
    """Read, validate and convert a YAML job file.

    Raises
    ------
    OSError
        The file cannot be read.
    InvalidInputError
        Not YAML, or a field that fails validation (the message names the
        file and the field).
    UnreachableError
        A place outside the robot's reach.
    """
    p = Path(path)
    data = plain(read_document(p))
    return scenario_from_job(parse_job(data, str(p)), str(p))


def seed_job_path() -> Path:
    """Path of the shipped job of Cao et al. (2012), ``trajkit/data/seed_pallet.yaml``."""
    return Path(str(resources.files("trajkit") / "data" / "seed_pallet.yaml"))


def seed_cell_job_path() -> Path:
    """Path of the job of Cao et al. (2012) in its cell, ``trajkit/data/seed_cell.yaml``
    (conveyor, guides, end stop, pallet; 10 mm clearance, 20 mm settle)."""
    return Path(str(resources.files("trajkit") / "data" / "seed_cell.yaml"))
