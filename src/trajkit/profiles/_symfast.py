"""Step 1 with symmetric limits in closed form (the common case, ruckig's problem).

Kernel code (plain floats and views of the workspace, compiled by numba when
present), in the kernel's normalised units (see :mod:`._kernel`). It applies
when both legs share their limits (``a_max == a_max_decel``, ``j_max ==
j_max_decel``), the jerk and acceleration limits are finite and the start
lies inside the limits (no brake). :func:`sym_step1` fills the same result
vector as :func:`._shapes.step1`; when it finds nothing it says so and the
caller runs the general step 1.

The profiles
------------
Every time-optimal profile is UDDU in one of the two directions (the other
direction is the mirrored problem): with jerk ``J = 1/K`` ::

    ramp a0 -> c1 (+J) | hold c1 for t1 | ramp c1 -> c3 (-J), with a
    cruise of tc at v = v_max where it crosses a = 0 | hold c3 for t3 |
    ramp c3 -> af (+J)

With ``h0 = 2 J v0 - a0^2``, ``hf = 2 J vf - af^2``, ``g = (hf - h0) / 2``
and ``E = 3 D J^2 + 3 J (a0 v0 - af vf) - a0^3 + af^3`` (``D`` the
distance), the end velocity fixes one unknown and the end position leaves
one polynomial equation per shape (derived symbolically; each equals a
known multiple of the position residual, which the tests confirm):

* NONE (``t1 = t3 = tc = 0``), ``w = c1 - c3``, ``c1 + c3 = g / w``::

      3 w^4 + 6 (h0 + hf) w^2 - 4 E w - 3 g^2 = 0          (12 J^2 w  x residual)

* ACC0 (``c1 = A``, ``u = c3``, ``t1 = (g - A^2 + u^2) / (J A)``)::

      3 u^4 - 6 A u^3 + 3 (A^2 + hf) u^2 - 6 A hf u
      + 3/2 A^2 (h0 + hf) + 3/4 (hf^2 - h0^2) - 2 A E = 0   (6 A J^2 x residual)

* ACC1 (``c3 = -A``, ``u = c1``, ``t3 = (u^2 - A^2 - g) / (J A)``)::

      3 u^4 + 6 A u^3 + 3 (A^2 + h0) u^2 + 6 A h0 u
      + 3/2 A^2 (h0 + hf) + 3/4 (h0^2 - hf^2) - 2 A E = 0   (6 A J^2 x residual)

* ACC0_ACC1 (``c1 = A``, ``c3 = -A``, ``x = t1``, ``t3 = x - g / (J A)``)::

      6 A^2 J^2 x^2 + 6 A J (3 A^2 + h0) x
      + 12 A^4 + 21/2 A^2 h0 + 3/2 A^2 hf - 2 A E + 3/4 (h0^2 - hf^2) = 0

* with a cruise (VEL, ACC0_VEL, ACC1_VEL, ACC0_ACC1_VEL) both halves are
  closed forms (``c1^2 = J v_max - h0 / 2``, ``c3^2 = J v_max - hf / 2``,
  held at ``A`` where they exceed it) and the cruise is linear.

The real roots on each shape's interval come from :func:`._roots.quartic_roots_unit`
(derivative recursion, no grid), are polished by Newton steps on the
polynomial, and each candidate is built as a phase table and checked exactly
(:func:`._check.check_equal_legs`: :func:`._check.check` for equal legs). The
minimum time is the fastest candidate that passes.

For the minimum alone, one direction is searched first: the one the goal
lies in from the minimum-time velocity change ``(v0, a0) -> (vf, af)``
(:func:`first_direction`: +1 where the distance exceeds that change's
displacement). Its fastest valid candidate is taken as the minimum; the
other direction is searched only when the first has none (about 0.2 % of
random problems). That the first direction's fastest valid profile is never
slower than the other's is established by measurement, not proven: the tests
compare it with the search of both directions on random problems, and the
minimum-time sweeps compare the durations with ruckig's (which searches
both).

With every valid duration wanted (the blocked intervals), both directions are
searched and all candidates are checked; the valid durations of step 1 come as the minimum
plus pairs (ruckig's block scheme), so an even count of distinct durations
means that a profile was missed or is degenerate, and the caller's general
step 1 decides.
"""

from __future__ import annotations

import math

from ._check import check_equal_legs, clean
from ._compile import jit_raw
from ._roots import illinois, merge_equal, no_root_certain, quartic_roots_unit, sort_ascending
from ._shapes import NVALID, R_N, R_NV, R_SHAPE, R_T, R_V0, S2_NN, S_NONEW

__all__ = ["NSF", "NCF", "SF_SCRATCH", "build_candidate", "coef_acc0", "coef_acc01", "coef_acc1",
           "coef_none", "first_direction", "invariants", "sym_applies", "sym_step1", "sym_step2",
           "STEP2_SCRATCH"]

