"""Exact check of a candidate profile (kernel side).

A candidate is a table ``ph[k] = (duration, jerk, start acceleration)``. The
check integrates it from the start state with :func:`._phase.phase_end`,
cuts every phase at the zeros of the acceleration (velocity extrema) and of
the velocity (the leg changes there), and checks on every piece, at its
ends:

* ``|v| <= v_max``;
* while ``|v|`` grows (``v a > 0``): ``|a| <= a_max``, ``|j| <= j_max``;
  while it shrinks (``v a < 0``): ``a_max_decel``, ``j_max_decel``;
* an acceleration jump only where the jerk limit of the leg is infinite;
* the end state equals the goal.

Limits are in the kernel's form: ``L = (V, A1, K1, A2, K2)`` with
``K = 1/j_max`` (0 for an infinite jerk limit).
"""

from __future__ import annotations

import math

from ._compile import jit_raw
from ._phase import phase_end

__all__ = ["LIMIT_RTOL", "GOAL_RTOL", "SLIVER_RTOL", "check", "check_equal_legs", "clean", "leg_cuts"]

#: Relative tolerance of every limit in the kernel check (ten times tighter
#: than :data:`trajkit._constants.LIMIT_RTOL` of the public verifier).
LIMIT_RTOL = 1e-10

#: Relative tolerance of the end state (position relative to the distance
#: travelled, velocity relative to the velocity change along the path,
#: acceleration relative to its scale).
GOAL_RTOL = 1e-10

#: Pieces whose |v| or |a| stays below this fraction of its scale have no
#: meaningful leg (v a is round-off): they take the leg of their neighbour in
#: the phase, or where the whole phase is such a sliver, the larger of both
#: legs' bounds (as the public verifier does).
SLIVER_RTOL = 1e-9

#: Negative phase durations above ``-ZERO_T * duration`` are round-off of a
#: phase that is absent and are set to zero.
ZERO_T = 1e-12


@jit_raw
def clean(ph, n):
    """Zero round-off negative durations; False when a duration is really negative."""
    tot = 0.0
    for k in range(n):
        tot += abs(ph[k, 0])
    for k in range(n):
        d = ph[k, 0]
        if not (d >= 0.0):
            if d >= -ZERO_T * tot:
                ph[k, 0] = 0.0
            else:
                return False
        elif d > 1e300:
            return False
    return True


@jit_raw
def _leg(v, a, A1, K1, A2, K2):
    """(a bound, 1/jerk bound) of the leg in force at (v, a); speeding up at v = 0."""
    if v * a < 0.0:
        return A2, K2
    return A1, K1


@jit_raw
def leg_cuts(v, a, j, dt):
    """The instants in ``(0, dt)`` where a phase of jerk ``j`` from ``(v, a)`` may
    change its leg (``a = 0`` and ``v = 0``), ascending; ``dt`` where there is none."""
    c0 = dt
    c1 = dt
    c2 = dt
    if j != 0.0:
        ta = -a / j
        if 0.0 < ta < dt:
            c0 = ta
        disc = a * a - 2.0 * j * v
        if disc >= 0.0:
            sq = math.sqrt(disc)
            q = -(a + math.copysign(sq, a)) if a != 0.0 else sq
            if q != 0.0:
                r1 = q / j
                r2 = 2.0 * v / q
                if 0.0 < r1 < dt:
                    c1 = r1
                if 0.0 < r2 < dt:
                    c2 = r2
    elif a != 0.0:
        tv = -v / a
        if 0.0 < tv < dt:
            c1 = tv
    if c0 > c1:
        c0, c1 = c1, c0
    if c1 > c2:
        c1, c2 = c2, c1
    if c0 > c1:
        c0, c1 = c1, c0
    return c0, c1, c2


