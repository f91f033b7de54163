"""One axis: closed-form time-optimal and fixed-duration S-curves, at rest or
between moving states, all of one motion type (:class:`JerkMotion`)."""

from .batch import MoveBatch, plan_moves
from .motion import JerkMotion, MotionExtrema, ProfileSample
from .profile import PHASE_NAMES, Profile, min_duration, plan_move
from .state import (
    BlockedDurationError,
    DurationSet,
    StateProfile,
    feasible_durations,
    min_state_duration,
    plan_state_to_state,
    plan_velocity,
)
from .state_batch import StateMoveBatch, plan_state_moves

__all__ = [
    "PHASE_NAMES",
    "JerkMotion",
    "MotionExtrema",
    "DurationSet",
    "feasible_durations",
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
    "plan_state_moves",
    "StateMoveBatch",
]
