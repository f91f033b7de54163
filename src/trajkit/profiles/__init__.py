"""One-axis profiles: closed-form time-optimal and fixed-duration S-curves."""

from .batch import MoveBatch, plan_moves
from .profile import PHASE_NAMES, Profile, ProfileSample, min_duration, plan_move
from .state import (
    BlockedDurationError,
    StateProfile,
    min_state_duration,
    plan_state_to_state,
    plan_velocity,
)

__all__ = [
    "PHASE_NAMES",
    "Profile",
    "ProfileSample",
    "plan_move",
    "min_duration",
    "plan_moves",
    "MoveBatch",
    "StateProfile",
    "BlockedDurationError",
    "plan_state_to_state",
    "plan_velocity",
    "min_state_duration",
]
