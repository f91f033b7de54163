"""The brake pre-phase: returning a state into the limits (kernel).

A state ``(v, a)`` is *inside the limits* when a motion from it can keep
every limit from now on:

* ``|v| <= v_max``;
* speeding up (``v a > 0``, or ``v = 0``): ``|a| <= a_max`` and the velocity
  reached by ramping the acceleration to zero at ``j_max`` stays within
  ``v_max`` (``|v| + a^2 / (2 j_max) <= v_max``);
* slowing down (``v a < 0``): ``|a| <= a_max_decel``; if the velocity would
  reverse before the acceleration can come back to zero (ramping it at
  ``j_max_decel``), the acceleration at the reversal is within ``a_max`` and
  the velocity then reached in the new direction within ``v_max``.

From a state outside, every motion breaks a limit for a while; the planner
brakes first and plans the time-optimal motion from where the brake ends.
Brake candidates (each with the jerk at the limit of its leg, no limit
checked while outside):

* ``path(s)``, ``s = +1, -1``: the jerk ``-s j``, the acceleration held once
  it reaches ``-s a_max_decel`` (ruckig's brake rule, for both signs), up to
  the **first instant inside the limits** -- found exactly: the boundary of
  the inside set along a constant-jerk phase is where ``v``, ``a`` or the
  natural velocity reach a bound, all roots of quadratics;
* ``bump(+-v_max)``: the fastest velocity change to ``(+-v_max, 0)`` (from a
  deceleration beyond ``a_max_decel``: ramped back to it, held, ramped to
  zero), cut at the first instant inside;
* ``natural``: the acceleration ramped to zero at each leg's jerk limit
  (through a reversal), then the bump to ``(sign(v) v_max, 0)``;
* ``hold``: slowing down, the acceleration held (jerk 0) up to the first
  instant inside, before the velocity reverses;
* ``ruckig``: ruckig's brake (its published rule, at the smaller jerk and
  acceleration of both legs): an acceleration beyond the limit ramped back
  and held until ramping it to zero would end at a velocity limit (possibly
  the far one, through a reversal), then ramped towards zero; cut at the
  first instant inside.

A candidate whose velocity exceeds what the start state forces (the
velocity reached by ramping its acceleration to zero, :func:`forced_speed`)
is not used, nor one that keeps an acceleration beyond its leg's bound other
than by ramping it back at that leg's jerk limit (:func:`lingers`): a brake
leaves the limits no longer and no further than the start state forces.

The planner (:mod:`._kernel`) plans from the end of each candidate that
ends inside and keeps the fastest total: the brake is part of the
minimum-time solution. The rules are mirror-symmetric. Limits as in
:mod:`._check`: ``V, A1, K1, A2, K2`` (``K = 1/j_max``).
"""

from __future__ import annotations

import math

from ._check import leg_cuts
from ._compile import jit_raw
from ._phase import phase_end

__all__ = ["BRAKE_PHASES", "inside", "brake_path", "brake_bump", "brake_natural", "brake_hold",
           "brake_ruckig", "forced_speed", "lingers", "peak_speed"]

#: Largest number of phases of one brake candidate.
BRAKE_PHASES = 10

#: Relative slack of the "inside the limits" test.
INSIDE_RTOL = 1e-12


@jit_raw
def _speed_zero(v, a, j, tmax):
    """The first instant in ``(0, tmax)`` where a phase of jerk ``j`` from ``(v, a)``
    reaches zero velocity: ``(t, True)``, or ``(tmax, False)`` where it does not.
    The roots of ``v + a t + j t^2 / 2`` in the cancellation-free form (a start
    velocity tiny against ``a^2 / j`` keeps its full relative accuracy)."""
    disc = a * a - 2.0 * j * v
    if not (disc >= 0.0 and v != 0.0):
        return tmax, False
    sq = math.sqrt(disc)
    q = -(a + math.copysign(sq, a)) if a != 0.0 else sq
    found = False
    for t in (q / j, 2.0 * v / q):
        if 0.0 < t < tmax:
            tmax = t
            found = True
    return tmax, found


