"""One-axis profiles: closed-form time-optimal and fixed-duration S-curves."""

from .batch import MoveBatch, plan_moves
from .profile import PHASE_NAMES, Profile, ProfileSample, min_duration, plan_move

__all__ = [
    "PHASE_NAMES",
    "Profile",
    "ProfileSample",
    "plan_move",
    "min_duration",
    "plan_moves",
    "MoveBatch",
]
