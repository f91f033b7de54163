"""Interpolation along paths: feed profiles, fixed-period setpoints, machine axes."""

from .feed import (
    CHORD_REASON,
    MAX_PERIOD,
    MIN_PERIOD,
    FeedPlan,
    FeedSample,
    Slowdown,
    chord_speed_limit,
    plan_feed,
    setpoint_times,
)
from .machine import (
    AXIS_NAMES,
    AxisCheck,
    SaddleAxesPath,
    SaddleMachine,
    SaddlePlan,
    axis_states,
    check_axes,
    plan_saddle,
)

__all__ = [
    "CHORD_REASON",
    "AXIS_NAMES",
    "SaddleAxesPath",
    "AxisCheck",
    "SaddleMachine",
    "SaddlePlan",
    "axis_states",
    "check_axes",
    "plan_saddle",
    "MIN_PERIOD",
    "MAX_PERIOD",
    "FeedPlan",
    "FeedSample",
    "Slowdown",
    "plan_feed",
    "chord_speed_limit",
    "setpoint_times",
]
