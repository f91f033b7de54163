"""Scalar kernels for profiles between arbitrary states (one axis).

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
"""

from __future__ import annotations

import math
import sys

from .._constants import GOAL_RTOL, LIMIT_RTOL

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
HOLD_SCAN_POINTS = 10

#: The hold length is solved to this fraction of the duration (the hold then
#: absorbs the remainder exactly), in at most ``HOLD_MAX_ITER`` steps.
HOLD_TIME_RTOL = 1e-13
HOLD_MAX_ITER = 60

#: Edge bisection steps in the F2-with-hold scan.
HOLD_EDGE_BISECT = 20

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


def _bump_frame(dv, a0, a1, A1, J1, A2, J2):
    """Fastest bump in the positive-velocity frame; list of phases or None.

    Four branches of the peak ``ap``, each with ``dv(ap) = k ap^2 + c``:

    1. up-bump, ``ap in [max(a0, a1, 0), A1]``, ``k = +1/J1``, plateau at A1;
    2. up-bump, ``ap in [max(a0, a1), 0]`` (both ends negative), ``k = +1/J2``;
    3. down-bump, ``ap in [-A2, min(a0, a1, 0)]``, ``k = -1/J2``, plateau at -A2;
    4. down-bump, ``ap in [0, min(a0, a1)]`` (both ends positive), ``k = -1/J1``.

    ``dv`` is monotone in ``|ap|`` on every branch, so each has at most one
    solution; the fastest wins.
    """
    best_ap = None
    best_tp = 0.0
    best_t = _inf
    hi = max(a1, a0)
    lo = min(a0, a1)
    rdd = ramp_dv_dt
    for b in range(4):
        if b == 0:
            if hi > A1 * (1.0 + SNAP_RTOL):
                continue
            inner, outer, J, ksign, side, plat = (min(hi, A1) if hi > 0.0 else 0.0), A1, J1, 1.0, 1.0, A1
        elif b == 1:
            if hi >= 0.0:
                continue
            inner, outer, J, ksign, side, plat = 0.0, hi, J2, 1.0, -1.0, None
        elif b == 2:
            if lo < -A2 * (1.0 + SNAP_RTOL):
                continue
            inner, outer, J, ksign, side, plat = (max(lo, -A2) if lo < 0.0 else 0.0), -A2, J2, -1.0, -1.0, -A2
        else:
            if lo <= 0.0:
                continue
            inner, outer, J, ksign, side, plat = 0.0, lo, J1, -1.0, 1.0, None
        if abs(outer) < abs(inner):
            continue
        ap = None
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
        if ap is None and plat is not None and plat != _inf and plat != -_inf:
            d1, t1 = rdd(a0, plat, J1, J2)
            d2, t2 = rdd(plat, a1, J1, J2)
            tp = (dv - d1 - d2) / plat
            if tp >= 0.0:
                ap = plat
            else:
                tp = 0.0
        if ap is None:
            continue
        t = rdd(a0, ap, J1, J2)[1] + tp + rdd(ap, a1, J1, J2)[1]
        if t < best_t:
            best_ap, best_tp, best_t = ap, tp, t
    if best_ap is None:
        return None
    return _bump_phases(a0, best_ap, a1, best_tp, J1, J2)


def bump(v0, a0, v1, a1, L):
    """Fastest phases from ``(v0, a0)`` to ``(v1, a1)`` (position free).

    The regime frame is the sign of the velocity; a bump whose velocity
    changes sign uses the tighter of both legs' limits (conservative).
    Returns a phase list or ``None``.
    """
    V, A1, J1, A2, J2 = L
    s = 1.0 if (v0 + v1) > 0.0 or (v0 + v1 == 0.0 and (a0 + a1) >= 0.0) else -1.0
    if (v0 >= 0.0 and v1 >= 0.0) or (v0 <= 0.0 and v1 <= 0.0):
        ph = _bump_frame(s * (v1 - v0), s * a0, s * a1, A1, J1, A2, J2)
        if ph is not None and _same_sign(ph, s * v0, s):
            return ph if s > 0 else negate(ph)
    Am, Jm = min(A1, A2), min(J1, J2)
    ph = _bump_frame(s * (v1 - v0), s * a0, s * a1, Am, Jm, Am, Jm)
    if ph is None:
        return None
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


