"""Palletizing job files (YAML), validated with pydantic.

A job file gives lengths in millimetres and angles in degrees (the names
say so: ``x_mm``, ``yaw_deg``); :func:`scenario_from_job` converts to SI and
builds a :class:`~trajkit.palletizing.PalletScenario`. Every error names the
field (``pallet.length_mm``) and the offending value. The seed scenario ships
as ``trajkit/data/seed_pallet.yaml`` (:func:`seed_job_path`).

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

The seed scenario in its cell ships as ``trajkit/data/seed_cell.yaml``
(:func:`seed_cell_job_path`).
"""

from __future__ import annotations

import math
import os
from importlib import resources
from pathlib import Path
from typing import Any, Literal, Optional

import numpy as np
import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from ..errors import InvalidInputError
from ..kinematics.palletizer import DEFAULT_JOINT_TABLE, JOINT_NAMES, CylindricalPalletizer
from ..palletizing.cell import Cell, GripperVolume, Obstacle
from ..palletizing.patterns import BoxSize, LayerPattern, StackPattern, make_pattern
from ..palletizing.scenario import PalletScenario

__all__ = ["PalletJob", "load_job", "scenario_from_job", "seed_job_path", "seed_cell_job_path",
           "parse_job"]

_MM = 1e-3
_DEG = math.pi / 180.0


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class JointSpec(_Model):
    """One joint's limits in deg (A, D) or mm (B, C) units."""

    v_max: float = Field(gt=0, allow_inf_nan=False)
    a_max: float = Field(gt=0, allow_inf_nan=False)
    j_max: float = Field(gt=0, allow_inf_nan=False)
    min: float = Field(allow_inf_nan=False)
    max: float = Field(allow_inf_nan=False)
    a_max_decel: Optional[float] = Field(default=None, gt=0, allow_inf_nan=False)
    j_max_decel: Optional[float] = Field(default=None, gt=0, allow_inf_nan=False)


class RobotSpec(_Model):
    """Robot joint table; joints not given keep the default robot's values."""

    name: str = "cylindrical palletizer"
    joints: dict[Literal["A", "B", "C", "D"], JointSpec] = Field(default_factory=dict)


class PickSpec(_Model):
    x_mm: float = Field(allow_inf_nan=False)
    y_mm: float = Field(allow_inf_nan=False)
    z_mm: float = Field(allow_inf_nan=False)
    yaw_deg: float = Field(default=0.0, allow_inf_nan=False)


class PalletSpec(_Model):
    centre_mm: tuple[float, float, float]
    length_mm: float = Field(gt=0, allow_inf_nan=False)
    width_mm: float = Field(gt=0, allow_inf_nan=False)
    overhang_mm: float = Field(default=0.0, ge=0, allow_inf_nan=False)

    @field_validator("centre_mm")
    @classmethod
    def _finite(cls, v):
        if not all(math.isfinite(x) for x in v):
            raise ValueError("must be finite numbers")
        return v


class BoxSpec(_Model):
    length_mm: float = Field(gt=0, allow_inf_nan=False)
    width_mm: float = Field(gt=0, allow_inf_nan=False)
    height_mm: float = Field(gt=0, allow_inf_nan=False)


class BoxPlace(_Model):
    """A box of a custom layer: centre offset from the pallet centre and yaw."""

    x_mm: float = Field(allow_inf_nan=False)
    y_mm: float = Field(allow_inf_nan=False)
    yaw_deg: float = Field(default=0.0, allow_inf_nan=False)


class PatternSpec(_Model):
    name: Literal["seed", "column", "interlock", "pinwheel", "custom"] = "interlock"
    alternate: Literal["none", "rotate180", "mirror"] = "rotate180"
    boxes: Optional[list[BoxPlace]] = Field(default=None, min_length=1)


class GripperSpec(_Model):
    grip_s: float = Field(default=0.0, ge=0, allow_inf_nan=False)
    release_s: float = Field(default=0.0, ge=0, allow_inf_nan=False)


def _interval(v, what: str):
    lo, hi = v
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise ValueError(f"{what} must be finite numbers")
    if not hi > lo:
        raise ValueError(f"{what} [min, max] needs max > min")
    return v