#: Largest number of candidates of both directions (4 roots of each quartic,
#: 2 of the quadratic, 1 cruise profile).
NCF = 32

#: Columns of a candidate row: direction, shape code, c1, t1, c3, t3, tc, duration.
NSF = 8

#: Scratch floats :func:`sym_step1` needs besides the candidate table (polynomial
#: coefficients, on the unit interval, roots, the root finder's break points).
SF_SCRATCH = 32

#: A candidate whose durations or corners miss their bounds by more than this
#: (relative) is not built; the exact check decides on the rest.
PRE_RTOL = 1e-9

#: The quartics' parameter intervals are solved where their least duration is
#: at most the fastest valid closed-form duration times ``1 + CUT_RTOL``.
CUT_RTOL = 1e-9

#: 1/6 (the direction's estimate needs no exact division).
SIXTH = 1.0 / 6.0

#: Newton steps polishing a root on the shape's polynomial.
NEWTON_STEPS = 2

#: Valid durations closer than this (relative) are one profile (as the blocks).
MERGE_RTOL = 1e-10

#: Most bracket updates of the cruise velocity of :func:`sym_step2` (each root
#: is found to round-off in far fewer).
STEP2_MAX_ITER = 200

#: Scratch floats of :func:`sym_step2` (8 break points, their cruise durations
#: and residuals).
STEP2_SCRATCH = 24

# candidate columns
C_SG, C_CODE, C_C1, C_T1, C_C3, C_T3, C_TC, C_T = range(NSF)

# shape codes (as :data:`._shapes.SHAPE_NAMES`; NONE as the general step 1 reports it)
CODE_NONE = S_NONEW
CODE_ACC0, CODE_ACC1, CODE_ACC01, CODE_VEL = 1, 2, 3, 4


@jit_raw
def sym_applies(lim):
    """Whether :func:`sym_step1` applies to the (normalised) limits ``lim``: both
    legs alike, finite jerk, acceleration and velocity limits. (The caller
    checks that the start lies inside them.)"""
    V, A, K = lim[0], lim[1], lim[2]
    return A == lim[3] and K == lim[4] and K > 0.0 and A < math.inf and V < math.inf


@jit_raw
def invariants(v0, a0, D, vf, af, J):
    """``(h0, hf, g, E)`` of the problem (see the module text)."""
    h0 = 2.0 * J * v0 - a0 * a0
    hf = 2.0 * J * vf - af * af
    E = 3.0 * D * J * J + 3.0 * J * (a0 * v0 - af * vf) - a0 * a0 * a0 + af * af * af
    return h0, hf, 0.5 * (hf - h0), E


@jit_raw
def coef_none(coef, h0, hf, g, E):
    """NONE: coefficients (ascending, in ``w = c1 - c3``) into ``coef[:5]``."""
    coef[0] = -3.0 * g * g
    coef[1] = -4.0 * E
    coef[2] = 6.0 * (h0 + hf)
    coef[3] = 0.0
    coef[4] = 3.0


@jit_raw
def coef_acc0(coef, A, h0, hf, E):
    """ACC0: coefficients (ascending, in ``u = c3``) into ``coef[:5]``."""
    coef[0] = 1.5 * A * A * (h0 + hf) - 2.0 * A * E + 0.75 * (hf * hf - h0 * h0)
    coef[1] = -6.0 * A * hf
    coef[2] = 3.0 * (A * A + hf)
    coef[3] = -6.0 * A
    coef[4] = 3.0


@jit_raw
def coef_acc1(coef, A, h0, hf, E):
    """ACC1: coefficients (ascending, in ``u = c1``) into ``coef[:5]``."""
    coef[0] = 1.5 * A * A * (h0 + hf) - 2.0 * A * E + 0.75 * (h0 * h0 - hf * hf)
    coef[1] = 6.0 * A * h0
    coef[2] = 3.0 * (A * A + h0)
    coef[3] = 6.0 * A
    coef[4] = 3.0


@jit_raw
def coef_acc01(A, J, h0, hf, E):
    """ACC0_ACC1: coefficients ``(q0, q1, q2)`` (ascending, in ``x = t1``)."""
    return (12.0 * A * A * A * A + 10.5 * A * A * h0 + 1.5 * A * A * hf - 2.0 * A * E
            + 0.75 * (h0 * h0 - hf * hf), 6.0 * A * J * (3.0 * A * A + h0), 6.0 * A * A * J * J)


@jit_raw
def _horner4(c, u):
    return (((c[4] * u + c[3]) * u + c[2]) * u + c[1]) * u + c[0]


@jit_raw
def _dhorner4(c, u):
    return ((4.0 * c[4] * u + 3.0 * c[3]) * u + 2.0 * c[2]) * u + c[1]