# ------------------------------------------------------------- verification
def verify(phases, p0, v0, a0, L, goal, rtol=LIMIT_RTOL, check_goal=True):
    """Exact check of limits and goal; returns ``None`` or a reason string.

    Limits are checked at every phase boundary and at every in-phase
    extremum or regime change: the velocity at ``a = 0``, the acceleration
    and jerk on both sides of every ``v = 0`` crossing (the speeding-up /
    slowing-down regime decides which limits apply).
    """
    V, A1, J1, A2, J2 = L
    p, v, a = p0, v0, a0
    vscale = max(abs(v0), abs(goal[1]), TINY)
    ascale = max(abs(a0), abs(goal[2]), TINY)
    vtol = V * rtol if V != _inf else 0.0
    vref = vscale
    for dt, j, a_s in phases:
        vref = max(vref, abs(a_s) * dt, abs(j) * dt * dt)
    for dt, j, a_s in phases:
        a = a_s
        if dt < 0.0 or not math.isfinite(dt):
            return f"negative or non-finite phase duration {dt!r}"
        # split points: a = 0 and v = 0 inside the phase
        ts = [0.0, dt]
        if j != 0.0:
            tz = -a / j
            if 0.0 < tz < dt:
                ts.append(tz)
        # v(t) = v + a t + j t^2/2 = 0
        for tr in _quad_roots(0.5 * j, a, v):
            if 0.0 < tr < dt:
                ts.append(tr)
        ts.sort()
        for k in range(len(ts)):
            t = ts[k]
            vt = v + t * (a + 0.5 * t * j)
            if V != _inf and abs(vt) > V + vtol:
                return f"velocity {vt!r} exceeds v_max {V!r}"
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
            for t in (t0, t1):
                at = a + t * j
                if abs(at) > A * (1.0 + rtol) + VERIFY_ATOL_SCALE * ascale:
                    return f"acceleration {at!r} exceeds {'a_max' if speeding else 'a_max_decel'} {A!r}"
            if am != 0.0 and abs(j) > J * (1.0 + rtol):
                return f"jerk {j!r} exceeds {'j_max' if speeding else 'j_max_decel'} {J!r}"
            if am == 0.0 and j != 0.0 and abs(j) > max(J1, J2) * (1.0 + rtol):
                return f"jerk {j!r} exceeds the jerk limits"
        p = p + dt * (v + dt * (0.5 * a + dt * j / 6.0))
        v = v + dt * (a + 0.5 * dt * j)
        a = a + dt * j
        vscale = max(vscale, abs(v))
        ascale = max(ascale, abs(a))
    if check_goal:
        pg, vg, ag = goal
        T = total_time(phases)
        pscale = max(abs(pg - p0), vscale * T, ascale * T * T, TINY)
        floor = FLOAT_ULPS * _eps * max(abs(p0), abs(pg))
        if abs(p - pg) > GOAL_RTOL * pscale + floor:
            return f"goal position missed by {p - pg!r}"
        if abs(v - vg) > GOAL_RTOL * vscale:
            return f"goal velocity missed by {v - vg!r}"
        if abs(a - ag) > GOAL_RTOL * max(ascale, A1 if A1 != _inf else 0.0):
            return f"goal acceleration missed by {a - ag!r}"
    return None


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
def f1_profile(vc, start, goal, L, cruise=0.0):
    """F1: bump to ``(vc, 0)``, cruise ``cruise`` s, bump to the goal state."""
    _, v0, a0 = start
    _, vf, af = goal
    b1 = bump(v0, a0, vc, 0.0, L)
    if b1 is None:
        return None
    b2 = bump(vc, 0.0, vf, af, L)
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