class ObstacleSpec(_Model):
    """A static obstacle: an axis-aligned box ``[x] x [y] x [z]`` in mm (robot base frame)."""

    name: str = "obstacle"
    x_mm: tuple[float, float]
    y_mm: tuple[float, float]
    z_mm: tuple[float, float]

    @field_validator("x_mm", "y_mm", "z_mm")
    @classmethod
    def _iv(cls, v):
        return _interval(v, "an interval")


class GripperVolumeSpec(_Model):
    """The gripper above the gripper point; length/width default to the box's."""

    height_mm: float = Field(default=100.0, gt=0, allow_inf_nan=False)
    length_mm: Optional[float] = Field(default=None, gt=0, allow_inf_nan=False)
    width_mm: Optional[float] = Field(default=None, gt=0, allow_inf_nan=False)


class CellSpec(_Model):
    """The cell around the robot (obstacles, gripper volume, clearance, settle height)."""

    clearance_mm: float = Field(default=10.0, ge=0, allow_inf_nan=False)
    settle_mm: float = Field(default=20.0, ge=0, allow_inf_nan=False)
    box_at_pick: bool = True
    gripper: GripperVolumeSpec = Field(default_factory=GripperVolumeSpec)
    obstacles: list[ObstacleSpec] = Field(default_factory=list, max_length=1000)


class PalletJob(_Model):
    """A palletizing job (the schema of a job file; mm and deg)."""

    name: str = "pallet job"
    robot: RobotSpec = Field(default_factory=RobotSpec)
    pick: PickSpec
    pallet: PalletSpec
    box: BoxSpec
    pattern: PatternSpec = Field(default_factory=PatternSpec)
    layers: int = Field(ge=1)
    lift_mm: float = Field(default=400.0, ge=0, allow_inf_nan=False)
    approach_mm: float = Field(default=200.0, ge=0, allow_inf_nan=False)
    gripper: GripperSpec = Field(default_factory=GripperSpec)
    cell: Optional[CellSpec] = None


def cell_from_spec(spec: CellSpec) -> Cell:
    """The SI :class:`~trajkit.palletizing.cell.Cell` of a job's ``cell`` section."""
    g = spec.gripper
    return Cell(
        obstacles=tuple(Obstacle(tuple(v * _MM for v in o.x_mm), tuple(v * _MM for v in o.y_mm),
                                 tuple(v * _MM for v in o.z_mm), o.name) for o in spec.obstacles),
        gripper=GripperVolume(g.height_mm * _MM,
                              None if g.length_mm is None else g.length_mm * _MM,
                              None if g.width_mm is None else g.width_mm * _MM),
        clearance=spec.clearance_mm * _MM,
        settle=spec.settle_mm * _MM,
        box_at_pick=spec.box_at_pick,
    )


def _fmt_error(err: ValidationError, source: str) -> str:
    e = err.errors()[0]
    loc = ".".join(str(x) for x in e["loc"]) or "(top level)"
    val = e.get("input")
    shown = "" if isinstance(val, dict) else f" (got {val!r})"
    more = f" [+{err.error_count() - 1} more]" if err.error_count() > 1 else ""
    return f"{source}: field {loc}: {e['msg']}{shown}{more}"


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
        raise InvalidInputError(_fmt_error(exc, source)) from None


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
    decel = {}
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
    text = p.read_text(encoding="utf-8")
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        raise InvalidInputError(f"{p}: not valid YAML{where}: {getattr(exc, 'problem', exc)}") from None
    return scenario_from_job(parse_job(data, str(p)), str(p))


def seed_job_path() -> Path:
    """Path of the shipped seed-scenario job file ``trajkit/data/seed_pallet.yaml``."""
    return Path(str(resources.files("trajkit") / "data" / "seed_pallet.yaml"))


def seed_cell_job_path() -> Path:
    """Path of the seed scenario in its cell, ``trajkit/data/seed_cell.yaml``
    (conveyor, guides, end stop, pallet; 10 mm clearance, 20 mm settle)."""
    return Path(str(resources.files("trajkit") / "data" / "seed_cell.yaml"))
