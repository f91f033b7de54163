"""The retired one-parameter scan kernel, kept as an independent reference.

This is the state-to-state kernel trajkit shipped before the closed-form
shape enumeration (``trajkit.profiles._shapes``) replaced it: profile
families scanned on grids with root refinement. It lives on only here, in
plain Python, as the asymmetric-limits oracle of the tests (the new planner
must never be slower than it by more than 1e-9). Text below is its original
documentation.

Scalar kernels for profiles between arbitrary states (one axis).

Pure-float code; validation happens in :mod:`trajkit.profiles.state`.

Representation
--------------
A profile is a list of phases ``(dt, j, a_start)``: duration [s], constant
jerk [unit/s^3] and the acceleration at the start of the phase [unit/s^2]
(stored so that an infinite-jerk limit can make the acceleration jump between
phases). Integration is exact: ``p + dt*(v + dt*(a/2 + dt*j/6))``.

Limits are the tuple ``L = (V, A1, J1, A2, J2)``: velocity limit, the
acceleration and jerk limits while |v| grows (accel leg) and while |v|
shrinks (decel leg).

Building blocks
---------------
* :func:`ramp` -- acceleration from ``a_s`` to ``a_e`` at the largest jerk,
  split at ``a = 0`` where the regime (speeding up / slowing down) changes.
* :func:`bump` -- the minimum-time velocity change from ``(v0, a0)`` to
  ``(v1, a1)``: one acceleration "bump" (ramp to a peak ``ap``, an optional
  plateau at the acceleration limit, ramp to ``a1``). The change of velocity
  over a bump is ``k*ap**2 + c`` on each branch of ``ap``, so each branch has
  a closed-form peak; the fastest branch wins.
* Families for the full problem (position, velocity, acceleration):
  ``F1`` two bumps through a velocity extremum ``(vc, a=0)`` with an optional
  cruise at ``vc = +-V``; ``F2`` a bump then a single ramp joined at an
  acceleration valley/peak ``am`` (velocity monotone through it). The
  minimum time is the fastest *verified* candidate of all families; every
  candidate is checked exactly (:func:`verify`) before it may win.

Speed
-----
The scans evaluate fused residuals (:func:`f1_residual`, ...: the end
position of a family member with the same floating-point operations as
integrating its phases, without building them), scanned by
:func:`scan_family`; these, the bump choice (:func:`_bump_plan`) and the
exact check (:func:`_verify_core`) are plain scalar code that
:mod:`._state_jit` compiles with numba when it is installed (same results
bit for bit; ``TRAJKIT_NO_JIT=1`` keeps everything in Python).
"""

from __future__ import annotations

import math
import sys

from trajkit._constants import GOAL_RTOL, LIMIT_RTOL

_inf = math.inf
_sqrt = math.sqrt

#: Points per family scan (velocity or acceleration parameter).
SCAN_POINTS = 16

#: Offsets (fractions of the scan width) of extra grid points around the
#: special parameter values, where legs change shape (square-root behaviour).
MARK_OFFSETS = (1e-6,)

#: Round-off allowance (in units of machine epsilon times the position
#: magnitude) for the goal position check: positions far from the origin
#: cannot be hit more precisely than their own representation.
FLOAT_ULPS = 64.0

_eps = sys.float_info.epsilon

#: Margin on the acceleration scan range ``sqrt(4 J V)``.
ACC_CAP_FACTOR = 1.01

#: Bisection steps locating the edge of a family's feasible parameter set.
EDGE_BISECT = 48

#: A local extremum of a scanned residual is searched for hidden roots when
#: the parabola through it dips below this fraction of its sampled value.
PROMISING_FRACTION = 0.5

#: Points of the (nested, slower) F2-with-hold scan for fixed durations.
HOLD_SCAN_POINTS = 32

#: The hold length is solved to this fraction of the duration (the hold then
#: absorbs the remainder exactly), in at most ``HOLD_MAX_ITER`` steps.
HOLD_TIME_RTOL = 1e-13
HOLD_MAX_ITER = 60

#: Extra points of the F2-with-hold scan in every gap between the boundary
#: accelerations, zero and the scan ends (the family's window can be narrow).
HOLD_GAP_POINTS = 8

#: A hold root whose duration still misses ``T`` by more than this fraction
#: (the bracket closed on a jump of the duration, where the bump changes
#: branch) is not a member of the F2-with-hold family.
HOLD_ACCEPT_RTOL = 1e-9

#: Edge bisection steps in the F2-with-hold scan.
HOLD_EDGE_BISECT = 48

#: Closest candidates from each side tried for a blend (fixed duration).
BLEND_TRIES = 3

#: Margin on the velocity window scanned for fixed-duration profiles.
WINDOW_MARGIN = 1.01

#: A boundary acceleration this close to its limit counts as at the limit.
SNAP_RTOL = 1e-12

#: Relative round-off allowance when a closed-form peak lands on a branch end.
ROUND_RTOL = 4e-16

#: Smallest positive magnitude used to guard divisions and comparisons.
TINY = 1e-300

#: Golden-section steps when looking for roots hidden between grid points.
GOLDEN_ITER = 28

#: Relative x-tolerance of the scalar root finder on a family parameter.
SCAN_XRTOL = 1e-15

#: Maximum bisection/secant steps in :func:`_root`.
SCAN_MAX_ITER = 200

#: Absolute floor (relative to the problem's natural scale) used by the
#: verification to accept round-off at zero-valued limits comparisons.
VERIFY_ATOL_SCALE = 1e-12


# ------------------------------------------------------------------ phases
def integrate(phases, p, v, a):
    """Exact end state ``(p, v, a)`` after ``phases`` from ``(p, v, a)``."""
    for dt, j, a_s in phases:
        a = a_s
        p = p + dt * (v + dt * (0.5 * a + dt * j / 6.0))
        v = v + dt * (a + 0.5 * dt * j)
        a = a + dt * j
    return p, v, a


def integrate_va(phases, v, a):
    """Exact end velocity and acceleration after ``phases``."""
    for dt, j, a_s in phases:
        v = v + dt * (a_s + 0.5 * dt * j)
        a = a_s + dt * j
    return v, a


def total_time(phases):
    t = 0.0
    for dt, _, _ in phases:
        t += dt
    return t


def negate(phases):
    """Mirror a phase list (p, v, a, j -> -p, -v, -a, -j)."""
    return [(dt, -j, -a) for dt, j, a in phases]


# ------------------------------------------------------------------- ramps
def ramp(a_s, a_e, J1, J2, out):
    """Append the fastest ramp ``a_s -> a_e`` (positive-velocity frame).

    In the frame where the velocity is >= 0, a positive acceleration speeds
    up (jerk limit ``J1``) and a negative one slows down (``J2``); the ramp
    is split at zero. Returns ``(dv, dt)``.
    """
    if a_s == a_e:
        return 0.0, 0.0
    pts = (a_s, 0.0, a_e) if (a_s < 0.0 < a_e or a_e < 0.0 < a_s) else (a_s, a_e)
    up = a_e > a_s
    dv = 0.0
    tt = 0.0
    for x, y in zip(pts[:-1], pts[1:]):
        m = x + y
        J = J1 if m > 0.0 else J2
        if J == _inf:
            # infinite jerk: the acceleration jumps; a zero-length phase
            # carries the new value (a_start) so the end state is exact
            out.append((0.0, 0.0, y))
            continue
        dt = abs(y - x) / J
        out.append((dt, J if up else -J, x))
        dv += 0.5 * (x + y) * dt
        tt += dt
    return dv, tt


def _part(x, y, J1, J2):
    J = J1 if x + y > 0.0 else J2
    if J == _inf:
        return 0.0, 0.0
    dt = abs(y - x) / J
    return 0.5 * (x + y) * dt, dt


def ramp_dv_dt(a_s, a_e, J1, J2):
    """``(dv, dt)`` of :func:`ramp` without building phases."""
    if a_s == a_e:
        return 0.0, 0.0
    if a_s * a_e < 0.0:
        dv1, t1 = _part(a_s, 0.0, J1, J2)
        dv2, t2 = _part(0.0, a_e, J1, J2)
        return dv1 + dv2, t1 + t2
    return _part(a_s, a_e, J1, J2)


def ramp_dv(a_s, a_e, J1, J2):
    """Velocity change of :func:`ramp` without building phases."""
    return ramp_dv_dt(a_s, a_e, J1, J2)[0]


def _bump_phases(a0, ap, a1, tp, J1, J2):
    out = []
    ramp(a0, ap, J1, J2, out)
    if tp > 0.0:
        out.append((tp, 0.0, ap))
    ramp(ap, a1, J1, J2, out)
    return out


def _bump_dv(a0, ap, a1, J1, J2):
    return ramp_dv_dt(a0, ap, J1, J2)[0] + ramp_dv_dt(ap, a1, J1, J2)[0]


def _bump_dt(a0, ap, a1, tp, J1, J2):
    return ramp_dv_dt(a0, ap, J1, J2)[1] + tp + ramp_dv_dt(ap, a1, J1, J2)[1]