@jit_raw
def inside(v, a, V, A1, K1, A2, K2):
    """True when ``(v, a)`` lies inside the limits (see the module text)."""
    if v < 0.0 or (v == 0.0 and a < 0.0):
        v = -v
        a = -a
    tol = 1.0 + INSIDE_RTOL
    if v > V * tol:
        return False
    if a > 0.0 or (v == 0.0 and a != 0.0):
        if a > A1 * tol:
            return False
        if v + 0.5 * a * a * K1 > V * tol + 1e-300:
            return False
        return True
    if a < 0.0:
        if -a > A2 * tol:
            return False
        rem = v - 0.5 * a * a * K2
        if rem < 0.0:
            # the velocity reverses at a_z^2 = a^2 - 2 v / K2, then speeds up
            az2 = a * a - 2.0 * v / K2
            if az2 > A1 * A1 * tol * tol:
                return False
            if 0.5 * az2 * K1 > V * tol + 1e-300:
                return False
    return True


@jit_raw
def _add(buf, t, x):
    """Append ``x`` to the candidate times if in (0, t_max = buf[0]]."""
    if 0.0 < x <= buf[0]:
        n = int(buf[1])
        if n < buf.shape[0] - 2:
            buf[2 + n] = x
            buf[1] = n + 1


@jit_raw
def _quad(buf, qa, qb, qc):
    """Add the real roots of qa t^2 + qb t + qc."""
    if qa == 0.0:
        if qb != 0.0:
            _add(buf, 0.0, -qc / qb)
        return
    disc = qb * qb - 4.0 * qa * qc
    if disc < 0.0:
        return
    sq = math.sqrt(disc)
    q = -0.5 * (qb + math.copysign(sq, qb))
    if q != 0.0:
        _add(buf, 0.0, q / qa)
        _add(buf, 0.0, qc / q)
    else:
        _add(buf, 0.0, 0.0)


@jit_raw
def _first_inside(v, a, j, tmax, V, A1, K1, A2, K2, buf):
    """First t in [0, tmax] where the state of the phase (v, a, j) is inside, or inf.

    The inside set changes only where v, a or a natural velocity meet a bound:
    every such instant is a root of a quadratic in t (computed here); the
    state is tested at each, in order.
    """
    if inside(v, a, V, A1, K1, A2, K2):
        return 0.0
    buf[0] = tmax
    buf[1] = 0.0
    h = 0.5 * j
    # v(t) = v + a t + h t^2 ;  a(t) = a + j t
    for sv in (-1.0, 1.0):
        _quad(buf, h, a, v - sv * V)           # |v| = V
    _quad(buf, h, a, v)                         # v = 0
    if j != 0.0:
        for x in (0.0, A1, -A1, A2, -A2):      # a = bounds, a = 0
            _add(buf, 0.0, (x - a) / j)
    for K in (K1, K2):
        if K > 0.0:
            # v + s a^2 K / 2 = c  (natural velocities, both signs):
            # (h + s j^2 K/2) t^2 + (a + s a j K) t + (v + s a^2 K/2 - c) = 0
            for s in (-1.0, 1.0):
                for c in (-V, 0.0, V):
                    _quad(buf, h + s * 0.5 * j * j * K, a + s * a * j * K,
                          v + s * 0.5 * a * a * K - c)
            # reversal acceleration a^2 - 2 v / K = A1^2
            _quad(buf, j * j - 2.0 * h / K, 2.0 * a * j - 2.0 * a / K, a * a - 2.0 * v / K - A1 * A1)
    n = int(buf[1])
    # ascending
    for i in range(1, n):
        x = buf[2 + i]
        k = i - 1
        while k >= 0 and buf[2 + k] > x:
            buf[3 + k] = buf[2 + k]
            k -= 1
        buf[3 + k] = x
    for i in range(n):
        t = buf[2 + i]
        _, vt, at = phase_end(0.0, v, a, j, t)
        if inside(vt, at, V, A1, K1, A2, K2):
            return t
    if tmax < math.inf:
        _, vt, at = phase_end(0.0, v, a, j, tmax)
        if inside(vt, at, V, A1, K1, A2, K2):
            return tmax
    return math.inf


