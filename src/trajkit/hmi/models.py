"""Pydantic models of every request the HMI accepts (validated on the server).

Units at this boundary, as in the CLI: lengths in mm, speeds in mm/s
(mm/s^2, mm/s^3), angles in degrees (deg/s ...), the control period in
seconds. A request that fails validation changes nothing; the API answers
422 with one line per bad field (see :func:`trajkit.hmi.app.create_app`).
"""

from __future__ import annotations

import re
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator

__all__ = [
    "SaddleJob",
    "PalletJob",
    "ProgramJob",
    "JobRequest",
    "OverrideRequest",
    "JogRequest",
    "TeachRequest",
    "RobotRequest",
    "ProgramStep",
    "BuildProgramRequest",
    "SaveProgramRequest",
    "MIN_PERIOD_S",
    "MAX_PERIOD_S",
    "NAME_PATTERN",
]

#: Control period bounds [s] (the interpolation module's bounds).
MIN_PERIOD_S = 1e-4
MAX_PERIOD_S = 0.1

#: Feed override range [%] (0 stops the feed without ending the run).
MAX_OVERRIDE_PCT = 100.0

#: Names of taught points and program files: letters, digits, ``_`` and ``-``.
NAME_PATTERN = r"^[A-Za-z][A-Za-z0-9_-]{0,39}$"

#: Largest program text accepted [characters].
MAX_PROGRAM_CHARS = 200_000

#: Largest jog step [deg or mm].
MAX_JOG_STEP = 360.0


def _pos(**kw):
    return Field(gt=0, allow_inf_nan=False, **kw)


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)  # true or "50" is not a number


class SaddleJob(_Model):
    """A saddle (pipe-intersection) seam on the theta/Z machine (a rotary table and a vertical axis).

    Attributes
    ----------
    main_radius_mm, branch_radius_mm : float
        Pipe radii R > r [mm].
    angle_deg : float
        Angle between the pipe axes, (0, 180) [deg] (90: orthogonal).
    offset_mm : float
        Distance between the axes [mm].
    feed_mm_s, accel_mm_s2, jerk_mm_s3 : float
        Torch speed along the seam and its tangential limits.
    tolerance_mm : float
        Chord tolerance [mm].
    period_s : float
        Control period [s], 1e-4 .. 0.1.
    theta_vmax_deg_s ... z_jmax_mm_s3 : float
        Machine-axis limits.
    """

    kind: Literal["saddle"] = "saddle"
    main_radius_mm: float = _pos(default=150.0, le=10_000)
    branch_radius_mm: float = _pos(default=100.0, le=10_000)
    angle_deg: float = Field(default=90.0, gt=0, lt=180, allow_inf_nan=False)
    offset_mm: float = Field(default=0.0, ge=-10_000, le=10_000, allow_inf_nan=False)
    feed_mm_s: float = _pos(default=40.0, le=5_000)
    accel_mm_s2: float = _pos(default=500.0)
    jerk_mm_s3: float = _pos(default=5000.0)
    tolerance_mm: float = _pos(default=0.01, le=10)
    period_s: float = Field(default=0.004, ge=MIN_PERIOD_S, le=MAX_PERIOD_S, allow_inf_nan=False)
    theta_vmax_deg_s: float = _pos(default=180.0)
    theta_amax_deg_s2: float = _pos(default=720.0)
    theta_jmax_deg_s3: float = _pos(default=7200.0)
    z_vmax_mm_s: float = _pos(default=100.0)
    z_amax_mm_s2: float = _pos(default=1000.0)
    z_jmax_mm_s3: float = _pos(default=10000.0)


class PalletJob(_Model):
    """The reference palletizing cell (:func:`trajkit.palletizing.seed_scenario`) with a cycle planner.

    Attributes
    ----------
    planner : {"ptp", "merged", "optimal"}
    layers : int
        Number of layers of the reference stack to place, 1 .. 5 (5 boxes each).
    period_s : float
    """

    kind: Literal["pallet"] = "pallet"
    planner: Literal["ptp", "merged", "optimal"] = "merged"
    layers: int = Field(default=1, ge=1, le=5)
    period_s: float = Field(default=0.004, ge=MIN_PERIOD_S, le=MAX_PERIOD_S, allow_inf_nan=False)


class ProgramJob(_Model):
    """A robot program (PTP/LIN/CIRC/WAIT) in the YAML format of ``trajkit run``."""

    kind: Literal["program"] = "program"
    text: str = Field(min_length=1, max_length=MAX_PROGRAM_CHARS)
    period_s: float = Field(default=0.004, ge=MIN_PERIOD_S, le=MAX_PERIOD_S, allow_inf_nan=False)


JobRequest = SaddleJob | PalletJob | ProgramJob


class OverrideRequest(_Model):
    """Feed override [%], 0 .. 100 (0 holds the feed without ending the run)."""

    percent: float = Field(ge=0, le=MAX_OVERRIDE_PCT, allow_inf_nan=False)


class RobotRequest(_Model):
    """Choose the robot for jog and teach (resets the current joints to its home)."""

    robot: Literal["arm6", "scara", "palletizer"]


class JogRequest(_Model):
    """Jog one joint by a step [deg for revolute, mm for prismatic joints]."""

    joint: str = Field(min_length=1, max_length=20)
    step: float = Field(ge=-MAX_JOG_STEP, le=MAX_JOG_STEP, allow_inf_nan=False)
    speed_pct: float = Field(default=20.0, gt=0, le=100, allow_inf_nan=False)

    @field_validator("step")
    @classmethod
    def _nonzero(cls, v: float) -> float:
        if v == 0:
            raise ValueError("jog step must not be zero")
        return v


class TeachRequest(_Model):
    """Store the current joints under a name."""

    name: str = Field(pattern=NAME_PATTERN)


class ProgramStep(_Model):
    """One instruction built from taught points."""

    op: Literal["PTP", "LIN", "CIRC"]
    point: str = Field(pattern=NAME_PATTERN)
    via: str | None = Field(default=None, pattern=NAME_PATTERN)
    speed_pct: float | None = Field(default=None, gt=0, le=100, allow_inf_nan=False)
    speed_mm_s: float | None = Field(default=None, gt=0, le=5_000, allow_inf_nan=False)


class BuildProgramRequest(_Model):
    """Build program text from taught points (the first step should be a PTP)."""

    steps: list[ProgramStep] = Field(min_length=1, max_length=500)
    speed_mm_s: float = _pos(default=200.0, le=5_000)


class SaveProgramRequest(_Model):
    """Save program text as ``<name>.yaml`` in the programs folder."""

    name: str = Field(pattern=NAME_PATTERN)
    text: str = Field(min_length=1, max_length=MAX_PROGRAM_CHARS)

    @field_validator("name")
    @classmethod
    def _plain(cls, v: str) -> str:
        if not re.fullmatch(NAME_PATTERN, v):  # pragma: no cover - pattern checks first
            raise ValueError("bad name")
        return v