def _bump_select(dv, a0, a1, A1, J1, A2, J2):
    """Peak and plateau of the fastest bump (positive-velocity frame).

    Four branches of the peak ``ap``, each with ``dv(ap) = k ap^2 + c``:

    1. up-bump, ``ap in [max(a0, a1, 0), A1]``, ``k = +1/J1``, plateau at A1;
    2. up-bump, ``ap in [max(a0, a1), 0]`` (both ends negative), ``k = +1/J2``;
    3. down-bump, ``ap in [-A2, min(a0, a1, 0)]``, ``k = -1/J2``, plateau at -A2;
    4. down-bump, ``ap in [0, min(a0, a1)]`` (both ends positive), ``k = -1/J1``.

    ``dv`` is monotone in ``|ap|`` on every branch, so each has at most one
    solution; the fastest wins. Scalar code (compiled by :mod:`._state_jit`).

    Returns
    -------
    found : bool
    ap : float
        Peak acceleration [unit/s^2].
    tp : float
        Plateau duration at ``ap`` [s].
    """
    found = False
    best_ap = 0.0
    best_tp = 0.0
    best_t = _inf
    hi = max(a1, a0)
    lo = min(a0, a1)
    rdd = ramp_dv_dt
    for b in range(4):
        has_plat = False
        plat = 0.0
        if b == 0:
            if hi > A1 * (1.0 + SNAP_RTOL):
                continue
            inner = min(hi, A1) if hi > 0.0 else 0.0
            outer, J, ksign, side = A1, J1, 1.0, 1.0
            has_plat, plat = True, A1
        elif b == 1:
            if hi >= 0.0:
                continue
            inner, outer, J, ksign, side = 0.0, hi, J2, 1.0, -1.0
        elif b == 2:
            if lo < -A2 * (1.0 + SNAP_RTOL):
                continue
            inner = max(lo, -A2) if lo < 0.0 else 0.0
            outer, J, ksign, side = -A2, J2, -1.0, -1.0
            has_plat, plat = True, -A2
        else:
            if lo <= 0.0:
                continue
            inner, outer, J, ksign, side = 0.0, lo, J1, -1.0, 1.0
        if abs(outer) < abs(inner):
            continue
        ok = False
        ap = 0.0
        tp = 0.0
        if J != _inf:
            k = ksign / J
            d1, t1 = rdd(a0, inner, J1, J2)
            d2, t2 = rdd(inner, a1, J1, J2)
            in2 = inner * inner
            s2 = (dv - (d1 + d2 - k * in2)) / k
            if s2 >= in2 * (1.0 - ROUND_RTOL) or s2 >= in2 - TINY:
                r = _sqrt(max(in2, s2))
                if r <= abs(outer) * (1.0 + ROUND_RTOL):
                    ao = abs(outer)
                    ap = side * (min(ao, r))
                    ok = True
        if not ok and has_plat and plat != _inf and plat != -_inf:
            d1, t1 = rdd(a0, plat, J1, J2)
            d2, t2 = rdd(plat, a1, J1, J2)
            tp = (dv - d1 - d2) / plat
            if tp >= 0.0:
                ap = plat
                ok = True
            else:
                tp = 0.0
        if not ok:
            continue
        t = rdd(a0, ap, J1, J2)[1] + tp + rdd(ap, a1, J1, J2)[1]
        if t < best_t:
            found, best_ap, best_tp, best_t = True, ap, tp, t
    return found, best_ap, best_tp


def _bump_frame(dv, a0, a1, A1, J1, A2, J2):
    """Fastest bump in the positive-velocity frame; list of phases or None
    (see :func:`_bump_select`)."""
    found, ap, tp = _bump_select(dv, a0, a1, A1, J1, A2, J2)
    if not found:
        return None
    return _bump_phases(a0, ap, a1, tp, J1, J2)


def bump(v0, a0, v1, a1, L, jk=False):
    """Fastest phases from ``(v0, a0)`` to ``(v1, a1)`` (position free).

    The regime frame is the sign of the velocity; a bump whose velocity
    changes sign uses the tighter of both legs' limits (conservative).
    Returns a phase list or ``None``. The choice is :func:`_bump_plan`
    (compiled when :mod:`._state_jit` is enabled, same result); ``jk`` is
    :func:`_jit_kernels`'s answer when the caller has it already.
    """
    _, A1, J1, A2, J2 = L
    if jk is False:
        jk = _jit_kernels()
    plan = _bump_plan if jk is None else jk["_bump_plan"]
    found, s, ap, tp, Ja, Jb = plan(v0, a0, v1, a1, A1, J1, A2, J2)
    if not found:
        return None
    ph = _bump_phases(s * a0, ap, s * a1, tp, Ja, Jb)
    return ph if s > 0 else negate(ph)


def _same_sign(ph, v, s):
    """True when the velocity (frame) never goes negative along ``ph``."""
    scale = abs(v)
    for dt, j, a in ph:
        v = v + dt * (a + 0.5 * dt * j)
        scale = max(scale, abs(v))
        if v < -VERIFY_ATOL_SCALE * scale:
            return False
    return True


# --------------------------------------------------------- fused residuals
# The family scans evaluate the end position of a one-parameter profile many
# times. The functions below compute exactly what ``integrate(profile(x))``
# computes (the same phases, the same floating-point operations in the same
# order) without building phase lists, so a scan gives the same numbers bit
# for bit. They are plain scalar code: :mod:`._state_jit` compiles them with
# numba when it is installed (``TRAJKIT_NO_JIT=1`` keeps them in Python).
def _seg_int(p, v, t, x, y, J1, J2, up, sg):
    """Integrate one ramp segment ``x -> y`` as :func:`ramp` builds it
    (mirrored when ``sg < 0``); returns ``(p, v, t)``."""
    J = J1 if x + y > 0.0 else J2
    if J == _inf:
        dt, j, a = 0.0, 0.0, y
    else:
        dt = abs(y - x) / J
        j = J if up else -J
        a = x
    if sg < 0.0:
        j, a = -j, -a
    p = p + dt * (v + dt * (0.5 * a + dt * j / 6.0))
    v = v + dt * (a + 0.5 * dt * j)
    return p, v, t + dt


def _ramp_int(p, v, t, x, y, J1, J2, sg):
    """Integrate :func:`ramp` ``x -> y`` (frame values); ``(p, v, t)``."""
    if x == y:
        return p, v, t
    up = y > x
    if x < 0.0 < y or y < 0.0 < x:
        p, v, t = _seg_int(p, v, t, x, 0.0, J1, J2, up, sg)
        x = 0.0
    return _seg_int(p, v, t, x, y, J1, J2, up, sg)


def _ramp_dv(x, y, J1, J2):
    """The ``dv`` :func:`ramp` returns (same summation)."""
    if x == y:
        return 0.0
    dv = 0.0
    if x < 0.0 < y or y < 0.0 < x:
        J = J1 if x + 0.0 > 0.0 else J2
        if J != _inf:
            dt = abs(0.0 - x) / J
            dv += 0.5 * (x + 0.0) * dt
        x = 0.0
    J = J1 if x + y > 0.0 else J2
    if J != _inf:
        dt = abs(y - x) / J
        dv += 0.5 * (x + y) * dt
    return dv


def _bump_int(p, v, sg, a0, ap, a1, tp, J1, J2):
    """Integrate the bump phases of :func:`_bump_phases` (frame values,
    mirrored when ``sg < 0``) from ``(p, v)``; returns ``(p, v, duration)``."""
    return _bump_int_t(p, v, 0.0, sg, a0, ap, a1, tp, J1, J2)


def _bump_int_t(p, v, t, sg, a0, ap, a1, tp, J1, J2):
    """:func:`_bump_int` continuing the time sum ``t``."""
    p, v, t = _ramp_int(p, v, t, a0, ap, J1, J2, sg)
    if tp > 0.0:
        j, a = 0.0, ap
        if sg < 0.0:
            j, a = -j, -a
        p = p + tp * (v + tp * (0.5 * a + tp * j / 6.0))
        v = v + tp * (a + 0.5 * tp * j)
        t = t + tp
    return _ramp_int(p, v, t, ap, a1, J1, J2, sg)


def _seg_same_sign(v, scale, x, y, J1, J2, up):
    J = J1 if x + y > 0.0 else J2
    if J == _inf:
        dt, j, a = 0.0, 0.0, y
    else:
        dt = abs(y - x) / J
        j = J if up else -J
        a = x
    v = v + dt * (a + 0.5 * dt * j)
    scale = max(scale, abs(v))
    return not (v < -VERIFY_ATOL_SCALE * scale), v, scale


def _ramp_same_sign(v, scale, x, y, J1, J2):
    if x == y:
        return True, v, scale
    up = y > x
    if x < 0.0 < y or y < 0.0 < x:
        ok, v, scale = _seg_same_sign(v, scale, x, 0.0, J1, J2, up)
        if not ok:
            return False, v, scale
        x = 0.0
    return _seg_same_sign(v, scale, x, y, J1, J2, up)


def _bump_same_sign(v, a0, ap, a1, tp, J1, J2):
    """:func:`_same_sign` of the frame bump phases (same arithmetic)."""
    scale = abs(v)
    ok, v, scale = _ramp_same_sign(v, scale, a0, ap, J1, J2)
    if not ok:
        return False
    if tp > 0.0:
        v = v + tp * (ap + 0.5 * tp * 0.0)
        scale = max(scale, abs(v))
        if v < -VERIFY_ATOL_SCALE * scale:
            return False
    ok, v, scale = _ramp_same_sign(v, scale, ap, a1, J1, J2)
    return ok