@jit_raw
def brake_path(s, v, a, V, A1, K1, A2, K2, out, buf):
    """Brake candidate ``path(s)``: phases ``out[k] = (dt, j, a_start)``.

    Returns the number of phases (0 when already inside) or -1 when the path
    does not reach the inside set within :data:`BRAKE_PHASES` phases.
    """
    n = 0
    clamp = -s * A2
    for _ in range(BRAKE_PHASES):
        if inside(v, a, V, A1, K1, A2, K2):
            return n
        an = a - s * 1e-300
        # the phase ends where the velocity (or the acceleration) reaches zero:
        # exactly zero there, so that the next phase is in the right leg
        v_zero = False
        a_zero = False
        beyond = (a > 0.0 and v >= 0.0 and a > A1) or (a < 0.0 and v <= 0.0 and -a > A1) or \
            (v * a < 0.0 and abs(a) > A2)
        holding = (a - clamp) * s <= 0.0 and not beyond
        if beyond:
            # the acceleration beyond its leg's bound: ramp it back towards zero first
            slowing = v * a < 0.0
            K = K2 if slowing else K1
            lim_a = A2 if slowing else A1
            tgt = lim_a if a > 0.0 else -lim_a
            if K == 0.0:
                a = tgt
                continue
            j = (-1.0 if a > 0.0 else 1.0) / K
            tmax = (tgt - a) / j
            tmax, v_zero = _speed_zero(v, a, j, tmax)
        elif holding:
            j = 0.0
            tmax = math.inf
            # leave the hold when the leg changes (v crosses 0: the clamp may change)
            if a != 0.0 and v * a < 0.0:
                tmax = -v / a
        else:
            # the jerk of the current leg (the next instant's leg at a = 0 or v = 0)
            slowing = v * an < 0.0
            K = K2 if slowing else K1
            if K == 0.0:
                # infinite jerk: the acceleration jumps to zero (leg change) or the clamp
                a = 0.0 if a * s > 0.0 else clamp
                continue
            j = -s / K
            # phase end: a reaches 0 (leg change), v reaches 0 (leg change) or the clamp
            tmax = (clamp - a) / j
            if a * s > 0.0 and -a / j < tmax:
                tmax = -a / j
                a_zero = True
            tmax, v_zero = _speed_zero(v, a, j, tmax)
            a_zero = a_zero and not v_zero
        t = _first_inside(v, a, j, tmax, V, A1, K1, A2, K2, buf)
        if t < math.inf:
            if t > 0.0:
                out[n, 0] = t
                out[n, 1] = j
                out[n, 2] = a
                n += 1
            return n
        if not (tmax < math.inf):
            return -1
        out[n, 0] = tmax
        out[n, 1] = j
        out[n, 2] = a
        n += 1
        _, v, a = phase_end(0.0, v, a, j, tmax)
        if v_zero:
            v = 0.0
        if a_zero:
            a = 0.0
        if j != 0.0 and abs(a - clamp) <= 1e-12 * A2:
            a = clamp
    return -1


@jit_raw
def _seq(buf, k, t, j, a):
    buf[80 + k] = t
    buf[84 + k] = j
    buf[88 + k] = a
    return k + 1


@jit_raw
def _walk_cut(buf, k, v, V, A1, K1, A2, K2, out, fb):
    """Copy the ``k`` phases of :func:`_seq` in ``buf`` (from velocity ``v``) to ``out``,
    cut at the first instant inside the limits: (phase count, whether it got inside)."""
    n = 0
    for i in range(k):
        tt = buf[80 + i]
        jj = buf[84 + i]
        aa = buf[88 + i]
        t = _first_inside(v, aa, jj, tt, V, A1, K1, A2, K2, fb)
        if t < math.inf:
            if t > 0.0:
                out[n, 0] = t
                out[n, 1] = jj
                out[n, 2] = aa
                n += 1
            return n, True
        out[n, 0] = tt
        out[n, 1] = jj
        out[n, 2] = aa
        n += 1
        _, v, _ = phase_end(0.0, v, aa, jj, tt)
    return n, False