def f2_profile(am, start, goal, L, first_is_ramp):
    """F2: a bump and a single ramp joined at acceleration ``am``.

    ``first_is_ramp=False``: bump ``(v0, a0) -> (vm, am)`` then the ramp
    ``am -> af``; ``True``: ramp ``a0 -> am`` then a bump to the goal.
    """
    _, v0, a0 = start
    _, vf, af = goal
    if not first_is_ramp:
        r, dv = _ramp_signed(am, af, vf, L)
        vm = vf - dv
        b = bump(v0, a0, vm, am, L)
        if b is None:
            return None
        return b + r
    r, dv = _ramp_signed(a0, am, v0, L)
    vm = v0 + dv
    b = bump(vm, am, vf, af, L)
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
    """All roots of ``fun`` on ``grid``: sign changes between grid points,
    plus pairs of roots hidden next to a local extremum of ``|fun|`` (found
    by golden-section search), each refined by :func:`_root`."""
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
    vals.sort(key=lambda t: t[0])
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


def _grid(lo, hi, marks, n=SCAN_POINTS):
    """Scan grid on ``[lo, hi]``: uniform points plus clustered marks."""
    pts = {lo, hi}
    w = hi - lo
    for k in range(1, n):
        pts.add(lo + w * k / n)
    for m in marks:
        if lo <= m <= hi:
            pts.add(m)
            for e in MARK_OFFSETS:
                for sgn in (-1.0, 1.0):
                    x = m + sgn * e * w
                    if lo <= x <= hi:
                        pts.add(x)
    return sorted(pts)


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


def candidates_min_time(start, goal, L):
    """Every verified candidate profile of the minimum-time problem.

    Returns a list of ``(duration, family, phases)``. With asymmetric
    limits the families are also solved under the tighter symmetric limits
    ``(V, min(A1, A2), min(J1, J2))`` (valid under the real ones); that
    covers motions whose velocity changes sign, where the regime-exact
    families (conservative inside a sign-changing bump) can have gaps.
    """
    V, A1, J1, A2, J2 = L
    out = _candidates(start, goal, L, L)
    if A1 != A2 or J1 != J2:
        Am, Jm = min(A1, A2), min(J1, J2)
        out += [(t, fam + "-sym", ph) for t, fam, ph in
                _candidates(start, goal, (V, Am, Jm, Am, Jm), L)]
    return out