def _bump_plan(v0, a0, v1, a1, A1, J1, A2, J2):
    """What :func:`bump` chooses, without phases.

    Returns ``(found, s, ap, tp, Ja, Jb)``: the frame sign, the peak and
    plateau of :func:`_bump_select` and the jerk limits used.
    """
    s = 1.0 if (v0 + v1) > 0.0 or (v0 + v1 == 0.0 and (a0 + a1) >= 0.0) else -1.0
    if (v0 >= 0.0 and v1 >= 0.0) or (v0 <= 0.0 and v1 <= 0.0):
        found, ap, tp = _bump_select(s * (v1 - v0), s * a0, s * a1, A1, J1, A2, J2)
        if found and _bump_same_sign(s * v0, s * a0, ap, s * a1, tp, J1, J2):
            return True, s, ap, tp, J1, J2
    Am, Jm = min(A1, A2), min(J1, J2)
    found, ap, tp = _bump_select(s * (v1 - v0), s * a0, s * a1, Am, Jm, Am, Jm)
    return found, s, ap, tp, Jm, Jm


def _ramp_signed_plan(a_s, a_e, v_ref, J1, J2):
    """What :func:`_ramp_signed` chooses: ``(s, Ja, Jb, signed dv)``."""
    s = 1.0 if v_ref > 0.0 or (v_ref == 0.0 and a_e + a_s >= 0.0) else -1.0
    dv = _ramp_dv(s * a_s, s * a_e, J1, J2)
    if (v_ref + s * dv) * s < 0.0 and J1 != J2:
        Jm = min(J1, J2)
        return s, Jm, Jm, s * _ramp_dv(s * a_s, s * a_e, Jm, Jm)
    return s, J1, J2, s * dv


def f1_residual(vc, p0, v0, a0, pf, vf, af, A1, J1, A2, J2):
    """``integrate(f1_profile(vc))[0] - pf`` without phases: ``(ok, r)``."""
    ok1, s1, ap1, tp1, Ja1, Jb1 = _bump_plan(v0, a0, vc, 0.0, A1, J1, A2, J2)
    if not ok1:
        return False, 0.0
    ok2, s2, ap2, tp2, Ja2, Jb2 = _bump_plan(vc, 0.0, vf, af, A1, J1, A2, J2)
    if not ok2:
        return False, 0.0
    p, v, _ = _bump_int(p0, v0, s1, s1 * a0, ap1, s1 * 0.0, tp1, Ja1, Jb1)
    p, v, _ = _bump_int(p, v, s2, s2 * 0.0, ap2, s2 * af, tp2, Ja2, Jb2)
    return True, p - pf


def f2_residual(am, p0, v0, a0, pf, vf, af, A1, J1, A2, J2, first_is_ramp):
    """``integrate(f2_profile(am, ...))[0] - pf`` without phases: ``(ok, r)``."""
    if not first_is_ramp:
        s, Ja, Jb, dv = _ramp_signed_plan(am, af, vf, J1, J2)
        vm = vf - dv
        ok, sb, ap, tp, Jc, Jd = _bump_plan(v0, a0, vm, am, A1, J1, A2, J2)
        if not ok:
            return False, 0.0
        p, v, _ = _bump_int(p0, v0, sb, sb * a0, ap, sb * am, tp, Jc, Jd)
        p, v, _ = _ramp_int(p, v, 0.0, s * am, s * af, Ja, Jb, s)
        return True, p - pf
    s, Ja, Jb, dv = _ramp_signed_plan(a0, am, v0, J1, J2)
    vm = v0 + dv
    ok, sb, ap, tp, Jc, Jd = _bump_plan(vm, am, vf, af, A1, J1, A2, J2)
    if not ok:
        return False, 0.0
    p, v, _ = _ramp_int(p0, v0, 0.0, s * a0, s * am, Ja, Jb, s)
    p, v, _ = _bump_int(p, v, sb, sb * am, ap, sb * af, tp, Jc, Jd)
    return True, p - pf


def fixed_residual(vc, T, p0, v0, a0, pf, vf, af, A1, J1, A2, J2):
    """Position error of the fixed-duration F1 profile (bump, cruise at
    ``vc`` filling ``T``, bump) of :func:`fixed_time_profile`: ``(ok, r)``."""
    ok1, s1, ap1, tp1, Ja1, Jb1 = _bump_plan(v0, a0, vc, 0.0, A1, J1, A2, J2)
    if not ok1:
        return False, 0.0
    ok2, s2, ap2, tp2, Ja2, Jb2 = _bump_plan(vc, 0.0, vf, af, A1, J1, A2, J2)
    if not ok2:
        return False, 0.0
    p, v, t1 = _bump_int(p0, v0, s1, s1 * a0, ap1, s1 * 0.0, tp1, Ja1, Jb1)
    t2 = _bump_int(0.0, 0.0, s2, s2 * 0.0, ap2, s2 * af, tp2, Ja2, Jb2)[2]
    tc = T - t1 - t2
    if tc < -ROUND_RTOL * T:
        return False, 0.0
    dt = max(tc, 0.0)
    p = p + dt * (v + dt * (0.5 * 0.0 + dt * 0.0 / 6.0))
    v = v + dt * (0.0 + 0.5 * dt * 0.0)
    p, v, _ = _bump_int(p, v, s2, s2 * 0.0, ap2, s2 * af, tp2, Ja2, Jb2)
    return True, p - pf


def _hold_build(th, first, am, T, p0, v0, a0, vf, af, A1, J1, A2, J2,
                s, Ja, Jb, dv, with_position):
    """One member of :func:`f2_hold_profile` with hold ``th`` (fused).

    Returns ``(ok, total duration, end position)`` of the phases
    ``build(th)`` there (the position only when ``with_position``; the
    hold is then stretched by the duration's round-off, as there).
    """
    if first:
        vm = v0 + dv + am * th
        ok, sb, ap, tp, Jc, Jd = _bump_plan(vm, am, vf, af, A1, J1, A2, J2)
    else:
        vm = vf - dv - am * th
        ok, sb, ap, tp, Jc, Jd = _bump_plan(v0, a0, vm, am, A1, J1, A2, J2)
    if not ok:
        return False, 0.0, 0.0
    # the duration: phases in order (ramp, hold, bump) or (bump, hold, ramp)
    if first:
        t = _ramp_int(0.0, 0.0, 0.0, s * a0, s * am, Ja, Jb, s)[2]
        if th > 0.0:
            t = t + th
        t = _bump_int_t(0.0, 0.0, t, sb, sb * am, ap, sb * af, tp, Jc, Jd)[2]
    else:
        t = _bump_int_t(0.0, 0.0, 0.0, sb, sb * a0, ap, sb * am, tp, Jc, Jd)[2]
        if th > 0.0:
            t = t + th
        t = _ramp_int(0.0, 0.0, t, s * am, s * af, Ja, Jb, s)[2]
    if not with_position:
        return True, t, 0.0
    hold = th
    if th > 0.0 and abs(t - T) > 0.0:
        hold = max(th + (T - t), 0.0)
    if first:
        p, v, _ = _ramp_int(p0, v0, 0.0, s * a0, s * am, Ja, Jb, s)
        if th > 0.0:
            p = p + hold * (v + hold * (0.5 * am + hold * 0.0 / 6.0))
            v = v + hold * (am + 0.5 * hold * 0.0)
        p, v, _ = _bump_int(p, v, sb, sb * am, ap, sb * af, tp, Jc, Jd)
    else:
        p, v, _ = _bump_int(p0, v0, sb, sb * a0, ap, sb * am, tp, Jc, Jd)
        if th > 0.0:
            p = p + hold * (v + hold * (0.5 * am + hold * 0.0 / 6.0))
            v = v + hold * (am + 0.5 * hold * 0.0)
        p, v, _ = _ramp_int(p, v, 0.0, s * am, s * af, Ja, Jb, s)
    return True, t, p


def f2_hold_residual(am, T, p0, v0, a0, pf, vf, af, A1, J1, A2, J2, first_is_ramp):
    """``integrate(f2_hold_profile(am, ...))[0] - pf`` without phases: ``(ok, r)``.

    The same hold root (:func:`_root` on the duration excess, same steps)
    and the same round-off absorption as :func:`f2_hold_profile`.
    """
    first = first_is_ramp
    if first:
        s, Ja, Jb, dv = _ramp_signed_plan(a0, am, v0, J1, J2)
        tr = _ramp_int(0.0, 0.0, 0.0, s * a0, s * am, Ja, Jb, s)[2]
    else:
        s, Ja, Jb, dv = _ramp_signed_plan(am, af, vf, J1, J2)
        tr = _ramp_int(0.0, 0.0, 0.0, s * am, s * af, Ja, Jb, s)[2]
    span = T - tr
    if span <= 0.0:
        return False, 0.0
    ok0, t0, _ = _hold_build(0.0, first, am, T, p0, v0, a0, vf, af, A1, J1, A2, J2,
                             s, Ja, Jb, dv, False)
    ok1, t1, _ = _hold_build(span, first, am, T, p0, v0, a0, vf, af, A1, J1, A2, J2,
                             s, Ja, Jb, dv, False)
    if not ok0 or not ok1:
        return False, 0.0
    e0 = t0 - T
    e1 = t1 - T
    if e0 > 0.0 or e1 < 0.0:
        return False, 0.0
    # _root(excess, 0, e0, span, e1, ftol=HOLD_TIME_RTOL*T, max_iter=HOLD_MAX_ITER)
    ftol = HOLD_TIME_RTOL * T
    x0, f0, x1, f1 = 0.0, e0, span, e1
    th = 0.0
    found = False
    if f0 == 0.0:
        th, found = x0, True
    elif f1 == 0.0:
        th, found = x1, True
    else:
        side = 0
        for _ in range(HOLD_MAX_ITER):
            if abs(x1 - x0) <= SCAN_XRTOL * max(abs(x0), abs(x1)) + TINY:
                break
            x = (x0 * f1 - x1 * f0) / (f1 - f0)
            if not (min(x0, x1) < x < max(x0, x1)):
                x = 0.5 * (x0 + x1)
            ok, tx, _ = _hold_build(x, first, am, T, p0, v0, a0, vf, af, A1, J1, A2, J2,
                                    s, Ja, Jb, dv, False)
            if not ok:
                x = 0.5 * (x0 + x1)
                ok, tx, _ = _hold_build(x, first, am, T, p0, v0, a0, vf, af, A1, J1, A2, J2,
                                        s, Ja, Jb, dv, False)
                if not ok:
                    return False, 0.0
            fx = tx - T
            if abs(fx) <= ftol:
                th, found = x, True
                break
            if (fx > 0.0) == (f0 > 0.0):
                x0, f0 = x, fx
                if side == -1:
                    f1 *= 0.5
                side = -1
            else:
                x1, f1 = x, fx
                if side == 1:
                    f0 *= 0.5
                side = 1
        if not found:
            th, found = (x0 if abs(f0) < abs(f1) else x1), True
    ok, t, p = _hold_build(th, first, am, T, p0, v0, a0, vf, af, A1, J1, A2, J2,
                           s, Ja, Jb, dv, True)
    if not ok or abs(t - T) > HOLD_ACCEPT_RTOL * T:
        return False, 0.0
    return True, p - pf


