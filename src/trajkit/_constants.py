"""Named numerical tolerances, one per quantity (no stray literals in the code)."""

from __future__ import annotations

#: Relative tolerance used when comparing a requested duration with the
#: minimum duration: a request within this fraction below the minimum is
#: treated as equal to the minimum (float round-off), not as infeasible.
DURATION_RTOL = 1e-12

#: Relative tolerance to which root finders converge (distance equations).
ROOT_RTOL = 1e-15

#: Maximum Newton iterations for the monotone polynomial roots.
ROOT_MAX_ITER = 60

#: Relative tolerance used by limit checks in verification helpers.
LIMIT_RTOL = 1e-9

#: Relative tolerance for "goal reached".
GOAL_RTOL = 1e-9

#: Phase durations below this fraction of the total duration are treated as
#: absent when naming the profile shape.
PHASE_EPS = 1e-12

#: A peak velocity / acceleration within this fraction below its limit counts
#: as "reaching" that limit (``Profile.reached``).
REACHED_RTOL = 1e-12

#: Sample times ``k * period`` within this fraction of a period of the
#: duration count as landing on it (``Trajectory.times``).
PERIOD_RTOL = 1e-9