def _candidates(start, goal, L, L_check):
    V, A1, J1, A2, J2 = L
    p0, v0, a0 = start
    pf, vf, af = goal
    out = []

    def add(ph, fam):
        if ph is None:
            return
        if verify(ph, p0, v0, a0, L_check, goal) is None:
            out.append((total_time(ph), fam, ph))

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

    def r1(vc):
        ph = f1_profile(vc, start, goal, L)
        if ph is None:
            return None
        return integrate(ph, p0, v0, a0)[0] - pf

    if V == _inf:
        # widen until the residual brackets the goal on both sides
        for _ in range(200):
            rl, rh = r1(lo), r1(hi)
            if rl is not None and rh is not None and rl < 0.0 < rh:
                break
            lo *= 2.0
            hi *= 2.0
    marks = [v0, vf, vn0, vnf, 0.0]
    for vc in scan_roots(r1, _grid(lo, hi, marks)):
        add(f1_profile(vc, start, goal, L), "F1")
    if V != _inf:
        for vc in (V, -V):
            ph = f1_profile(vc, start, goal, L)
            if ph is None:
                continue
            rem = pf - integrate(ph, p0, v0, a0)[0]
            tc = rem / vc
            if tc >= 0.0:
                add(f1_profile(vc, start, goal, L, cruise=tc), "F1-cruise")
    # ---- F2: bump + ramp joined at an acceleration extremum am
    if Am > 0.0:
        Acap = max(A1 if A1 != _inf else Am, A2 if A2 != _inf else Am)
        if V != _inf:
            # |a| cannot exceed sqrt(4 J V) without |v| passing v_max
            Acap = min(Acap, ACC_CAP_FACTOR * _sqrt(4.0 * max(J1, J2) * V))
        Acap = max(Acap, abs(a0), abs(af))
        A_lo, A_hi = -Acap, Acap
        amarks = [a0, af, 0.0]
        for first in (False, True):
            def r2(am, first=first):
                ph = f2_profile(am, start, goal, L, first)
                if ph is None:
                    return None
                return integrate(ph, p0, v0, a0)[0] - pf
            for am in scan_roots(r2, _grid(A_lo, A_hi, amarks)):
                add(f2_profile(am, start, goal, L, first), "F2")
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
    for v_e, k, tz in {min(pts), max(pts)}:
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
        b1 = bump(v0, a0, vc, 0.0, L)
        if b1 is None:
            return None
        b2 = bump(vc, 0.0, vf, af, L)
        if b2 is None:
            return None
        tc = T - total_time(b1) - total_time(b2)
        if tc < -ROUND_RTOL * T:
            return None
        return b1 + [(max(tc, 0.0), 0.0, 0.0)] + b2

    def r(vc):
        ph = prof(vc)
        if ph is None:
            return None
        return integrate(ph, p0, v0, a0)[0] - pf

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
    for vc in scan_roots(r, grid):
        ph = prof(vc)
        if ph is not None and verify(ph, p0, v0, a0, L, goal) is None:
            return ph
    pool = []
    for x in grid:
        ph = prof(x)
        if ph is not None:
            pool.append((integrate(ph, p0, v0, a0)[0] - pf, ph))
    for sp in seeds:
        dT = T - total_time(sp)
        if dT < 0.0:
            continue
        for ph in insert_cruise(sp, v0, dT):
            pool.append((integrate(ph, p0, v0, a0)[0] - pf, ph))
    for e, ph in pool:
        if e == 0.0 and verify(ph, p0, v0, a0, L, goal) is None:
            return ph
    below = [(e, i) for i, (e, _) in enumerate(pool) if e < 0.0]
    above = [(e, i) for i, (e, _) in enumerate(pool) if e > 0.0]
    if below and above:
        # try the closest pairs first
        below.sort(reverse=True)
        above.sort()
        for eb, ib in below[:BLEND_TRIES]:
            for ea, ia in above[:BLEND_TRIES]:
                ph = blend(pool[ib][1], pool[ia][1], ea / (ea - eb))
                if verify(ph, p0, v0, a0, L, goal) is None:
                    return ph
    return _f2_hold_fixed(start, goal, L, T) if hold else None


def f2_hold_profile(am, start, goal, L, T, first_is_ramp):
    """F2 with a hold at the junction acceleration ``am`` lasting exactly ``T``.

    ``first_is_ramp=False``: bump to ``(vm, am)``, hold ``th``, ramp to
    ``af``; ``True``: ramp ``a0 -> am``, hold, bump to the goal. The hold
    length solves the duration equation (bracketed root in ``th``).
    """
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
            b = bump(vm, am, vf, af, L)
            if b is None:
                return None
            return r + ([(th, 0.0, am)] if th > 0.0 else []) + b
        vm = vf - dv - am * th
        b = bump(v0, a0, vm, am, L)
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
    # absorb the root's round-off in the hold so the duration is exact
    tt = total_time(ph)
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
    for first in (False, True):
        def r(am, first=first):
            ph = f2_hold_profile(am, start, goal, L, T, first)
            if ph is None:
                return None
            return integrate(ph, p0, v0, a0)[0] - pf
        for am in scan_roots(r, _grid(-Acap, Acap, [a0, af, 0.0], n=HOLD_SCAN_POINTS),
                             edge_steps=HOLD_EDGE_BISECT):
            ph = f2_hold_profile(am, start, goal, L, T, first)
            if ph is not None and verify(ph, p0, v0, a0, L, goal) is None:
                return ph
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