@jit_raw
def brake_bump(vt, v, a, V, A1, K1, A2, K2, out, buf):
    """Brake candidate ``bump(vt)``: the fastest velocity change to ``(vt, 0)``
    (``vt = +-V``), held at ``-+a_max_decel`` when its peak would exceed it,
    cut at the first instant inside the limits. Towards ``sign(v) V`` from an
    overspeed each ramp has the jerk of its leg; through a reversal (``vt``
    of the other sign) the smaller of both. Returns the phase count or -1."""
    fb = buf[:78]
    k = 0
    sv = 1.0 if v > 0.0 else -1.0
    Kn = K1 if v * a > 0.0 else K2
    down = sv * (v + 0.5 * a * abs(a) * Kn) > abs(vt)  # the natural motion ends above V
    if vt * sv > 0.0 and abs(v) > V and down:
        if K2 == 0.0:
            return -1
        # frame with v > V > 0: down to a valley c <= min(a, 0), back up to 0
        vm = sv * v
        am = sv * a
        if am < -A2:
            # slowing down beyond -a_max_decel: back up to it, hold, up to zero
            c = -A2
            th = (V - vm + 0.5 * am * am * K2) / c
            if th < 0.0:
                return -1  # ramping straight to zero already ends below V
            k = _seq(buf, k, (c - am) * K2, sv / K2, sv * am)
            if th > 0.0:
                k = _seq(buf, k, th, 0.0, sv * c)
            k = _seq(buf, k, -c * K2, sv / K2, sv * c)
            n, _inside = _walk_cut(buf, k, v, V, A1, K1, A2, K2, out, fb)
            return n
        if am > 0.0:
            c2 = (vm - V + 0.5 * am * am * K1) / K2
        else:
            c2 = (vm - V) / K2 + 0.5 * am * am
        if c2 < 0.0:
            return -1
        c = -math.sqrt(c2)
        th = 0.0
        if c < -A2:
            c = -A2
            if am > 0.0:
                vr = vm + 0.5 * am * am * K1 - c * c * K2
            else:
                vr = vm + 0.5 * am * am * K2 - c * c * K2
            th = (V - vr) / c
            if th < 0.0:
                return -1
        if c > min(am, 0.0):
            return -1
        if am > 0.0:
            if K1 > 0.0:
                k = _seq(buf, k, am * K1, -sv / K1, sv * am)
            k = _seq(buf, k, -c * K2, -sv / K2, 0.0)
        else:
            k = _seq(buf, k, (am - c) * K2, -sv / K2, sv * am)
        if th > 0.0:
            k = _seq(buf, k, th, 0.0, sv * c)
        k = _seq(buf, k, -c * K2, sv / K2, sv * c)
    else:
        Km = max(K1, K2)
        if Km == 0.0:
            return -1
        vnat = v + 0.5 * a * abs(a) * Km
        s = -1.0 if vnat > vt else 1.0   # direction of the bump's peak
        # mirror so that the peak is negative: vm + (am^2 - 2 c^2) Km/2 = vtm
        vm = -s * v
        am = -s * a
        vtm = -s * vt
        c2 = 0.5 * am * am + (vm - vtm) / Km
        if c2 < 0.0:
            return -1
        c = -math.sqrt(c2)
        if c > min(am, 0.0):
            return -1
        if c >= -A2:
            k = _seq(buf, k, (am - c) * Km, s / Km, -s * am)
            k = _seq(buf, k, -c * Km, -s / Km, -s * c)
        else:
            c = -A2
            if am < c:
                return -1
            vr = vm + 0.5 * (am * am - c * c) * Km - 0.5 * c * c * Km
            th = (vtm - vr) / c
            if th < 0.0:
                return -1
            k = _seq(buf, k, (am - c) * Km, s / Km, -s * am)
            k = _seq(buf, k, th, 0.0, -s * c)
            k = _seq(buf, k, -c * Km, -s / Km, -s * c)
    n, _inside = _walk_cut(buf, k, v, V, A1, K1, A2, K2, out, fb)
    return n


@jit_raw
def brake_natural(v, a, V, A1, K1, A2, K2, out, buf):
    """Brake candidate ``natural``: the acceleration ramped to zero at the jerk
    limit of each leg (through a reversal), then, when the velocity is still
    above ``v_max``, the bump to ``(sign(v) V, 0)``; cut at the first instant
    inside the limits. Returns the phase count or -1."""
    fb = buf[:78]
    n = 0
    for _ in range(3):
        if a == 0.0:
            break
        if inside(v, a, V, A1, K1, A2, K2):
            return n
        an = a
        slowing = v * an < 0.0
        K = K2 if slowing else K1
        if K == 0.0:
            a = 0.0
            break
        j = (-1.0 if a > 0.0 else 1.0) / K
        tmax = -a / j
        tmax, crossing = _speed_zero(v, a, j, tmax)
        t = _first_inside(v, a, j, tmax, V, A1, K1, A2, K2, fb)
        if t < math.inf:
            if t > 0.0:
                out[n, 0] = t
                out[n, 1] = j
                out[n, 2] = a
                n += 1
            return n
        out[n, 0] = tmax
        out[n, 1] = j
        out[n, 2] = a
        n += 1
        _, v, a = phase_end(0.0, v, a, j, tmax)
        if crossing:
            v = 0.0  # the reversal: speeding up from here (the leg changes)
        else:
            a = 0.0
    if inside(v, a, V, A1, K1, A2, K2):
        return n
    if not (abs(v) > V):
        return -1
    m = brake_bump(V if v > 0.0 else -V, v, a, V, A1, K1, A2, K2, out[n:], buf)
    if m < 0:
        return -1
    return n + m