@jit_raw
def _roots_in(c, lo, hi, unit, roots, tmp):
    """Real roots in ``[lo, hi]`` of the quartic ``c[0] + ... + c[4] u^4``, each
    polished by Newton steps (written to ``roots``): their count (-1 when the
    interval is too small for the quartic to be resolved)."""
    m = 0.5 * (lo + hi)
    h = 0.5 * (hi - lo)
    if not (h > 0.0):
        return 0
    # q(x) = p(m + h x): Taylor shift to m, then scale by h
    b0, b1, b2, b3, b4 = c[0], c[1], c[2], c[3], c[4]
    # synthetic division by (u - m), repeated
    b3 = b3 + m * b4
    b2 = b2 + m * b3
    b1 = b1 + m * b2
    b0 = b0 + m * b1
    b3 = b3 + m * b4
    b2 = b2 + m * b3
    b1 = b1 + m * b2
    b3 = b3 + m * b4
    b2 = b2 + m * b3
    b3 = b3 + m * b4
    unit[0] = b0
    unit[1] = b1 * h
    unit[2] = b2 * h * h
    unit[3] = b3 * h * h * h
    unit[4] = b4 * h * h * h * h
    if no_root_certain(unit, 4):
        return 0
    if unit[4] == 0.0:
        return -1
    nr = quartic_roots_unit(unit, roots, tmp)
    for i in range(nr):
        u = m + h * roots[i]
        f = _horner4(c, u)
        for _ in range(NEWTON_STEPS):
            if f == 0.0:
                break
            d = _dhorner4(c, u)
            if d == 0.0:
                break
            un = u - f / d
            fn = _horner4(c, un)
            if not (abs(fn) < abs(f)):
                break
            u = un
            f = fn
        roots[i] = u
    return nr


@jit_raw
def _add(cand, nc, sg, code, c1, t1, c3, t3, tc, a0, af, A, K, tscale):
    """Append a candidate when it meets the cheap necessary bounds: the new count."""
    tol = PRE_RTOL * A
    if not (c1 - a0 >= -tol and c1 - c3 >= -tol and af - c3 >= -tol):
        return nc
    if not (abs(c1) <= A + tol and abs(c3) <= A + tol):
        return nc
    ttol = -PRE_RTOL * tscale
    if not (t1 >= ttol and t3 >= ttol and tc >= ttol):
        return nc
    if nc >= NCF:
        return nc
    T = (c1 - a0) * K + t1 + (c1 - c3) * K + tc + t3 + (af - c3) * K
    b = nc * NSF
    cand[b + C_SG] = sg
    cand[b + C_CODE] = code
    cand[b + C_C1] = c1
    cand[b + C_T1] = t1
    cand[b + C_C3] = c3
    cand[b + C_T3] = t3
    cand[b + C_TC] = tc
    cand[b + C_T] = T
    return nc + 1


@jit_raw
def _build(ph, c1, t1, c3, t3, tc, a0, af, K):
    """The UDDU phase table (mirrored frame) into ``ph``: its phase count."""
    J = 1.0 / K
    ph[0, 0] = (c1 - a0) * K
    ph[0, 1] = J
    ph[0, 2] = a0
    n = 1
    if t1 != 0.0:
        ph[n, 0] = t1
        ph[n, 1] = 0.0
        ph[n, 2] = c1
        n += 1
    if tc != 0.0 or c1 >= 0.0 >= c3:
        ph[n, 0] = c1 * K
        ph[n, 1] = -J
        ph[n, 2] = c1
        n += 1
        if tc != 0.0:
            ph[n, 0] = tc
            ph[n, 1] = 0.0
            ph[n, 2] = 0.0
            n += 1
        ph[n, 0] = -c3 * K
        ph[n, 1] = -J
        ph[n, 2] = 0.0
        n += 1
    else:
        ph[n, 0] = (c1 - c3) * K
        ph[n, 1] = -J
        ph[n, 2] = c1
        n += 1
    if t3 != 0.0:
        ph[n, 0] = t3
        ph[n, 1] = 0.0
        ph[n, 2] = c3
        n += 1
    ph[n, 0] = (af - c3) * K
    ph[n, 1] = J
    ph[n, 2] = c3
    return n + 1


@jit_raw
def _cruise_half(x, A, J):
    """(corner, hold) of a half whose velocity changes by ``x / J`` between
    ``a = 0`` and its outer corner (``x = corner^2`` without a hold)."""
    if x <= A * A:
        return math.sqrt(x), 0.0
    return A, (x - A * A) / (J * A)