def _jit_kernels():
    """The oracle runs in plain Python (its compiled variant was retired)."""
    return None


def _scan(jk, kind, grid, P, edge_steps=EDGE_BISECT, near=False):
    """:func:`scan_family`, compiled when ``jk`` (:func:`_jit_kernels`) is set."""
    if jk is None:
        return scan_family(kind, grid, P, edge_steps, near)
    from . import _state_jit

    return _state_jit.scan_family(kind, grid, P, edge_steps, near)


# ------------------------------------------------------------- verification
def verify(phases, p0, v0, a0, L, goal, rtol=LIMIT_RTOL, check_goal=True):
    """Exact check of limits and goal; returns ``None`` or a reason string.

    Limits are checked at every phase boundary and at every in-phase
    extremum or regime change: the velocity at ``a = 0``, the acceleration
    and jerk on both sides of every ``v = 0`` crossing (the speeding-up /
    slowing-down regime decides which limits apply). The check itself is
    :func:`_verify_core` (compiled when :mod:`._state_jit` is enabled, same
    decisions); this wrapper words its answer.
    """
    V, A1, J1, A2, J2 = L
    pg, vg, ag = goal
    jk = _jit_kernels()
    if jk is None:
        res = _verify_core(phases, len(phases), p0, v0, a0, V, A1, J1, A2, J2,
                           pg, vg, ag, rtol, check_goal)
    else:
        from . import _state_jit

        res = _state_jit.verify_core(phases, p0, v0, a0, V, A1, J1, A2, J2,
                                     pg, vg, ag, rtol, check_goal)
    code, x, lim, speeding = res
    if code == 0:
        return None
    if code == 1:
        return f"negative or non-finite phase duration {x!r}"
    if code == 2:
        return f"velocity {x!r} exceeds v_max {lim!r}"
    if code == 3:
        return f"acceleration {x!r} exceeds {'a_max' if speeding else 'a_max_decel'} {lim!r}"
    if code == 4:
        return f"jerk {x!r} exceeds {'j_max' if speeding else 'j_max_decel'} {lim!r}"
    if code == 5:
        return f"jerk {x!r} exceeds the jerk limits"
    if code == 6:
        return f"goal position missed by {x!r}"
    if code == 7:
        return f"goal velocity missed by {x!r}"
    return f"goal acceleration missed by {x!r}"


def _verify_core(ph, n, p0, v0, a0, V, A1, J1, A2, J2, pg, vg, ag, rtol, check_goal):
    """The checks of :func:`verify` on ``ph[k] = (dt, j, a_start)``, k < n.

    Scalar code (``ph`` a list of tuples or an (n, 3) array). Returns
    ``(code, value, limit, speeding)``: code 0 passes; 1 a bad phase
    duration; 2 velocity, 3 acceleration, 4 jerk (of the regime), 5 jerk
    (either limit, at a = 0) above its limit; 6, 7, 8 the goal position,
    velocity, acceleration missed (``value`` is the error).
    """
    p, v, a = p0, v0, a0
    vscale = max(abs(v0), abs(vg), TINY)
    ascale = max(abs(a0), abs(ag), TINY)
    vtol = V * rtol if V != _inf else 0.0
    vref = vscale
    T = 0.0
    for k in range(n):
        dt, j, a_s = ph[k][0], ph[k][1], ph[k][2]
        vref = max(vref, abs(a_s) * dt, abs(j) * dt * dt)
        T += dt
    for kk in range(n):
        dt, j, a_s = ph[kk][0], ph[kk][1], ph[kk][2]
        a = a_s
        if dt < 0.0 or not math.isfinite(dt):
            return 1, dt, 0.0, False
        # split points: a = 0 and v = 0 inside the phase
        ts = [0.0, dt]
        if j != 0.0:
            tz = -a / j
            if 0.0 < tz < dt:
                ts.append(tz)
        # v(t) = v + a t + j t^2/2 = 0
        nr, r1, r2 = _quad_roots2(0.5 * j, a, v)
        if nr >= 1 and 0.0 < r1 < dt:
            ts.append(r1)
        if nr >= 2 and 0.0 < r2 < dt:
            ts.append(r2)
        ts.sort()
        for k in range(len(ts)):
            t = ts[k]
            vt = v + t * (a + 0.5 * t * j)
            if V != _inf and abs(vt) > V + vtol:
                return 2, vt, V, False
        for k in range(len(ts) - 1):
            t0, t1 = ts[k], ts[k + 1]
            if t1 <= t0:
                continue
            tm = 0.5 * (t0 + t1)
            vm = v + tm * (a + 0.5 * tm * j)
            am = a + tm * j
            speeding = vm * am > 0.0 or vm == 0.0
            A = A1 if speeding else A2
            J = J1 if speeding else J2
            if abs(vm) <= VERIFY_ATOL_SCALE * vref:
                # |v| is at round-off level: the regime is undetermined
                A, J = max(A1, A2), max(J1, J2)
            at = a + t0 * j
            if abs(at) > A * (1.0 + rtol) + VERIFY_ATOL_SCALE * ascale:
                return 3, at, A, speeding
            at = a + t1 * j
            if abs(at) > A * (1.0 + rtol) + VERIFY_ATOL_SCALE * ascale:
                return 3, at, A, speeding
            if am != 0.0 and abs(j) > J * (1.0 + rtol):
                return 4, j, J, speeding
            if am == 0.0 and j != 0.0 and abs(j) > max(J1, J2) * (1.0 + rtol):
                return 5, j, max(J1, J2), speeding
        p = p + dt * (v + dt * (0.5 * a + dt * j / 6.0))
        v = v + dt * (a + 0.5 * dt * j)
        a = a + dt * j
        vscale = max(vscale, abs(v))
        ascale = max(ascale, abs(a))
    if check_goal:
        pscale = max(abs(pg - p0), vscale * T, ascale * T * T, TINY)
        floor = FLOAT_ULPS * _eps * max(abs(p0), abs(pg))
        if abs(p - pg) > GOAL_RTOL * pscale + floor:
            return 6, p - pg, 0.0, False
        if abs(v - vg) > GOAL_RTOL * vscale:
            return 7, v - vg, 0.0, False
        if abs(a - ag) > GOAL_RTOL * max(ascale, A1 if A1 != _inf else 0.0):
            return 8, a - ag, 0.0, False
    return 0, 0.0, 0.0, False


def _quad_roots2(qa, qb, qc):
    """:func:`_quad_roots` as ``(count, r1, r2)`` (fixed-size result)."""
    if qa == 0.0:
        if qb == 0.0:
            return 0, 0.0, 0.0
        return 1, -qc / qb, 0.0
    disc = qb * qb - 4.0 * qa * qc
    if disc < 0.0:
        return 0, 0.0, 0.0
    sq = _sqrt(disc)
    q = -0.5 * (qb + math.copysign(sq, qb))
    if q == 0.0:
        return 1, 0.0, 0.0
    return 2, q / qa, qc / q


def _quad_roots(qa, qb, qc):
    """Real roots of ``qa x^2 + qb x + qc`` (stable formula)."""
    if qa == 0.0:
        if qb == 0.0:
            return ()
        return (-qc / qb,)
    disc = qb * qb - 4.0 * qa * qc
    if disc < 0.0:
        return ()
    sq = _sqrt(disc)
    q = -0.5 * (qb + math.copysign(sq, qb))
    if q == 0.0:
        return (0.0,)
    return (q / qa, qc / q)


# ----------------------------------------------------------------- families
def f1_profile(vc, start, goal, L, cruise=0.0, jk=False):
    """F1: bump to ``(vc, 0)``, cruise ``cruise`` s, bump to the goal state."""
    _, v0, a0 = start
    _, vf, af = goal
    b1 = bump(v0, a0, vc, 0.0, L, jk)
    if b1 is None:
        return None
    b2 = bump(vc, 0.0, vf, af, L, jk)
    if b2 is None:
        return None
    if cruise > 0.0:
        return b1 + [(cruise, 0.0, 0.0)] + b2
    return b1 + b2