@jit_raw
def brake_hold(v, a, V, A1, K1, A2, K2, out, buf):
    """Brake candidate ``hold``: slowing down (``v a < 0``), the acceleration
    held up to the first instant inside the limits, before ``v`` reaches zero.
    Returns the phase count or -1."""
    if not (v * a < 0.0):
        return -1
    t = _first_inside(v, a, 0.0, -v / a, V, A1, K1, A2, K2, buf[:78])
    if not (t < math.inf):
        return -1
    if t == 0.0:
        return 0
    out[0, 0] = t
    out[0, 1] = 0.0
    out[0, 2] = a
    return 1


@jit_raw
def _rk_acc(v0, a0, vMax, vMin, aMax, J):
    """ruckig's acceleration brake (``a0`` beyond ``aMax`` in the direction of
    ``J``'s sign convention): returns (t0, t1, use_velocity_brake)."""
    t_to_a_max = (a0 - aMax) / J
    t_to_a_zero = a0 / J
    v_at_a_max = v0 + t_to_a_max * (a0 - J * t_to_a_max / 2.0)
    v_at_a_zero = v0 + t_to_a_zero * (a0 - J * t_to_a_zero / 2.0)
    if (v_at_a_zero > vMax and J > 0.0) or (v_at_a_zero < vMax and J < 0.0):
        return 0.0, 0.0, True
    if (v_at_a_max < vMin and J > 0.0) or (v_at_a_max > vMin and J < 0.0):
        t_to_v_min = -(v_at_a_max - vMin) / aMax
        t_to_v_max = -aMax / (2.0 * J) - (v_at_a_max - vMax) / aMax
        return t_to_a_max, max(min(t_to_v_min, t_to_v_max), 0.0), False
    return t_to_a_max, 0.0, False


@jit_raw
def _rk_vel(v0, a0, vMax, vMin, aMin, J):
    """ruckig's velocity brake: returns (t0, t1)."""
    t_to_a_min = (a0 - aMin) / J
    r1 = a0 * a0 + 2.0 * J * (v0 - vMax)
    r2 = a0 * a0 / 2.0 + J * (v0 - vMin)
    t_to_v_max = a0 / J + math.sqrt(r1) / abs(J) if r1 >= 0.0 else math.inf
    t_to_v_min = a0 / J + math.sqrt(r2) / abs(J) if r2 >= 0.0 else math.inf
    t_min_to_v_max = min(t_to_v_max, t_to_v_min)
    if t_to_a_min < t_min_to_v_max:
        v_at_a_min = v0 + t_to_a_min * (a0 - J * t_to_a_min / 2.0)
        t_c_max = -(v_at_a_min - vMax) / aMin
        t_c_min = aMin / (2.0 * J) - (v_at_a_min - vMin) / aMin
        return max(t_to_a_min, 0.0), max(min(t_c_max, t_c_min), 0.0)
    if not (t_min_to_v_max < math.inf):
        return -1.0, 0.0
    return max(t_min_to_v_max, 0.0), 0.0


@jit_raw
def brake_ruckig(v, a, V, A1, K1, A2, K2, out, buf):
    """Brake candidate ``ruckig``: ruckig's brake rule at the smaller jerk and
    acceleration of both legs, then the acceleration ramped towards zero; cut
    at the first instant inside the limits. Returns the phase count or -1."""
    Km = max(K1, K2)
    if Km == 0.0 or not (V < math.inf):
        return -1
    J = 1.0 / Km
    A = min(A1, A2)
    vza_m = v - a * a / (2.0 * J)   # velocity after ramping a to zero at -J (a > 0)
    vza_p = v + a * a / (2.0 * J)   # ... at +J (a < 0)
    if a > A:
        t0, t1, vb = _rk_acc(v, a, V, -V, A, J)
        jj = -J
        if vb:
            t0, t1 = _rk_vel(v, a, V, -V, -A, J)
    elif a < -A:
        t0, t1, vb = _rk_acc(v, a, -V, V, -A, -J)
        jj = J
        if vb:
            t0, t1 = _rk_vel(v, a, -V, V, A, -J)
    elif (v > V and vza_m > -V) or (a > 0.0 and vza_m > V):
        t0, t1 = _rk_vel(v, a, V, -V, -A, J)
        jj = -J
    elif (v < -V and vza_p < V) or (a < 0.0 and vza_p < -V):
        t0, t1 = _rk_vel(v, a, -V, V, A, -J)
        jj = J
    else:
        return -1
    if t0 < 0.0:
        return -1
    k = 0
    if t0 > 0.0:
        k = _seq(buf, k, t0, jj, a)
    a1 = a + jj * t0
    if t1 > 0.0:
        k = _seq(buf, k, t1, 0.0, a1)
    if a1 != 0.0:
        k = _seq(buf, k, abs(a1) / J, -J if a1 > 0.0 else J, a1)
    n, inside_ = _walk_cut(buf, k, v, V, A1, K1, A2, K2, out, buf[:78])
    return n if inside_ else -1


