"""trajkit: time-optimal, jerk-limited motion planning for robots and CNC machines.

The public API is re-exported here; see :data:`__all__`.
"""

from __future__ import annotations

import logging

from .errors import (
    InfeasibleError,
    InvalidInputError,
    SafetyFault,
    TrajkitError,
    UnreachableError,
)
from .limits import AxisLimits
from .profiles import (
    PHASE_NAMES,
    BlockedDurationError,
    DurationSet,
    JerkMotion,
    MoveBatch,
    Profile,
    ProfileSample,
    StateMoveBatch,
    StateProfile,
    feasible_durations,
    min_duration,
    min_state_duration,
    plan_move,
    plan_moves,
    plan_state_moves,
    plan_state_to_state,
    plan_velocity,
)
from .sync import plan_ptp, plan_ptp_states
from .trajectory import SYNC_MODES, Trajectory, TrajectorySample
from .verify import (
    TrajectoryReport,
    VerificationError,
    VerificationReport,
    Violation,
    verify_motion,
    verify_profile,
    verify_state_profile,
    verify_trajectory,
)

__version__ = "0.1.0"

logging.getLogger("trajkit").addHandler(logging.NullHandler())

__all__ = [
    "__version__",
    "TrajkitError",
    "InvalidInputError",
    "InfeasibleError",
    "UnreachableError",
    "SafetyFault",
    "AxisLimits",
    "PHASE_NAMES",
    "Profile",
    "ProfileSample",
    "MoveBatch",
    "plan_move",
    "plan_moves",
    "plan_state_moves",
    "StateMoveBatch",
    "min_duration",
    "Trajectory",
    "TrajectorySample",
    "plan_ptp",
    "SYNC_MODES",
    "StateProfile",
    "BlockedDurationError",
    "plan_state_to_state",
    "plan_velocity",
    "min_state_duration",
    "plan_ptp_states",
    "JerkMotion",
    "DurationSet",
    "feasible_durations",
    "verify_profile",
    "verify_state_profile",
    "verify_motion",
    "verify_trajectory",
    "VerificationReport",
    "TrajectoryReport",
    "VerificationError",
    "Violation",
]
