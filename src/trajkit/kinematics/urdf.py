"""Robots from a URDF file, through pinocchio (PyPI package ``pin``).

Pinocchio parses the URDF and computes forward kinematics and frame
Jacobians; trajkit adds a damped least-squares inverse kinematics seeded
from the previous sample (so a Cartesian path stays on one branch), the
joint limits and the :class:`~trajkit.kinematics.base.RobotModel` interface.

``pin`` is an optional dependency (``pip install pin``); importing this
module without it raises an :class:`ImportError` that says so.

URDF gives joint ranges and velocity limits but no acceleration or jerk
limits: they default to ``accel_factor * v_max`` and ``jerk_factor *
a_max`` (overridable per joint with ``limits=``).
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from typing import Any

import numpy as np

from .._validate import check_array, check_positive
from ..errors import InvalidInputError, UnreachableError
from ..limits import AxisLimits
from .base import PRISMATIC, REVOLUTE, Pose, RobotModel, _fmt_xyz

try:  # pragma: no cover - depends on the install
    import pinocchio as _pin
except ImportError as exc:  # pragma: no cover
    raise ImportError("URDF robots need pinocchio: pip install pin") from exc

__all__ = ["UrdfRobot", "URDF_CONFIG"]

#: The single configuration label of a numerically solved URDF robot.
URDF_CONFIG = "numeric"

#: IK converges when the pose error (position [m] / length scale, and angle
#: [rad]) is below this.
IK_TOL = 1e-12

#: Iterations of the damped least-squares IK per seed.
IK_MAX_ITER = 200

#: Damping of the least-squares step (squared, relative to 1).
IK_DAMPING = 1e-10

#: Largest joint step per IK iteration [rad or m] (keeps Newton local).
IK_MAX_STEP = 0.5

#: Number of deterministic extra seeds tried by :meth:`UrdfRobot.ik_all`.
IK_ALL_SEEDS = 24

#: Two numeric solutions closer than this in every joint are the same [rad or m].
IK_DISTINCT_TOL = 1e-6

#: Smallest length scale [m] assumed for a URDF robot (relative tolerances).
MIN_LENGTH_SCALE = 1e-3

_KINDS = {
    "JointModelRX": REVOLUTE, "JointModelRY": REVOLUTE, "JointModelRZ": REVOLUTE,
    "JointModelRevoluteUnaligned": REVOLUTE,
    "JointModelPX": PRISMATIC, "JointModelPY": PRISMATIC, "JointModelPZ": PRISMATIC,
    "JointModelPrismaticUnaligned": PRISMATIC,
}


class UrdfRobot(RobotModel):
    """A serial robot read from a URDF file.

    Parameters
    ----------
    path : str or PathLike
        URDF file.
    tip_link : str
        Name of the tool link (or any frame) whose pose is the tool pose. Only
        the joints of the chain from the base to it are the robot's joints;
        any other joint (a gripper's fingers) is locked at its neutral position.
    accel_factor, jerk_factor : float
        Default a_max = accel_factor * v_max [1/s], j_max = jerk_factor *
        a_max [1/s] for joints whose limits are not given.
    limits : sequence of AxisLimits, optional
        Per-joint limits overriding the URDF (ranges included).
    name : str, optional
        Model name (default: the URDF robot name).

    Raises
    ------
    InvalidInputError
        A missing file or link, a joint type other than revolute/prismatic
        (continuous, floating, planar joints are not supported), a joint
        without range or velocity limit.
    """

    configs = (URDF_CONFIG,)

    def __init__(self, path: str | os.PathLike, tip_link: str, accel_factor: float = 4.0,
                 jerk_factor: float = 10.0, limits: Sequence[AxisLimits] | None = None,
                 name: str | None = None) -> None:
        path = os.fspath(path)
        if not os.path.isfile(path):
            raise InvalidInputError(f"URDF file {path!r} does not exist")
        try:
            model = _pin.buildModelFromUrdf(path)
        except Exception as exc:  # pinocchio raises plain RuntimeError/ValueError
            raise InvalidInputError(f"cannot read URDF {path!r}: {exc}") from None
        if not model.existFrame(tip_link):
            raise InvalidInputError(f"URDF {path!r} has no link named {tip_link!r}")
        # joints that do not move the tip (a gripper's fingers, other branches) are
        # locked at their neutral position: the robot is the chain to the tip
        support = set(model.supports[model.frames[model.getFrameId(tip_link)].parentJoint])
        lock = [j for j in range(1, model.njoints) if j not in support]
        if lock:
            model = _pin.buildReducedModel(model, lock, _pin.neutral(model))
        af = check_positive(accel_factor, "accel_factor")
        jf = check_positive(jerk_factor, "jerk_factor")
        self.model = model
        self.data = model.createData()
        self.frame_id = model.getFrameId(tip_link)
        self.tip_link = tip_link
        self.path = path
        self.name = name or model.name
        names, kinds = [], []
        for i in range(1, model.njoints):
            short = model.joints[i].shortname()
            if short not in _KINDS or model.joints[i].nq != 1:
                raise InvalidInputError(
                    f"joint {model.names[i]!r} of {path!r} has type {short}; only revolute and "
                    "prismatic joints with finite ranges are supported"
                )
            names.append(model.names[i])
            kinds.append(_KINDS[short])
        self.joint_names = tuple(names)
        self.joint_kinds = tuple(kinds)
        lims: list[AxisLimits]
        if limits is not None:
            lims = list(limits)
            if len(lims) != len(names):
                raise InvalidInputError(f"limits has {len(lims)} entries, the URDF has {len(names)} joints")
        else:
            lims = []
            for k, nm in enumerate(names):
                lo, hi = float(model.lowerPositionLimit[k]), float(model.upperPositionLimit[k])
                v = float(model.velocityLimit[k])
                if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
                    raise InvalidInputError(f"joint {nm!r} of {path!r} has no valid range [{lo}, {hi}]")
                if not (math.isfinite(v) and v > 0):
                    raise InvalidInputError(f"joint {nm!r} of {path!r} has no velocity limit (got {v})")
                lims.append(AxisLimits(v, af * v, jf * af * v, position_min=lo, position_max=hi))
        self.limits = tuple(lim.with_name(n) for lim, n in zip(lims, names))
        self.length_scale = self._reach_estimate()

    def _reach_estimate(self) -> float:
        mid = 0.5 * (self.joint_ranges[:, 0] + self.joint_ranges[:, 1])
        _pin.framesForwardKinematics(self.model, self.data, mid)
        total = 0.0
        for i in range(1, self.model.njoints):
            total += float(np.linalg.norm(self.model.jointPlacements[i].translation))
        total += float(np.linalg.norm(self.model.frames[self.frame_id].placement.translation))
        return max(total, MIN_LENGTH_SCALE)

    def fk(self, q: Any) -> Pose:
        """Tool pose of joints ``q`` (n_joints,) [rad or m]."""
        qq = check_array(q, "joints", ndim=1, size=self.n_joints)
        _pin.framesForwardKinematics(self.model, self.data, qq)
        m = self.data.oMf[self.frame_id]
        return Pose(np.array(m.translation), np.array(m.rotation))

    def config_of(self, q: Any) -> str:
        """Always :data:`URDF_CONFIG` (numeric IK follows its seed)."""
        return URDF_CONFIG

    def _solve_from(self, pose: Pose, seed: np.ndarray) -> np.ndarray | None:
        target = _pin.SE3(pose.rotation, pose.position)
        q = np.array(seed, dtype=np.float64)
        lo, hi = self.joint_ranges[:, 0], self.joint_ranges[:, 1]
        scale = np.array([1.0 / self.length_scale] * 3 + [1.0] * 3)
        polish = False
        for _ in range(IK_MAX_ITER):
            _pin.framesForwardKinematics(self.model, self.data, q)
            cur = self.data.oMf[self.frame_id]
            err = _pin.log6(cur.actInv(target)).vector  # in the tool frame
            if float(np.abs(err * scale).max()) < IK_TOL:
                if polish:
                    return q
                # one more Newton step: the error is squared, far below IK_TOL, so
                # neighbouring solutions along a path differ by round-off only (their
                # differences are the joint path's derivatives)
                polish = True
            jac = _pin.computeFrameJacobian(self.model, self.data, q, self.frame_id,
                                            _pin.ReferenceFrame.LOCAL)
            js = jac * scale[:, None]
            es = err * scale
            dq = js.T @ np.linalg.solve(js @ js.T + IK_DAMPING * np.eye(6), es)
            step = float(np.abs(dq).max())
            if step > IK_MAX_STEP:
                dq *= IK_MAX_STEP / step
            q = np.clip(q + dq, lo, hi)
            if polish:
                return q
        return None

    def ik_near(self, pose: Pose, seed: Any) -> np.ndarray:
        """Numeric IK started at ``seed`` (n_joints,); the solution nearest the seed's branch.

        Raises
        ------
        UnreachableError
            When the solver does not converge inside the joint ranges.
        """
        s = check_array(seed, "seed", ndim=1, size=self.n_joints)
        q = self._solve_from(pose, s)
        if q is None:
            raise UnreachableError(
                f"pose at {_fmt_xyz(pose.position)} could not be reached by {self.name} "
                "from the previous joints (out of reach, outside the joint ranges, or singular)"
            )
        return q

    def ik(self, pose: Pose, config: Any = None, seed: Any = None) -> np.ndarray:
        """Numeric IK from ``seed`` (default: the middle of the ranges, then other seeds)."""
        if config is not None:
            self.parse_config(config)
        seeds = [] if seed is None else [check_array(seed, "seed", ndim=1, size=self.n_joints)]
        seeds += self._seeds()
        for s in seeds:
            q = self._solve_from(pose, s)
            if q is not None:
                return q
        raise UnreachableError(
            f"pose at {_fmt_xyz(pose.position)} is outside the workspace of {self.name} "
            f"(no IK solution from {len(seeds)} seeds)"
        )

    def _seeds(self) -> list[np.ndarray]:
        lo, hi = self.joint_ranges[:, 0], self.joint_ranges[:, 1]
        rng = np.random.default_rng(0)
        out = [0.5 * (lo + hi)]
        out += [lo + (hi - lo) * rng.uniform(0.1, 0.9, self.n_joints) for _ in range(IK_ALL_SEEDS)]
        return out

    def ik_all(self, pose: Pose) -> list[tuple[str, np.ndarray]]:
        """Distinct solutions found from deterministic seeds (not guaranteed complete)."""
        sols: list[np.ndarray] = []
        for s in self._seeds():
            q = self._solve_from(pose, s)
            if q is not None and not any(np.abs(q - p).max() < IK_DISTINCT_TOL for p in sols):
                sols.append(q)
        return [(URDF_CONFIG, q) for q in sols]

    def to_dict(self) -> dict:
        """JSON-ready description."""
        return {"model": "urdf", "path": self.path, "tip_link": self.tip_link}