@jit_raw
def _direction(sg, s1, lim, cand, nc, coef, unit, roots, tmp, ph, res, lazy):
    """The candidates of one direction (``sg``: +1 as given, -1 mirrored), appended
    to ``cand[nc:]``: first the shapes in closed form (the cruise, ACC0_ACC1),
    then the shapes of a quartic (NONE, ACC0, ACC1).

    With ``lazy`` (the minimum only), the closed-form candidates are checked
    first (:func:`_fastest_valid`, into ``res``) and the quartics solved only on
    the parameter intervals where some duration is below the fastest valid
    one (each duration is linear or convex in the shape parameter, so its
    least value on an interval is exact). Returns ``(end of the closed-form
    candidates, count, index of the fastest valid closed-form one or -1)``;
    the count is -1 when a quartic could not be resolved."""
    n0 = nc
    v0 = sg * s1[1]
    a0 = sg * s1[2]
    D = sg * (s1[3] - s1[0])
    vf = sg * s1[4]
    af = sg * s1[5]
    V = lim[0]
    A = lim[1]
    K = lim[2]
    J = 1.0 / K
    h0, hf, g, E = invariants(v0, a0, D, vf, af, J)
    # the scale of the durations (for the cheap bounds)
    tscale = 4.0 * A * K + abs(D) / V + (abs(v0) + abs(vf) + V) / A
    slack = PRE_RTOL * A
    # ---- a cruise at v_max: both halves in closed form, the cruise linear
    x1 = J * V - 0.5 * h0
    x3 = J * V - 0.5 * hf
    if x1 >= 0.0 and x3 >= 0.0:
        c1, t1 = _cruise_half(x1, A, J)
        c3, t3 = _cruise_half(x3, A, J)
        c3 = -c3
        n = _build(ph, c1, t1, c3, t3, 0.0, a0, af, K)
        p = 0.0
        v = v0
        for k in range(n):
            dt = ph[k, 0]
            jk = ph[k, 1]
            a = ph[k, 2]
            p = p + dt * (v + dt * (0.5 * a + dt * jk / 6.0))
            v = v + dt * (a + 0.5 * dt * jk)
        tc = (D - p) / V
        code = CODE_VEL + (1 if t1 > 0.0 else 0) + (2 if t3 > 0.0 else 0)
        nc = _add(cand, nc, sg, code, c1, t1, c3, t3, tc, a0, af, A, K, tscale)
    # The velocity limit where the acceleration crosses zero going down
    # (c1 >= 0 >= c3): c1^2 <= x1 and c3^2 <= x3 (both from the one velocity
    # of that point); they bound the corners of such profiles (p1, p3), and a
    # hold at A needs x1 >= A^2 (c1 = A) or x3 >= A^2 (c3 = -A).
    p1 = min(A, math.sqrt(max(x1, 0.0)))
    p3 = min(A, math.sqrt(max(x3, 0.0)))
    hold1 = x1 >= A * A * (1.0 - PRE_RTOL)
    hold3 = x3 >= A * A * (1.0 - PRE_RTOL)
    if hold1 and hold3:
        nc = _acc01(cand, nc, sg, a0, af, A, K, J, h0, hf, g, E, tscale)
    nclosed = nc
    ib = -1
    tcut = math.inf
    if lazy:
        ib = _fastest_valid(cand, n0, nc, math.inf, s1, lim, ph, res)
        if ib >= 0:
            tcut = res[R_T] * (1.0 + CUT_RTOL)
    # ---- NONE: w = c1 - c3 > 0, c1 + c3 = g / w; c1 >= 0 >= c3 where w^2 >= |g|
    coef_none(coef, h0, hf, g, E)
    sg0 = math.sqrt(abs(g))
    for part in range(2):
        if part == 0:
            # crossing: c1 <= p1, c3 >= -p3
            d1 = p1 * p1 - g
            d3 = p3 * p3 + g
            if d1 < -slack * A or d3 < -slack * A:
                continue
            r1 = math.sqrt(max(d1, 0.0))
            r3 = math.sqrt(max(d3, 0.0))
            lo = max(sg0, p1 - r1, p3 - r3)
            hi = min(p1 + r1, p3 + r3)
        elif g > 0.0:
            # every acceleration >= 0: 0 < c3 <= af, c1 <= A
            if not (af > 0.0) or A * A < g:
                continue
            lo = max(A - math.sqrt(A * A - g), math.sqrt(af * af + g) - af)
            hi = sg0
        elif g < 0.0:
            # every acceleration <= 0: a0 <= c1 < 0, c3 >= -A
            if not (a0 < 0.0) or A * A < -g:
                continue
            lo = max(A - math.sqrt(A * A + g), a0 + math.sqrt(a0 * a0 - g))
            hi = sg0
        else:
            continue
        # T = K (2 w + af - a0), increasing in w
        if K * (2.0 * max(lo - slack, 0.0) + af - a0) > tcut:
            continue
        nr = _roots_in(coef, max(lo - slack, 0.0), hi + slack, unit, roots, tmp)
        if nr < 0:
            return nclosed, -1, ib
        for i in range(nr):
            w = roots[i]
            if w > 0.0:
                q = g / w
                c1 = 0.5 * (w + q)
                c3 = 0.5 * (q - w)
            elif g == 0.0:
                c1 = 0.0
                c3 = 0.0
            else:
                continue
            nc = _add(cand, nc, sg, CODE_NONE, c1, 0.0, c3, 0.0, 0.0, a0, af, A, K, tscale)
    # ---- ACC0: c1 = A, u = c3; t1 >= 0: u^2 >= A^2 - g
    coef_acc0(coef, A, h0, hf, E)
    r = math.sqrt(max(A * A - g, 0.0))
    for part in range(2):
        if part == 0:  # c3 <= 0
            if not hold1:
                continue
            lo = -p3
            hi = -r
        else:  # c3 > 0
            lo = r
            hi = min(A, af)
        if hi + slack < lo - slack:
            continue
        # T = K ((A - a0) + (g - A^2 + u^2) / A + A - 2 u + af), least at u = A
        u = min(max(A, lo - slack), hi + slack)
        if K * ((A - a0) + (g - A * A + u * u) / A + A - 2.0 * u + af) > tcut:
            continue
        nr = _roots_in(coef, lo - slack, hi + slack, unit, roots, tmp)
        if nr < 0:
            return nclosed, -1, ib
        for i in range(nr):
            u = roots[i]
            t1 = (g - A * A + u * u) * K / A
            nc = _add(cand, nc, sg, CODE_ACC0, A, t1, u, 0.0, 0.0, a0, af, A, K, tscale)
    # ---- ACC1: c3 = -A, u = c1; t3 >= 0: u^2 >= A^2 + g
    coef_acc1(coef, A, h0, hf, E)
    r = math.sqrt(max(A * A + g, 0.0))
    for part in range(2):
        if part == 0:  # c1 >= 0
            if not hold3:
                continue
            lo = r
            hi = p1
        else:  # c1 < 0
            lo = max(-A, a0)
            hi = -r
        if hi + slack < lo - slack:
            continue
        # T = K ((u - a0) + (u + A) + (u^2 - A^2 - g) / A + (af + A)), least at u = -A
        u = min(max(-A, lo - slack), hi + slack)
        if K * (2.0 * u - a0 + (u * u - A * A - g) / A + af + 2.0 * A) > tcut:
            continue
        nr = _roots_in(coef, lo - slack, hi + slack, unit, roots, tmp)
        if nr < 0:
            return nclosed, -1, ib
        for i in range(nr):
            u = roots[i]
            t3 = (u * u - A * A - g) * K / A
            nc = _add(cand, nc, sg, CODE_ACC1, u, 0.0, -A, t3, 0.0, a0, af, A, K, tscale)
    return nclosed, nc, ib


