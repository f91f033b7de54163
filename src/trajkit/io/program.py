"""Robot program files (YAML): taught points and PTP/LIN/CIRC/WAIT instructions.

Lengths are millimetres and angles degrees in the file (the field names say
so); :func:`load_program` converts to SI and returns a :class:`Program`
whose :meth:`Program.run` plans it. Every error names the file, the line and
the field, e.g. ``prog.yaml:14: program[2].speed_mm_s: Input should be
greater than 0 (got -5)``.

Example::

    robot: arm6                 # arm6 | scara | palletizer | {urdf: arm.urdf, tip_link: tool0}
    defaults: {speed_mm_s: 250, speed_pct: 100, zone_mm: 0}
    start: home                 # optional; default: the first PTP's target
    points:
      home: {joints_deg: [0, 20, 10, 0, 60, 0]}
      p1:   {xyz_mm: [550, 0, 580], abc_deg: [0, 90, 0], config: front-up-noflip}
      p2:   {xyz_mm: [550, 200, 580], abc_deg: [0, 90, 0]}
      aux:  {xyz_mm: [600, 100, 500], abc_deg: [0, 90, 0]}
    program:
      - PTP: home
        speed_pct: 50
      - LIN: p1
      - LIN: p2
        speed_mm_s: 200
        zone_mm: 20             # blend into the next motion
      - CIRC: p1
        via: aux
      - WAIT: {time_s: 0.5}

Joint points: ``joints_deg`` (a list, robots whose joints are all revolute)
or ``joints`` (a mapping ``{J1_deg: 10, J3_mm: 50, ...}`` naming every joint
with its unit). Cartesian points: ``xyz_mm`` and ``abc_deg`` (KUKA A, B, C:
``R = Rz(A) Ry(B) Rx(C)``) and an optional IK ``config``.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from ..errors import InvalidInputError, UnreachableError
from ..kinematics.base import Pose, RobotModel
from .document import MAX_DOCUMENT_BYTES, LineDict, LineList, parse_document, plain
from .schema import Angle_deg, Coordinate_mm, Length_mm, PositiveLength_mm, Real, Time_s, short_repr

if TYPE_CHECKING:
    from ..robot.execute import RobotRun
    from ..robot.motion import Motion, Target

__all__ = ["Program", "load_program", "parse_program", "make_robot", "ROBOT_MODELS"]

_MM = 1e-3
_DEG = math.pi / 180.0

#: Built-in robot model names accepted by ``robot:``.
ROBOT_MODELS = ("arm6", "scara", "palletizer")

INSTRUCTIONS = ("PTP", "LIN", "CIRC", "WAIT")

#: Most instructions in a program (planning costs about 30 ms per LIN/CIRC).
MAX_INSTRUCTIONS = 2000

#: Most taught points in a program.
MAX_POINTS = 10000

#: Most joints of a point.
MAX_JOINTS = 64


def _line_of(raw: Any, loc: tuple) -> int:
    line = getattr(raw, "line", 0)
    node = raw
    for part in loc:
        if isinstance(node, LineDict) and part in node:
            line = node.key_lines.get(part, line)
            node = node[part]
        elif isinstance(node, LineList) and isinstance(part, int) and 0 <= part < len(node):
            line = node.item_lines[part]
            node = node[part]
        else:
            break
    return line


def _loc_str(loc: tuple) -> str:
    out = ""
    for p in loc:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out


# --------------------------------------------------------------------------- schema
class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class UrdfSpec(_Model):
    """A robot from a URDF file (path relative to the program file)."""

    urdf: str
    tip_link: str


class Defaults(_Model):
    speed_mm_s: PositiveLength_mm = 250.0
    speed_pct: Real = Field(default=100.0, gt=0, le=100, allow_inf_nan=False)
    zone_mm: Length_mm = 0.0


class PointSpec(_Model):
    joints_deg: list[Angle_deg] | None = Field(default=None, max_length=MAX_JOINTS)
    joints: dict[str, Angle_deg] | None = Field(default=None, max_length=MAX_JOINTS)
    xyz_mm: list[Coordinate_mm] | None = Field(default=None, min_length=3, max_length=3)
    abc_deg: list[Angle_deg] | None = Field(default=None, min_length=3, max_length=3)
    config: str | dict[str, str] | None = None

    @model_validator(mode="after")
    def _one_kind(self) -> PointSpec:
        kinds = [k for k in ("joints_deg", "joints", "xyz_mm") if getattr(self, k) is not None]
        if len(kinds) != 1:
            raise ValueError(
                f"a point needs exactly one of joints_deg, joints, xyz_mm (got {kinds or 'none'})"
            )
        if self.abc_deg is not None and self.xyz_mm is None:
            raise ValueError("abc_deg is only allowed with xyz_mm")
        for k in ("joints_deg", "xyz_mm", "abc_deg"):
            v = getattr(self, k)
            if v is not None and not all(math.isfinite(x) for x in v):
                raise ValueError(f"{k} must be finite numbers, got {v}")
        return self


class PtpSpec(_Model):
    PTP: str
    speed_pct: Real | None = Field(default=None, gt=0, le=100, allow_inf_nan=False)
    zone_mm: Length_mm | None = None


class LinSpec(_Model):
    LIN: str
    speed_mm_s: PositiveLength_mm | None = None
    zone_mm: Length_mm | None = None


class CircSpec(_Model):
    CIRC: str
    via: str
    speed_mm_s: PositiveLength_mm | None = None
    zone_mm: Length_mm | None = None


class WaitBody(_Model):
    time_s: Time_s


class WaitSpec(_Model):
    WAIT: WaitBody


_SPECS: dict[str, type[_Model]] = {"PTP": PtpSpec, "LIN": LinSpec, "CIRC": CircSpec, "WAIT": WaitSpec}


class ProgramFile(_Model):
    robot: str | UrdfSpec
    defaults: Defaults = Defaults()
    start: str | None = None
    points: dict[str, PointSpec] = Field(min_length=1, max_length=MAX_POINTS)
    program: list[dict[str, Any]] = Field(min_length=1, max_length=MAX_INSTRUCTIONS)


# --------------------------------------------------------------------------- result
@dataclass
class Program:
    """A validated program in SI units.

    Attributes
    ----------
    robot : RobotModel
    points : dict of str -> JointTarget or CartesianTarget
    motions : list of Ptp, Lin, Circ, Wait
        Each carries a ``label`` naming the instruction and its line.
    start : ndarray, shape (n_joints,)
        Joints at the start [rad or m].
    source : str
        File name (or ``"<string>"``) used in messages.
    lines : list of int
        Line of each instruction.
    """

    robot: RobotModel
    points: dict[str, Target]
    motions: list[Motion]
    start: np.ndarray
    source: str
    lines: list[int]

    def run(self) -> RobotRun:
        """Plan the program: a :class:`trajkit.robot.RobotRun`."""
        from ..robot.execute import run_motions

        return run_motions(self.robot, self.motions, self.start)


class UrdfRefusedError(InvalidInputError):
    """A URDF path outside the allowed folders (the message never says whether it exists)."""


def make_robot(spec: Any, base_dir: str | os.PathLike | None = None, *,
               urdf_dirs: Any = None) -> RobotModel:
    """Robot model from a ``robot:`` value: ``"arm6"``, ``"scara"``, ``"palletizer"`` or a URDF spec.

    Parameters
    ----------
    spec : str or UrdfSpec
    base_dir : path, optional
        Folder that a relative URDF path is relative to (without ``urdf_dirs``).
    urdf_dirs : sequence of path, optional
        When given, a URDF file is opened only if it is a ``.urdf`` file
        inside one of these folders once links and ``..`` are resolved (a
        relative path is looked up in each folder in turn); any other path
        is refused with :class:`UrdfRefusedError`, with the same message
        whether or not it exists. Empty: built-in robots only.
    """
    if isinstance(spec, str):
        from ..robot.models import robot_by_name

        return robot_by_name(spec)
    if urdf_dirs is not None:
        p = _urdf_inside(spec.urdf, urdf_dirs)
    else:
        p = Path(spec.urdf)
        if not p.is_absolute() and base_dir is not None:
            p = Path(base_dir) / p
    from ..kinematics.urdf import UrdfRobot

    return UrdfRobot(p, spec.tip_link)


def _urdf_inside(name: str, dirs: Any) -> Path:
    shown = name if len(name) <= 60 else name[:57] + "..."
    if "\x00" not in name and name.lower().endswith(".urdf"):
        for d in dirs:
            root = Path(d).resolve()
            cand = (root / name).resolve()
            if cand.is_relative_to(root) and cand.is_file():
                return cand
    where = "the robots folder" if dirs else "a robots folder (none is configured)"
    raise UrdfRefusedError(f"{shown!r} is not a URDF file of {where}")


def load_program(path: str | os.PathLike) -> Program:
    """Read and validate a program file; see the module docstring for the format.

    Raises
    ------
    InvalidInputError
        Malformed YAML or a field that fails validation (the message names
        the file, the line and the field), unknown points, joints outside
        their ranges.
    UnreachableError
        A start point that cannot be reached.
    OSError
        The file cannot be read.
    """
    p = Path(path)
    if p.is_dir():
        raise InvalidInputError(f"{p}: is a folder, not a file")
    with open(p, "rb") as fh:
        data = fh.read(MAX_DOCUMENT_BYTES + 1)
    return parse_program(data, source=str(p), base_dir=p.parent)


def parse_program(text: str | bytes, source: str = "<string>",
                  base_dir: str | os.PathLike | None = None, *, urdf_dirs: Any = None) -> Program:
    """Validate program ``text`` (YAML, str or UTF-8 bytes); see :func:`load_program` and,
    for ``urdf_dirs``, :func:`make_robot`."""
    raw = parse_document(text, source=source, kind="yaml")
    if not isinstance(raw, dict):
        raise InvalidInputError(f"{source}: a program must be a mapping with robot, points, program")

    def fail(loc: tuple[str | int, ...], msg: str, cls: type[Exception] = InvalidInputError) -> NoReturn:
        raise cls(f"{source}:{_line_of(raw, loc)}: {_loc_str(loc)}: {msg}")

    try:
        spec = ProgramFile.model_validate(plain(raw))
    except ValidationError as exc:
        err = exc.errors()[0]
        loc = tuple(x for x in err["loc"] if not (isinstance(x, str) and x.startswith("function-")))
        loc = tuple(x for x in loc if x not in ("str", "UrdfSpec", "dict[str,str]"))
        got = err.get("input")
        got_s = "" if isinstance(got, (dict, list)) else f" (got {short_repr(got)})"
        fail(loc, f"{err['msg']}{got_s}")

    try:
        robot = make_robot(spec.robot, base_dir, urdf_dirs=urdf_dirs)
    except UrdfRefusedError as exc:
        fail(("robot", "urdf"), str(exc))

    from ..robot.motion import CartesianTarget, Circ, JointTarget, Lin, Ptp, Wait

    # ---- points
    points: dict[str, Target] = {}
    for name, pt in spec.points.items():
        loc = ("points", name)
        try:
            if pt.joints_deg is not None:
                if any(k != "revolute" for k in robot.joint_kinds):
                    fail(loc + ("joints_deg",), f"robot {robot.name} has prismatic joints: give "
                         "joints as a mapping {NAME_deg: ..., NAME_mm: ...}")
                if len(pt.joints_deg) != robot.n_joints:
                    fail(loc + ("joints_deg",), f"needs {robot.n_joints} values "
                         f"({', '.join(robot.joint_names)}), got {len(pt.joints_deg)}")
                q = np.array(pt.joints_deg) * _DEG
                points[name] = JointTarget(robot.check_joints(q, f"joints of point {name}"), name)
            elif pt.joints is not None:
                q = np.empty(robot.n_joints)
                expected = [f"{n}_{'deg' if k == 'revolute' else 'mm'}"
                            for n, k in zip(robot.joint_names, robot.joint_kinds)]
                if sorted(pt.joints) != sorted(expected):
                    fail(loc + ("joints",), f"must name every joint with its unit: {expected}, "
                         f"got {sorted(pt.joints)}")
                for j, key in enumerate(expected):
                    q[j] = pt.joints[key] * (_DEG if key.endswith("_deg") else _MM)
                points[name] = JointTarget(robot.check_joints(q, f"joints of point {name}"), name)
            else:
                abc = pt.abc_deg if pt.abc_deg is not None else [0.0, 0.0, 0.0]
                pose = Pose.from_xyz_abc(np.array(pt.xyz_mm) * _MM, np.array(abc) * _DEG)
                cfg = None if pt.config is None else robot.parse_config(pt.config)
                points[name] = CartesianTarget(pose, cfg, name)
        except InvalidInputError as exc:
            if str(exc).startswith(source):
                raise
            fail(loc, str(exc))

    def point(ref: str, loc: tuple[str | int, ...]) -> Target:
        if ref not in points:
            fail(loc, f"unknown point {ref!r} (known: {', '.join(points)})")
        return points[ref]

    # ---- instructions
    d = spec.defaults
    motions: list[Motion] = []
    lines = []
    for i, item in enumerate(spec.program):
        loc = ("program", i)
        keys = [k for k in INSTRUCTIONS if k in item]
        if len(keys) != 1:
            fail(loc, f"an instruction needs exactly one of {', '.join(INSTRUCTIONS)}, "
                 f"got keys {sorted(item)}")
        kind = keys[0]
        try:
            ins = _SPECS[kind].model_validate(item)
        except ValidationError as exc:
            err = exc.errors()[0]
            got = err.get("input")
            got_s = "" if isinstance(got, (dict, list)) else f" (got {got!r})"
            fail(loc + tuple(err["loc"]), f"{err['msg']}{got_s}")
        line = _line_of(raw, loc)
        lines.append(line)
        ref = getattr(ins, kind) if kind != "WAIT" else None
        label = f"instruction {i} ({kind}{' ' + ref if ref else ''}, line {line})"
        # the spec class of each instruction kind (_SPECS)
        if isinstance(ins, PtpSpec):
            pct = d.speed_pct if ins.speed_pct is None else ins.speed_pct
            z = (d.zone_mm if ins.zone_mm is None else ins.zone_mm) * _MM
            motions.append(Ptp(point(ins.PTP, loc + ("PTP",)), pct, label, z))
        elif isinstance(ins, LinSpec):
            v = (d.speed_mm_s if ins.speed_mm_s is None else ins.speed_mm_s) * _MM
            z = (d.zone_mm if ins.zone_mm is None else ins.zone_mm) * _MM
            motions.append(Lin(point(ins.LIN, loc + ("LIN",)), v, z, label))
        elif isinstance(ins, CircSpec):
            v = (d.speed_mm_s if ins.speed_mm_s is None else ins.speed_mm_s) * _MM
            z = (d.zone_mm if ins.zone_mm is None else ins.zone_mm) * _MM
            motions.append(Circ(point(ins.via, loc + ("via",)), point(ins.CIRC, loc + ("CIRC",)), v, z, label))
        else:
            assert isinstance(ins, WaitSpec)
            motions.append(Wait(ins.WAIT.time_s, label))

    # ---- start joints
    if spec.start is not None:
        start_t = point(spec.start, ("start",))
        start_loc: tuple[str | int, ...] = ("start",)
    else:
        first = motions[0]
        if not isinstance(first, Ptp):
            fail(("program", 0), "without a start point the first instruction must be a PTP")
        start_t = first.target
        start_loc = ("program", 0)
    if isinstance(start_t, JointTarget):
        start = start_t.q
    else:
        try:
            start = robot.ik(start_t.pose, start_t.config)
        except UnreachableError as exc:
            fail(start_loc, f"start point {start_t.name}: {exc}", UnreachableError)
    return Program(robot, points, motions, np.asarray(start, dtype=float), source, lines)