def _ramp_signed(a_s, a_e, v_ref, L):
    """Ramp ``a_s -> a_e`` in the frame of ``v_ref``; (phases, dv).

    Uses the tighter jerk of both legs when the velocity would change sign.
    """
    V, A1, J1, A2, J2 = L
    s = 1.0 if v_ref > 0.0 or (v_ref == 0.0 and a_e + a_s >= 0.0) else -1.0
    r = []
    dv, _ = ramp(s * a_s, s * a_e, J1, J2, r)
    if (v_ref + s * dv) * s < 0.0 and J1 != J2:
        Jm = min(J1, J2)
        r = []
        dv, _ = ramp(s * a_s, s * a_e, Jm, Jm, r)
    return (r if s > 0 else negate(r)), s * dv


def f2_profile(am, start, goal, L, first_is_ramp, jk=False):
    """F2: a bump and a single ramp joined at acceleration ``am``.

    ``first_is_ramp=False``: bump ``(v0, a0) -> (vm, am)`` then the ramp
    ``am -> af``; ``True``: ramp ``a0 -> am`` then a bump to the goal.
    """
    _, v0, a0 = start
    _, vf, af = goal
    if not first_is_ramp:
        r, dv = _ramp_signed(am, af, vf, L)
        vm = vf - dv
        b = bump(v0, a0, vm, am, L, jk)
        if b is None:
            return None
        return b + r
    r, dv = _ramp_signed(a0, am, v0, L)
    vm = v0 + dv
    b = bump(vm, am, vf, af, L, jk)
    if b is None:
        return None
    return r + b


def _root(fun, x0, f0, x1, f1, ftol=0.0, max_iter=SCAN_MAX_ITER):
    """Bracketed root (Illinois regula falsi + bisection safeguard).

    Stops when the bracket is below ``SCAN_XRTOL`` relative or ``|f| <= ftol``.
    """
    if f0 == 0.0:
        return x0
    if f1 == 0.0:
        return x1
    side = 0
    for _ in range(max_iter):
        if abs(x1 - x0) <= SCAN_XRTOL * max(abs(x0), abs(x1)) + TINY:
            break
        x = (x0 * f1 - x1 * f0) / (f1 - f0)
        if not (min(x0, x1) < x < max(x0, x1)):
            x = 0.5 * (x0 + x1)
        fx = fun(x)
        if fx is None:
            x = 0.5 * (x0 + x1)
            fx = fun(x)
            if fx is None:
                return None
        if abs(fx) <= ftol:
            return x
        if (fx > 0.0) == (f0 > 0.0):
            x0, f0 = x, fx
            if side == -1:
                f1 *= 0.5
            side = -1
        else:
            x1, f1 = x, fx
            if side == 1:
                f0 *= 0.5
            side = 1
    return x0 if abs(f0) < abs(f1) else x1


def _golden_min(fun, a, b, sgn, n=GOLDEN_ITER):
    """Minimise ``sgn*fun`` on ``[a, b]`` (golden section); ``(x, f(x))``."""
    g = 0.5 * (math.sqrt(5.0) - 1.0)
    c = b - g * (b - a)
    d = a + g * (b - a)
    fc, fd = fun(c), fun(d)
    if fc is None or fd is None:
        return None
    for _ in range(n):
        if sgn * fc < sgn * fd:
            b, d, fd = d, c, fc
            c = b - g * (b - a)
            fc = fun(c)
        else:
            a, c, fc = c, d, fd
            d = a + g * (b - a)
            fd = fun(d)
        if fc is None or fd is None:
            return None
    return (c, fc) if sgn * fc < sgn * fd else (d, fd)


def _promising(x0, f0, x1, f1, x2, f2):
    """Does the parabola through three samples dip near or past zero?"""
    d1 = (f1 - f0) / (x1 - x0) if x1 != x0 else 0.0
    d2 = (f2 - f1) / (x2 - x1) if x2 != x1 else 0.0
    c = (d2 - d1) / (x2 - x0) if x2 != x0 else 0.0
    if c == 0.0:
        return False
    b = d1 - c * (x0 + x1)
    xv = -b / (2.0 * c)

    # vertex value of p(x) = f0 + d1 (x - x0) + c (x - x0)(x - x1)
    fv = f0 + d1 * (xv - x0) + c * (xv - x0) * (xv - x1)
    return (fv > 0.0) != (f1 > 0.0) or abs(fv) < PROMISING_FRACTION * abs(f1)


def scan_roots(fun, grid, edge_steps=None):
    """All roots of ``fun`` on the sorted ``grid``: sign changes between grid
    points, plus pairs of roots hidden next to a local extremum of ``|fun|``
    (found by golden-section search), each refined by :func:`_root`."""
    raw = [(x, fun(x)) for x in grid]
    # where the family stops existing (None), add its last valid point: a
    # root often sits right at the edge of the feasible parameter set
    vals = []
    for i, (x, fx) in enumerate(raw):
        if i > 0:
            xp, fp = raw[i - 1]
            if (fp is None) != (fx is None):
                good, bad = (xp, x) if fx is None else (x, xp)
                fgood = fp if fx is None else fx
                for _ in range(EDGE_BISECT if edge_steps is None else edge_steps):
                    mid = 0.5 * (good + bad)
                    fm = fun(mid)
                    if fm is None:
                        bad = mid
                    else:
                        good, fgood = mid, fm
                vals.append((good, fgood))
        vals.append((x, fx))
    # (the grid is sorted and every edge point lies between its neighbours,
    # so ``vals`` is sorted by x)
    roots = []
    n = len(vals)
    for i in range(n):
        x, fx = vals[i]
        if fx is None:
            continue
        if fx == 0.0:
            roots.append(x)
        if i > 0:
            xp, fp = vals[i - 1]
            if fp is not None and fp != 0.0 and fx != 0.0 and (fp > 0.0) != (fx > 0.0):
                r = _root(fun, xp, fp, x, fx)
                if r is not None:
                    roots.append(r)
        if 0 < i < n - 1:
            xp, fp = vals[i - 1]
            xn, fn = vals[i + 1]
            if fp is None or fn is None or fx == 0.0:
                continue
            sgn = 1.0 if fx > 0.0 else -1.0
            if sgn * fp > sgn * fx <= sgn * fn and sgn * fp > 0.0 and sgn * fn > 0.0:
                if not _promising(xp, fp, x, fx, xn, fn):
                    continue
                m = _golden_min(fun, xp, xn, sgn)
                if m is not None and sgn * m[1] < 0.0:
                    xm, fm = m
                    for xa, fa in ((xp, fp), (xn, fn)):
                        r = _root(fun, xa, fa, xm, fm)
                        if r is not None:
                            roots.append(r)
    return roots


# Scans of the fused families. ``kind``: 0 = F1 (:func:`f1_residual`),
# 1 / 2 = F2 with the bump / the ramp first (:func:`f2_residual`), 3 = the
# fixed-duration F1 with a cruise (:func:`fixed_residual`). ``P`` is the
# tuple ``(T, p0, v0, a0, pf, vf, af, A1, J1, A2, J2)``. The three functions
# below are :func:`scan_roots`, :func:`_root` and :func:`_golden_min` for
# these residuals, written as scalar code so that :mod:`._state_jit` can
# compile them (same operations in the same order as the generic ones).
def _fam(kind, x, P):
    T, p0, v0, a0, pf, vf, af, A1, J1, A2, J2 = P
    if kind == 0:
        return f1_residual(x, p0, v0, a0, pf, vf, af, A1, J1, A2, J2)
    if kind == 1:
        return f2_residual(x, p0, v0, a0, pf, vf, af, A1, J1, A2, J2, False)
    if kind == 2:
        return f2_residual(x, p0, v0, a0, pf, vf, af, A1, J1, A2, J2, True)
    if kind == 3:
        return fixed_residual(x, T, p0, v0, a0, pf, vf, af, A1, J1, A2, J2)
    return f2_hold_residual(x, T, p0, v0, a0, pf, vf, af, A1, J1, A2, J2, kind == 5)


def _fam_time(kind, x, P):
    """``total_time`` of the phases of F1 (kind 0) or F2 (kinds 1, 2) at
    ``x``, summed in phase order as :func:`total_time` does: ``(ok, t)``."""
    _, _, v0, a0, _, vf, af, A1, J1, A2, J2 = P
    if kind == 0:
        ok1, s1, ap1, tp1, Ja1, Jb1 = _bump_plan(v0, a0, x, 0.0, A1, J1, A2, J2)
        ok2, s2, ap2, tp2, Ja2, Jb2 = _bump_plan(x, 0.0, vf, af, A1, J1, A2, J2)
        if not ok1 or not ok2:
            return False, 0.0
        t = _bump_int_t(0.0, 0.0, 0.0, s1, s1 * a0, ap1, s1 * 0.0, tp1, Ja1, Jb1)[2]
        return True, _bump_int_t(0.0, 0.0, t, s2, s2 * 0.0, ap2, s2 * af, tp2, Ja2, Jb2)[2]
    if kind == 1:
        s, Ja, Jb, dv = _ramp_signed_plan(x, af, vf, J1, J2)
        ok, sb, ap, tp, Jc, Jd = _bump_plan(v0, a0, vf - dv, x, A1, J1, A2, J2)
        if not ok:
            return False, 0.0
        t = _bump_int_t(0.0, 0.0, 0.0, sb, sb * a0, ap, sb * x, tp, Jc, Jd)[2]
        return True, _ramp_int(0.0, 0.0, t, s * x, s * af, Ja, Jb, s)[2]
    s, Ja, Jb, dv = _ramp_signed_plan(a0, x, v0, J1, J2)
    ok, sb, ap, tp, Jc, Jd = _bump_plan(v0 + dv, x, vf, af, A1, J1, A2, J2)
    if not ok:
        return False, 0.0
    t = _ramp_int(0.0, 0.0, 0.0, s * a0, s * x, Ja, Jb, s)[2]
    return True, _bump_int_t(0.0, 0.0, t, sb, sb * x, ap, sb * af, tp, Jc, Jd)[2]