@jit_raw
def _acc01(cand, nc, sg, a0, af, A, K, J, h0, hf, g, E, tscale):
    """ACC0_ACC1 (``c1 = A``, ``c3 = -A``, ``x = t1``): the roots of its quadratic
    (stable forms) appended as candidates: the new count."""
    q0, q1, q2 = coef_acc01(A, J, h0, hf, E)
    disc = q1 * q1 - 4.0 * q2 * q0
    if disc >= 0.0:
        sq = math.sqrt(disc)
        qq = -0.5 * (q1 + math.copysign(sq, q1))
        for k in range(2):
            if k == 0:
                x = qq / q2
            elif qq != 0.0:
                x = q0 / qq
            else:
                continue
            t3 = x - g * K / A
            nc = _add(cand, nc, sg, CODE_ACC01, A, x, -A, t3, 0.0, a0, af, A, K, tscale)
    return nc


@jit_raw
def build_candidate(cand, i, s1, lim, ph):
    """Phase table of candidate ``i`` (in its own, possibly mirrored, frame) into
    ``ph``, round-off negative durations zeroed: (phase count, or 0 when a
    duration is really negative; duration; direction)."""
    b = i * NSF
    sg = cand[b + C_SG]
    n = _build(ph, cand[b + C_C1], cand[b + C_T1], cand[b + C_C3], cand[b + C_T3],
               cand[b + C_TC], sg * s1[2], sg * s1[5], lim[2])
    if not clean(ph, n):
        return 0, 0.0, sg
    T = 0.0
    for k in range(n):
        T += ph[k, 0]
    return n, T, sg


@jit_raw
def _try(cand, i, s1, lim, ph):
    """Build and exactly check candidate ``i``: (phase count, duration), count 0
    when it fails."""
    n, T, sg = build_candidate(cand, i, s1, lim, ph)
    if n == 0:
        return 0, 0.0
    if not check_equal_legs(ph, n, 0.0, sg * s1[1], sg * s1[2], sg * (s1[3] - s1[0]), sg * s1[4],
                            sg * s1[5], lim[0], lim[1], lim[2]):
        return 0, 0.0
    return n, T


