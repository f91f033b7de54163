"""Robot models: forward/inverse kinematics, joint ranges and per-joint limits.

Every model exposes ``joints_from_pose``, ``pose_from_joints``,
``joint_ranges`` and per-joint :class:`~trajkit.AxisLimits` (``limits``),
vectorised over a leading batch dimension, SI units inside.
"""

from .palletizer import (
    DEFAULT_JOINT_TABLE,
    JOINT_NAMES,
    CylindricalPalletizer,
    default_palletizer,
)

__all__ = [
    "CylindricalPalletizer",
    "default_palletizer",
    "DEFAULT_JOINT_TABLE",
    "JOINT_NAMES",
]