def _f1_cruise_time(vc, tc, P):
    """``total_time(f1_profile(vc, cruise=tc))`` (phase order): ``(ok, t)``."""
    _, _, v0, a0, _, vf, af, A1, J1, A2, J2 = P
    ok1, s1, ap1, tp1, Ja1, Jb1 = _bump_plan(v0, a0, vc, 0.0, A1, J1, A2, J2)
    ok2, s2, ap2, tp2, Ja2, Jb2 = _bump_plan(vc, 0.0, vf, af, A1, J1, A2, J2)
    if not ok1 or not ok2:
        return False, 0.0
    t = _bump_int_t(0.0, 0.0, 0.0, s1, s1 * a0, ap1, s1 * 0.0, tp1, Ja1, Jb1)[2]
    if tc > 0.0:
        t = t + tc
    return True, _bump_int_t(0.0, 0.0, t, s2, s2 * 0.0, ap2, s2 * af, tp2, Ja2, Jb2)[2]


def _fam_root(kind, P, x0, f0, x1, f1):
    """:func:`_root` (``ftol = 0``) on a fused family: ``(found, x)``."""
    if f0 == 0.0:
        return True, x0
    if f1 == 0.0:
        return True, x1
    side = 0
    for _ in range(SCAN_MAX_ITER):
        if abs(x1 - x0) <= SCAN_XRTOL * max(abs(x0), abs(x1)) + TINY:
            break
        x = (x0 * f1 - x1 * f0) / (f1 - f0)
        if not (min(x0, x1) < x < max(x0, x1)):
            x = 0.5 * (x0 + x1)
        ok, fx = _fam(kind, x, P)
        if not ok:
            x = 0.5 * (x0 + x1)
            ok, fx = _fam(kind, x, P)
            if not ok:
                return False, 0.0
        if abs(fx) <= 0.0:
            return True, x
        if (fx > 0.0) == (f0 > 0.0):
            x0, f0 = x, fx
            if side == -1:
                f1 *= 0.5
            side = -1
        else:
            x1, f1 = x, fx
            if side == 1:
                f0 *= 0.5
            side = 1
    return True, (x0 if abs(f0) < abs(f1) else x1)


def _fam_golden(kind, P, a, b, sgn):
    """:func:`_golden_min` on a fused family: ``(found, x, f(x))``."""
    g = 0.5 * (math.sqrt(5.0) - 1.0)
    c = b - g * (b - a)
    d = a + g * (b - a)
    okc, fc = _fam(kind, c, P)
    okd, fd = _fam(kind, d, P)
    if not okc or not okd:
        return False, 0.0, 0.0
    for _ in range(GOLDEN_ITER):
        if sgn * fc < sgn * fd:
            b, d, fd = d, c, fc
            c = b - g * (b - a)
            okc, fc = _fam(kind, c, P)
        else:
            a, c, fc = c, d, fd
            d = a + g * (b - a)
            okd, fd = _fam(kind, d, P)
        if not okc or not okd:
            return False, 0.0, 0.0
    if sgn * fc < sgn * fd:
        return True, c, fc
    return True, d, fd


def scan_family(kind, grid, P, edge_steps, near):
    """:func:`scan_roots` of a fused family over the sorted ``grid``.

    Returns the list of roots (in the order :func:`scan_roots` finds them).
    With ``near``, also the points where a root may touch zero without a
    sign change (a double root, or one at the edge of the family): every
    edge point found by bisection and every extremum found by the
    golden-section search that does not cross zero, after the roots (the
    caller verifies each).
    """
    n0 = len(grid)
    rok = [False] * n0
    rf = [0.0] * n0
    for i in range(n0):
        rok[i], rf[i] = _fam(kind, grid[i], P)
    vx = [0.0] * (2 * n0)
    vf = [0.0] * (2 * n0)
    vok = [False] * (2 * n0)
    vedge = [False] * (2 * n0)
    m = 0
    for i in range(n0):
        x = grid[i]
        okx = rok[i]
        fx = rf[i]
        if i > 0:
            okp = rok[i - 1]
            if okp != okx:
                if okx:
                    good, bad, fgood = x, grid[i - 1], fx
                else:
                    good, bad, fgood = grid[i - 1], x, rf[i - 1]
                for _ in range(edge_steps):
                    mid = 0.5 * (good + bad)
                    okm, fm = _fam(kind, mid, P)
                    if not okm:
                        bad = mid
                    else:
                        good, fgood = mid, fm
                vx[m], vf[m], vok[m] = good, fgood, True
                vedge[m] = True
                m += 1
        vx[m], vf[m], vok[m] = x, fx, okx
        m += 1
    roots = [0.0] * (6 * m)
    nr = 0
    extra = [0.0] * (3 * m)
    ne = 0
    if near:
        for i in range(m):
            if vedge[i]:
                extra[ne] = vx[i]
                ne += 1
    for i in range(m):
        if not vok[i]:
            continue
        x, fx = vx[i], vf[i]
        if fx == 0.0:
            roots[nr] = x
            nr += 1
        if i > 0:
            xp, fp = vx[i - 1], vf[i - 1]
            if vok[i - 1] and fp != 0.0 and fx != 0.0 and (fp > 0.0) != (fx > 0.0):
                ok, r = _fam_root(kind, P, xp, fp, x, fx)
                if ok:
                    roots[nr] = r
                    nr += 1
        if 0 < i < m - 1:
            xp, fp = vx[i - 1], vf[i - 1]
            xn, fn = vx[i + 1], vf[i + 1]
            if not vok[i - 1] or not vok[i + 1] or fx == 0.0:
                continue
            sgn = 1.0 if fx > 0.0 else -1.0
            if sgn * fp > sgn * fx <= sgn * fn and sgn * fp > 0.0 and sgn * fn > 0.0:
                if not _promising(xp, fp, x, fx, xn, fn):
                    continue
                okm, xm, fm = _fam_golden(kind, P, xp, xn, sgn)
                if okm and sgn * fm < 0.0:
                    ok, r = _fam_root(kind, P, xp, fp, xm, fm)
                    if ok:
                        roots[nr] = r
                        nr += 1
                    ok, r = _fam_root(kind, P, xn, fn, xm, fm)
                    if ok:
                        roots[nr] = r
                        nr += 1
                elif okm and near:
                    extra[ne] = xm
                    ne += 1
        if near and i > 0 and vok[i - 1] and fx != 0.0:
            # a valid run's end whose |f| still falls towards it: the
            # smallest |f| may lie between the last two points (a root
            # pair pressed against the edge of the family)
            last = i == m - 1 or not vok[i + 1]
            first = i - 1 == 0 or not vok[i - 2]
            xp, fp = vx[i - 1], vf[i - 1]
            sgn = 1.0 if fx > 0.0 else -1.0
            if (last or first) and sgn * fp > 0.0 and (
                    (last and sgn * fx < sgn * fp) or (first and sgn * fp < sgn * fx)):
                okm, xm, fm = _fam_golden(kind, P, xp, x, sgn)
                if okm and sgn * fm < 0.0:
                    ok, r = _fam_root(kind, P, xp, fp, xm, fm)
                    if ok:
                        roots[nr] = r
                        nr += 1
                    ok, r = _fam_root(kind, P, x, fx, xm, fm)
                    if ok:
                        roots[nr] = r
                        nr += 1
                elif okm:
                    extra[ne] = xm
                    ne += 1
    out = roots[:nr]
    for i in range(ne):
        out.append(extra[i])
    return out


def _grid(lo, hi, marks, n=SCAN_POINTS):
    """Scan grid on ``[lo, hi]``: uniform points plus clustered marks."""
    w = hi - lo
    pts = [lo, hi]
    pts += [lo + w * k / n for k in range(1, n)]
    for m in marks:
        if lo <= m <= hi:
            pts.append(m)
            for e in MARK_OFFSETS:
                for sgn in (-1.0, 1.0):
                    x = m + sgn * e * w
                    if lo <= x <= hi:
                        pts.append(x)
    # (a set built in this order keeps the same representative of equal
    # values, e.g. 0.0 / -0.0, as adding them one by one did)
    return sorted(set(pts))


def natural_scale(start, goal, L):
    """A velocity and acceleration scale of the problem (for grids)."""
    V, A1, J1, A2, J2 = L
    _, v0, a0 = start
    _, vf, af = goal
    Am = max(A1 if A1 != _inf else 0.0, A2 if A2 != _inf else 0.0, abs(a0), abs(af))
    Jm = min(J1, J2)
    vn0 = v0 + a0 * abs(a0) / (2.0 * Jm) if Jm != _inf else v0
    vnf = vf - af * abs(af) / (2.0 * Jm) if Jm != _inf else vf
    return Am, vn0, vnf


