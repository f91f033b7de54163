"""The path-timing engine: minimum-time jerk-limited motion along any geometric path.

:func:`plan_path_timing` times a joint path ``q(s)`` (:class:`JointPath`)
under per-joint velocity, acceleration and jerk limits (both legs) and the
path's own speed, tangential acceleration and jerk limits; every path motion
of trajkit (robot LIN/CIRC chains with their blends, the saddle machine,
composite tool paths, joint-space waypoints) is timed by it.
"""

from .engine import LimitUse, PathTiming, plan_path_timing
from .paths import JointPath, LinearJointPath, PathRest
from .waypoints import BlendedJointPath, SplineJointPath, WaypointSample, WaypointTrajectory, plan_waypoints

__all__ = ["plan_path_timing", "PathTiming", "LimitUse", "JointPath", "LinearJointPath",
           "PathRest", "plan_waypoints", "WaypointTrajectory", "WaypointSample", "BlendedJointPath",
           "SplineJointPath"]