@jit_raw
def _scales(ph, n, p0, v0, a0, vf, af):
    """Scales of a candidate for its slivers and end-state tolerances: ``(duration,
    largest |v|, largest |a|, summed |velocity change|, summed distance)`` (the
    round-off of the end state accumulates along the path; each scale at least
    1e-300)."""
    T = 0.0
    vsc = max(abs(v0), abs(vf))
    asc = max(abs(a0), abs(af))
    dv_path = 0.0
    dp_path = 0.0
    p = p0
    v = v0
    for k in range(n):
        dt = ph[k, 0]
        j = ph[k, 1]
        a = ph[k, 2]
        vb = abs(v)
        p, v, ae = phase_end(p, v, a, j, dt)
        T, vsc, asc, dv_path, dp_path = _gather(T, vsc, asc, dv_path, dp_path, dt, a, ae, vb, v)
    return T, max(vsc, 1e-300), max(asc, 1e-300), dv_path, dp_path


@jit_raw
def _gather(T, vsc, asc, dv_path, dp_path, dt, a, ae, vb, v):
    """The scales of :func:`_scales` after one more phase of duration ``dt`` from
    acceleration ``a`` (``ae`` at its end), speed ``vb`` at its start and
    velocity ``v`` at its end."""
    asc = max(asc, abs(a), abs(ae))
    da = max(abs(a), abs(ae)) * dt
    return (T + dt, max(vsc, abs(v)), asc, dv_path + da,
            dp_path + (max(vb, abs(v)) + da) * dt)


@jit_raw
def _at_goal(p, v, a, p0, pf, vf, af, vsc, asc, dv_path, dp_path):
    """Whether the end state ``(p, v, a)`` is the goal within the tolerances of the
    scales (:func:`_scales`); a NaN goal position is free (velocity interface)."""
    if pf == pf:
        psc = max(abs(pf - p0), dp_path, 1e-300)
        if abs(p - pf) > GOAL_RTOL * psc + 4.0 * 2.2e-16 * max(abs(pf), abs(p0)):
            return False
    if abs(v - vf) > GOAL_RTOL * max(vsc, dv_path):
        return False
    return not (abs(a - af) > GOAL_RTOL * asc)


@jit_raw
def _piece_leg(p, v, a, j, t0, t1, vsc, asc):
    """The leg of the piece ``[t0, t1]`` of a phase (no leg change inside): 1
    speeding up, 2 slowing down (from its midpoint), 0 for a sliver (``|v|`` or
    ``|a|`` within :data:`SLIVER_RTOL` of its scale at both ends: ``v a`` is
    round-off there; both are monotone on a piece, so their ends bound them)."""
    _, va, aa = phase_end(p, v, a, j, t0)
    _, vb, ab = phase_end(p, v, a, j, t1)
    if max(abs(va), abs(vb)) <= SLIVER_RTOL * vsc or max(abs(aa), abs(ab)) <= SLIVER_RTOL * asc:
        return 0
    _, vm, am = phase_end(p, v, a, j, 0.5 * (t0 + t1))
    return 2 if vm * am < 0.0 else 1