def candidates_min_time(start, goal, L, verified=True):
    """Every candidate profile of the minimum-time problem.

    Returns a list of ``(duration, family, phases)``. With asymmetric
    limits the families are also solved under the tighter symmetric limits
    ``(V, min(A1, A2), min(J1, J2))`` (valid under the real ones); that
    covers motions whose velocity changes sign, where the regime-exact
    families (conservative inside a sign-changing bump) can have gaps.

    With ``verified=False`` the candidates are not checked, and most are not
    even built yet (their phases are a :class:`LazyPhases`): the caller must
    build and :func:`verify` each (against ``L``) before using it; the
    minimum-time planner does that through :class:`VerifiedSeeds`, in order
    of duration, stopping at the first that passes.
    """
    V, A1, J1, A2, J2 = L
    out = _candidates(start, goal, L, L, verified)
    if A1 != A2 or J1 != J2:
        Am, Jm = min(A1, A2), min(J1, J2)
        out += [(t, fam + "-sym", ph) for t, fam, ph in
                _candidates(start, goal, (V, Am, Jm, Am, Jm), L, verified)]
    return out


class LazyPhases:
    """A candidate's phase list, built on first use (``build()``)."""

    __slots__ = ("_build",)

    def __init__(self, build):
        self._build = build

    def build(self):
        return self._build()


class VerifiedSeeds:
    """The verified candidates of an unverified candidate list, lazily.

    Iterating yields, in the list's order, the phases of every candidate
    that passes :func:`verify` (each checked once, on first need); so a
    caller that stops early checks only what it used. :meth:`fastest` is
    the first verified candidate of smallest duration (what
    ``min(verified candidates)`` gives).
    """

    def __init__(self, cands, start, goal, L):
        self._cands = list(cands)
        self._ok = [None] * len(self._cands)
        self._start = start
        self._goal = goal
        self._L = L

    def _check(self, i):
        ok = self._ok[i]
        if ok is None:
            t, fam, ph = self._cands[i]
            if isinstance(ph, LazyPhases):
                ph = ph.build()
                self._cands[i] = (t, fam, ph)
            ok = ph is not None and verify(ph, *self._start, self._L, self._goal) is None
            self._ok[i] = ok
        return ok

    def fastest(self):
        """``(duration, family, phases)`` of the fastest verified candidate, or None."""
        order = sorted(range(len(self._cands)), key=lambda i: self._cands[i][0])
        for i in order:
            if self._check(i):
                return self._cands[i]
        return None

    def __iter__(self):
        for i in range(len(self._cands)):
            if self._check(i):
                yield self._cands[i][2]


def _candidates(start, goal, L, L_check, verified=True):
    V, A1, J1, A2, J2 = L
    p0, v0, a0 = start
    pf, vf, af = goal
    out = []

    def add(ph, fam):
        if ph is None:
            return
        if not verified or verify(ph, p0, v0, a0, L_check, goal) is None:
            out.append((total_time(ph), fam, ph))

    def add_root(kind, x, fam, build):
        # unverified candidates are built only when used (LazyPhases): the
        # fused duration equals total_time(build()) bit for bit
        if verified:
            add(build(), fam)
            return
        ok, t = ftime(kind, x, P)
        if ok:
            out.append((t, fam, LazyPhases(build)))

    Am, vn0, vnf = natural_scale(start, goal, L)
    # ---- F1: velocity extremum vc with a = 0
    if V != _inf:
        lo, hi = -V, V
    else:
        d = abs(pf - p0)
        Jm, Amin = min(J1, J2), min(A1, A2)
        dscale = (d * d * Jm) ** (1.0 / 3.0) if Jm != _inf else _sqrt(d * Amin)
        w = max(abs(v0), abs(vf), abs(vn0), abs(vnf), dscale, TINY)
        lo, hi = -2.0 * w, 2.0 * w

    jk = _jit_kernels()
    f1r = f1_residual if jk is None else jk["f1_residual"]
    ftime = _fam_time if jk is None else jk["_fam_time"]
    fctime = _f1_cruise_time if jk is None else jk["_f1_cruise_time"]
    P = (0.0, p0, v0, a0, pf, vf, af, A1, J1, A2, J2)

    def r1(vc):
        ok, r = f1r(vc, p0, v0, a0, pf, vf, af, A1, J1, A2, J2)
        return r if ok else None

    if V == _inf:
        # widen until the residual brackets the goal on both sides
        for _ in range(200):
            rl, rh = r1(lo), r1(hi)
            if rl is not None and rh is not None and rl < 0.0 < rh:
                break
            lo *= 2.0
            hi *= 2.0
    marks = [v0, vf, vn0, vnf, 0.0]
    for vc in _scan(jk, 0, _grid(lo, hi, marks), P):
        add_root(0, vc, "F1", lambda vc=vc: f1_profile(vc, start, goal, L, jk=jk))
    if V != _inf:
        for vc in (V, -V):
            ok, r = f1r(vc, p0, v0, a0, pf, vf, af, A1, J1, A2, J2)
            if not ok:
                continue
            # r == integrate(f1_profile(vc))[0] - pf, so -r is the distance
            # left for the cruise (IEEE subtraction is antisymmetric)
            rem = -r
            tc = rem / vc
            if tc >= 0.0:
                build = lambda vc=vc, tc=tc: f1_profile(vc, start, goal, L, cruise=tc, jk=jk)
                if verified:
                    add(build(), "F1-cruise")
                else:
                    okt, t = fctime(vc, tc, P)
                    if okt:
                        out.append((t, "F1-cruise", LazyPhases(build)))
    # ---- F2: bump + ramp joined at an acceleration extremum am
    if Am > 0.0:
        Acap = max(A1 if A1 != _inf else Am, A2 if A2 != _inf else Am)
        if V != _inf:
            # |a| cannot exceed sqrt(4 J V) without |v| passing v_max
            Acap = min(Acap, ACC_CAP_FACTOR * _sqrt(4.0 * max(J1, J2) * V))
        Acap = max(Acap, abs(a0), abs(af))
        A_lo, A_hi = -Acap, Acap
        amarks = [a0, af, 0.0]
        agrid = _grid(A_lo, A_hi, amarks)
        for first in (False, True):
            kind = 2 if first else 1
            for am in _scan(jk, kind, agrid, P):
                add_root(kind, am, "F2",
                         lambda am=am, first=first: f2_profile(am, start, goal, L, first, jk))
    return out


def insert_cruise(phases, v0, dT):
    """Insert a cruise of ``dT`` s at the fastest and the slowest ``a = 0`` point.

    Returns up to two phase lists (the acceleration is zero there, so the
    inserted constant-velocity phase keeps every limit; the end state's
    velocity and acceleration are unchanged, the position moves by
    ``v_e * dT``).
    """
    pts = []  # (velocity, phase index, split time)
    v = v0
    n = len(phases)
    for k, (dt, j, a) in enumerate(phases):
        if a == 0.0:
            pts.append((v, k, 0.0))
        if j != 0.0 and a != 0.0:
            tz = -a / j
            if 0.0 < tz < dt:
                pts.append((v + tz * (a + 0.5 * tz * j), k, tz))
        v = v + dt * (a + 0.5 * dt * j)
    if n and phases[-1][2] + phases[-1][0] * phases[-1][1] == 0.0 or n == 0:
        pts.append((v, n, 0.0))
    if not pts:
        return []
    out = []
    for _v_e, k, tz in {min(pts), max(pts)}:
        ph = list(phases[:k])
        if k < n and tz > 0.0:
            dt, j, a = phases[k]
            ph.append((tz, j, a))
            ph.append((dT, 0.0, 0.0))
            ph.append((dt - tz, j, 0.0))
            ph += phases[k + 1:]
        else:
            ph.append((dT, 0.0, 0.0))
            ph += phases[k:]
        out.append(ph)
    return out


