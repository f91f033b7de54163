"""Robot models by name, and the cylindrical palletizer as a :class:`RobotModel`.

``robot_by_name("arm6" | "scara" | "palletizer")`` returns the default model.
:class:`PalletizerRobot` adapts :class:`trajkit.kinematics.CylindricalPalletizer`
(the default palletizer) to the program interface: the tool pose is ``(x, y, z)`` with the
gripper yaw about the vertical, ``R = Rz(theta + d)``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._validate import check_array
from ..errors import InvalidInputError, UnreachableError
from ..kinematics import _jets
from ..kinematics.base import PRISMATIC, REVOLUTE, Pose, RobotModel, rot_z

__all__ = ["PalletizerRobot", "robot_by_name", "ROBOT_NAMES"]

#: Names accepted by :func:`robot_by_name`.
ROBOT_NAMES = ("arm6", "scara", "palletizer")

#: Largest tilt of the gripper axis from vertical accepted for a palletizer pose.
PALLETIZER_TILT_TOL = 1e-9

PALLETIZER_CONFIG = "default"


class PalletizerRobot(RobotModel):
    """The 4-axis cylindrical palletizer (A theta, B Z, C R, D wrist) as a RobotModel.

    Parameters
    ----------
    model : CylindricalPalletizer, optional
        Default: :func:`trajkit.kinematics.default_palletizer`.
    """

    configs = (PALLETIZER_CONFIG,)

    def __init__(self, model: Any = None) -> None:
        if model is None:
            from ..kinematics.palletizer import default_palletizer

            model = default_palletizer()
        self.model = model
        self.name = "palletizer"
        self.joint_names = tuple(model.joint_names)
        self.joint_kinds = (REVOLUTE, PRISMATIC, PRISMATIC, REVOLUTE)
        self.limits = tuple(model.limits)
        self.length_scale = float(model.limits[2].position_max)

    def fk(self, q: Any) -> Pose:
        """Tool pose of joints ``(theta [rad], z [m], r [m], d [rad])``."""
        x, y, z, yaw = self.model.pose_from_joints(check_array(q, "joints", ndim=1, size=4)).tolist()
        return Pose(np.array([x, y, z]), rot_z(yaw))

    def fk_jet(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Forward kinematics of joint jets: ``q`` (n, N, 4) Taylor coefficients of the
        joints (N <= 4) -> those of the tool position (n, N, 3) [m] and rotation
        (n, N, 3, 3): ``(r cos theta, r sin theta, z)`` and the yaw ``theta + d``
        (see :mod:`trajkit.kinematics._jets`)."""
        c, s = _jets.cos_sin(q[:, :, 0])
        pos = _jets.scale(q[:, :, 2], np.stack([c, s, np.zeros_like(c)], axis=-1))
        pos[:, :, 2] += q[:, :, 1]
        rot = _jets.axis_motion(q[:, :, 0] + q[:, :, 3], np.array([0.0, 0.0, 1.0]))
        return pos, rot

    def config_of(self, q: Any) -> str:
        return PALLETIZER_CONFIG

    def _pose4(self, pose: Pose) -> np.ndarray:
        r = pose.rotation
        if r[2, 2] <= 0.0 or math.hypot(r[0, 2], r[1, 2]) > PALLETIZER_TILT_TOL:
            raise UnreachableError(
                f"pose at {_mm(pose.position)}: a palletizer cannot tilt its gripper"
            )
        return np.array([*pose.position, math.atan2(r[1, 0], r[0, 0])])

    def ik_all(self, pose: Pose) -> list[tuple[str, np.ndarray]]:
        try:
            return [(PALLETIZER_CONFIG, self.model.joints_from_pose(self._pose4(pose), check=False))]
        except UnreachableError:
            return []

    def ik(self, pose: Pose, config: Any = None, seed: Any = None) -> np.ndarray:
        if config is not None:
            self.parse_config(config)
        ref = 0.0 if seed is None else float(np.asarray(seed)[3])
        try:
            return self.model.joints_from_pose(self._pose4(pose), wrist_reference=ref)
        except UnreachableError as exc:
            raise UnreachableError(f"pose at {_mm(pose.position)}: {exc}") from None

    def to_dict(self) -> dict:
        return {"model": "palletizer", "joints": self.model.to_dict()}


def _mm(p: Any) -> str:
    return "(" + ", ".join(f"{1e3 * float(x):.3f}" for x in p) + ") mm"


def robot_by_name(name: str) -> RobotModel:
    """Default model of ``name`` in :data:`ROBOT_NAMES`."""
    if name == "arm6":
        from ..kinematics.arm6 import default_arm6

        return default_arm6()
    if name == "scara":
        from ..kinematics.scara import default_scara

        return default_scara()
    if name == "palletizer":
        return PalletizerRobot()
    raise InvalidInputError(f"robot must be one of {list(ROBOT_NAMES)} or a URDF spec, got {name!r}")
