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
"""

from __future__ import annotations

import math
import os
from importlib import resources
from pathlib import Path
from typing import Any, Literal, Optional

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from ..errors import InvalidInputError
from ..kinematics.palletizer import DEFAULT_JOINT_TABLE, JOINT_NAMES, CylindricalPalletizer
from ..palletizing.patterns import BoxSize, LayerPattern, StackPattern, make_pattern
from ..palletizing.scenario import PalletScenario
from .document import plain, read_document
from .schema import Count, Real, validation_message

__all__ = ["PalletJob", "load_job", "scenario_from_job", "seed_job_path", "parse_job"]

_MM = 1e-3
_DEG = math.pi / 180.0


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class JointSpec(_Model):
    """One joint's limits in deg (A, D) or mm (B, C) units."""

    v_max: Real = Field(gt=0, allow_inf_nan=False)
    a_max: Real = Field(gt=0, allow_inf_nan=False)
    j_max: Real = Field(gt=0, allow_inf_nan=False)
    min: Real = Field(allow_inf_nan=False)
    max: Real = Field(allow_inf_nan=False)
    a_max_decel: Optional[Real] = Field(default=None, gt=0, allow_inf_nan=False)
    j_max_decel: Optional[Real] = Field(default=None, gt=0, allow_inf_nan=False)


class RobotSpec(_Model):
    """Robot joint table; joints not given keep the default robot's values."""

    name: str = "cylindrical palletizer"
    joints: dict[Literal["A", "B", "C", "D"], JointSpec] = Field(default_factory=dict)


class PickSpec(_Model):
    x_mm: Real = Field(allow_inf_nan=False)
    y_mm: Real = Field(allow_inf_nan=False)
    z_mm: Real = Field(allow_inf_nan=False)
    yaw_deg: Real = Field(default=0.0, allow_inf_nan=False)


class PalletSpec(_Model):
    centre_mm: tuple[Real, Real, Real]
    length_mm: Real = Field(gt=0, allow_inf_nan=False)
    width_mm: Real = Field(gt=0, allow_inf_nan=False)
    overhang_mm: Real = Field(default=0.0, ge=0, allow_inf_nan=False)

    @field_validator("centre_mm")
    @classmethod
    def _finite(cls, v):
        if not all(math.isfinite(x) for x in v):
            raise ValueError("must be finite numbers")
        return v


class BoxSpec(_Model):
    length_mm: Real = Field(gt=0, allow_inf_nan=False)
    width_mm: Real = Field(gt=0, allow_inf_nan=False)
    height_mm: Real = Field(gt=0, allow_inf_nan=False)


class BoxPlace(_Model):
    """A box of a custom layer: centre offset from the pallet centre and yaw."""

    x_mm: Real = Field(allow_inf_nan=False)
    y_mm: Real = Field(allow_inf_nan=False)
    yaw_deg: Real = Field(default=0.0, allow_inf_nan=False)


class PatternSpec(_Model):
    name: Literal["seed", "column", "interlock", "pinwheel", "custom"] = "interlock"
    alternate: Literal["none", "rotate180", "mirror"] = "rotate180"
    boxes: Optional[list[BoxPlace]] = Field(default=None, min_length=1)


class GripperSpec(_Model):
    grip_s: Real = Field(default=0.0, ge=0, allow_inf_nan=False)
    release_s: Real = Field(default=0.0, ge=0, allow_inf_nan=False)


class PalletJob(_Model):
    """A palletizing job (the schema of a job file; mm and deg)."""

    name: str = "pallet job"
    robot: RobotSpec = Field(default_factory=RobotSpec)
    pick: PickSpec
    pallet: PalletSpec
    box: BoxSpec
    pattern: PatternSpec = Field(default_factory=PatternSpec)
    layers: Count = Field(ge=1)
    lift_mm: Real = Field(default=400.0, ge=0, allow_inf_nan=False)
    approach_mm: Real = Field(default=200.0, ge=0, allow_inf_nan=False)
    gripper: GripperSpec = Field(default_factory=GripperSpec)


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
    """Path of the shipped seed-scenario job file ``trajkit/data/seed_pallet.yaml``."""
    return Path(str(resources.files("trajkit") / "data" / "seed_pallet.yaml"))
