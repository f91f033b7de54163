"""Time at which a rest-to-rest profile passes a given position (exact inversion).

A rest-to-rest :class:`~trajkit.Profile` is monotone in position, so each
position between start and goal is passed exactly once (or held, on a
zero-velocity boundary). The phase that contains the position is found from
the exact boundary states, then the cubic of that phase is solved by a
safeguarded Newton iteration (bisection fallback) to float precision.
"""

from __future__ import annotations

import math

from ..profiles import Profile

__all__ = ["time_at_position", "level_crossings", "position_peak", "clearance_crossings"]

#: Iterations of the safeguarded Newton solve (each at least halves the bracket).
_MAX_ITER = 200

#: Stop when the bracket is below this fraction of the phase duration
#: (a few units of float64 round-off).
_BRACKET_RTOL = 4.0 * 2.0**-52

#: Zeros of the velocity closer than this fraction of the phase duration to a
#: phase end are taken to lie on that end.
_ROOT_EDGE_RTOL = 1e-9


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


# ------------------------------------------------- any constant-jerk profile
def _v_roots(v0: float, a0: float, j: float, dt: float) -> list[float]:
    """Times in (0, dt) where ``v0 + a0 t + j t^2/2`` is zero."""
    out = []
    if j != 0.0:
        disc = a0 * a0 - 2.0 * j * v0
        if disc >= 0.0:
            sq = math.sqrt(disc)
            q = -(a0 + math.copysign(sq, a0)) if a0 != 0.0 else sq
            if q != 0.0:
                out += [q / j, 2.0 * v0 / q]
    elif a0 != 0.0:
        out.append(-v0 / a0)
    # a root within round-off of a phase end is that end (a velocity that
    # reaches zero exactly at the boundary): splitting there would leave a
    # sliver whose end position is off by an ulp
    edge = _ROOT_EDGE_RTOL * dt
    return sorted(t for t in out if edge < t < dt - edge)


def _monotone_pieces(profile):
    """Split every phase where v = 0.

    Yields ``(t_start, dt, p0, v0, a0, j, p_end)``: position monotone on each
    piece; a piece that ends a phase takes its end position from the
    profile's boundary table (what sampling returns), not from integration.
    """
    bs = profile.boundary_states()
    tb = profile.phase_times
    out = []
    for k, j in enumerate(profile.jerks):
        dt = float(tb[k + 1] - tb[k])
        if not dt > 0.0:
            continue
        p, v, a = (float(x) for x in bs[k, :3])
        j = float(j)
        t_prev = 0.0
        for tc in _v_roots(v, a, j, dt) + [dt]:
            ps = p + t_prev * (v + t_prev * (0.5 * a + t_prev * j / 6.0))
            vs = v + t_prev * (a + 0.5 * t_prev * j)
            as_ = a + t_prev * j
            pe = float(bs[k + 1, 0]) if tc == dt else p + tc * (v + tc * (0.5 * a + tc * j / 6.0))
            out.append((float(tb[k]) + t_prev, tc - t_prev, ps, vs, as_, j, pe))
            t_prev = tc
    return out


def level_crossings(profile, x: float) -> list[tuple[float, int]]:
    """Every time a constant-jerk profile passes position ``x``, exactly.

    Works for any profile with ``phase_times``, ``boundary_states()`` and
    ``jerks`` (rest-to-rest :class:`~trajkit.Profile` or a
    :class:`~trajkit.profiles.state.StateProfile` that goes up and down).
    Each phase is cut where the velocity is zero, so the position is
    monotone on each piece, and the cubic is solved on the piece that
    brackets ``x`` (safeguarded Newton, float precision). A piece that ends
    exactly at ``x`` reaches it at its end time (no solve: near a rest the
    time of a position is ill-conditioned).

    Parameters
    ----------
    profile : Profile or StateProfile
    x : float
        Position [unit].

    Returns
    -------
    list of (float, int)
        ``(time [s], direction)`` in time order: direction ``+1`` where the
        position rises to or through ``x``, ``-1`` where it falls to or
        through it (from above).
    """
    out: list[tuple[float, int]] = []
    for i, (t0, dt, p, v, a, j, pe) in enumerate(_monotone_pieces(profile)):
        first = i == 0 and p == x  # the profile starts exactly at x
        if p < x <= pe or (first and pe > x):
            t = 0.0 if p == x else dt if pe == x else _solve_phase(p, v, a, j, x, dt, 1.0)
            out.append((t0 + t, 1))
        elif p > x >= pe or (first and pe < x):
            t = 0.0 if p == x else dt if pe == x else _solve_phase(p, v, a, j, x, dt, -1.0)
            out.append((t0 + t, -1))
    return out