@jit_raw
def check(ph, n, p0, v0, a0, pf, vf, af, V, A1, K1, A2, K2):
    """True when the candidate keeps every limit and ends at the goal state."""
    T, vsc, asc, dv_path, dp_path = _scales(ph, n, p0, v0, a0, vf, af)
    if not (T < 1e300):
        return False
    p = p0
    v = v0
    a_prev = a0
    for k in range(n):
        dt = ph[k, 0]
        j = ph[k, 1]
        a = ph[k, 2]
        if a != a_prev and abs(a - a_prev) > 1e-12 * asc:
            # an acceleration jump: only within legs whose jerk limit is infinite
            if not (K1 == 0.0 and K2 == 0.0):
                if a * a_prev < 0.0 and v != 0.0:
                    return False
                if a_prev != 0.0 and _leg(v, a_prev, A1, K1, A2, K2)[1] != 0.0:
                    return False
                if a != 0.0 and _leg(v, a, A1, K1, A2, K2)[1] != 0.0:
                    return False
        if dt > 0.0:
            c0, c1, c2 = leg_cuts(v, a, j, dt)
            # a sliver takes the leg of the piece before it, the first ones that of
            # the first piece with a leg (as the public verifier does)
            last = 0
            t_prev = 0.0
            for cut in (c0, c1, c2, dt):
                if cut > t_prev:
                    last = _piece_leg(p, v, a, j, t_prev, cut, vsc, asc)
                    if last != 0:
                        break
                    t_prev = cut
            t_prev = 0.0
            for cut in (c0, c1, c2, dt):
                if cut <= t_prev:
                    continue
                _, vb, ab = phase_end(p, v, a, j, cut)
                _, va, aa = phase_end(p, v, a, j, t_prev)
                if abs(vb) > V * (1.0 + LIMIT_RTOL):
                    return False
                leg = _piece_leg(p, v, a, j, t_prev, cut, vsc, asc)
                if leg != 0:
                    last = leg
                if last == 2:
                    Am = A2
                    Km = K2
                elif last == 1:
                    Am = A1
                    Km = K1
                else:  # (the whole phase within round-off of v = 0 or a = 0)
                    Am = max(A1, A2)
                    Km = min(K1, K2)
                if abs(ab) > Am * (1.0 + LIMIT_RTOL) or abs(aa) > Am * (1.0 + LIMIT_RTOL):
                    return False
                if j != 0.0 and abs(j) * Km > 1.0 + LIMIT_RTOL:
                    return False
                t_prev = cut
        elif abs(v) > V * (1.0 + LIMIT_RTOL):
            return False
        p, v, a_prev = phase_end(p, v, a, j, dt)
    # end state (an acceleration jump onto the goal is a zero-length phase)
    return _at_goal(p, v, a_prev, p0, pf, vf, af, vsc, asc, dv_path, dp_path)


@jit_raw
def check_equal_legs(ph, n, p0, v0, a0, pf, vf, af, V, A, K):
    """:func:`check` for limits whose legs are equal (``A1 = A2 = A``,
    ``K1 = K2 = K > 0``), with its tolerances: the leg of a piece does not
    matter, so the pieces are the phases cut where the acceleration crosses
    zero (the velocity extrema); the velocity is checked at the ends of the
    pieces, the acceleration (linear in a phase) and the jerk per phase, and
    no acceleration may jump (the jerk is finite). One pass: the scales of
    :func:`_scales` are gathered on the way (the same integration) and the
    tolerances that need them applied at the end."""
    vlim = V * (1.0 + LIMIT_RTOL)
    alim = A * (1.0 + LIMIT_RTOL)
    T = 0.0
    vsc = max(abs(v0), abs(vf))
    asc = max(abs(a0), abs(af))
    dv_path = 0.0
    dp_path = 0.0
    jump = 0.0
    p = p0
    v = v0
    a_prev = a0
    for k in range(n):
        dt = ph[k, 0]
        j = ph[k, 1]
        a = ph[k, 2]
        jump = max(jump, abs(a - a_prev))
        vb = abs(v)
        if dt > 0.0:
            if j != 0.0:
                if abs(j) * K > 1.0 + LIMIT_RTOL:
                    return False
                ta = -a / j
                if 0.0 < ta < dt:
                    _, vm, _ = phase_end(p, v, a, j, ta)
                    if abs(vm) > vlim:
                        return False
            if abs(a) > alim:
                return False
            p, v, a_prev = phase_end(p, v, a, j, dt)
            if abs(v) > vlim or abs(a_prev) > alim:
                return False
        else:
            if abs(v) > vlim:
                return False
            p, v, a_prev = phase_end(p, v, a, j, dt)
        T, vsc, asc, dv_path, dp_path = _gather(T, vsc, asc, dv_path, dp_path, dt, a, a_prev, vb, v)
    vsc = max(vsc, 1e-300)
    asc = max(asc, 1e-300)
    if not (T < 1e300) or jump > 1e-12 * asc:
        return False
    return _at_goal(p, v, a_prev, p0, pf, vf, af, vsc, asc, dv_path, dp_path)
