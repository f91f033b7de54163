"""A 6-axis industrial arm with a spherical wrist, closed-form IK (8 branches).

Geometry (standard Denavit-Hartenberg, ``T_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)``):

=====  ==========  ======  ======  ========
joint  theta_i     d_i     a_i     alpha_i
=====  ==========  ======  ======  ========
A1     q1          d1      a1      -pi/2
A2     q2 - pi/2   0       a2      0
A3     q3          0       a3      -pi/2
A4     q4          d4      0       +pi/2
A5     q5          0       0       -pi/2
A6     q6          d6      0       0
=====  ==========  ======  ======  ========

At q = 0 the upper arm points straight up and the forearm horizontally
forward (+x); q2 > 0 tilts the upper arm forward, q3 > 0 tilts the forearm
down. The flange (tool frame) z axis is the wrist's last axis.

Configurations (``"shoulder-elbow-wrist"``, 8 in all):

- shoulder ``front`` / ``back``: the wrist centre lies in front of / behind
  axis A1 (seen along the arm's plane);
- elbow ``up`` / ``down``: the angle ``q3 + atan2(d4, a3)`` is positive /
  negative (elbow above / below the shoulder-wrist line for a front shoulder);
- wrist ``noflip`` / ``flip``: q5 >= 0 / q5 < 0.

Singularities: wrist (q5 = 0: only q4 + q6 is defined; q4 is taken from the
seed), shoulder (wrist centre on axis A1: q1 from the seed), elbow (arm
stretched).

Default parameters (:func:`default_arm6`): the dimensions of a common 6 kg
class arm with about 900 mm reach (KUKA KR 6 R900 sixx / KR AGILUS class,
from its public data sheet): d1 = 400 mm, a1 = 25 mm, a2 = 455 mm,
a3 = 35 mm, d4 = 420 mm, d6 = 80 mm; joint speeds 360, 300, 360, 381, 388,
615 deg/s; ranges A1 +-170, A2 -100..135 (our zero: upper arm vertical), A3
-156..120 (our zero: forearm horizontal), A4 +-185, A5 +-120, A6 +-350 deg.
Joint zero positions and directions follow this model, not a vendor's
controller. Acceleration and jerk limits are not published; we assume
a = 4 v per second and j = 10 a per second.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from .._validate import check_array, check_positive
from ..errors import InvalidInputError
from ..limits import AxisLimits
from . import _jets
from .base import REACH_RTOL, REVOLUTE, Pose, RobotModel, parse_flags, rot_z, wrap_angle

__all__ = ["Arm6", "default_arm6", "ARM6_FLAGS"]

#: Configuration flags and their values, in order.
ARM6_FLAGS: Mapping[str, tuple[str, str]] = {
    "shoulder": ("front", "back"),
    "elbow": ("up", "down"),
    "wrist": ("noflip", "flip"),
}

#: sin(q5) below this counts as the wrist singularity (q4 taken from the seed).
WRIST_SINGULAR_SIN = 1e-10

#: Horizontal wrist-centre distance from axis A1 below this [m] is the
#: shoulder singularity (q1 taken from the seed).
SHOULDER_SINGULAR_DIST = 1e-12

_RX_M90 = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])

_ALPHA = (-math.pi / 2, 0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, 0.0)
_THETA_OFFSET = (0.0, -math.pi / 2, 0.0, 0.0, 0.0, 0.0)


def _dh(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    ct, st = math.cos(theta), math.sin(theta)
    ca, sa = math.cos(alpha), math.sin(alpha)
    return np.array([
        [ct, -st * ca, st * sa, a * ct],
        [st, ct * ca, -ct * sa, a * st],
        [0.0, sa, ca, d],
        [0.0, 0.0, 0.0, 1.0],
    ])


class Arm6(RobotModel):
    """6-axis arm with a spherical wrist (see the module docstring).

    Parameters
    ----------
    d1, a1, a2, a3, d4, d6 : float
        DH lengths [m]: base height, shoulder offset, upper arm, elbow
        offset, forearm (elbow to wrist centre), flange distance.
    limits : sequence of 6 AxisLimits
        Per joint [rad], with ranges.
    name : str
    """

    configs = tuple(
        f"{s}-{e}-{w}" for s in ARM6_FLAGS["shoulder"] for e in ARM6_FLAGS["elbow"]
        for w in ARM6_FLAGS["wrist"]
    )

    def __init__(self, d1: float, a1: float, a2: float, a3: float, d4: float, d6: float,
                 limits: Any, name: str = "arm6") -> None:
        self.d1 = float(d1)
        self.a1 = float(a1)
        self.a2 = check_positive(a2, "a2")
        self.a3 = float(a3)
        self.d4 = check_positive(d4, "d4")
        self.d6 = float(d6)
        for fld, v in (("d1", self.d1), ("a1", self.a1), ("a3", self.a3), ("d6", self.d6)):
            if not math.isfinite(v):
                raise InvalidInputError(f"{fld} must be finite, got {v!r}")
        self.name = name
        self.joint_names = ("A1", "A2", "A3", "A4", "A5", "A6")
        self.joint_kinds = (REVOLUTE,) * 6
        lims = tuple(limits)
        if len(lims) != 6 or not all(isinstance(x, AxisLimits) for x in lims):
            raise InvalidInputError(f"Arm6 needs 6 AxisLimits, got {len(lims)} entries")
        self.limits = tuple(lim.with_name(n) for lim, n in zip(lims, self.joint_names))
        self._L = math.hypot(self.a3, self.d4)
        self._gamma = math.atan2(self.d4, self.a3)
        self.length_scale = abs(self.a1) + self.a2 + self._L + abs(self.d6)
        self.cartesian_accel = 5.0
        self.cartesian_jerk = 50.0

    @property
    def home(self) -> np.ndarray:
        """The ready configuration: the wrist (J5) bent 90 deg (clipped into its
        range; the tool then points down), the rest as :attr:`RobotModel.home`;
        a straight wrist (J5 = 0) is a singularity."""
        return self._home_with(4, 0.5 * math.pi)

    def parse_config(self, config: Any) -> str:
        """Canonical ``"front-up-noflip"`` style string from a string or a flag mapping."""
        return parse_flags(config, ARM6_FLAGS, self.name)

    # ------------------------------------------------------------ forward
    def _frames(self, q: np.ndarray) -> list[np.ndarray]:
        d = (self.d1, 0.0, 0.0, self.d4, 0.0, self.d6)
        a = (self.a1, self.a2, self.a3, 0.0, 0.0, 0.0)
        t = np.eye(4)
        out = []
        for i in range(6):
            t = t @ _dh(q[i] + _THETA_OFFSET[i], d[i], a[i], _ALPHA[i])
            out.append(t)
        return out

    def fk_jet(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Forward kinematics of joint jets: ``q`` (n, N, 6) Taylor coefficients of the
        joints (N <= 4) -> those of the flange position (n, N, 3) [m] and rotation (n, N, 3, 3)
        (see :mod:`trajkit.kinematics._jets`)."""
        d = (self.d1, 0.0, 0.0, self.d4, 0.0, self.d6)
        a = (self.a1, self.a2, self.a3, 0.0, 0.0, 0.0)
        lead = (q.shape[0],)
        nc = q.shape[1]
        rot = _jets.constant(np.eye(3), lead, nc)
        pos = _jets.constant(np.zeros(3), lead, nc)
        z = np.array([0.0, 0.0, 1.0])
        for i in range(6):
            theta = q[:, :, i].copy()
            theta[:, 0] += _THETA_OFFSET[i]
            rz = _jets.axis_motion(theta, z)
            c, s = _jets.cos_sin(theta)
            # DH: Rz(theta) then (a cos theta, a sin theta, d), then Rx(alpha)
            t = np.zeros(lead + (nc, 3))
            t[..., 0] = a[i] * c
            t[..., 1] = a[i] * s
            t[:, 0, 2] = d[i]
            pos = pos + _jets.mat_vec(rot, t)
            ca, sa = math.cos(_ALPHA[i]), math.sin(_ALPHA[i])
            rot = _jets.mat_mul(rot, rz) @ np.array([[1.0, 0.0, 0.0], [0.0, ca, -sa], [0.0, sa, ca]])
        return pos, rot

    def fk(self, q: Any) -> Pose:
        """Flange pose of joints ``q`` (6,) [rad]."""
        qq = check_array(q, "joints", ndim=1, size=6)
        t = self._frames(qq)[-1]
        return Pose(t[:3, 3].copy(), t[:3, :3].copy())

    def wrist_center(self, pose: Pose) -> np.ndarray:
        """Wrist centre [m], shape (3,), of a flange pose."""
        return pose.position - self.d6 * pose.rotation[:, 2]

    # ------------------------------------------------------------ inverse
    def config_of(self, q: Any) -> str:
        """Configuration string of joint vector ``q`` (6,)."""
        q2, q3, q5 = (float(x) for x in np.asarray(q, dtype=np.float64)[[1, 2, 4]])
        # radial coordinate of the wrist centre in the arm plane (see _solve)
        beta2 = math.pi / 2 - q2
        along = self.a1 + self.a2 * math.cos(beta2) + self._L * math.cos(beta2 - q3 - self._gamma)
        shoulder = "front" if along >= 0.0 else "back"
        elbow = "up" if wrap_angle(q3 + self._gamma) > 0.0 else "down"
        wrist = "noflip" if wrap_angle(q5) >= 0.0 else "flip"
        return f"{shoulder}-{elbow}-{wrist}"

    def ik_all(self, pose: Pose) -> list[tuple[str, np.ndarray]]:
        """All (up to 8) solutions, joints in (-pi, pi]; ranges not checked."""
        return self._solve(pose, None)

    def _solutions(self, pose: Pose, seed: np.ndarray | None,
                   config: str | None = None) -> list[tuple[str, np.ndarray]]:
        return self._solve(pose, seed, config)

    def _solve(self, pose: Pose, seed: np.ndarray | None,
               config: str | None = None) -> list[tuple[str, np.ndarray]]:
        want = (None, None, None) if config is None else tuple(config.split("-"))
        w = self.wrist_center(pose)
        rho = math.hypot(w[0], w[1])
        if rho < SHOULDER_SINGULAR_DIST:
            q1_front = 0.0 if seed is None else float(seed[0])
        else:
            q1_front = math.atan2(w[1], w[0])
        out = []
        for shoulder, q1, r in (
            ("front", q1_front, rho - self.a1),
            ("back", wrap_angle(q1_front + math.pi), -rho - self.a1),
        ):
            if want[0] not in (None, shoulder):
                continue
            s = w[2] - self.d1
            dd = r * r + s * s
            c = (dd - self.a2**2 - self._L**2) / (2.0 * self.a2 * self._L)
            if abs(c) > 1.0 + REACH_RTOL:
                continue
            c = max(-1.0, min(1.0, c))
            for elbow, th in (("up", math.acos(c)), ("down", -math.acos(c))):
                if want[1] not in (None, elbow):
                    continue
                beta2 = math.atan2(s, r) - math.atan2(-self._L * math.sin(th),
                                                       self.a2 + self._L * math.cos(th))
                q2 = wrap_angle(math.pi / 2 - beta2)
                q3 = wrap_angle(th - self._gamma)
                r03 = rot_z(q1) @ _RX_M90 @ rot_z(q2 + q3 - math.pi / 2) @ _RX_M90
                r36 = r03.T @ pose.rotation
                for wrist, q456 in self._wrist(r36, seed).items():
                    if want[2] not in (None, wrist):
                        continue
                    q = np.array([q1, q2, q3, *q456])
                    out.append((f"{shoulder}-{elbow}-{wrist}", q))
        return out

    @staticmethod
    def _wrist(r: np.ndarray, seed: np.ndarray | None) -> dict[str, tuple[float, float, float]]:
        # R36 = Rz(q4) Ry(-q5) Rz(q6)
        s5 = math.hypot(r[0, 2], r[1, 2])
        c5 = max(-1.0, min(1.0, r[2, 2]))
        if s5 < WRIST_SINGULAR_SIN:
            q4 = 0.0 if seed is None else float(seed[3])
            if c5 > 0:
                q5, q46 = 0.0, math.atan2(r[1, 0], r[0, 0])
                q6 = wrap_angle(q46 - q4)
            else:  # q5 = pi: R = Rz(q4) diag(-1, 1, -1) Rz(q6)
                q5, q46 = math.pi, math.atan2(r[1, 0], -r[0, 0])
                q6 = wrap_angle(q4 - q46)
            return {"noflip": (q4, q5, q6), "flip": (q4, -q5, q6)}
        q5 = math.atan2(s5, c5)
        nf = (math.atan2(-r[1, 2], -r[0, 2]), q5, math.atan2(-r[2, 1], r[2, 0]))
        fl = (math.atan2(r[1, 2], r[0, 2]), -q5, math.atan2(r[2, 1], -r[2, 0]))
        return {"noflip": nf, "flip": fl}

    def to_dict(self) -> dict:
        """JSON-ready parameters [m]."""
        return {"model": "arm6", "d1": self.d1, "a1": self.a1, "a2": self.a2, "a3": self.a3,
                "d4": self.d4, "d6": self.d6}


def default_arm6() -> Arm6:
    """The 6 kg-class default arm (values in the module docstring)."""
    d = math.pi / 180.0
    speeds = (360.0, 300.0, 360.0, 381.0, 388.0, 615.0)
    ranges = ((-170, 170), (-100, 135), (-156, 120), (-185, 185), (-120, 120), (-350, 350))
    lims = [
        AxisLimits(v * d, 4 * v * d, 40 * v * d, position_min=lo * d, position_max=hi * d)
        for v, (lo, hi) in zip(speeds, ranges)
    ]
    return Arm6(0.400, 0.025, 0.455, 0.035, 0.420, 0.080, lims, name="arm6")