def position_peak(profile) -> tuple[float, float, float]:
    """Highest position of a profile and the first and last time it is there.

    Returns
    -------
    (float, float, float)
        ``(z_peak, t_first, t_last)`` [unit, s, s]: exact, from the phase
        boundaries and the zeros of the velocity.
    """
    cands = []
    for t0, dt, p, _v, _a, _j, pe in _monotone_pieces(profile):
        cands.append((p, t0))
        cands.append((pe, t0 + dt))
    if not cands:
        p = float(profile.start)
        return p, 0.0, 0.0
    zp = max(c[0] for c in cands)
    tol = 1e-12 * max(1.0, abs(zp))
    ts = [t for z, t in cands if z >= zp - tol]
    return zp, min(ts), max(ts)


def clearance_crossings(pieces, z1: float, z2: float, t_start: float, t_end: float,
                        z_start: float) -> tuple[float, float, float] | None:
    """When B passes ``z1`` going up and ``z2`` coming down over one trip.

    Parameters
    ----------
    pieces : sequence of (float, profile)
        B's pieces in the trip: absolute start time [s] and a rest-to-rest
        profile (:class:`~trajkit.Profile` or a state profile that goes up
        and down); B rests between them.
    z1, z2 : float
        Clearance heights near the start and near the goal [m].
    t_start, t_end : float
        The trip's start and end [s].
    z_start : float
        B's position at the trip start [m].

    Returns
    -------
    (float, float, float) or None
        ``(t_up, t_down, z_peak)``: the last time B rises through ``z1``
        before it first reaches its peak (``t_start`` if it starts at or above
        ``z1``; the peak time if the peak only touches ``z1``), the first
        time it falls through ``z2`` after it last leaves its peak
        (``t_end`` if it ends at or above ``z2``; the peak time if the peak
        only touches ``z2``), and the peak [s, s, m]. ``None`` if B never
        reaches ``max(z1, z2)``.
    """
    zp, tp0, tp1 = z_start, t_start, t_end
    peaks = [(zs, t0 + a, t0 + b) for t0, prof in pieces for zs, a, b in [position_peak(prof)]]
    if peaks:
        zp = max(z for z, _, _ in peaks)
    tol = 1e-12 * max(1.0, abs(zp))
    if zp < max(z1, z2) - tol:
        return None
    at_top = [(a, b) for z, a, b in peaks if z >= zp - tol]
    if at_top:
        tp0 = min(a for a, _ in at_top)
        tp1 = max(b for _, b in at_top)
        if z_start >= zp - tol:
            tp0 = t_start
    if zp <= z1 + tol:
        t_up = tp0
    else:
        ups = [t0 + t for t0, prof in pieces for t, d in level_crossings(prof, z1)
               if d > 0 and t0 + t <= tp0]
        t_up = max(ups) if ups else t_start
    if zp <= z2 + tol:
        t_dn = tp1
    else:
        dns = [t0 + t for t0, prof in pieces for t, d in level_crossings(prof, z2)
               if d < 0 and t0 + t >= tp1]
        t_dn = min(dns) if dns else t_end
    return t_up, t_dn, zp
