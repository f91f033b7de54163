"""Time at which a rest-to-rest profile passes a given position (exact inversion).

A rest-to-rest :class:`~trajkit.Profile` is monotone in position, so each
position between start and goal is passed exactly once (or held, on a
zero-velocity boundary). The phase that contains the position is found from
the exact boundary states, then the cubic of that phase is solved by a
safeguarded Newton iteration (bisection fallback) to float precision.
"""

from __future__ import annotations

from ..profiles import Profile

__all__ = ["time_at_position"]

#: Iterations of the safeguarded Newton solve (each at least halves the bracket).
_MAX_ITER = 200

#: Stop when the bracket is below this fraction of the phase duration
#: (a few units of float64 round-off).
_BRACKET_RTOL = 4.0 * 2.0**-52


def time_at_position(profile: Profile, x: float) -> float:
    """Return the first time [s] at which ``profile`` reaches position ``x``.

    Parameters
    ----------
    profile : Profile
        A rest-to-rest profile (monotone position).
    x : float
        Position [unit]. A position at or before the start gives 0; one
        beyond the goal raises (it is never reached).

    Returns
    -------
    float
        Time since the profile's start [s], in [0, duration].

    Raises
    ------
    ValueError
        ``x`` lies beyond the goal (never reached).
    """
    s = profile.direction
    start, goal = profile.start, profile.goal
    if s == 0.0 or s * (x - start) <= 0.0:
        return 0.0
    if s * (x - goal) > 0.0:
        raise ValueError(f"position {x!r} is never reached by a move from {start!r} to {goal!r}")
    if x == goal:
        # first time the goal is reached: end of the last phase with motion
        return _last_motion_time(profile)
    bs = profile.boundary_states()
    tb = profile.phase_times
    jerks = profile.jerks
    for k in range(7):
        dt = tb[k + 1] - tb[k]
        if dt <= 0.0:
            continue
        p0, v0, a0 = bs[k]
        p1 = bs[k + 1, 0] if k < 6 else goal
        if s * (x - p1) <= 0.0:
            return tb[k] + _solve_phase(p0, v0, a0, jerks[k], x, dt, s)
    return _last_motion_time(profile)


def _last_motion_time(profile: Profile) -> float:
    return float(profile.duration)


def _solve_phase(p0: float, v0: float, a0: float, j: float, x: float, dt: float, s: float) -> float:
    """Solve p0 + t v0 + t^2 a0/2 + t^3 j/6 = x for t in [0, dt] (monotone in t)."""
    lo, hi = 0.0, dt
    t = 0.5 * dt
    for _ in range(_MAX_ITER):
        f = s * (p0 + t * (v0 + t * (0.5 * a0 + t * j / 6.0)) - x)
        if f == 0.0:
            return t
        if f < 0.0:
            lo = t
        else:
            hi = t
        df = s * (v0 + t * (a0 + 0.5 * t * j))
        tn = t - f / df if df > 0.0 else 0.5 * (lo + hi)
        if not (lo < tn < hi):
            tn = 0.5 * (lo + hi)
        if tn == t or hi - lo <= 0.0:
            return tn
        t = tn
        if hi - lo <= _BRACKET_RTOL * dt:
            break
    return t
