"""Robot motion instructions: PTP, LIN, CIRC, WAIT, and their targets (SI units)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._validate import check_array, check_finite, check_positive
from ..errors import InvalidInputError
from ..kinematics.base import Pose

__all__ = ["JointTarget", "CartesianTarget", "Ptp", "Lin", "Circ", "Wait", "Motion", "Target"]


@dataclass(frozen=True)
class JointTarget:
    """A taught point given in joint space.

    Attributes
    ----------
    q : ndarray, shape (n_joints,)
        Joint values [rad or m].
    name : str
        Point name (for messages).
    """

    q: np.ndarray
    name: str = "point"

    def __post_init__(self) -> None:
        object.__setattr__(self, "q", check_array(self.q, f"joints of point {self.name}", ndim=1))


@dataclass(frozen=True)
class CartesianTarget:
    """A taught point given as a tool pose, optionally with its IK configuration.

    Attributes
    ----------
    pose : Pose
    config : str or mapping or None
        IK configuration to pin (model specific, e.g. ``"front-up-noflip"``).
    name : str
    """

    pose: Pose
    config: Any = None
    name: str = "point"


Target = JointTarget | CartesianTarget


def _check_target(t: Any, field_name: str) -> None:
    if not isinstance(t, (JointTarget, CartesianTarget)):
        raise InvalidInputError(
            f"{field_name} must be a JointTarget or CartesianTarget, got {type(t).__name__}"
        )


@dataclass(frozen=True)
class Ptp:
    """Joint-space synchronised point-to-point motion.

    Attributes
    ----------
    target : JointTarget or CartesianTarget
    speed_pct : float
        Velocity override in percent (0, 100] of every joint's v_max.
    label : str
        Names the instruction in messages (e.g. ``"instruction 2 (PTP home, line 9)"``).
    zone : float
        Blend radius [m] >= 0: when the next motion is also a PTP, it starts
        before this one ends (joint-space superposition) while the tool is
        within ``zone`` of this target; 0 stops exactly.
    """

    target: Target
    speed_pct: float = 100.0
    label: str = "PTP"
    zone: float = 0.0

    def __post_init__(self) -> None:
        _check_target(self.target, f"{self.label}: target")
        p = check_positive(self.speed_pct, f"{self.label}: speed_pct")
        if p > 100.0:
            raise InvalidInputError(f"{self.label}: speed_pct must be <= 100, got {p!r}")
        z = check_finite(self.zone, f"{self.label}: zone")
        if z < 0:
            raise InvalidInputError(f"{self.label}: zone must be >= 0 m, got {z!r}")


def _check_speed_zone(label: str, speed: float, zone: float) -> None:
    """Programmed speed > 0 and blend zone >= 0, named by the instruction label."""
    check_positive(speed, f"{label}: speed")
    z = check_finite(zone, f"{label}: zone")
    if z < 0:
        raise InvalidInputError(f"{label}: zone must be >= 0 m, got {z!r}")


@dataclass(frozen=True)
class Lin:
    """Straight tool path at a programmed speed (orientation by slerp).

    Attributes
    ----------
    target : JointTarget or CartesianTarget
    speed : float
        Programmed tool speed [m/s], > 0.
    zone : float
        Blend radius [m] >= 0 at the end of this motion (0: exact stop).
    label : str
    """

    target: Target
    speed: float
    zone: float = 0.0
    label: str = "LIN"

    def __post_init__(self) -> None:
        _check_target(self.target, f"{self.label}: target")
        _check_speed_zone(self.label, self.speed, self.zone)


@dataclass(frozen=True)
class Circ:
    """Circular arc through the start, an auxiliary point and the target (Jiang, 1987).

    Attributes
    ----------
    via : JointTarget or CartesianTarget
        Auxiliary point (only its position is used).
    target : JointTarget or CartesianTarget
    speed : float
        Programmed tool speed [m/s], > 0.
    zone : float
        Blend radius [m] >= 0.
    label : str
    """

    via: Target
    target: Target
    speed: float
    zone: float = 0.0
    label: str = "CIRC"

    def __post_init__(self) -> None:
        _check_target(self.via, f"{self.label}: via")
        _check_target(self.target, f"{self.label}: target")
        _check_speed_zone(self.label, self.speed, self.zone)


@dataclass(frozen=True)
class Wait:
    """Stand still for ``time`` [s] >= 0."""

    time: float
    label: str = "WAIT"

    def __post_init__(self) -> None:
        t = check_finite(self.time, f"{self.label}: time")
        if t < 0 or math.isinf(t):
            raise InvalidInputError(f"{self.label}: time must be >= 0 s, got {t!r}")


Motion = Ptp | Lin | Circ | Wait