@jit_raw
def forced_speed(v, a, V, A1, K1, A2, K2):
    """The largest speeds a brake from (v, a) may reach: ``(ahead, back)``, in the
    direction of the start velocity (of its acceleration at ``v = 0``) and in the
    other. Ahead: the start's own speed or the peak its acceleration forces
    (ramped to zero at the speeding-up jerk limit); back: the peak reached when
    an acceleration that slows the axis down cannot be ramped to zero (at the
    slowing-down jerk limit) before the velocity reverses. At least ``V`` each."""
    if v < 0.0 or (v == 0.0 and a < 0.0):
        v = -v
        a = -a
    ahead = max(V, v)
    back = V
    if a > 0.0:
        ahead = max(ahead, v + 0.5 * a * a * K1)
    elif a < 0.0:
        rem = v - 0.5 * a * a * K2
        if rem < 0.0 and K2 > 0.0:
            az2 = a * a - 2.0 * v / K2
            back = max(back, 0.5 * az2 * K1)
    return ahead, back


@jit_raw
def peak_speed(ph, n, v, a):
    """Exact largest speeds along phases ``ph[:n]`` from (v, a) (phase ends and
    a = 0): ``(ahead, back)`` as in :func:`forced_speed`."""
    sg = 1.0 if (v > 0.0 or (v == 0.0 and a >= 0.0)) else -1.0
    ahead = max(sg * v, 0.0)
    back = 0.0
    for k in range(n):
        dt = ph[k, 0]
        j = ph[k, 1]
        a = ph[k, 2]
        if j != 0.0:
            ta = -a / j
            if 0.0 < ta < dt:
                _, vv, _ = phase_end(0.0, v, a, j, ta)
                ahead = max(ahead, sg * vv)
                back = max(back, -sg * vv)
        _, v, a = phase_end(0.0, v, a, j, dt)
        ahead = max(ahead, sg * v)
        back = max(back, -sg * v)
    return ahead, back


@jit_raw
def _lingers_piece(v, a, j, t0, t1, dt, A1, K1, A2, K2):
    """:func:`lingers` on the piece ``[t0, t1]`` of one phase (no leg change inside)."""
    tol = 1e-9
    if not (t1 - t0 > tol * dt):
        return False
    tm = 0.5 * (t0 + t1)
    vm = v + tm * (a + 0.5 * tm * j)
    am = a + j * tm
    amax = max(abs(a + j * t0), abs(a + j * t1))
    speeding = vm * am > 0.0
    Ab = A1 if speeding else A2
    Kb = K1 if speeding else K2
    if amax > Ab * (1.0 + tol):
        return not (j * am < 0.0 and abs(j) * Kb >= 1.0 - tol)
    return False


@jit_raw
def lingers(ph, n, v, a, A1, K1, A2, K2):
    """True when the phases ``ph[:n]`` from ``(v, a)`` hold an acceleration beyond
    the bound of its leg (``a_max`` while ``|v|`` grows, ``a_max_decel`` while it
    shrinks) other than by ramping it back towards zero at that leg's jerk limit:
    such a brake stays outside the limits longer than the start state forces."""
    for k in range(n):
        dt = ph[k, 0]
        j = ph[k, 1]
        a = ph[k, 2]
        c1, c2, c3 = leg_cuts(v, a, j, dt)
        t0 = 0.0
        for t1 in (c1, c2, c3, dt):
            if t1 > t0:
                if _lingers_piece(v, a, j, t0, t1, dt, A1, K1, A2, K2):
                    return True
                t0 = t1
        _, v, _ = phase_end(0.0, v, a, j, dt)
    return False
