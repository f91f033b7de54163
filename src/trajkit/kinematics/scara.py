"""A 4-axis SCARA robot: two horizontal revolute arms, a vertical quill, a tool roll.

Joints (SI): ``J1`` shoulder [rad], ``J2`` elbow [rad], ``J3`` quill stroke
[m] (positive downwards), ``J4`` tool roll [rad]. Forward kinematics::

    x = a1 cos q1 + a2 cos(q1 + q2)
    y = a1 sin q1 + a2 sin(q1 + q2)
    z = z0 - d3
    R = Rz(q1 + q2 + q4)          (the tool z axis stays vertical)

Configurations: ``"lefty"`` (elbow angle q2 >= 0) and ``"righty"`` (q2 < 0).
At q2 = 0 (arm stretched) both coincide: that is the SCARA's singularity.

Default parameters (:func:`default_scara`) are those of a typical 6 kg-class
SCARA with 600 mm reach (arm lengths 325 + 275 mm, 200 mm stroke; speeds and
ranges approximated from public data sheets of that class; accelerations and
jerks are our assumptions, as data sheets do not give them).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._validate import check_array, check_positive
from ..errors import InvalidInputError
from ..limits import AxisLimits
from . import _jets
from .base import PRISMATIC, REACH_RTOL, REVOLUTE, Pose, RobotModel, rot_z, wrap_angle

__all__ = ["Scara", "default_scara"]

#: Largest tilt of the tool z axis from vertical that a SCARA pose may have
#: [rad] (a SCARA cannot tilt its tool).
SCARA_TILT_TOL = 1e-9


class Scara(RobotModel):
    """SCARA model with closed-form IK (two configurations).

    Parameters
    ----------
    a1, a2 : float
        Lengths of the inner and outer arm [m], > 0.
    z0 : float
        Height of the tool centre point when the quill is up (J3 = 0) [m].
    limits : sequence of 4 AxisLimits
        Per joint (J1, J2 [rad], J3 [m], J4 [rad]) with ranges.
    name : str
    """

    configs = ("lefty", "righty")

    def __init__(self, a1: float, a2: float, z0: float, limits: Any, name: str = "scara") -> None:
        self.a1 = check_positive(a1, "a1")
        self.a2 = check_positive(a2, "a2")
        self.z0 = float(z0)
        self.name = name
        self.joint_names = ("J1", "J2", "J3", "J4")
        self.joint_kinds = (REVOLUTE, REVOLUTE, PRISMATIC, REVOLUTE)
        lims = tuple(limits)
        if len(lims) != 4 or not all(isinstance(x, AxisLimits) for x in lims):
            raise InvalidInputError(f"Scara needs 4 AxisLimits, got {len(lims)} entries")
        self.limits = tuple(lim.with_name(n) for lim, n in zip(lims, self.joint_names))
        self.length_scale = self.a1 + self.a2

    @property
    def home(self) -> np.ndarray:
        """The ready configuration: the elbow (J2) bent 90 deg (clipped into its
        range), the rest as :attr:`RobotModel.home`; the arm stretched (J2 = 0) is
        a singularity that a line cannot leave along the arm."""
        return self._home_with(1, 0.5 * math.pi)

    def fk(self, q: Any) -> Pose:
        """Tool pose of joints ``q`` (4,) [rad, rad, m, rad]."""
        q1, q2, d3, q4 = check_array(q, "joints", ndim=1, size=4).tolist()
        x = self.a1 * math.cos(q1) + self.a2 * math.cos(q1 + q2)
        y = self.a1 * math.sin(q1) + self.a2 * math.sin(q1 + q2)
        return Pose(np.array([x, y, self.z0 - d3]), rot_z(q1 + q2 + q4))

    def fk_jet(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Forward kinematics of joint jets: ``q`` (n, N, 4) Taylor coefficients of the
        joints (N <= 4) -> those of the tool position (n, N, 3) [m] and rotation (n, N, 3, 3)
        (see :mod:`trajkit.kinematics._jets`)."""
        c1, s1 = _jets.cos_sin(q[:, :, 0])
        c12, s12 = _jets.cos_sin(q[:, :, 0] + q[:, :, 1])
        pos = np.stack([self.a1 * c1 + self.a2 * c12, self.a1 * s1 + self.a2 * s12, -q[:, :, 2]],
                       axis=-1)
        pos[:, 0, 2] += self.z0
        rot = _jets.axis_motion(q[:, :, 0] + q[:, :, 1] + q[:, :, 3], np.array([0.0, 0.0, 1.0]))
        return pos, rot

    def config_of(self, q: Any) -> str:
        """``"lefty"`` if q2 >= 0 else ``"righty"``."""
        return "lefty" if float(np.asarray(q)[1]) >= 0.0 else "righty"

    def ik_all(self, pose: Pose) -> list[tuple[str, np.ndarray]]:
        """Both solutions (lefty, righty); empty when out of reach or tilted."""
        r = pose.rotation
        if r[2, 2] <= 0.0 or math.hypot(r[0, 2], r[1, 2]) > SCARA_TILT_TOL:
            return []
        x, y, z = pose.position.tolist()
        yaw = math.atan2(r[1, 0], r[0, 0])
        rr = x * x + y * y
        c2 = (rr - self.a1**2 - self.a2**2) / (2.0 * self.a1 * self.a2)
        if abs(c2) > 1.0 + REACH_RTOL:
            return []
        c2 = max(-1.0, min(1.0, c2))
        out = []
        for cfg, sgn in (("lefty", 1.0), ("righty", -1.0)):
            q2 = sgn * math.acos(c2)
            q1 = math.atan2(y, x) - math.atan2(self.a2 * math.sin(q2), self.a1 + self.a2 * math.cos(q2))
            q1 = wrap_angle(q1)
            q4 = wrap_angle(yaw - q1 - q2)
            out.append((cfg, np.array([q1, q2, self.z0 - z, q4])))
        return out

    def to_dict(self) -> dict:
        """JSON-ready parameters [m]."""
        return {"model": "scara", "a1": self.a1, "a2": self.a2, "z0": self.z0}


def default_scara() -> Scara:
    """A 600 mm-reach, 6 kg-class SCARA (see the module docstring for the values)."""
    d = math.pi / 180.0
    lims = [
        AxisLimits(420 * d, 2100 * d, 21000 * d, position_min=-132 * d, position_max=132 * d),
        AxisLimits(720 * d, 3600 * d, 36000 * d, position_min=-150 * d, position_max=150 * d),
        AxisLimits(1.1, 5.5, 55.0, position_min=0.0, position_max=0.2),
        AxisLimits(2500 * d, 12500 * d, 125000 * d, position_min=-360 * d, position_max=360 * d),
    ]
    return Scara(0.325, 0.275, 0.2, lims, name="scara")