@jit_raw
def sym_step1(s1, lim, res, want_all, cand, scr, ph):
    """Minimum-time step 1 from ``s1[:3]`` to ``s1[3:6]`` (see the module text).

    ``cand``: scratch of ``NCF * NSF`` floats, ``scr`` of :data:`SF_SCRATCH`,
    ``ph`` a phase table of at least 8 rows. Fills ``res`` as
    :func:`._shapes.step1` does (``R_T``, ``R_N``, ``R_SHAPE``, and with
    ``want_all`` every valid duration in ``res[R_V0:]``, else the fastest) and
    returns the index of the fastest valid candidate (without ``want_all`` it is
    left built in ``ph``, its phase count in ``res[R_N]``; with it, rebuild it
    with :func:`build_candidate`). Returns -1 when no candidate passes, or (with
    ``want_all``) when the count of distinct valid durations is even: the
    caller then runs the general step 1.
    """
    coef = scr[0:8]
    unit = scr[8:16]
    roots = scr[16:24]
    tmp = scr[24:32]
    res[R_T] = math.inf
    res[R_N] = 0.0
    res[R_NV] = 0.0
    res[R_SHAPE] = 0.0
    if not want_all:
        # the minimum only: the direction the goal lies in first, the other only
        # when it has no valid profile (see the module text)
        # (the shapes in closed form first: the quartics' parameter intervals whose
        # durations all exceed the fastest valid one are not solved)
        sg = first_direction(s1, lim)
        for d in (sg, -sg):
            nclosed, nc, ib = _direction(d, s1, lim, cand, 0, coef, unit, roots, tmp, ph, res,
                                         True)
            if nc < 0:
                return -1
            tb = res[R_T] if ib >= 0 else math.inf
            iq = _fastest_valid(cand, nclosed, nc, tb, s1, lim, ph, res)
            if iq >= 0:
                return iq  # (built in ph: the last candidate tried)
            if ib >= 0:
                if nc > nclosed:  # (a quartic candidate may have been tried since)
                    build_candidate(cand, ib, s1, lim, ph)
                return ib
        return -1
    _, nc, _ = _direction(1.0, s1, lim, cand, 0, coef, unit, roots, tmp, ph, res, False)
    if nc < 0:
        return -1
    _, nc, _ = _direction(-1.0, s1, lim, cand, nc, coef, unit, roots, tmp, ph, res, False)
    if nc < 0:
        return -1
    # every valid duration (the blocked intervals) and the fastest
    ib = -1
    nv = 0
    for i in range(nc):
        n, T = _try(cand, i, s1, lim, ph)
        if n == 0:
            continue
        if nv < NVALID:
            res[R_V0 + nv] = T
            nv += 1
        if T < res[R_T]:
            ib = i
            _keep(cand, i, n, T, res)
    res[R_NV] = nv
    if nv == 0:
        return -1
    # distinct durations (sorted, merged as the blocked intervals merge them):
    # their count must be odd
    v = res[R_V0:R_V0 + nv]
    sort_ascending(v, nv)
    m = merge_equal(v, nv, MERGE_RTOL)
    res[R_NV] = m
    return ib if m % 2 == 1 else -1


@jit_raw
def _fastest_valid(cand, i0, nc, tmax, s1, lim, ph, res):
    """The fastest of the candidates ``i0 .. nc - 1`` faster than ``tmax`` that
    passes the exact check (tried fastest first; kept in ``res``): its index,
    -1 when none passes (``res`` untouched)."""
    for _ in range(i0, nc):
        ib = -1
        tb = tmax
        for i in range(i0, nc):
            t = cand[i * NSF + C_T]
            if t < tb:
                tb = t
                ib = i
        if ib < 0:
            break
        n, T = _try(cand, ib, s1, lim, ph)
        if n > 0:
            _keep(cand, ib, n, T, res)
            res[R_V0] = T
            res[R_NV] = 1.0
            return ib
        cand[ib * NSF + C_T] = math.inf
    return -1