def fixed_time_profile(start, goal, L, T, seeds=(), hold=True):
    """A verified profile of exactly ``T`` s, or ``None``.

    Candidates of exactly ``T`` s:

    * F1 with a cruise at ``vc`` filling the time the two bumps leave
      (scanned over the velocity window reachable within ``T``; a sign change
      of the position error between two scan points is refined to a root);
    * every profile in ``seeds`` (faster solutions, e.g. the minimum-time
      candidates) with a cruise inserted at its fastest or slowest
      zero-acceleration point;
    * with ``hold=True``, last, F2 with a hold at the junction acceleration
      (a nested root; slow, so the blocked-interval search leaves it out).

    When no root is exact, the two candidates closest to the goal position
    from below and above are blended: their convex combination has the same
    duration and boundary velocity/acceleration, the position in between,
    and keeps every convex (symmetric) limit; it is kept if it verifies.
    """
    V, A1, J1, A2, J2 = L
    p0, v0, a0 = start
    pf, vf, af = goal
    Am, vn0, vnf = natural_scale(start, goal, L)

    def prof(vc):
        b1 = bump(v0, a0, vc, 0.0, L, jk)
        if b1 is None:
            return None
        b2 = bump(vc, 0.0, vf, af, L, jk)
        if b2 is None:
            return None
        tc = T - total_time(b1) - total_time(b2)
        if tc < -ROUND_RTOL * T:
            return None
        return b1 + [(max(tc, 0.0), 0.0, 0.0)] + b2

    jk = _jit_kernels()
    fxr = fixed_residual if jk is None else jk["fixed_residual"]

    P = (T, p0, v0, a0, pf, vf, af, A1, J1, A2, J2)

    # within T the velocity cannot move further than min(A T, J T^2 / 4)
    # from the boundary velocities: scan only that window (inside +-V)
    Amax = max(A1, A2, abs(a0), abs(af))
    Jmax = max(J1, J2)
    reach = min(Amax * T, Jmax * T * T / 4.0) * WINDOW_MARGIN
    marks = [v0, vf, vn0, vnf]
    lo, hi = min(marks) - reach, max(marks) + reach
    if V != _inf:
        lo, hi = max(lo, -V), min(hi, V)
    if not (lo < hi) or not math.isfinite(lo) or not math.isfinite(hi):
        w = max(abs(v0), abs(vf), abs(vn0), abs(vnf), abs(pf - p0) / max(T, TINY), TINY)
        lo, hi = (-V, V) if V != _inf else (-4.0 * w, 4.0 * w)
    grid = _grid(lo, hi, marks + [0.0], n=2 * SCAN_POINTS)
    for vc in _scan(jk, 3, grid, P):
        ph = prof(vc)
        if ph is not None and verify(ph, p0, v0, a0, L, goal) is None:
            return ph
    # pool of (position error, phases or None, grid point): the grid
    # profiles are built only when used (their error is fixed_residual's,
    # equal to integrate(prof(x))[0] - pf bit for bit)
    pool = []
    for x in grid:
        ok, e = fxr(x, T, p0, v0, a0, pf, vf, af, A1, J1, A2, J2)
        if ok:
            pool.append((e, None, x))
    for sp in seeds:
        dT = T - total_time(sp)
        if dT < 0.0:
            continue
        for ph in insert_cruise(sp, v0, dT):
            pool.append((integrate(ph, p0, v0, a0)[0] - pf, ph, 0.0))

    def pool_phases(i):
        _, ph, x = pool[i]
        return prof(x) if ph is None else ph

    for i, (e, _, _) in enumerate(pool):
        if e == 0.0:
            ph = pool_phases(i)
            if verify(ph, p0, v0, a0, L, goal) is None:
                return ph
    below = [(e, i) for i, (e, _, _) in enumerate(pool) if e < 0.0]
    above = [(e, i) for i, (e, _, _) in enumerate(pool) if e > 0.0]
    if below and above:
        # try the closest pairs first
        below.sort(reverse=True)
        above.sort()
        for eb, ib in below[:BLEND_TRIES]:
            for ea, ia in above[:BLEND_TRIES]:
                ph = blend(pool_phases(ib), pool_phases(ia), ea / (ea - eb))
                if verify(ph, p0, v0, a0, L, goal) is None:
                    return ph
    return _f2_hold_fixed(start, goal, L, T) if hold else None


def f2_hold_profile(am, start, goal, L, T, first_is_ramp, jk=False):
    """F2 with a hold at the junction acceleration ``am`` lasting exactly ``T``.

    ``first_is_ramp=False``: bump to ``(vm, am)``, hold ``th``, ramp to
    ``af``; ``True``: ramp ``a0 -> am``, hold, bump to the goal. The hold
    length solves the duration equation (bracketed root in ``th``).
    """
    if jk is False:
        jk = _jit_kernels()
    _, v0, a0 = start
    _, vf, af = goal
    if first_is_ramp:
        r, dv = _ramp_signed(a0, am, v0, L)
    else:
        r, dv = _ramp_signed(am, af, vf, L)
    tr = total_time(r)

    def build(th):
        if first_is_ramp:
            vm = v0 + dv + am * th
            b = bump(vm, am, vf, af, L, jk)
            if b is None:
                return None
            return r + ([(th, 0.0, am)] if th > 0.0 else []) + b
        vm = vf - dv - am * th
        b = bump(v0, a0, vm, am, L, jk)
        if b is None:
            return None
        return b + ([(th, 0.0, am)] if th > 0.0 else []) + r

    def excess(th):
        ph = build(th)
        if ph is None:
            return None
        return total_time(ph) - T

    span = T - tr
    if span <= 0.0:
        return None
    e0 = excess(0.0)
    e1 = excess(span)
    if e0 is None or e1 is None or e0 > 0.0 or e1 < 0.0:
        return None
    th = _root(excess, 0.0, e0, span, e1, ftol=HOLD_TIME_RTOL * T, max_iter=HOLD_MAX_ITER)
    if th is None:
        return None
    ph = build(th)
    if ph is None:
        return None
    # absorb the root's round-off in the hold so the duration is exact; a
    # bracket that closed on a jump of the duration (the bump changes
    # branch there) is no root: no member
    tt = total_time(ph)
    if abs(tt - T) > HOLD_ACCEPT_RTOL * T:
        return None
    if th > 0.0 and abs(tt - T) > 0.0:
        k = (len(ph) - len(r) - 1) if not first_is_ramp else len(r)
        dt, j, a = ph[k]
        if j == 0.0 and a == am:
            ph[k] = (max(dt + (T - tt), 0.0), 0.0, a)
    return ph


def _f2_hold_fixed(start, goal, L, T):
    """Fixed-duration fallback over the F2-with-hold family (slow, rare)."""
    V, A1, J1, A2, J2 = L
    p0, v0, a0 = start
    pf, vf, af = goal
    Am, _, _ = natural_scale(start, goal, L)
    if Am <= 0.0:
        return None
    Acap = max(A1 if A1 != _inf else Am, A2 if A2 != _inf else Am)
    if V != _inf:
        Acap = min(Acap, ACC_CAP_FACTOR * _sqrt(4.0 * max(J1, J2) * V))
    Acap = max(Acap, abs(a0), abs(af))
    jk = _jit_kernels()
    P = (T, p0, v0, a0, pf, vf, af, A1, J1, A2, J2)
    # the family often exists only in a narrow window of am between the
    # boundary accelerations: refine the grid between the marks too
    marks = sorted(x for x in (-Acap, a0, af, 0.0, Acap) if -Acap <= x <= Acap)
    extra = [marks[i] + (marks[i + 1] - marks[i]) * k / HOLD_GAP_POINTS
             for i in range(len(marks) - 1) for k in range(1, HOLD_GAP_POINTS)]
    grid = _grid(-Acap, Acap, [a0, af, 0.0] + extra, n=HOLD_SCAN_POINTS)
    for first in (False, True):
        for am in _scan(jk, 5 if first else 4, grid, P, HOLD_EDGE_BISECT, True):
            ph = f2_hold_profile(am, start, goal, L, T, first, jk)
            if ph is not None and verify(ph, p0, v0, a0, L, goal) is None:
                return ph
    return _ramp_hold_ramp_fixed(start, goal, L, T, grid)


def _ramp_hold_ramp(am, start, goal, L, T):
    """Ramp ``a0 -> am``, hold at ``am``, ramp ``am -> af``, lasting ``T``.

    Returns ``(phases, velocity error at the end)`` or ``None`` when the
    ramps alone last longer than ``T``.
    """
    _, v0, a0 = start
    _, vf, af = goal
    r1 = _ramp_signed(a0, am, v0, L)[0]
    r2 = _ramp_signed(am, af, vf, L)[0]
    th = T - total_time(r1) - total_time(r2)
    if th < 0.0:
        return None
    ph = r1 + [(th, 0.0, am)] + r2
    return ph, integrate_va(ph, v0, a0)[0] - vf


def _ramp_hold_ramp_fixed(start, goal, L, T, grid):
    """Last fixed-duration family: two ramps around a hold (rare, slow).

    The common limit of both F2-with-hold variants when their bump shrinks
    to a single ramp: there the F2 position error behaves like a square
    root of the distance to the family's edge and cannot be driven to zero
    by bisection. Here the hold acceleration ``am`` solves the velocity
    equation (the hold fills the duration); the position must then match,
    which the verification decides (it does e.g. for a reversal between
    mirrored states, where the symmetry fixes the position).
    """
    p0, v0, a0 = start

    def r(am):
        out = _ramp_hold_ramp(am, start, goal, L, T)
        return None if out is None else out[1]

    for am in scan_roots(r, grid, edge_steps=HOLD_EDGE_BISECT):
        out = _ramp_hold_ramp(am, start, goal, L, T)
        if out is not None and verify(out[0], p0, v0, a0, L, goal) is None:
            return out[0]
    return None


def blend(pa, pb, lam):
    """Exact convex combination ``lam*pa + (1-lam)*pb`` of two phase lists.

    Both must last the same time and start from the same state; the jerk
    (and acceleration offsets) combine linearly on the merged breakpoints.
    """
    ta = [0.0]
    for dt, _, _ in pa:
        ta.append(ta[-1] + dt)
    tb = [0.0]
    for dt, _, _ in pb:
        tb.append(tb[-1] + dt)
    T = min(ta[-1], tb[-1])
    cuts = sorted(set([t for t in ta + tb if t < T] + [T]))
    out = []

    def state_at(ph, tt, t):
        # phase index and local acceleration/jerk at time t (right-continuous)
        for k in range(len(ph)):
            if tt[k] <= t < tt[k + 1] or (k == len(ph) - 1):
                dt = t - tt[k]
                return ph[k][2] + dt * ph[k][1], ph[k][1]
        return 0.0, 0.0

    for k in range(len(cuts) - 1):
        t0, t1 = cuts[k], cuts[k + 1]
        if t1 <= t0:
            continue
        aa, ja = state_at(pa, ta, t0)
        ab, jb = state_at(pb, tb, t0)
        out.append((t1 - t0, lam * ja + (1.0 - lam) * jb, lam * aa + (1.0 - lam) * ab))
    return out
