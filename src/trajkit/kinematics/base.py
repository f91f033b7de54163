"""The robot-model interface shared by SCARA, 6-axis arm and URDF models.

A :class:`RobotModel` has ``n_joints`` joints with names, kinds (revolute
[rad] or prismatic [m]) and per-joint :class:`~trajkit.AxisLimits` whose
position range is the joint range. It maps joints to the tool pose
(:meth:`RobotModel.fk`) and back (:meth:`RobotModel.ik`,
:meth:`RobotModel.ik_all`, :meth:`RobotModel.ik_near`).

A tool pose is a :class:`Pose`: a position [m] and a rotation matrix (the
tool frame's axes in the base frame). Orientation angles at the I/O boundary
are KUKA-style A, B, C (intrinsic Z-Y'-X'': ``R = Rz(A) Ry(B) Rx(C)``).

A *configuration* is a short string naming one IK branch (``"lefty"``,
``"front-up-noflip"``, ...); every model lists its own in
:attr:`RobotModel.configs` and parses them with
:meth:`RobotModel.parse_config`.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._validate import check_array
from ..errors import InvalidInputError, UnreachableError
from ..limits import AxisLimits

__all__ = [
    "Pose",
    "RobotModel",
    "rotation_from_abc",
    "abc_from_rotation",
    "rot_x",
    "rot_y",
    "rot_z",
    "wrap_angle",
    "REVOLUTE",
    "PRISMATIC",
]

REVOLUTE = "revolute"
PRISMATIC = "prismatic"

#: Largest deviation of R^T R from the identity accepted for a rotation matrix.
ROTATION_ORTHO_TOL = 1e-6

#: Two IK solutions closer than this in every joint [rad or m] are the same.
IK_DUPLICATE_TOL = 1e-9

#: Relative slack on the reach test (round-off at the workspace boundary).
REACH_RTOL = 1e-12

#: Joint values within this of a range bound count as inside [rad or m].
RANGE_TOL = 1e-9


def rot_x(a: float) -> np.ndarray:
    """Rotation matrix (3, 3) about x by ``a`` [rad]."""
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(a: float) -> np.ndarray:
    """Rotation matrix (3, 3) about y by ``a`` [rad]."""
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(a: float) -> np.ndarray:
    """Rotation matrix (3, 3) about z by ``a`` [rad]."""
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rotation_from_abc(abc: Any) -> np.ndarray:
    """Rotation matrix from KUKA-style angles.

    Parameters
    ----------
    abc : array_like, shape (3,)
        Angles A, B, C [rad]: ``R = Rz(A) Ry(B) Rx(C)``.

    Returns
    -------
    ndarray, shape (3, 3)
    """
    a, b, c = check_array(abc, "abc", ndim=1, size=3).tolist()
    return rot_z(a) @ rot_y(b) @ rot_x(c)


def abc_from_rotation(rotation: Any) -> np.ndarray:
    """Inverse of :func:`rotation_from_abc`: angles A, B, C [rad], shape (3,).

    At the gimbal lock (B = +-90 deg) C is set to zero.
    """
    r = np.asarray(rotation, dtype=np.float64)
    sb = -r[2, 0]
    b = math.atan2(sb, math.hypot(r[0, 0], r[1, 0]))
    if math.hypot(r[0, 0], r[1, 0]) < ROTATION_ORTHO_TOL:
        a = math.atan2(-r[0, 1], r[1, 1])
        c = 0.0
    else:
        a = math.atan2(r[1, 0], r[0, 0])
        c = math.atan2(r[2, 1], r[2, 2])
    return np.array([a, b, c])


def wrap_angle(a: Any) -> Any:
    """Wrap angles [rad] into (-pi, pi]."""
    if isinstance(a, float):
        w = math.fmod(a + math.pi, 2.0 * math.pi)
        w = (w + 2.0 * math.pi if w < 0.0 else w) - math.pi
        return math.pi if w == -math.pi else w
    wa = np.mod(np.asarray(a, dtype=np.float64) + math.pi, 2.0 * math.pi) - math.pi
    wa = np.where(wa == -math.pi, math.pi, wa)
    return float(wa) if np.ndim(wa) == 0 else wa


@dataclass(frozen=True)
class Pose:
    """A tool pose: position and orientation in the robot base frame.

    Attributes
    ----------
    position : ndarray, shape (3,)
        Tool centre point [m].
    rotation : ndarray, shape (3, 3)
        Tool frame axes (columns) in the base frame.
    """

    position: np.ndarray
    rotation: np.ndarray

    def __post_init__(self) -> None:
        p = check_array(self.position, "pose position", ndim=1, size=3)
        r = check_array(self.rotation, "pose rotation", ndim=2, size=9)
        if r.shape != (3, 3):
            raise InvalidInputError(f"pose rotation must have shape (3, 3), got {r.shape}")
        err = float(np.abs(r.T @ r - np.eye(3)).max())
        if err > ROTATION_ORTHO_TOL or np.linalg.det(r) < 0:
            raise InvalidInputError(
                f"pose rotation is not a rotation matrix (|R^T R - I| = {err:.3g}, "
                f"bound {ROTATION_ORTHO_TOL})"
            )
        object.__setattr__(self, "position", p)
        object.__setattr__(self, "rotation", r)

    @classmethod
    def trusted(cls, position: np.ndarray, rotation: np.ndarray) -> Pose:
        """Build without validation (for internal hot loops: inputs already float arrays)."""
        obj = object.__new__(cls)
        object.__setattr__(obj, "position", position)
        object.__setattr__(obj, "rotation", rotation)
        return obj

    @classmethod
    def from_xyz_abc(cls, xyz: Any, abc: Any = (0.0, 0.0, 0.0)) -> Pose:
        """Pose from a position [m] and KUKA angles A, B, C [rad]."""
        return cls(np.asarray(xyz, dtype=np.float64), rotation_from_abc(abc))

    @property
    def abc(self) -> np.ndarray:
        """Orientation as KUKA angles A, B, C [rad], shape (3,)."""
        return abc_from_rotation(self.rotation)

    def as_matrix(self) -> np.ndarray:
        """Homogeneous transform, shape (4, 4)."""
        m = np.eye(4)
        m[:3, :3] = self.rotation
        m[:3, 3] = self.position
        return m

    def distance(self, other: Pose) -> tuple[float, float]:
        """(position error [m], rotation angle error [rad]) to ``other``."""
        dp = float(np.linalg.norm(self.position - other.position))
        # |Ra - Rb|_F = 2 sqrt(2) sin(angle / 2): accurate for small angles.
        f = float(np.linalg.norm(self.rotation - other.rotation)) / (2.0 * math.sqrt(2.0))
        return dp, 2.0 * math.asin(min(1.0, f))


class RobotModel(ABC):
    """Interface of a serial robot model (SI units: m, rad, s).

    Subclasses set :attr:`name`, :attr:`joint_names`, :attr:`joint_kinds`,
    :attr:`limits`, :attr:`configs`, :attr:`length_scale` and implement
    :meth:`fk`, :meth:`ik_all` (and, for numeric solvers, :meth:`ik_near`).

    Attributes
    ----------
    name : str
        Model name.
    joint_names : tuple of str
    joint_kinds : tuple of str
        ``"revolute"`` [rad] or ``"prismatic"`` [m] per joint.
    limits : tuple of AxisLimits
        Per joint: velocity, acceleration, jerk limits and the joint range.
    configs : tuple of str
        The IK configurations (branches) this model knows.
    length_scale : float
        Characteristic tool length (reach) [m], used for relative tolerances.
    cartesian_accel, cartesian_jerk : float
        Default tool-path acceleration [m/s^2] and jerk [m/s^3] of Cartesian
        motions.
    orientation_speed : float
        Default largest tool rotation speed [rad/s] of Cartesian motions.
    """

    name: str = "robot"
    joint_names: tuple[str, ...] = ()
    joint_kinds: tuple[str, ...] = ()
    limits: tuple[AxisLimits, ...] = ()
    configs: tuple[str, ...] = ()
    length_scale: float = 1.0
    cartesian_accel: float = 5.0
    cartesian_jerk: float = 50.0
    orientation_speed: float = math.pi

    # ------------------------------------------------------------ structure
    @property
    def n_joints(self) -> int:
        """Number of joints."""
        return len(self.joint_names)

    @property
    def joint_ranges(self) -> np.ndarray:
        """Joint ranges, shape (n_joints, 2) [rad or m]."""
        return np.array([[lim.position_min, lim.position_max] for lim in self.limits])

    @property
    def home(self) -> np.ndarray:
        """A ready configuration (n_joints,) [rad or m] inside the joint ranges:
        every joint at 0, or at the middle of its range where 0 lies outside.
        Models with a singularity at 0 (a stretched arm, a straight wrist)
        bend away from it, so that Cartesian motions can start from home."""
        return self._home_with(-1, 0.0)

    def _home_with(self, k: int, value: float) -> np.ndarray:
        """Every joint at 0 (or mid-range), joint ``k`` (if >= 0) at ``value``
        clipped into its range."""
        q = np.zeros(self.n_joints)
        for i, lim in enumerate(self.limits):
            if not lim.position_min <= 0.0 <= lim.position_max:
                q[i] = 0.5 * (lim.position_min + lim.position_max)
        if k < 0:
            return q
        lim = self.limits[k]
        q[k] = min(max(value, lim.position_min), lim.position_max)
        return q

    def joint_unit(self, k: int) -> tuple[str, float]:
        """Display unit of joint ``k`` and the factor from SI: ``("deg", 180/pi)`` or ``("mm", 1000)``."""
        return ("deg", 180.0 / math.pi) if self.joint_kinds[k] == REVOLUTE else ("mm", 1e3)

    def check_joints(self, q: Any, field: str = "joints") -> np.ndarray:
        """Return ``q`` [rad or m] as a float array (n_joints,); raise if outside a range.

        Raises
        ------
        InvalidInputError
            Wrong size, NaN, or a joint outside its range (the message names
            the joint, and the value and the range in deg or mm).
        """
        arr = check_array(q, field, ndim=1, size=self.n_joints)
        for k, lim in enumerate(self.limits):
            x = float(arr[k])
            if not lim.position_min <= x <= lim.position_max:
                unit, sc = self.joint_unit(k)
                raise InvalidInputError(
                    f"{field}: joint {self.joint_names[k]} = {x * sc:.6g} {unit} is outside its "
                    f"range [{lim.position_min * sc:.6g}, {lim.position_max * sc:.6g}] {unit}")
        return arr

    def parse_config(self, config: Any) -> str:
        """Return the canonical configuration string.

        Accepts a string from :attr:`configs` or a mapping of flags (see the
        model's documentation). Raises :class:`InvalidInputError` otherwise.
        """
        if isinstance(config, str) and config in self.configs:
            return config
        raise InvalidInputError(
            f"configuration {config!r} is not one of {list(self.configs)} for robot {self.name}"
        )

    # ----------------------------------------------------------- kinematics
    @abstractmethod
    def fk(self, q: Any) -> Pose:
        """Forward kinematics: joints (n_joints,) [rad or m] -> tool :class:`Pose`."""

    @abstractmethod
    def ik_all(self, pose: Pose) -> list[tuple[str, np.ndarray]]:
        """Every IK solution of ``pose`` as ``(config, q)`` pairs.

        Revolute joints are returned in (-pi, pi]; joint ranges are not
        checked (use :meth:`ik` for that). An empty list means the pose is
        out of reach.
        """

    @abstractmethod
    def config_of(self, q: Any) -> str:
        """The configuration (IK branch) that joint vector ``q`` lies in."""

    def ik(self, pose: Pose, config: Any = None, seed: Any = None) -> np.ndarray:
        """Inverse kinematics for one configuration, inside the joint ranges.

        Parameters
        ----------
        pose : Pose
            Target tool pose.
        config : str or mapping, optional
            Configuration to use; default: that of ``seed`` if given, else
            the first in :attr:`configs` that is reachable.
        seed : array_like, shape (n_joints,), optional
            Joints to stay close to: of the 2 pi-equivalent angles inside the
            range, the closest to ``seed`` is returned (and the free angle at
            a singularity is taken from it).

        Returns
        -------
        ndarray, shape (n_joints,)

        Raises
        ------
        UnreachableError
            The pose is out of reach in that configuration or needs a joint
            outside its range (the message names the joint and the range).
        """
        seed_arr = None if seed is None else np.asarray(seed, dtype=np.float64)
        if config is None and seed_arr is not None:
            config = self.config_of(seed_arr)
        cfg = None if config is None else self.parse_config(config)
        sols = self._solutions(pose, seed_arr, cfg)
        if not sols:
            raise UnreachableError(
                f"pose at {_fmt_xyz(pose.position)} is outside the workspace of {self.name}"
            )
        candidates = [(c, q) for c, q in sols if cfg is None or c == cfg]
        if not candidates:
            raise UnreachableError(
                f"pose at {_fmt_xyz(pose.position)} cannot be reached in configuration "
                f"{cfg!r} of {self.name}"
            )
        last_err = None
        for _, q in candidates:
            try:
                return self._fit_ranges(q, seed_arr)
            except UnreachableError as exc:
                last_err = exc
        raise UnreachableError(
            f"pose at {_fmt_xyz(pose.position)}"
            + (f" in configuration {cfg!r}" if cfg else "")
            + f": {last_err}"
        )

    def ik_near(self, pose: Pose, seed: Any) -> np.ndarray:
        """IK in the configuration of ``seed``, closest to ``seed`` (path following)."""
        return self.ik(pose, None, seed)

    # -------------------------------------------------------------- helpers
    def _solutions(self, pose: Pose, seed: np.ndarray | None,
                   config: str | None = None) -> list[tuple[str, np.ndarray]]:
        return self.ik_all(pose)

    def _fit_ranges(self, q: np.ndarray, seed: np.ndarray | None) -> np.ndarray:
        """Shift revolute joints by 2 pi to fit their range (closest to seed)."""
        out = np.array(q, dtype=np.float64)
        for k, (kind, lim) in enumerate(zip(self.joint_kinds, self.limits)):
            lo, hi = lim.position_min, lim.position_max
            x = out[k]
            if kind == REVOLUTE:
                ref = x if seed is None else float(seed[k])
                base = x + 2.0 * math.pi * round((ref - x) / (2.0 * math.pi))
                options = [base + 2.0 * math.pi * m for m in (-1, 0, 1, -2, 2)]
                inside = [v for v in options if lo - RANGE_TOL <= v <= hi + RANGE_TOL]
                if not inside:
                    raise UnreachableError(
                        f"joint {self.joint_names[k]} would be at {math.degrees(x):.3f} deg, "
                        f"outside its range [{math.degrees(lo):.3f}, {math.degrees(hi):.3f}] deg"
                    )
                x = min(inside, key=lambda v: abs(v - ref))
            elif not lo - RANGE_TOL <= x <= hi + RANGE_TOL:
                raise UnreachableError(
                    f"joint {self.joint_names[k]} would be at {x * 1e3:.3f} mm, outside its "
                    f"range [{lo * 1e3:.3f}, {hi * 1e3:.3f}] mm"
                )
            out[k] = min(max(x, lo), hi)
        return out


def _fmt_xyz(p: Iterable[float]) -> str:
    return "(" + ", ".join(f"{1e3 * float(v):.3f}" for v in p) + ") mm"


def parse_flags(
    config: Any, flags: Mapping[str, Sequence[str]], model: str
) -> str:
    """Canonical ``"a-b-c"`` string from a string or a mapping of flags.

    ``flags`` maps flag name -> allowed values, in order.
    """
    names = list(flags)
    if isinstance(config, str):
        parts = config.replace("/", "-").replace(",", "-").split("-")
        parts = [p.strip().lower() for p in parts if p.strip()]
        if len(parts) == len(names) and all(p in flags[n] for p, n in zip(parts, names)):
            return "-".join(parts)
    elif isinstance(config, Mapping):
        vals = []
        for n in names:
            v = config.get(n)
            if not isinstance(v, str) or v.lower() not in flags[n]:
                raise InvalidInputError(
                    f"configuration flag {n!r} of {model} must be one of {list(flags[n])}, "
                    f"got {v!r}"
                )
            vals.append(v.lower())
        extra = set(config) - set(names)
        if extra:
            raise InvalidInputError(
                f"unknown configuration flag(s) {sorted(extra)} for {model}; known: {names}"
            )
        return "-".join(vals)
    allowed = "-".join("|".join(flags[n]) for n in names)
    raise InvalidInputError(
        f"configuration {config!r} of {model} must look like {allowed!r} "
        f"or be a mapping of {names}"
    )