@jit_raw
def first_direction(s1, lim):
    """The direction (+1: as given, -1: mirrored) whose profiles reach the goal
    position from the start first: +1 when the distance exceeds the
    displacement of the minimum-time velocity change ``(v0, a0) -> (vf, af)``
    (position free; one acceleration peak, held at ``a_max`` where it would pass
    it), else -1."""
    v0, a0, vf, af = s1[1], s1[2], s1[4], s1[5]
    A = lim[1]
    K = lim[2]
    J = 1.0 / K
    dv = vf - v0
    # the velocity change of ramping a0 -> af directly
    up = dv >= 0.5 * (a0 + af) * abs(af - a0) * K
    # the peak: above both (up) or below both
    x = dv * J + 0.5 * (a0 * a0 + af * af) if up else 0.5 * (a0 * a0 + af * af) - dv * J
    c = math.sqrt(max(x, 0.0))
    th = 0.0
    if c > A:
        th = (x - A * A) * K / A
        c = A
    if not up:
        c = -c
    p = 0.0
    v = v0
    t1 = abs(c - a0) * K
    j1 = J if up else -J
    p = p + t1 * (v + t1 * (0.5 * a0 + t1 * j1 * SIXTH))
    v = v + t1 * (a0 + 0.5 * t1 * j1)
    p = p + th * (v + 0.5 * th * c)
    v = v + th * c
    t3 = abs(af - c) * K
    p = p + t3 * (v + t3 * (0.5 * c - t3 * j1 * SIXTH))
    return 1.0 if s1[3] - s1[0] > p else -1.0


@jit_raw
def _keep(cand, i, n, T, res):
    res[R_T] = T
    res[R_N] = n
    res[R_SHAPE] = cand[i * NSF + C_CODE] + (16.0 if cand[i * NSF + C_SG] < 0.0 else 0.0)


# ------------------------------------------------------------------ step 2
@jit_raw
def _half(dv, a, A, K):
    """A velocity change by ``dv`` from acceleration ``a`` to 0 with one corner
    (at jerk ``1/K``, held at ``+-A`` where it would exceed it): on the side of
    the change that ramping ``a`` straight to 0 gives, ``a -> c -> 0``.

    Returns ``(side, c, hold, duration, deficit)``: the corner's side (+1: the
    acceleration goes up first), the corner, its hold [s], the duration and
    ``int (v_end - v) dt`` over the change (velocities relative to its start)."""
    sd = 1.0 if dv >= 0.5 * a * abs(a) * K else -1.0
    a1 = sd * a
    c, h = _cruise_half(max(dv * sd / K + 0.5 * a1 * a1, 0.0), A, 1.0 / K)
    J = 1.0 / K
    # in the side's frame: ramp a1 -> c (+J), hold c, ramp c -> 0 (-J)
    d1 = (c - a1) * K
    d3 = c * K
    p = d1 * d1 * (0.5 * a1 + d1 * J / 6.0)
    v = d1 * (a1 + 0.5 * d1 * J)
    p = p + h * (v + 0.5 * h * c)
    v = v + h * c
    p = p + d3 * (v + d3 * (0.5 * c - d3 * J / 6.0))
    v = v + d3 * (c - 0.5 * d3 * J)
    dur = d1 + h + d3
    return sd, c, h, dur, sd * (v * dur - p)


@jit_raw
def _cruise_eval(vc, T, v0, a0, D, vf, af, A, K):
    """The profile of duration ``T`` with a cruise at ``vc`` (both halves by
    :func:`_half`; the second one as the reverse of a change from the goal):
    (cruise duration, position residual)."""
    _, _, _, t1, e1 = _half(vc - v0, a0, A, K)
    _, _, _, t3, e3 = _half(vc - vf, -af, A, K)
    return T - t1 - t3, vc * T - e1 - e3 - D


@jit_raw
def _cruise_table(vc, T, v0, a0, vf, af, A, K, ph):
    """The phase table of :func:`_cruise_eval`'s profile into ``ph``: (phase
    count, shape code)."""
    J = 1.0 / K
    s1, c1, h1, t1, _ = _half(vc - v0, a0, A, K)
    s3, c3, h3, t3, _ = _half(vc - vf, -af, A, K)
    n = 0
    # first half: a0 -> s1 c1 (jerk s1 J), hold, -> 0 (jerk -s1 J)
    for dt, jk, ak in (((c1 - s1 * a0) * K, s1 * J, a0), (h1, 0.0, s1 * c1),
                       (c1 * K, -s1 * J, s1 * c1), (T - t1 - t3, 0.0, 0.0),
                       # second half, the reverse of -af -> s3 c3 -> 0: 0 -> -s3 c3 -> af
                       (c3 * K, -s3 * J, 0.0), (h3, 0.0, -s3 * c3),
                       ((c3 + s3 * af) * K, s3 * J, -s3 * c3)):
        if dt != 0.0:
            ph[n, 0] = dt
            ph[n, 1] = jk
            ph[n, 2] = ak
            n += 1
    code = S2_NN + (1 if h1 > 0.0 else 0) + (2 if h3 > 0.0 else 0) + (16 if s1 < 0.0 else 0)
    return n, code


@jit_raw
def _vc_root(what, a, fa, b, fb, T, v0, a0, D, vf, af, A, K):
    """Regula falsi (Illinois) over the cruise velocity in ``[a, b]`` (``fa``,
    ``fb`` of opposite signs, or one zero) on the cruise duration (``what`` 0)
    or the position residual (1): (the final bracket's ends, on ``a``'s side
    and on ``b``'s, the velocity of the least |value| met, that value)."""
    xb, fxb = (a, abs(fa)) if abs(fa) <= abs(fb) else (b, abs(fb))
    side = 0
    for _ in range(STEP2_MAX_ITER):
        if fxb == 0.0:
            break
        x = b - fb * (b - a) / (fb - fa)
        if not (a < x < b):
            x = 0.5 * (a + b)
            if not (a < x < b):
                break
        tx, rx = _cruise_eval(x, T, v0, a0, D, vf, af, A, K)
        fx = tx if what == 0 else rx
        if abs(fx) < fxb:
            xb, fxb = x, abs(fx)
        a, fa, b, fb, side = illinois(x, fx, a, fa, b, fb, side)
    return a, b, xb, fxb


@jit_raw
def _try_vc(vc, T, s1, lim, ph):
    """Build the profile of cruise velocity ``vc`` and check it exactly:
    (phase count, 0 when it fails; shape code)."""
    n, code = _cruise_table(vc, T, s1[1], s1[2], s1[4], s1[5], lim[1], lim[2], ph)
    if not clean(ph, n):
        return 0, 0
    if not check_equal_legs(ph, n, 0.0, s1[1], s1[2], s1[3] - s1[0], s1[4], s1[5], lim[0],
                            lim[1], lim[2]):
        return 0, 0
    return n, code


@jit_raw
def sym_step2(s1, T, lim, ph, scr):
    """Step 2 (a profile of exactly ``T``) in closed form where it applies:
    symmetric limits (:func:`sym_applies`), a start inside them, and a profile
    with a cruise at a free velocity ``vc`` in ``[-v_max, v_max]`` (the family
    of almost every axis that time synchronisation stretches).

    Each half is the one-corner velocity change of :func:`_half` (its corner's
    side, its hold, its duration and its area are closed forms of ``vc``), so
    the cruise duration and the position residual are functions of ``vc``
    alone, smooth between the break points where a corner changes side or
    starts a hold. Each piece whose residual changes sign where the cruise
    lasts no less than nothing is solved by regula falsi (Illinois), its
    profile built and checked exactly; the first that passes is returned.
    ``scr``: scratch of :data:`STEP2_SCRATCH` floats.

    Returns ``(phase count, shape code)`` with the phases in ``ph``; count 0
    when it found nothing (the general step 2 decides).
    """
    if not sym_applies(lim):
        return 0, 0
    v0 = s1[1]
    a0 = s1[2]
    D = s1[3] - s1[0]
    vf = s1[4]
    af = s1[5]
    V = lim[0]
    A = lim[1]
    K = lim[2]
    # break points: the natural velocities (a corner changes side) and the
    # holds' starts of both halves, within [-V, V]
    pts = scr[0:8]
    pts[0] = -V
    pts[1] = V
    m = 2
    for vb, ab in ((v0, a0), (vf, -af)):
        for x in (vb + 0.5 * ab * abs(ab) * K, vb + (A * A - 0.5 * ab * ab) * K,
                  vb - (A * A - 0.5 * ab * ab) * K):
            if -V < x < V:
                pts[m] = x
                m += 1
    sort_ascending(pts, m)
    tcs = scr[8:16]
    res = scr[16:24]
    for i in range(m):
        tcs[i], res[i] = _cruise_eval(pts[i], T, v0, a0, D, vf, af, A, K)
    for i in range(m - 1):
        a = pts[i]
        b = pts[i + 1]
        ta = tcs[i]
        tb = tcs[i + 1]
        ra = res[i]
        rb = res[i + 1]
        if not (b > a) or (ta < 0.0 and tb < 0.0):
            continue
        if ta < 0.0 or tb < 0.0:
            # the cruise ends within the piece: cut it where it lasts nothing
            ea, eb, x, fx = _vc_root(0, a, ta, b, tb, T, v0, a0, D, vf, af, A, K)
            if ta < 0.0:
                a = x if fx == 0.0 else eb
                ra = _cruise_eval(a, T, v0, a0, D, vf, af, A, K)[1]
            else:
                b = x if fx == 0.0 else ea
                rb = _cruise_eval(b, T, v0, a0, D, vf, af, A, K)[1]
        if not (ra == 0.0 or rb == 0.0 or (ra < 0.0) != (rb < 0.0)):
            continue
        _, _, vc, _ = _vc_root(1, a, ra, b, rb, T, v0, a0, D, vf, af, A, K)
        n, code = _try_vc(vc, T, s1, lim, ph)
        if n > 0:
            return n, code
    return 0, 0
