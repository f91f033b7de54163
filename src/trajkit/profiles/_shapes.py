"""Step 1 of the state-to-state planner: the profile shapes, each in closed form.

Kernel code (plain floats and small arrays, compiled by numba when present).
Units are the kernel's normalised ones (see :mod:`._kernel`); limits come as
``V, A1, K1, A2, K2`` with ``K = 1/j_max`` (0 for an infinite jerk limit):
``A1, K1`` while ``|v|`` grows (``v a > 0``), ``A2, K2`` while it shrinks.

The template
------------
Every time-optimal profile found here has the jerk-sign pattern UDDU (up,
down, down, up) in one of the two directions (the other direction is the
mirrored problem; the leg rule is mirror-invariant)::

    ramp a_s -> c1 (jerk +) | hold c1 for t1 | ramp c1 -> c3 (jerk -),
    through a = 0 with a cruise of tc at v = v_max | hold c3 for t3 |
    ramp c3 -> a_e (jerk +)

Each ramp is traversed at the largest jerk of the leg it lies in, a hold at
``c1`` / ``c3`` is one at the acceleration limit of its leg, a cruise one at
``v_max``. Which of ``t1``, ``t3``, ``tc`` are non-zero is the *shape*
(ruckig's names: NONE, ACC0, ACC1, ACC0_ACC1, VEL, ACC0_VEL, ACC1_VEL,
ACC0_ACC1_VEL). The velocity over a ramp from ``x`` to ``y`` changes by
``(y^2 - x^2) K/2``, so the end velocity is linear in the squared corners
and in the holds; the end position is a cubic in them. Eliminating one
unknown with the velocity equation leaves one equation in one parameter
``u``:

* NONE: ``u = c1``, ``c3 = s sqrt(Q(u))`` with ``Q`` quadratic; the product
  of both signs ``R(u, +r) R(u, -r)`` is a polynomial of degree 6;
* ACC0 (``u = c3``) and ACC1 (``u = c1``): the hold is quadratic in ``u``,
  the end position a quartic;
* ACC0_ACC1 (``u = t3``): ``t1`` linear, the end position a quadratic;
* with a cruise: both halves are independent square roots, the cruise
  length is linear.

:mod:`._roots` finds every real root of these polynomials on the parameter's
interval; each root is polished by Newton steps on the exact residual, the
candidate built as a phase table, and checked exactly (:mod:`._check`). The
minimum time is the fastest candidate that passes; the durations of all
that pass are the block boundaries (:mod:`._block`).

Asymmetric legs
---------------
A ramp that crosses ``a = 0`` is split there (the leg changes when the
velocity keeps its sign). Which leg applies to each run of constant
acceleration sign depends on the sign of the velocity there; the runs at the
start and end have known velocities (a velocity reversal inside them is
split exactly at the acceleration where ``v = 0``, a closed form of the
boundary state: a fixed prefix or suffix); for the runs in the middle the
sign is a hypothesis (both are tried), and a reversal inside a middle run is
planned with the tighter of both legs' limits on that run. With symmetric
limits there is one hypothesis and no split.
"""

from __future__ import annotations

import math

from ._check import check, clean
from ._compile import jit_raw
from ._phase import phase_end
from ._roots import NODES, illinois, interp_unit, real_roots_unit, sort_ascending

__all__ = ["NPH", "NVALID", "step1", "step2_pairs"]

#: Largest number of phases of a profile (brake + prefix + template + suffix).
NPH = 40

#: Largest number of valid candidates kept for the block computation.
NVALID = 64

#: Secant steps polishing a root on the exact residual.
POLISH_STEPS = 16

#: A residual below this fraction of the problem's scale is exact (no polishing).
POLISH_RTOL = 1e-15

#: Stop at the first valid profile for a rest goal (symmetric limits).
EARLY = True

#: Where the shape polynomial nearly vanishes at an end of its interval
#: (``|N(end)| <= ZOOM_RTOL * sum |c_k|``), a root may hide within round-off of
#: that end (tiny moves): the roots are searched again on ever smaller pieces
#: at that end, each ``ZOOM_FACTOR`` of the interval, at most ``ZOOM_LEVELS``.
ZOOM_RTOL = 1e-6
ZOOM_FACTOR = 2.0 ** -4
ZOOM_LEVELS = 10

#: Slack of the cheap pre-check of a root before it is polished (normalised units).
PLAUSIBLE_RTOL = 1e-6

#: Regula-falsi steps of the bracketed root a step-2 cruise tries first.
BRANCH_ROOT_ITER = 100

# configuration vector (one template instance)
(PS, VS, AS, PE, VE, AE, K1, K2P, K2N, K2Q, K4, MODE, L1, L3, VM, C1LO, C1HI, C3LO, C3HI, S3,
 SZ, K2R, TT, SG2) = range(24)
NCFG = 24
#: (the configuration array holds ``2 * NCFG`` entries: the second half saves the
#: first while a stage of step 2 changes it)

# ramp-2 modes: where the ramp c1 -> c3 is split (at a = 0 and/or at a reversal z)
M_SINGLE = 0  # c1 -> c3 (K2P)
M_ZERO = 1    # c1 -> 0 (K2P), cruise, 0 -> c3 (K2N)
M_ZFIRST = 2  # c1 -> z (K2P), z -> 0 (K2Q), cruise, 0 -> c3 (K2N); v(z) = 0
M_ZSECOND = 3 # c1 -> 0 (K2P), cruise, 0 -> z (K2N), z -> c3 (K2Q); v(z) = 0
M_ZSINGLE = 4 # c1 -> z (K2P), z -> c3 (K2Q); v(z) = 0
M_ZBOTH = 5   # c1 -> z (K2P), z -> 0 (K2Q), cruise, 0 -> z2 (K2N), z2 -> c3 (K2R); v(z) = v(z2) = 0
M_MID = 6     # c1 -> z (K2P), hold tc at z, z -> c3 (K2N): a hold at a free level z

# shapes (which unknowns the velocity equation leaves); step 1 (minimum time):
S_NONE, S_ACC0, S_ACC1, S_ACC01 = 0, 1, 2, 3
# step 2 (duration T): a cruise at a free velocity with both halves NONE/ACC, or a
# hold at a free acceleration at c1 / c3
S2_NN, S2_AN, S2_NA, S2_AA, S2_H1, S2_H3 = 4, 5, 6, 7, 8, 9
# step 2, equal jerk on every ramp: a hold at a free level h between two ramps
# down (ruckig's a3 != 0 profiles): c3 = ae (MH1: c1 free, MH2: hold at c1 = L1)
# or c1 = a0 (MH3: c3 free, MH4: hold at c3 = L3); and every ramp at a reduced jerk
S2_MH1, S2_MH2, S2_MH3, S2_MH4, S2_JF = 10, 11, 12, 13, 14
# step 2, the last stage (STAGE_HOLD2): a hold at a free c1 with the hold at
# c3 = L3 (HH1), a hold at a free c3 with the hold at c1 = L1 (HH3), and the holds
# at a free c1 / c3 of ramp 2 through a velocity reversal (H1X, H3X); searched
# on the exact residual (:func:`_hold2`). HH1/HH3 are reported under the codes
# C_HH1/C_HH3 (free in the fixed-duration context), H1X/H3X as H1/H3.
S2_HH1, S2_HH3, S2_H1X, S2_H3X = 16, 17, 18, 19
C_HH1, C_HH3 = 0, 1
# ... and, where ramp 2 of a one-run template (M_ZSINGLE) reverses the velocity,
# a hold at a level z of ramp 2 with the reversal inside it (c1 -> z on the
# slowing leg, z -> c3 = ae on the speeding leg): a free z with the hold at
# c1 = L1 (HZ1, reported as MH2) or a free c1 without a hold (HZ0, as MH1), or z
# at the smaller acceleration limit with a hold at a free c1 (HZ2, as C_HH1)
S2_HZ1, S2_HZ0, S2_HZ2 = 20, 21, 22
# ... and, where ramp 1 starts (ramp 4 ends) at a = 0, a second cruise there: at the
# start's velocity before ramp 1 (the goal's after ramp 4), with the cruise of ramp 2
# (C_DC; :func:`_delay_cruise`)
C_DC = 2
# ... and a cruise at the start's velocity before ramp 1 (the goal's after ramp 4)
# with a shape of step 1 (C_DS; :func:`_delay_step1`)
C_DS = 3
# step 1, NONE with equal jerks everywhere: parameter w = c1 - c3 (c1^2 - c3^2 is
# fixed by the velocity), w R(w) is a quartic (ruckig's NONE quartic)
S_NONEW = 15

# result vector: best duration, best phase count, number of valid durations, the
# shape of the best (code, see SHAPE_NAMES; +16 when mirrored), whether every valid
# duration is wanted (else candidates that cannot win are not checked; ALL_NEAREST:
# every one, and the one kept is the nearest to R_TARGET instead of the fastest),
# whether the search may stop at the first valid profile (set when it did), the
# stage of step 2 and its cruise shape tried first (see _cruise_hint), the target
# duration of ALL_NEAREST, valid durations...
R_T, R_N, R_NV, R_SHAPE, R_ALL, R_STOP, R_STAGE, R_HINT, R_TARGET, R_V0 = range(10)
ALL_NEAREST = 2.0

# step 2 searches the shape families in stages, each in both directions (the
# first profile of the duration found ends the search; the likeliest pair
# first, see _step2_pair): a cruise at a free velocity (UDDU), a hold at a free
# acceleration, a cruise at an inflection (UDUD), equal jerks on every ramp
STAGE_CRUISE, STAGE_HOLD, STAGE_INFLECTION, STAGE_EQUAL, STAGE_HOLD2 = 0, 1, 2, 3, 4

#: (stage, direction) pairs of step 2 (5 stages x 2 directions), searched in the
#: order of :func:`_step2_pair`.
STEP2_PAIRS = 10

#: The first pair of the last stage (:data:`STAGE_HOLD2`) in that order.
STEP2_HOLD2_FIRST = 8

#: Samples of the exact residual per sign branch in step 2's last stage.
HOLD2_SAMPLES = 16

#: Bisection steps locating the end of a sign branch between two samples (to
#: 2**-40 of their distance).
EDGE_STEPS = 40

#: Fixed-point rounds of the cruise-velocity estimate that orders step 2's search.
CRUISE_ESTIMATE_ROUNDS = 3

#: Names of the shape codes (ruckig's names of the reached limits).
SHAPE_NAMES = ("none", "acc0", "acc1", "acc0_acc1", "vel", "acc0_vel", "acc1_vel",
               "acc0_acc1_vel", "velocity", "velocity_acc0")


# ------------------------------------------------------------------ building
@jit_raw
def _ramp(ph, n, x, y, kap, sgn):
    """Ramp the acceleration from ``x`` to ``y`` at jerk ``sgn / kap``."""
    if kap == 0.0:  # infinite jerk: the acceleration jumps (next phase starts at y)
        return n
    ph[n, 0] = (y - x) * sgn * kap
    ph[n, 1] = sgn / kap
    ph[n, 2] = x
    return n + 1


@jit_raw
def _hold(ph, n, a, t):
    ph[n, 0] = t
    ph[n, 1] = 0.0
    ph[n, 2] = a
    return n + 1


@jit_raw
def template(ph, n, cfg, c1, t1, z, c3, t3, tc, final):
    """Append the UDDU template of ``cfg`` with its unknowns to ``ph[n:]``.

    While solving (``final=False``) the structure is the configuration's
    (phases may get negative durations: the algebra of the shape continues);
    a final candidate of symmetric legs splits ramp 2 at ``a = 0`` only
    where it crosses it.
    """
    n = _ramp(ph, n, cfg[AS], c1, cfg[K1], 1.0)
    if t1 != 0.0:
        n = _hold(ph, n, c1, t1)
    mode = int(cfg[MODE])
    if (final and mode == M_ZERO and tc == 0.0 and cfg[K2P] == cfg[K2N] and cfg[SG2] > 0.0
            and not (c1 >= 0.0 >= c3)):
        mode = M_SINGLE
    if mode == M_SINGLE:
        n = _ramp(ph, n, c1, c3, cfg[K2P], -1.0)
    elif mode == M_ZERO:
        n = _ramp(ph, n, c1, 0.0, cfg[K2P], -1.0)
        if tc != 0.0:
            n = _hold(ph, n, 0.0, tc)
        n = _ramp(ph, n, 0.0, c3, cfg[K2N], -cfg[SG2])
    elif mode == M_ZFIRST:
        n = _ramp(ph, n, c1, z, cfg[K2P], -1.0)
        n = _ramp(ph, n, z, 0.0, cfg[K2Q], -1.0)
        if tc != 0.0:
            n = _hold(ph, n, 0.0, tc)
        n = _ramp(ph, n, 0.0, c3, cfg[K2N], -1.0)
    elif mode == M_ZSECOND:
        n = _ramp(ph, n, c1, 0.0, cfg[K2P], -1.0)
        if tc != 0.0:
            n = _hold(ph, n, 0.0, tc)
        n = _ramp(ph, n, 0.0, z, cfg[K2N], -1.0)
        n = _ramp(ph, n, z, c3, cfg[K2Q], -1.0)
    elif mode == M_MID:
        n = _ramp(ph, n, c1, z, cfg[K2P], -1.0)
        if tc != 0.0:
            n = _hold(ph, n, z, tc)
        n = _ramp(ph, n, z, c3, cfg[K2N], -1.0)
    elif mode == M_ZBOTH:
        z2 = -z * math.sqrt(cfg[K2Q] / cfg[K2N]) if cfg[K2N] > 0.0 else 0.0
        n = _ramp(ph, n, c1, z, cfg[K2P], -1.0)
        n = _ramp(ph, n, z, 0.0, cfg[K2Q], -1.0)
        if tc != 0.0:
            n = _hold(ph, n, 0.0, tc)
        n = _ramp(ph, n, 0.0, z2, cfg[K2N], -1.0)
        n = _ramp(ph, n, z2, c3, cfg[K2R], -1.0)
    else:
        n = _ramp(ph, n, c1, z, cfg[K2P], -1.0)
        n = _ramp(ph, n, z, c3, cfg[K2Q], -1.0)
    if t3 != 0.0:
        n = _hold(ph, n, c3, t3)
    n = _ramp(ph, n, c3, cfg[AE], cfg[K4], cfg[SG2])
    if cfg[K4] == 0.0:
        n = _hold(ph, n, cfg[AE], 0.0)
    return n


@jit_raw
def _rp(p, v, T, x, y, K, sgn):
    """(p, v, T) after a ramp x -> y at jerk sgn/K (what :func:`_ramp` appends)."""
    if K == 0.0:
        return p, v, T
    dt = (y - x) * sgn * K
    p, v, _ = phase_end(p, v, x, sgn / K, dt)
    return p, v, T + dt


@jit_raw
def _hp(p, v, T, a, t):
    """(p, v, T) after a hold at ``a`` for ``t``."""
    p, v, _ = phase_end(p, v, a, 0.0, t)
    return p, v, T + t


@jit_raw
def walk(cfg, c1, t1, z, c3, t3, tc):
    """End position and duration of :func:`template` (``final=False``), without
    building the phase table (the same phases, integrated by the same formula)."""
    p = cfg[PS]
    v = cfg[VS]
    T = 0.0
    p, v, T = _rp(p, v, T, cfg[AS], c1, cfg[K1], 1.0)
    if t1 != 0.0:
        p, v, T = _hp(p, v, T, c1, t1)
    mode = int(cfg[MODE])
    if mode == M_SINGLE:
        p, v, T = _rp(p, v, T, c1, c3, cfg[K2P], -1.0)
    elif mode == M_ZERO:
        p, v, T = _rp(p, v, T, c1, 0.0, cfg[K2P], -1.0)
        if tc != 0.0:
            p, v, T = _hp(p, v, T, 0.0, tc)
        p, v, T = _rp(p, v, T, 0.0, c3, cfg[K2N], -cfg[SG2])
    elif mode == M_ZFIRST:
        p, v, T = _rp(p, v, T, c1, z, cfg[K2P], -1.0)
        p, v, T = _rp(p, v, T, z, 0.0, cfg[K2Q], -1.0)
        if tc != 0.0:
            p, v, T = _hp(p, v, T, 0.0, tc)
        p, v, T = _rp(p, v, T, 0.0, c3, cfg[K2N], -1.0)
    elif mode == M_ZSECOND:
        p, v, T = _rp(p, v, T, c1, 0.0, cfg[K2P], -1.0)
        if tc != 0.0:
            p, v, T = _hp(p, v, T, 0.0, tc)
        p, v, T = _rp(p, v, T, 0.0, z, cfg[K2N], -1.0)
        p, v, T = _rp(p, v, T, z, c3, cfg[K2Q], -1.0)
    elif mode == M_MID:
        p, v, T = _rp(p, v, T, c1, z, cfg[K2P], -1.0)
        if tc != 0.0:
            p, v, T = _hp(p, v, T, z, tc)
        p, v, T = _rp(p, v, T, z, c3, cfg[K2N], -1.0)
    elif mode == M_ZBOTH:
        z2 = -z * math.sqrt(cfg[K2Q] / cfg[K2N]) if cfg[K2N] > 0.0 else 0.0
        p, v, T = _rp(p, v, T, c1, z, cfg[K2P], -1.0)
        p, v, T = _rp(p, v, T, z, 0.0, cfg[K2Q], -1.0)
        if tc != 0.0:
            p, v, T = _hp(p, v, T, 0.0, tc)
        p, v, T = _rp(p, v, T, 0.0, z2, cfg[K2N], -1.0)
        p, v, T = _rp(p, v, T, z2, c3, cfg[K2R], -1.0)
    else:
        p, v, T = _rp(p, v, T, c1, z, cfg[K2P], -1.0)
        p, v, T = _rp(p, v, T, z, c3, cfg[K2Q], -1.0)
    if t3 != 0.0:
        p, v, T = _hp(p, v, T, c3, t3)
    p, v, T = _rp(p, v, T, c3, cfg[AE], cfg[K4], cfg[SG2])
    return p, T


@jit_raw
def integrate(ph, n0, n, p, v, a):
    """End state of phases ``n0..n-1`` from ``(p, v, a)``."""
    for k in range(n0, n):
        p, v, a = phase_end(p, v, ph[k, 2], ph[k, 1], ph[k, 0])
    return p, v, a


# --------------------------------------------------- velocity algebra of the template
# F(c1, t1): velocity at the top of ramp 2's first part (after ramp 1, hold 1 and
# the c1 -> 0 (or c1 -> z) part at K2P, counted to a = 0):
#   F = vs + (c1^2 - as^2) K1/2 + c1 t1 + c1^2 K2P/2
# E(c3, t3): velocity change from a = 0 on ramp 2 (or from z) to the end:
#   E = - c3^2 kc3 + c3 t3 + ae^2 K4/2,   kc3 = (K_c3 + K4)/2
# no reversal:  ve = F + E;   reversal at z:  F = z^2 kz,  ve = z^2 K2Q/2 + E.
@jit_raw
def _F(cfg, c1, t1):
    return (cfg[VS] + 0.5 * (c1 * c1 - cfg[AS] * cfg[AS]) * cfg[K1] + c1 * t1
            + 0.5 * c1 * c1 * cfg[K2P])


@jit_raw
def _kc3(cfg):
    mode = int(cfg[MODE])
    if mode == M_SINGLE:
        k = cfg[K2P]
    elif mode == M_ZERO or mode == M_ZFIRST:
        k = cfg[K2N]
    elif mode == M_ZBOTH:
        k = cfg[K2R]
    else:
        k = cfg[K2Q]
    return 0.5 * (k + cfg[K4])


@jit_raw
def _kze(cfg):
    """End side of a reversal: ve = z^2 _kze + E(c3, t3)."""
    if int(cfg[MODE]) == M_ZBOTH:
        return 0.5 * cfg[K2Q] * cfg[K2R] / cfg[K2N] if cfg[K2N] > 0.0 else 0.0
    return 0.5 * cfg[K2Q]


@jit_raw
def _E(cfg, c3, t3):
    return cfg[SG2] * (0.5 * cfg[AE] * cfg[AE] * cfg[K4] - c3 * c3 * _kc3(cfg)) + c3 * t3


@jit_raw
def _kz(cfg):
    if int(cfg[MODE]) == M_ZSECOND:
        return 0.5 * cfg[K2N]
    return 0.5 * cfg[K2P]


@jit_raw
def _sqrt_s(x, s):
    return s * math.sqrt(x) if x > 0.0 else 0.0


@jit_raw
def _rho1(cfg):
    """vc = rho1 F: the cruise velocity from the first half's top velocity."""
    mode = int(cfg[MODE])
    if mode == M_ZFIRST or mode == M_ZBOTH:
        return cfg[K2Q] / cfg[K2P] if cfg[K2P] > 0.0 else 0.0
    return 1.0


@jit_raw
def _g(cfg):
    """ve = g vc + E(c3, t3)."""
    mode = int(cfg[MODE])
    if mode == M_ZSECOND:
        return cfg[K2Q] / cfg[K2N] if cfg[K2N] > 0.0 else 0.0
    if mode == M_ZBOTH:
        return cfg[K2R] / cfg[K2N] if cfg[K2N] > 0.0 else 0.0
    return 1.0


@jit_raw
def _rt(T, x, y, K, sgn):
    """``T`` after a ramp x -> y at jerk sgn/K (the duration :func:`_rp` adds)."""
    if K == 0.0:
        return T
    return T + (y - x) * sgn * K


@jit_raw
def _durations(cfg, work, c1, t1, z, c3, t3):
    """Sum of the template's phase durations without a cruise: the duration
    :func:`walk` returns (the same sums in the same order), without integrating
    the positions."""
    T = _rt(0.0, cfg[AS], c1, cfg[K1], 1.0)
    if t1 != 0.0:
        T = T + t1
    mode = int(cfg[MODE])
    if mode == M_SINGLE:
        T = _rt(T, c1, c3, cfg[K2P], -1.0)
    elif mode == M_ZERO:
        T = _rt(T, c1, 0.0, cfg[K2P], -1.0)
        T = _rt(T, 0.0, c3, cfg[K2N], -cfg[SG2])
    elif mode == M_ZFIRST:
        T = _rt(T, c1, z, cfg[K2P], -1.0)
        T = _rt(T, z, 0.0, cfg[K2Q], -1.0)
        T = _rt(T, 0.0, c3, cfg[K2N], -1.0)
    elif mode == M_ZSECOND:
        T = _rt(T, c1, 0.0, cfg[K2P], -1.0)
        T = _rt(T, 0.0, z, cfg[K2N], -1.0)
        T = _rt(T, z, c3, cfg[K2Q], -1.0)
    elif mode == M_MID:
        T = _rt(T, c1, z, cfg[K2P], -1.0)
        T = _rt(T, z, c3, cfg[K2N], -1.0)
    elif mode == M_ZBOTH:
        z2 = -z * math.sqrt(cfg[K2Q] / cfg[K2N]) if cfg[K2N] > 0.0 else 0.0
        T = _rt(T, c1, z, cfg[K2P], -1.0)
        T = _rt(T, z, 0.0, cfg[K2Q], -1.0)
        T = _rt(T, 0.0, z2, cfg[K2N], -1.0)
        T = _rt(T, z2, c3, cfg[K2R], -1.0)
    else:
        T = _rt(T, c1, z, cfg[K2P], -1.0)
        T = _rt(T, z, c3, cfg[K2Q], -1.0)
    if t3 != 0.0:
        T = T + t3
    return _rt(T, c3, cfg[AE], cfg[K4], cfg[SG2])


@jit_raw
def _unknowns(cfg, work, shape, u, sz, s3):
    """(c1, t1, z, c3, t3, tc, rad_z, rad_3) of ``shape`` at parameter ``u``.

    ``rad_*`` are the radicands of the reversal acceleration ``z`` and of the
    second radical (``c3``, or ``c3 - u`` / ``c1 - u`` of the hold shapes), 1
    when not a radical; ``sz``, ``s3`` the signs of their square roots.
    """
    cross = M_ZFIRST <= int(cfg[MODE]) <= M_ZBOTH
    c1 = 0.0
    t1 = 0.0
    z = 0.0
    c3 = 0.0
    t3 = 0.0
    tc = 0.0
    rz = 1.0
    r3 = 1.0
    aek = 0.5 * cfg[AE] * cfg[AE] * cfg[K4]
    if shape == S_NONEW:
        g = _gamma(cfg)
        c1 = 0.5 * (u + g / u)
        c3 = 0.5 * (g / u - u)
    elif shape == S_NONE:
        c1 = u
        if cross:
            rz = _F(cfg, c1, 0.0) / _kz(cfg)
            z = _sqrt_s(rz, sz)
            r3 = (rz * _kze(cfg) + aek - cfg[VE]) / _kc3(cfg)
        else:
            r3 = (_F(cfg, c1, 0.0) + aek - cfg[VE]) / _kc3(cfg)
        c3 = _sqrt_s(r3, s3)
    elif shape == S_ACC0 or shape == S_ACC01:
        c1 = cfg[L1]
        if shape == S_ACC0:
            c3 = u
        else:
            c3 = cfg[L3]
            t3 = u
        base = _F(cfg, c1, 0.0)
        if cross:
            kze = _kze(cfg)
            rz = (cfg[VE] - _E(cfg, c3, t3)) / kze if kze > 0.0 else -1.0
            z = _sqrt_s(rz, sz)
            t1 = (rz * _kz(cfg) - base) / c1
        else:
            t1 = (cfg[VE] - _E(cfg, c3, t3) - base) / c1
    elif shape == S_ACC1:
        c1 = u
        c3 = cfg[L3]
        e0 = _E(cfg, c3, 0.0)
        if cross:
            rz = _F(cfg, c1, 0.0) / _kz(cfg)
            z = _sqrt_s(rz, sz)
            t3 = (cfg[VE] - rz * _kze(cfg) - e0) / c3
        else:
            t3 = (cfg[VE] - _F(cfg, c1, 0.0) - e0) / c3
    elif shape <= S2_AA:
        # a cruise at vc = rho1 F (the velocity at the a = 0 point), ve = g vc + E
        T = cfg[TT]
        rho = _rho1(cfg)
        g = _g(cfg)
        if shape == S2_NN or shape == S2_NA:
            c1 = u
            F = _F(cfg, c1, 0.0)
            vc = rho * F
            if shape == S2_NN:
                sg = cfg[SG2]
                r3 = (g * vc + sg * aek - cfg[VE]) / (sg * _kc3(cfg))
                c3 = _sqrt_s(r3, s3)
            else:
                c3 = cfg[L3]
                t3 = (cfg[VE] - g * vc - _E(cfg, c3, 0.0)) / c3
        elif shape == S2_AN:
            c1 = cfg[L1]
            c3 = u
            vc = (cfg[VE] - _E(cfg, c3, 0.0)) / g if g != 0.0 else 0.0
            F = vc / rho if rho != 0.0 else 0.0
            t1 = (F - _F(cfg, c1, 0.0)) / c1
        else:
            c1 = cfg[L1]
            c3 = cfg[L3]
            t1 = u
            F = _F(cfg, c1, t1)
            vc = rho * F
            t3 = (cfg[VE] - g * vc - _E(cfg, c3, 0.0)) / c3
        if cross:
            rz = F / _kz(cfg)
            z = _sqrt_s(rz, sz)
        tc = T - _durations(cfg, work, c1, t1, z, c3, t3)
    elif shape == S2_H1:
        # hold t1 at a free c1 = u; c3 = u + s r from the velocity equation
        T = cfg[TT]
        kc3 = _kc3(cfg)
        c1 = u
        T0 = _durations(cfg, work, c1, 0.0, 0.0, 0.0, 0.0)
        G = _F(cfg, c1, 0.0) + c1 * (T - T0) + aek - cfg[VE]
        r3 = c1 * c1 + G / kc3
        c3 = c1 + _sqrt_s(r3, s3)
        t1 = T - T0 + 2.0 * kc3 * c3
    elif shape >= S2_MH1:
        # equal jerk 1/k on every ramp (set by the caller; JF: k is the unknown)
        T = cfg[TT]
        k = cfg[K1]
        a0 = cfg[AS]
        ae = cfg[AE]
        dv = cfg[VE] - cfg[VS]
        if shape == S2_MH1:
            z = u
            G = z * T + z * k * (a0 + ae) - 0.5 * k * (a0 * a0 + ae * ae) - dv
            r3 = z * z - G / k
            c1 = z + _sqrt_s(r3, s3)
            c3 = ae
            tc = T - k * (2.0 * c1 - a0 - ae)
        elif shape == S2_MH2:
            z = u
            c1 = cfg[L1]
            c3 = ae
            base = k * (2.0 * c1 - a0 - ae)
            t1 = (dv - 0.5 * k * (2.0 * c1 * c1 - a0 * a0 - ae * ae) - z * (T - base)) / (c1 - z)
            tc = T - t1 - base
        elif shape == S2_MH3:
            z = u
            c1 = a0
            G = 0.5 * k * (a0 * a0 + ae * ae) + z * T - z * k * (a0 + ae) - dv
            r3 = z * z + G / k
            c3 = z + _sqrt_s(r3, s3)
            tc = T - k * (a0 - 2.0 * c3 + ae)
        elif shape == S2_MH4:
            z = u
            c1 = a0
            c3 = cfg[L3]
            base = k * (a0 - 2.0 * c3 + ae)
            t3 = (dv - 0.5 * k * (a0 * a0 - 2.0 * c3 * c3 + ae * ae) - z * (T - base)) / (c3 - z)
            tc = T - t3 - base
        else:  # S2_JF: every ramp at the jerk 1/k of the duration
            w = dv / T
            c1 = u
            r3 = (c1 - w) * (c1 - w) - 0.5 * ((a0 - w) * (a0 - w) - (ae - w) * (ae - w))
            c3 = w + _sqrt_s(r3, s3)
            dA = 2.0 * c1 - 2.0 * c3 - a0 + ae
            kk = T / dA if dA != 0.0 else 0.0
            cfg[K1] = kk
            cfg[K2P] = kk
            cfg[K2N] = kk
            cfg[K4] = kk
    else:  # S2_H3: hold t3 at a free c3 = u; c1 = u + s r
        T = cfg[TT]
        alpha = 0.5 * (cfg[K1] + cfg[K2P])
        c3 = u
        T0 = _durations(cfg, work, 0.0, 0.0, 0.0, c3, 0.0)
        H = _F(cfg, 0.0, 0.0) + _E(cfg, c3, 0.0) + c3 * (T - T0) - cfg[VE]
        r3 = c3 * c3 - H / alpha
        c1 = c3 + _sqrt_s(r3, s3)
        t3 = T - T0 - 2.0 * alpha * c1
    return c1, t1, z, c3, t3, tc, rz, r3


@jit_raw
def _gamma(cfg):
    """c1^2 - c3^2 of NONE with equal jerks (from the end velocity)."""
    return (cfg[VE] - _F(cfg, 0.0, 0.0) - _E(cfg, 0.0, 0.0)) / cfg[K1]


@jit_raw
def _none_w_domain(cfg):
    """Interval of w = c1 - c3 > 0 with c1 <= C1HI and c3 >= C3LO."""
    g = _gamma(cfg)
    h1 = cfg[C1HI]
    d1 = h1 * h1 - g
    if d1 < 0.0:
        return 1.0, 0.0
    s1 = math.sqrt(d1)
    lo = h1 - s1
    hi = h1 + s1
    l3 = cfg[C3LO]
    d3 = l3 * l3 + g
    if d3 < 0.0:
        return 1.0, 0.0
    s3 = math.sqrt(d3)
    lo = max(lo, -l3 - s3, 0.0)
    hi = min(hi, -l3 + s3)
    if lo == 0.0:
        lo = 1e-12 * hi
    return lo, hi


@jit_raw
def _resid(cfg, work, shape, u, sz, s3):
    c1, t1, z, c3, t3, tc, _, _ = _unknowns(cfg, work, shape, u, sz, s3)
    return walk(cfg, c1, t1, z, c3, t3, tc)[0] - cfg[PE]


# ------------------------------------------------------------------ recording
@jit_raw
def offer(cfg, work, pre, npre, suf, nsuf, c1, t1, z, c3, t3, tc, sgn, st, lim, best, res,
          scratch, code):
    """Build the full candidate, check it and record it (in the un-mirrored frame).

    ``st = (p0, v0, a0, pf, vf, af)`` is the step-1 problem in the mirrored
    frame (``sgn = -1``) or as given (``sgn = +1``).
    """
    if res[R_ALL] == 0.0:
        # only the fastest matters: a candidate that cannot beat it is not built
        T = walk(cfg, c1, t1, z, c3, t3, tc)[1]
        for k in range(npre):
            T += pre[k, 0]
        for k in range(nsuf):
            T += suf[k, 0]
        if not (T < res[R_T] * (1.0 + 1e-12)):
            return False
    n = 0
    for k in range(npre):
        scratch[n, 0] = pre[k, 0]
        scratch[n, 1] = pre[k, 1]
        scratch[n, 2] = pre[k, 2]
        n += 1
    n = template(scratch, n, cfg, c1, t1, z, c3, t3, tc, True)
    for k in range(nsuf):
        scratch[n, 0] = suf[k, 0]
        scratch[n, 1] = suf[k, 1]
        scratch[n, 2] = suf[k, 2]
        n += 1
    if not clean(scratch, n):
        return False
    T = 0.0
    for k in range(n):
        T += scratch[k, 0]
    if res[R_ALL] == 0.0 and not (T < res[R_T]):
        return False  # cannot be the fastest: not worth the exact check
    if not check(scratch, n, st[0], st[1], st[2], st[3], st[4], st[5],
                 lim[0], lim[1], lim[2], lim[3], lim[4]):
        return False
    if res[R_STOP] < 0.0:
        res[R_STOP] = 1.0  # a rest goal: this is the one valid profile
    nv = int(res[R_NV])
    if nv < NVALID:
        res[R_V0 + nv] = T
        res[R_NV] = nv + 1
    if res[R_ALL] == ALL_NEAREST:
        keep = abs(T - res[R_TARGET]) < abs(res[R_T] - res[R_TARGET])
    else:
        keep = T < res[R_T]
    if keep:
        res[R_T] = T
        res[R_N] = n
        res[R_SHAPE] = code + (16 if sgn < 0.0 else 0)
        for k in range(n):
            best[k, 0] = scratch[k, 0]
            best[k, 1] = sgn * scratch[k, 1]
            best[k, 2] = sgn * scratch[k, 2]
    return True


# ------------------------------------------------------------------ shapes
@jit_raw
def _nrad(cfg, shape):
    """Number of square roots in the shape's parameterisation."""
    cross = M_ZFIRST <= int(cfg[MODE]) <= M_ZBOTH
    n = 1 if cross else 0
    if (shape == S_NONE or shape == S2_NN or shape == S2_H1 or shape == S2_H3
            or shape == S2_MH1 or shape == S2_MH3 or shape == S2_JF):
        n += 1
    return n


@jit_raw
def _den(cfg, work, shape, u, s3):
    """Denominator of a rational shape (its residual times den^p is a polynomial)."""
    if shape == S2_MH2:
        return cfg[L1] - u
    if shape == S2_MH4:
        return cfg[L3] - u
    if shape == S2_JF:
        c1, _, _, c3, _, _, _, _ = _unknowns(cfg, work, shape, u, 1.0, s3)
        return 2.0 * c1 - 2.0 * c3 - cfg[AS] + cfg[AE]
    return 1.0


@jit_raw
def _norm(cfg, work, shape, u, nrad):
    """Product of the residual over every sign of the square roots (a polynomial in u)."""
    if shape == S_NONEW:
        return _resid(cfg, work, shape, u, 1.0, 1.0) * u
    if shape == S2_MH2 or shape == S2_MH4:
        d = _den(cfg, work, shape, u, 1.0)
        return _resid(cfg, work, shape, u, 1.0, 1.0) * d * d * d
    if shape == S2_JF:
        out = 1.0
        for s3 in (1.0, -1.0):
            d = _den(cfg, work, shape, u, s3)
            out *= _resid(cfg, work, shape, u, 1.0, s3) * d * d
        return out
    if nrad == 0:
        return _resid(cfg, work, shape, u, 1.0, 1.0)
    cross = M_ZFIRST <= int(cfg[MODE]) <= M_ZBOTH
    if nrad == 1:
        if cross:
            return _resid(cfg, work, shape, u, 1.0, 1.0) * _resid(cfg, work, shape, u, -1.0, 1.0)
        return _resid(cfg, work, shape, u, 1.0, 1.0) * _resid(cfg, work, shape, u, 1.0, -1.0)
    return (_resid(cfg, work, shape, u, 1.0, 1.0) * _resid(cfg, work, shape, u, 1.0, -1.0)
            * _resid(cfg, work, shape, u, -1.0, 1.0) * _resid(cfg, work, shape, u, -1.0, -1.0))


@jit_raw
def _domain(cfg, shape):
    """Interval of the shape parameter (before the radicands are considered)."""
    lo, hi = _domain0(cfg, shape)
    T = cfg[TT]
    if S2_NN <= shape <= S2_JF and T == T:
        # every ramp fits in the duration: bounds the corners by T / K
        if shape == S2_NN or shape == S2_NA or shape == S2_H1:
            if cfg[K1] > 0.0:
                hi = min(hi, cfg[AS] + T / cfg[K1])
            if cfg[K2P] > 0.0:
                hi = min(hi, max(cfg[AS], 0.0) + T / cfg[K2P])
        elif shape == S2_AN or shape == S2_H3:
            k = cfg[K2N] if int(cfg[MODE]) != M_SINGLE else cfg[K2P]
            if k > 0.0:
                if cfg[SG2] > 0.0:
                    lo = max(lo, min(cfg[AE], 0.0) - T / k)
                else:
                    hi = min(hi, max(cfg[AE], 0.0) + T / k)
    return lo, hi


@jit_raw
def _domain0(cfg, shape):
    if shape == S_NONEW:
        return _none_w_domain(cfg)
    if shape == S_NONE or shape == S2_NN or shape == S2_H1:
        return cfg[C1LO], cfg[C1HI]
    inflect = cfg[SG2] < 0.0  # c3 after a cruise at an inflection: not bounded by c1
    if shape == S_ACC0 or shape == S2_AN:
        return cfg[C3LO], (cfg[C3HI] if inflect else min(cfg[C3HI], cfg[L1]))
    if shape == S_ACC1 or shape == S2_NA:
        return (cfg[C1LO] if inflect else max(cfg[C1LO], cfg[L3])), cfg[C1HI]
    if shape == S2_H3:
        return cfg[C3LO], cfg[C3HI]
    if shape == S2_AA:
        return 0.0, cfg[TT]
    if shape == S2_MH1:
        return cfg[AE], cfg[L1]
    if shape == S2_MH2:
        return cfg[AE], cfg[L1]
    if shape == S2_MH3:
        return cfg[L3], cfg[AS]
    if shape == S2_MH4:
        return cfg[L3], cfg[AS]
    if shape == S2_JF:
        return cfg[AS], cfg[L1]
    # ACC01: t3 >= 0 up to the hold that would take the velocity across 2 v_max
    c3 = abs(cfg[L3])
    V = cfg[VM]
    if V < math.inf:
        return 0.0, (2.0 * V + abs(cfg[VS]) + abs(cfg[VE])) / c3 + 1.0
    return 0.0, math.inf


@jit_raw
def _quad_fit_roots(f0, f1, f2, lo, hi, out):
    """Roots in (lo, hi) of the quadratic through (lo, f0), (mid, f1), (hi, f2)."""
    h = 0.5 * (hi - lo)
    # q(x) on x in [-1, 1]: a x^2 + b x + c
    a = 0.5 * (f0 + f2) - f1
    b = 0.5 * (f2 - f0)
    c = f1
    n = 0
    if a == 0.0:
        if b != 0.0:
            x = -c / b
            if -1.0 < x < 1.0:
                out[n] = lo + h * (x + 1.0)
                n += 1
        return n
    disc = b * b - 4.0 * a * c
    if disc < 0.0:
        return 0
    sq = math.sqrt(disc)
    q = -0.5 * (b + math.copysign(sq, b))
    if q != 0.0:
        for x in (q / a, c / q):
            if -1.0 < x < 1.0:
                out[n] = lo + h * (x + 1.0)
                n += 1
    return n


@jit_raw
def _intervals(cfg, work, shape, lo, hi, ivl, bp):
    """Sub-intervals of [lo, hi] where every radicand is >= 0 (written to ``ivl``;
    ``bp``: scratch of at least 6 break points)."""
    nb = 0
    mid = 0.5 * (lo + hi)
    for which in range(2):
        _, _, _, _, _, _, a0, b0 = _unknowns(cfg, work, shape, lo, 1.0, 1.0)
        _, _, _, _, _, _, a1, b1 = _unknowns(cfg, work, shape, mid, 1.0, 1.0)
        _, _, _, _, _, _, a2, b2 = _unknowns(cfg, work, shape, hi, 1.0, 1.0)
        if which == 0:
            nb += _quad_fit_roots(a0, a1, a2, lo, hi, bp[nb:])
        else:
            nb += _quad_fit_roots(b0, b1, b2, lo, hi, bp[nb:])
    sort_ascending(bp, nb)  # the break points
    ni = 0
    a = lo
    for i in range(nb + 1):
        b = bp[i] if i < nb else hi
        if b > a or (b == a and nb == 0):
            _, _, _, _, _, _, rz, r3 = _unknowns(cfg, work, shape, 0.5 * (a + b), 1.0, 1.0)
            if rz >= 0.0 and r3 >= 0.0:
                if ni > 0 and ivl[ni - 1, 1] == a:
                    ivl[ni - 1, 1] = b
                else:
                    ivl[ni, 0] = a
                    ivl[ni, 1] = b
                    ni += 1
        a = b
    return ni


@jit_raw
def _degree(cfg, shape):
    if shape == S_NONEW:
        return 4
    if shape == S2_MH1 or shape == S2_MH3:
        return 6
    if shape == S2_MH2 or shape == S2_MH4:
        return 8
    if shape == S2_JF:
        return 12
    cross = M_ZFIRST <= int(cfg[MODE]) <= M_ZBOTH
    if shape == S_NONE or shape == S2_NN or shape == S2_H1 or shape == S2_H3:
        return 12 if cross else 6
    if shape == S_ACC01 or shape == S2_AA:
        return 6 if cross else 2
    return 8 if cross else 4


@jit_raw
def _polish(cfg, work, shape, u, sz, s3, lo, hi):
    """Secant steps on the exact residual from a polynomial root; returns (u, |R|).

    Stops at once when the root is already exact to round-off (the usual case).
    """
    R = _resid(cfg, work, shape, u, sz, s3)
    # the scale of the positions of this motion (a tiny rest-to-rest move is
    # resolved relative to its own distance)
    tol = POLISH_RTOL * (abs(cfg[PE] - cfg[PS]) + abs(cfg[VS]) + abs(cfg[VE]) + 1e-300)
    if abs(R) <= tol:
        return u, abs(R)
    h = 1e-7 * max(abs(u), hi - lo, 1e-300)
    if u + h > hi:
        h = -h
    uo = u + h
    Ro = _resid(cfg, work, shape, uo, sz, s3)
    for _ in range(POLISH_STEPS):
        den = R - Ro
        if den == 0.0:
            break
        un = min(max(u - R * (u - uo) / den, lo), hi)
        Rn = _resid(cfg, work, shape, un, sz, s3)
        if not (abs(Rn) < abs(R)):
            break
        uo = u
        Ro = R
        u = un
        R = Rn
        if abs(R) <= tol:
            break
    return u, abs(R)


@jit_raw
def _plausible(cfg, c1, t1, c3, t3, tc):
    """Cheap necessary conditions of a candidate (the exact check decides)."""
    eps = -PLAUSIBLE_RTOL * (1.0 + abs(cfg[TT]) if cfg[TT] == cfg[TT] else 1.0)
    if t1 < eps or t3 < eps or tc < eps:
        return False
    if cfg[K1] > 0.0 and (c1 - cfg[AS]) * cfg[K1] < eps:
        return False
    return True


@jit_raw
def _branch_root(cfg, work, shape, a, b, s3):
    """A root in ``[a, b]`` of the exact residual of one sign branch (``s3``) of a
    step-2 cruise shape, where its values at ``a`` and ``b`` differ in sign
    (regula falsi, Illinois variant, on the residual itself); NaN when they
    do not (the branch may still have roots there)."""
    if not (a < b):
        return math.nan
    fa = _resid(cfg, work, shape, a, 1.0, s3)
    fb = _resid(cfg, work, shape, b, 1.0, s3)
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    if not (fa * fb < 0.0):
        return math.nan
    tol = POLISH_RTOL * (abs(cfg[PE] - cfg[PS]) + abs(cfg[VS]) + abs(cfg[VE]) + 1e-300)
    side = 0
    x = 0.5 * (a + b)
    for _ in range(BRANCH_ROOT_ITER):
        x = (a * fb - b * fa) / (fb - fa)
        if not (a < x < b):
            x = 0.5 * (a + b)
            if not (a < x < b):
                return x
        fx = _resid(cfg, work, shape, x, 1.0, s3)
        if abs(fx) <= tol or not (fx == fx):
            return x
        a, fa, b, fb, side = illinois(x, fx, a, fa, b, fb, side)
    return x


@jit_raw
def _plausible_cruise(cfg, c1, c3):
    """Cheap necessary conditions of a step-2 cruise candidate of ramp 2 split at
    ``a = 0`` (:data:`M_ZERO`): the ramps ``c1 -> 0``, ``0 -> c3`` and ``c3 ->
    a_e`` have non-negative durations (to the slack of :func:`_plausible`);
    the root of the other sign branch of ``c3`` fails here, before polishing."""
    eps = -PLAUSIBLE_RTOL * (1.0 + abs(cfg[TT]))
    if c1 * cfg[K2P] < eps:
        return False
    if -cfg[SG2] * c3 * cfg[K2N] < eps:
        return False
    return cfg[SG2] * (cfg[AE] - c3) * cfg[K4] >= eps


@jit_raw
def _quad_branch(a, b, c, s):
    """Root ``(-b + s sqrt(b^2 - 4ac)) / 2a`` of ``a x^2 + b x + c`` (the linear
    root for ``a = 0`` and ``s = 1``), computed without cancellation; NaN when
    there is none."""
    if a == 0.0:
        return -c / b if (s > 0.0 and b != 0.0) else math.nan
    disc = b * b - 4.0 * a * c
    if not (disc >= 0.0):
        return math.nan
    sq = math.sqrt(disc)
    q = -0.5 * (b + math.copysign(sq, b))  # the root of larger magnitude times a
    # q / a carries the sign -sign(b) of the square root, c / q the other one
    if (s > 0.0) == (math.copysign(1.0, b) < 0.0):
        return q / a
    return c / q if q != 0.0 else math.nan


@jit_raw
def _ramp_time(cfg, work):
    """The ramps' duration of the template, affine in the corners: ``(b, d1, dz,
    d3)`` with ``T_ramps = b + d1 c1 + dz z + d3 c3`` (:func:`_durations`)."""
    b = _durations(cfg, work, 0.0, 0.0, 0.0, 0.0, 0.0)
    return (b, _durations(cfg, work, 1.0, 0.0, 0.0, 0.0, 0.0) - b,
            _durations(cfg, work, 0.0, 0.0, 1.0, 0.0, 0.0) - b,
            _durations(cfg, work, 0.0, 0.0, 0.0, 1.0, 0.0) - b)


@jit_raw
def _hold2_unknowns(cfg, shape, u, sa, sb, lin):
    """(c1, t1, z, c3, t3, tc) of a shape of :func:`_hold2` at parameter ``u`` on
    the sign branch ``(sa, sb)``; NaN where the branch has no real value.

    The duration of the ramps is affine in the corners, ``lin = (b, d1, dz,
    d3)`` of :func:`_ramp_time`; with the velocity equations (``ve = F + E``,
    or ``F = z^2 kz`` and ``ve = z^2 kze + E`` through a reversal) and the
    duration ``T`` the remaining unknowns are linear or roots of a quadratic.
    ``tc`` is the hold at the level ``z`` of HZ0 / HZ1 / HZ2 (0 for the others;
    HZ2's level is in ``cfg[L3]`` while :func:`_hold_mid` runs).
    """
    T = cfg[TT]
    b, d1, dz, d3 = lin
    ve = cfg[VE]
    nan = math.nan
    if S2_HZ1 <= shape <= S2_HZ2:
        # (mode M_MID, c3 = ae: no ramp 4) the velocity at the end without the
        # holds, vb = F(c1, 0) - z^2 K2P/2 + (z^2 - ae^2) K2N/2, then
        # c1 t1 + z tc = ve - vb and t1 + tc = T - (b + d1 c1 + dz z + d3 ae)
        z = cfg[L3] if shape == S2_HZ2 else u
        ae = cfg[AE]
        w = 0.5 * (cfg[K2N] - cfg[K2P]) * z * z - 0.5 * cfg[K2N] * ae * ae
        R0 = T - (b + dz * z + d3 * ae)
        if shape != S2_HZ0:
            c1 = cfg[L1] if shape == S2_HZ1 else u
            if c1 == z or sb < 0.0 or sa < 0.0:
                return nan, nan, nan, nan, nan, nan
            R = R0 - d1 * c1
            t1 = (ve - _F(cfg, c1, 0.0) - w - z * R) / (c1 - z)
            return c1, t1, z, ae, 0.0, R - t1
        # HZ0 (t1 = 0): tc = R0 - d1 c1 and h c1^2 - z d1 c1 + (P0 + w + z R0 - ve) = 0
        if sb < 0.0:
            return nan, nan, nan, nan, nan, nan
        h = 0.5 * (cfg[K1] + cfg[K2P])
        P0 = cfg[VS] - 0.5 * cfg[AS] * cfg[AS] * cfg[K1]
        c1 = _quad_branch(h, -z * d1, P0 + w + z * R0 - ve, sa)
        if not (c1 == c1):
            return nan, nan, nan, nan, nan, nan
        return c1, 0.0, z, ae, 0.0, R0 - d1 * c1
    kz = _kz(cfg)
    kze = _kze(cfg)
    if shape == S2_HH1 or shape == S2_HH3:
        hh1 = shape == S2_HH1
        c1 = u if hh1 else cfg[L1]
        c3 = cfg[L3] if hh1 else u
        F0 = _F(cfg, c1, 0.0)
        E0 = _E(cfg, c3, 0.0)
        if not (M_ZFIRST <= int(cfg[MODE]) <= M_ZBOTH):
            # t1 + t3 = R, c1 t1 + c3 t3 = G
            R = T - (b + d1 * c1 + d3 * c3)
            G = ve - F0 - E0
            if c1 == c3 or sa < 0.0:
                return nan, nan, nan, nan, nan, nan
            t1 = (G - c3 * R) / (c1 - c3)
            return c1, t1, 0.0, c3, R - t1, 0.0
        if c1 == 0.0 or c3 == 0.0:
            return nan, nan, nan, nan, nan, nan
        # t1 = (z^2 kz - F0) / c1, t3 = (ve - z^2 kze - E0) / c3, the duration T
        z = _quad_branch(kz / c1 - kze / c3, dz,
                         b + d1 * c1 + d3 * c3 - F0 / c1 + (ve - E0) / c3 - T, sa)
        if sb < 0.0 or not (z == z):
            return nan, nan, nan, nan, nan, nan
        return c1, (z * z * kz - F0) / c1, z, c3, (ve - z * z * kze - E0) / c3, 0.0
    z = u
    h = 0.5 * (cfg[K1] + cfg[K2P])
    P0 = cfg[VS] - 0.5 * cfg[AS] * cfg[AS] * cfg[K1]  # F(c1, 0) = P0 + h c1^2
    aek = 0.5 * cfg[AE] * cfg[AE] * cfg[K4]
    kc3 = _kc3(cfg)
    sg = cfg[SG2]
    if shape == S2_H1X:
        # c3 from the end velocity (no hold), then c1 (hold t1) from the duration
        if kc3 == 0.0:
            return nan, nan, nan, nan, nan, nan
        q = (z * z * kze + sg * aek - ve) / (sg * kc3)
        if not (q >= 0.0):
            return nan, nan, nan, nan, nan, nan
        c3 = sb * math.sqrt(q)
        c1 = _quad_branch(d1 - h, b + dz * z + d3 * c3 - T, z * z * kz - P0, sa)
        if not (c1 == c1) or c1 == 0.0:
            return nan, nan, nan, nan, nan, nan
        return c1, (z * z * kz - P0 - h * c1 * c1) / c1, z, c3, 0.0, 0.0
    # S2_H3X: c1 from the reversal (no hold), then c3 (hold t3) from the duration
    if h == 0.0:
        return nan, nan, nan, nan, nan, nan
    q = (z * z * kz - P0) / h
    if not (q >= 0.0):
        return nan, nan, nan, nan, nan, nan
    c1 = sa * math.sqrt(q)
    c3 = _quad_branch(d3 + sg * kc3, b + d1 * c1 + dz * z - T, ve - z * z * kze - sg * aek, sb)
    if not (c3 == c3) or c3 == 0.0:
        return nan, nan, nan, nan, nan, nan
    return c1, 0.0, z, c3, (ve - z * z * kze - _E(cfg, c3, 0.0)) / c3, 0.0


@jit_raw
def _h2_cand(cfg, work, kind, shape, u, sa, sb, lin, vd):
    """(c1, t1, z, c3, t3, tc, t0) of a shape of step 2's last stage at ``u`` on
    the sign branch ``(sa, sb)`` (NaN where it has none). ``kind`` 0: the holds
    of :func:`_hold2_unknowns` (``t0`` 0); 1: a step-1 shape (:func:`_unknowns`,
    ``sa``, ``sb`` the signs of its square roots; ``tc`` 0) after a cruise of
    ``t0`` at ``vd`` before ramp 1 or after ramp 4 that fills the duration; 2: a
    hold at a free ``c1 = u`` and ``c3 = ae`` (no ramp 4) with such a cruise, on
    a template without a reversal in ramp 2 (the velocity gives the hold, the
    duration the cruise)."""
    if kind == 0:
        c1, t1, z, c3, t3, tc = _hold2_unknowns(cfg, shape, u, sa, sb, lin)
        return c1, t1, z, c3, t3, tc, 0.0
    if kind == 2:
        if u == 0.0:
            return math.nan, math.nan, math.nan, math.nan, math.nan, math.nan, math.nan
        ae = cfg[AE]
        t1 = (cfg[VE] - _E(cfg, ae, 0.0) - _F(cfg, u, 0.0)) / u
        return u, t1, 0.0, ae, 0.0, 0.0, cfg[TT] - _durations(cfg, work, u, t1, 0.0, ae, 0.0)
    c1, t1, z, c3, t3, _, rz, r3 = _unknowns(cfg, work, shape, u, sa, sb)
    if not (rz >= 0.0 and r3 >= 0.0):
        return math.nan, math.nan, math.nan, math.nan, math.nan, math.nan, math.nan
    return c1, t1, z, c3, t3, 0.0, cfg[TT] - _durations(cfg, work, c1, t1, z, c3, t3)


@jit_raw
def _h2_resid(cfg, work, kind, shape, u, sa, sb, lin, vd):
    """End-position residual of :func:`_h2_cand` (NaN where it has no value)."""
    c1, t1, z, c3, t3, tc, t0 = _h2_cand(cfg, work, kind, shape, u, sa, sb, lin, vd)
    if not (t1 == t1 and t3 == t3 and tc == tc and t0 == t0):
        return math.nan
    return walk(cfg, c1, t1, z, c3, t3, tc)[0] + vd * t0 - cfg[PE]


@jit_raw
def _branch_edge(cfg, work, kind, shape, x0, f0, x1, f1, sa, sb, lin, vd):
    """Where exactly one of ``f0``, ``f1`` is NaN: the end of the branch between
    ``x0`` and ``x1`` by bisection; returns the interval from that end to the
    finite sample, with both values (in the order of ``x0``, ``x1``)."""
    good = x1 if f1 == f1 else x0
    fgood = f1 if f1 == f1 else f0
    bad = x0 if f1 == f1 else x1
    for _ in range(EDGE_STEPS):
        mid = 0.5 * (good + bad)
        if mid == good or mid == bad:
            break
        fm = _h2_resid(cfg, work, kind, shape, mid, sa, sb, lin, vd)
        if fm == fm:
            good = mid
            fgood = fm
        else:
            bad = mid
    if f1 == f1:
        return good, fgood, x1, f1
    return x0, f0, good, fgood


@jit_raw
def _insert_row(buf, n, k, t):
    """Insert a phase of ``t`` at ``a = 0`` (zero jerk) before row ``k`` of ``buf[:n]``."""
    for i in range(n, k, -1):
        buf[i, 0] = buf[i - 1, 0]
        buf[i, 1] = buf[i - 1, 1]
        buf[i, 2] = buf[i - 1, 2]
    buf[k, 0] = t
    buf[k, 1] = 0.0
    buf[k, 2] = 0.0


@jit_raw
def _remove_row(buf, n, k):
    """Undo :func:`_insert_row` (``n`` rows before it)."""
    for i in range(k, n):
        buf[i, 0] = buf[i + 1, 0]
        buf[i, 1] = buf[i + 1, 1]
        buf[i, 2] = buf[i + 1, 2]


@jit_raw
def _delay_at(cfg, pre, npre, suf, nsuf, st, end):
    """Where a cruise can wait at ``a = 0`` in the fixed prefix (``end = 0``: before
    its row ``k``, ``k = npre`` before ramp 1 where it starts at ``a = 0``) or in
    the fixed suffix (``end = 1``: before its row ``k``, ``k = 0`` after ramp 4
    where it ends at ``a = 0``): ``(k, v)`` with the velocity there, ``(-1, 0)``
    where there is no such point or no room for the phase."""
    if end == 0:
        if npre + 1 > NPH:
            return -1, 0.0
        k = npre if cfg[AS] == 0.0 else -1
        for i in range(npre):
            if k < 0 and pre[i, 2] == 0.0:
                k = i
        if k < 0:
            return -1, 0.0
        _, v, _ = integrate(pre, 0, k, st[0], st[1], st[2])
        return k, v
    if nsuf + 1 > NPH:
        return -1, 0.0
    k = 0 if cfg[AE] == 0.0 else -1
    for i in range(nsuf):
        if k < 0 and suf[i, 2] == 0.0:
            k = i
    if k < 0:
        return -1, 0.0
    _, v, _ = integrate(suf, 0, k, cfg[PE], cfg[VE], cfg[AE])
    return k, v


@jit_raw
def _offer_delay(cfg, work, pre, npre, suf, nsuf, c1, t1, z, c3, t3, tc, t0, end, k, sgn, st,
                 lim, best, res, scratch, code):
    """:func:`offer` with a cruise of ``t0`` at ``a = 0`` before row ``k`` of the
    fixed prefix (``end = 0``) or suffix (``end = 1``; none for ``end < 0``)."""
    if end < 0:
        offer(cfg, work, pre, npre, suf, nsuf, c1, t1, z, c3, t3, tc, sgn, st, lim, best, res,
              scratch, code)
    elif end == 0:
        _insert_row(pre, npre, k, t0)
        offer(cfg, work, pre, npre + 1, suf, nsuf, c1, t1, z, c3, t3, tc, sgn, st, lim, best,
              res, scratch, code)
        _remove_row(pre, npre, k)
    else:
        _insert_row(suf, nsuf, k, t0)
        offer(cfg, work, pre, npre, suf, nsuf + 1, c1, t1, z, c3, t3, tc, sgn, st, lim, best,
              res, scratch, code)
        _remove_row(suf, nsuf, k)


@jit_raw
def _scan(cfg, work, kind, shape, lo, hi, sa, sb, lin, vd, end, kd, pre, npre, suf, nsuf, sgn,
          st, lim, best, res, scratch, code):
    """The roots of one sign branch of a shape of step 2's last stage on ``[lo,
    hi]``: the exact residual sampled at :data:`HOLD2_SAMPLES` points, a branch
    end between two samples found by bisection, each sign change refined by
    regula falsi (Illinois) and offered. True when a profile was found."""
    tol = POLISH_RTOL * (abs(cfg[PE] - cfg[PS]) + abs(cfg[VS]) + abs(cfg[VE]) + 1e-300)
    eps = -PLAUSIBLE_RTOL * (1.0 + abs(cfg[TT]))
    x0 = lo
    f0 = _h2_resid(cfg, work, kind, shape, x0, sa, sb, lin, vd)
    for i in range(1, HOLD2_SAMPLES):
        x1 = lo + (hi - lo) * i / (HOLD2_SAMPLES - 1)
        f1 = _h2_resid(cfg, work, kind, shape, x1, sa, sb, lin, vd)
        a, fa, b, fb = x0, f0, x1, f1
        if (f0 == f0) != (f1 == f1):
            # the branch ends between the samples (a radicand crosses zero, where
            # two branches meet): its last value is the bracket's end
            a, fa, b, fb = _branch_edge(cfg, work, kind, shape, x0, f0, x1, f1, sa, sb, lin, vd)
        if fa == fa and fb == fb and (fa == 0.0 or fa * fb < 0.0):
            x = a
            if fa != 0.0:
                side = 0
                for _ in range(BRANCH_ROOT_ITER):
                    x = (a * fb - b * fa) / (fb - fa)
                    if not (a < x < b):
                        x = 0.5 * (a + b)
                        if not (a < x < b):
                            break
                    fx = _h2_resid(cfg, work, kind, shape, x, sa, sb, lin, vd)
                    if abs(fx) <= tol or not (fx == fx):
                        break
                    a, fa, b, fb, side = illinois(x, fx, a, fa, b, fb, side)
            c1, t1, z, c3, t3, tc, t0 = _h2_cand(cfg, work, kind, shape, x, sa, sb, lin, vd)
            if (t1 == t1 and t3 == t3 and tc == tc and t0 >= eps
                    and _plausible(cfg, c1, t1, c3, t3, tc)):
                _offer_delay(cfg, work, pre, npre, suf, nsuf, c1, t1, z, c3, t3, max(tc, 0.0),
                             max(t0, 0.0), end, kd, sgn, st, lim, best, res, scratch, code)
                if res[R_T] < math.inf:
                    return True
        x0 = x1
        f0 = f1
    return False


@jit_raw
def _hold2(cfg, work, pre, npre, suf, nsuf, sgn, st, lim, best, res, scratch):
    """Step 2's last stage on one template: the holds the earlier stages leave out.

    A hold at a free ``c1`` together with the hold at ``c3 = L3`` (and the
    mirror case), and the holds at a free level of ramp 2 through a velocity
    reversal (the leg changes inside ramp 2). Each shape has one parameter
    ``u`` (``c1``, ``c3`` or the reversal acceleration ``z``) and up to two
    sign branches, each scanned on the exact residual (:func:`_scan`).
    """
    cross = M_ZFIRST <= int(cfg[MODE]) <= M_ZBOTH
    for shape in range(S2_HH1, S2_H3X + 1):
        if not cross and shape >= S2_H1X:
            continue
        if shape == S2_HH1:
            if not (abs(cfg[L3]) < math.inf) or cfg[L3] == 0.0:
                continue
            lo, hi = cfg[C1LO], cfg[C1HI]
            code = C_HH1
        elif shape == S2_HH3:
            if not (abs(cfg[L1]) < math.inf) or cfg[L1] == 0.0:
                continue
            lo, hi = cfg[C3LO], cfg[C3HI]
            code = C_HH3
        else:
            lo, hi = min(cfg[C3LO], 0.0), max(cfg[C1HI], 0.0)
            code = S2_H1 if shape == S2_H1X else S2_H3
        if not (abs(lo) < math.inf and abs(hi) < math.inf and hi > lo):
            continue
        lin = _ramp_time(cfg, work)
        for br in range(4):
            sa = 1.0 if br % 2 == 0 else -1.0
            sb = 1.0 if br < 2 else -1.0
            if (shape == S2_HH1 or shape == S2_HH3) and sb < 0.0:
                continue
            if (shape == S2_HH1 or shape == S2_HH3) and not cross and sa < 0.0:
                continue
            if _scan(cfg, work, 0, shape, lo, hi, sa, sb, lin, 0.0, -1, 0, pre, npre, suf, nsuf,
                     sgn, st, lim, best, res, scratch, code):
                return
    if int(cfg[MODE]) == M_ZSINGLE and cfg[K2N] == cfg[K2Q]:
        _hold_mid(cfg, work, pre, npre, suf, nsuf, sgn, st, lim, best, res, scratch)


@jit_raw
def _hold_mid(cfg, work, pre, npre, suf, nsuf, sgn, st, lim, best, res, scratch):
    """The holds at a level ``z`` of ramp 2 with the velocity reversal inside (HZ1,
    HZ0, HZ2) of a one-run template (mode ``M_ZSINGLE``): ``c1 -> z`` on the
    slowing leg, the hold, ``z -> c3 = ae`` on the speeding leg (``K2N``, which
    equals ``K2Q`` there), no ramp 4. The hold lies on both legs: ``|z|`` at
    most the smaller acceleration limit, between ``ae`` and ramp 1's top (HZ2:
    at that limit, with a hold at a free ``c1``). Each has one parameter and
    closed-form unknowns (:func:`_hold2_unknowns`), scanned on the exact
    residual (:func:`_scan`)."""
    Am = min(lim[1], lim[3])
    lo = max(-Am, min(cfg[AE], cfg[C1LO]))
    hi = min(Am, max(cfg[AE], cfg[C1HI]))
    if not (hi > lo):
        return
    mode = cfg[MODE]
    l3 = cfg[L3]
    cfg[MODE] = M_MID
    cfg[L3] = math.copysign(Am, cfg[L1])  # HZ2's level
    lin = _ramp_time(cfg, work)
    for shape in (S2_HZ1, S2_HZ0, S2_HZ2):
        if shape == S2_HZ1 and not (abs(cfg[L1]) < math.inf and cfg[L1] != 0.0):
            continue
        code = S2_MH2 if shape == S2_HZ1 else (S2_MH1 if shape == S2_HZ0 else C_HH1)
        u_lo, u_hi = (cfg[C1LO], cfg[C1HI]) if shape == S2_HZ2 else (lo, hi)
        if not (abs(u_lo) < math.inf and abs(u_hi) < math.inf and u_hi > u_lo):
            continue
        for br in range(2 if shape == S2_HZ0 else 1):
            sa = 1.0 if br == 0 else -1.0
            if _scan(cfg, work, 0, shape, u_lo, u_hi, sa, 1.0, lin, 0.0, -1, 0, pre, npre, suf,
                     nsuf, sgn, st, lim, best, res, scratch, code):
                cfg[MODE] = mode
                cfg[L3] = l3
                return
    cfg[MODE] = mode
    cfg[L3] = l3


@jit_raw
def _delay_cruise(cfg, work, pre, npre, suf, nsuf, sgn, st, lim, best, res, scratch, end):
    """Step 2's two cruises on one template: a cruise of ``t0`` where the fixed
    prefix passes ``a = 0`` or ramp 1 starts there (``end = 0``; in the fixed
    suffix or at the end of ramp 4 for ``end = 1``, :func:`_delay_at`) and the
    cruise ``tc`` of ramp 2 at ``vc``.

    For a corner ``c1`` (``c3`` from the end velocity, both sign branches) the
    durations and the end position are linear in ``t0`` and ``tc``: ``t0 + tc
    = T - T_ramps`` and ``v0 t0 + vc tc = p_e - p_ramps``. The corners form a
    one-parameter family of such profiles (nothing left to solve for), so
    :data:`HOLD2_SAMPLES` values of ``c1`` are tried, each with non-negative
    ``t0`` and ``tc`` offered (the exact check decides).
    """
    kd, vd = _delay_at(cfg, pre, npre, suf, nsuf, st, end)
    if kd < 0:
        return
    lo, hi = cfg[C1LO], cfg[C1HI]
    if not (abs(lo) < math.inf and abs(hi) < math.inf and hi > lo) or _kc3(cfg) <= 0.0:
        return
    cross = M_ZFIRST <= int(cfg[MODE]) <= M_ZBOTH
    T = cfg[TT]
    rho = _rho1(cfg)
    g = _g(cfg)
    sg = cfg[SG2]
    aek = 0.5 * cfg[AE] * cfg[AE] * cfg[K4]
    eps = -PLAUSIBLE_RTOL * (1.0 + abs(T))
    for i in range(HOLD2_SAMPLES):
        c1 = lo + (hi - lo) * (i + 0.5) / HOLD2_SAMPLES
        F = _F(cfg, c1, 0.0)
        vc = rho * F
        if vc == vd:
            continue
        z = 0.0
        if cross:
            rz = F / _kz(cfg)
            if not (rz >= 0.0):
                continue
            z = cfg[SZ] * math.sqrt(rz)
        r3 = (g * vc + sg * aek - cfg[VE]) / (sg * _kc3(cfg))
        if not (r3 >= 0.0):
            continue
        for b in range(2):
            s3 = 1.0 if b == 0 else -1.0
            if cfg[S3] != 0.0 and s3 != cfg[S3]:
                continue
            c3 = s3 * math.sqrt(r3)
            p0, t_r = walk(cfg, c1, 0.0, z, c3, 0.0, 0.0)
            R = T - t_r
            t0 = (cfg[PE] - p0 - vc * R) / (vd - vc)
            tc = R - t0
            if not (t0 >= eps and tc >= eps and _plausible(cfg, c1, 0.0, c3, 0.0, tc)):
                continue
            _offer_delay(cfg, work, pre, npre, suf, nsuf, c1, 0.0, z, c3, 0.0, tc, max(t0, 0.0),
                         end, kd, sgn, st, lim, best, res, scratch, C_DC)
            if res[R_T] < math.inf:
                return


@jit_raw
def _delay_hold(cfg, work, pre, npre, suf, nsuf, sgn, st, lim, best, res, scratch, end):
    """A cruise at the start's velocity before ramp 1 (``end = 0``) or the goal's
    after ramp 4 (``end = 1``) with a hold at a free ``c1`` and ``c3 = ae`` (no
    ramp 4; with a hypothesis of a reversal inside the hold at ``c1``, the
    velocity reverses there): one parameter ``c1``, scanned on the exact
    residual (:func:`_scan`, kind 2)."""
    kd, vd = _delay_at(cfg, pre, npre, suf, nsuf, st, end)
    lo, hi = cfg[C1LO], cfg[C1HI]
    if kd < 0 or not (abs(lo) < math.inf and abs(hi) < math.inf and hi > lo):
        return
    _scan(cfg, work, 2, 0, lo, hi, 1.0, 1.0, _ramp_time(cfg, work), vd, end, kd, pre, npre, suf,
          nsuf, sgn, st, lim, best, res, scratch, C_DS)


@jit_raw
def _delay_step1(cfg, work, pre, npre, suf, nsuf, sgn, st, lim, best, res, scratch, end):
    """Step 2 on one template: a cruise that fills the duration where the fixed
    prefix passes ``a = 0`` or ramp 1 starts there (``end = 0``; in the fixed
    suffix or at the end of ramp 4 for ``end = 1``, :func:`_delay_at`), and a
    shape of step 1 (none, acc0, acc1, acc0_acc1: :func:`_unknowns`), its
    parameter scanned on the exact residual (:func:`_scan`; reported as
    ``C_DS``)."""
    kd, vd = _delay_at(cfg, pre, npre, suf, nsuf, st, end)
    if kd < 0:
        return
    cross = M_ZFIRST <= int(cfg[MODE]) <= M_ZBOTH
    lin = (0.0, 0.0, 0.0, 0.0)
    for shape in range(S_NONE, S_ACC01 + 1):
        if (shape == S_ACC0 or shape == S_ACC01) and not (abs(cfg[L1]) < math.inf
                                                           and cfg[L1] != 0.0):
            continue
        if (shape == S_ACC1 or shape == S_ACC01) and not (abs(cfg[L3]) < math.inf
                                                           and cfg[L3] != 0.0):
            continue
        if shape == S_NONE and _kc3(cfg) <= 0.0:
            continue
        lo, hi = _domain0(cfg, shape)
        if not (abs(lo) < math.inf and abs(hi) < math.inf and hi > lo):
            continue
        for b in range(2):
            s3 = 1.0 if b == 0 else -1.0
            if b == 1 and shape != S_NONE:
                continue
            if shape == S_NONE and cfg[S3] != 0.0 and s3 != cfg[S3]:
                continue
            if _scan(cfg, work, 1, shape, lo, hi, cfg[SZ] if cross else 1.0, s3, lin, vd, end,
                     kd, pre, npre, suf, nsuf, sgn, st, lim, best, res, scratch, C_DS):
                return


@jit_raw
def solve_shape(cfg, work, shape, pre, npre, suf, nsuf, sgn, st, lim, best, res, scratch,
                vals, coef, roots, ivl, dscr):
    """Every root of one shape of one template, each offered as a candidate."""
    lo, hi = _domain(cfg, shape)
    mode = int(cfg[MODE])
    cross = M_ZFIRST <= mode <= M_ZBOTH
    if S2_MH1 <= shape <= S2_JF:
        pass
    elif S2_NN <= shape <= S2_JF:
        if shape <= S2_AA and (mode == M_SINGLE or mode == M_ZSINGLE):
            return  # a cruise needs ramp 2 through a = 0
        if shape >= S2_H1 and cross:
            return
    if shape == S_ACC0 or shape == S_ACC01 or shape == S2_AN or shape == S2_AA:
        if not (abs(cfg[L1]) < math.inf) or cfg[L1] == 0.0:
            return
    if shape == S_ACC1 or shape == S_ACC01 or shape == S2_NA or shape == S2_AA:
        if not (abs(cfg[L3]) < math.inf) or cfg[L3] == 0.0:
            return
    if (shape == S_NONE or shape == S2_NN or shape == S2_H1) and _kc3(cfg) <= 0.0:
        return
    if shape == S_NONEW and not (cfg[K1] > 0.0):
        return
    if shape == S2_H3 and not (cfg[K1] + cfg[K2P] > 0.0):
        return
    if not (hi >= lo) or not (abs(lo) < math.inf and abs(hi) < math.inf):
        return
    nrad = _nrad(cfg, shape)
    deg = _degree(cfg, shape)
    if nrad == 0 and not (shape == S2_MH2 or shape == S2_MH4):
        ivl[0, 0] = lo
        ivl[0, 1] = hi
        ni = 1
    else:
        ni = _intervals(cfg, work, shape, lo, hi, ivl, dscr[0])
    for iv in range(ni):
        a = ivl[iv, 0]
        b = ivl[iv, 1]
        if b - a <= 1e-13 * max(abs(a), abs(b), 1e-300):
            roots[0] = 0.0
            _offer_roots(cfg, work, shape, pre, npre, suf, nsuf, sgn, st, lim, best, res,
                         scratch, roots, 1, 0.5 * (a + b), 0.0, a, b)
            if res[R_STOP] > 0.0 or (S2_NN <= shape <= S2_JF and res[R_T] < math.inf):
                return
            continue
        if S2_NN <= shape <= S2_AA and mode == M_ZERO:
            # step 2 needs one valid root: first the one that a sign change of
            # the valid branch's exact residual brackets (then every root)
            # (ramp c1 -> 0 needs c1 >= 0; above it the cruise velocity grows with u)
            u = _branch_root(cfg, work, shape, max(a, 0.0) if shape == S2_NN or shape == S2_NA
                             else a, b, cfg[S3] if cfg[S3] != 0.0 else -cfg[SG2])
            if u == u:
                roots[0] = 0.0
                _offer_roots(cfg, work, shape, pre, npre, suf, nsuf, sgn, st, lim, best, res,
                             scratch, roots, 1, u, 0.0, a, b)
                if res[R_T] < math.inf:
                    return
        # the whole interval, then (where N nearly vanishes at an end, i.e. a
        # root may sit within round-off of it) ever smaller pieces at that end
        zoom_lo = False
        zoom_hi = False
        for side in range(3):
            if (side == 1 and not zoom_lo) or (side == 2 and not zoom_hi):
                continue
            za = a
            zb = b
            for level in range(ZOOM_LEVELS + 1):
                if side == 0 and level > 0:
                    break
                if side > 0 and level == 0:
                    continue
                if side == 1:
                    zb = za + (b - a) * ZOOM_FACTOR ** level
                elif side == 2:
                    za = zb - (b - a) * ZOOM_FACTOR ** level
                mid = 0.5 * (za + zb)
                half = 0.5 * (zb - za)
                nn = deg + 1
                for k in range(nn):
                    vals[k] = _norm(cfg, work, shape, mid + half * NODES[nn, k], nrad)
                interp_unit(vals, nn, coef)
                nr = real_roots_unit(coef, deg, roots, dscr)
                _offer_roots(cfg, work, shape, pre, npre, suf, nsuf, sgn, st, lim, best, res,
                             scratch, roots, nr, mid, half, a, b)
                if res[R_STOP] > 0.0 or (S2_NN <= shape <= S2_JF and res[R_T] < math.inf):
                    return
                if side == 0:
                    # which ends need a closer look
                    tot = 0.0
                    e_lo = 0.0
                    e_hi = 0.0
                    sg = 1.0
                    for k in range(nn):
                        tot += abs(coef[k])
                        e_hi += coef[k]
                        e_lo += sg * coef[k]
                        sg = -sg
                    # (an exact zero at the end is a root there, found above)
                    zoom_lo = (abs(e_lo) <= ZOOM_RTOL * tot
                               and _norm(cfg, work, shape, a, nrad) != 0.0)
                    zoom_hi = (abs(e_hi) <= ZOOM_RTOL * tot
                               and _norm(cfg, work, shape, b, nrad) != 0.0)
                else:
                    tot = 0.0
                    e = 0.0
                    sg = 1.0
                    for k in range(nn):
                        tot += abs(coef[k])
                        e += (sg if side == 1 else 1.0) * coef[k]
                        sg = -sg
                    if not (abs(e) <= ZOOM_RTOL * tot):
                        break


@jit_raw
def _offer_roots(cfg, work, shape, pre, npre, suf, nsuf, sgn, st, lim, best, res, scratch,
                 roots, nr, mid, half, a, b):
    """Offer the candidate of every root ``mid + half * roots[i]`` (all sign branches)."""
    mode = int(cfg[MODE])
    cross = M_ZFIRST <= mode <= M_ZBOTH
    szs = cfg[SZ]
    s3s = cfg[S3]
    for i in range(nr):
        u0 = mid + half * roots[i]
        for isz in range(2):
            sz = 1.0 if isz == 0 else -1.0
            if cross and sz != szs:
                continue
            if not cross and isz == 1:
                continue
            for is3 in range(2):
                s3 = 1.0 if is3 == 0 else -1.0
                if shape == S_NONE or shape == S2_NN:
                    if s3s != 0.0 and s3 != s3s:
                        continue
                elif not (shape == S2_H1 or shape == S2_H3 or shape == S2_MH1
                          or shape == S2_MH3 or shape == S2_JF) and is3 == 1:
                    continue
                c1, t1, z, c3, t3, tc, _, _ = _unknowns(cfg, work, shape, u0, sz, s3)
                if not _plausible(cfg, c1, t1, c3, t3, tc):
                    continue
                if S2_NN <= shape <= S2_AA and mode == M_ZERO and not _plausible_cruise(cfg, c1,
                                                                                        c3):
                    continue
                u, _ = _polish(cfg, work, shape, u0, sz, s3, a, b)
                c1, t1, z, c3, t3, tc, _, _ = _unknowns(cfg, work, shape, u, sz, s3)
                offer(cfg, work, pre, npre, suf, nsuf, c1, t1, z, c3, t3, tc, sgn, st, lim,
                      best, res, scratch, shape)
                if res[R_STOP] > 0.0:
                    return
                if S2_NN <= shape <= S2_JF and res[R_T] < math.inf:
                    return


@jit_raw
def solve_vel(cfg, work, pre, npre, suf, nsuf, sgn, st, lim, best, res, scratch):
    """Shapes with a cruise at v_max (VEL, ACC0_VEL, ACC1_VEL, ACC0_ACC1_VEL)."""
    V = cfg[VM]
    mode = int(cfg[MODE])
    if not (V < math.inf) or mode == M_SINGLE or mode == M_ZSINGLE:
        return
    k1 = cfg[K1]
    k2p = cfg[K2P]
    kc3 = _kc3(cfg)
    a_s = cfg[AS]
    z = 0.0
    # first half: F(c1, t1) = target (V, or z^2 kz with the reversal before the cruise)
    tgt = V
    if mode == M_ZFIRST or mode == M_ZBOTH:
        if cfg[K2Q] <= 0.0:
            return
        z = math.sqrt(2.0 * V / cfg[K2Q])
        tgt = z * z * _kz(cfg)
    # second half: E(c3, t3) = ve - V (or ve - z2^2 K/2 with the reversal after it)
    etgt = cfg[VE] - V
    if mode == M_ZSECOND or mode == M_ZBOTH:
        if cfg[K2N] <= 0.0:
            return
        z2sq = 2.0 * V / cfg[K2N]
        if mode == M_ZSECOND:
            z = -math.sqrt(z2sq)
            etgt = cfg[VE] - z2sq * 0.5 * cfg[K2Q]
        else:
            etgt = cfg[VE] - z2sq * 0.5 * cfg[K2R]
    g1 = tgt - cfg[VS] + 0.5 * a_s * a_s * k1
    e_af = 0.5 * cfg[AE] * cfg[AE] * cfg[K4]
    for h1 in range(2):
        if h1 == 0:
            den = 0.5 * (k1 + k2p)
            if not (den > 0.0) or g1 < 0.0:
                continue
            c1 = math.sqrt(g1 / den)
            t1 = 0.0
        else:
            c1 = cfg[L1]
            if not (abs(c1) < math.inf) or c1 <= 0.0:
                continue
            t1 = (g1 - 0.5 * c1 * c1 * (k1 + k2p)) / c1
            if t1 < 0.0:
                continue
        for h2 in range(2):
            if h2 == 0:
                if not (kc3 > 0.0):
                    continue
                x = (e_af - etgt) / kc3
                if x < 0.0:
                    continue
                c3 = -math.sqrt(x)
                t3 = 0.0
            else:
                c3 = cfg[L3]
                if not (abs(c3) < math.inf) or c3 >= 0.0:
                    continue
                t3 = (etgt - e_af + c3 * c3 * kc3) / c3
                if t3 < 0.0:
                    continue
            p, _ = walk(cfg, c1, t1, z, c3, t3, 0.0)
            tc = (cfg[PE] - p) / V
            if tc < 0.0:
                continue
            offer(cfg, work, pre, npre, suf, nsuf, c1, t1, z, c3, t3, tc, sgn, st, lim, best, res,
                  scratch, 4 + h1 + 2 * h2)


@jit_raw
def solve_velocity(cfg, work, pre, npre, suf, nsuf, sgn, st, lim, best, res, scratch):
    """Velocity interface (position free): ramp 4 and hold 3 absent (c3 = a_e), the
    peak c1 (or the hold at it) from the velocity equation, in closed form."""
    c3 = cfg[AE]
    if c3 > cfg[C3HI] or c3 < cfg[C3LO]:
        return
    mode = int(cfg[MODE])
    cross = mode >= M_ZFIRST
    e0 = _E(cfg, c3, 0.0)
    if cross:
        kze = _kze(cfg)
        rz = (cfg[VE] - e0) / kze if kze > 0.0 else -1.0
        if rz < 0.0:
            return
        z = cfg[SZ] * math.sqrt(rz)
        ftgt = rz * _kz(cfg)
    else:
        z = 0.0
        ftgt = cfg[VE] - e0
    base = cfg[VS] - 0.5 * cfg[AS] * cfg[AS] * cfg[K1]
    den = 0.5 * (cfg[K1] + cfg[K2P])
    for h in range(3):
        t1 = 0.0
        if h < 2:
            if not (den > 0.0):
                continue
            x = (ftgt - base) / den
            if x < 0.0:
                continue
            c1 = math.sqrt(x) if h == 0 else -math.sqrt(x)
            if h == 1 and x == 0.0:
                continue
        else:
            c1 = cfg[L1]
            if not (abs(c1) < math.inf) or c1 == 0.0:
                continue
            t1 = (ftgt - base - den * c1 * c1) / c1
            if t1 <= 0.0:
                continue
        tol = 1e-12 * max(abs(cfg[C1LO]), abs(cfg[C1HI]), abs(c1))
        if c1 < cfg[C1LO] - tol or c1 > cfg[C1HI] + tol:
            continue
        offer(cfg, work, pre, npre, suf, nsuf, c1, t1, z, c3, 0.0, 0.0, sgn, st, lim, best, res,
              scratch, 8 if h < 2 else 9)


@jit_raw
def _cruise_shape(i, hint):
    """The ``i``-th cruise shape (S2_NN..S2_AA) to try: ``hint`` first, then the
    others in their order."""
    if i == 0:
        return hint
    shape = S2_NN + i - 1
    return shape + 1 if shape >= hint else shape


@jit_raw
def solve_template(cfg, W, vec, ivl, npre, nsuf, sgn, st, lim, best, res):
    """Every shape of one template instance."""
    work = W[0]
    pre = W[1]
    suf = W[2]
    scratch = W[3]
    if st[3] != st[3]:  # velocity interface
        solve_velocity(cfg, work, pre, npre, suf, nsuf, sgn, st, lim, best, res, scratch)
        return
    if cfg[TT] == cfg[TT]:  # step 2: exactly T
        stage = int(res[R_STAGE])
        if stage == STAGE_CRUISE or stage == STAGE_HOLD:
            hint = int(res[R_HINT])
            for i in range(4 if stage == STAGE_CRUISE else 2):
                shape = _cruise_shape(i, hint) if stage == STAGE_CRUISE else S2_H1 + i
                solve_shape(cfg, work, shape, pre, npre, suf, nsuf, sgn, st, lim, best, res,
                            scratch, vec[0], vec[1], vec[2], ivl, vec[3:])
                if res[R_T] < math.inf:
                    return
            return
        if stage == STAGE_INFLECTION and int(cfg[MODE]) == M_ZERO:
            # the cruise at an inflection (UDUD): the second half a bump up again,
            # at the tighter of both legs' limits
            save = cfg[NCFG:]
            for k in range(NCFG):
                save[k] = cfg[k]
            cfg[SG2] = -1.0
            Km = max(lim[2], lim[4])
            Am = min(lim[1], lim[3])
            cfg[K2N] = Km
            cfg[K4] = Km
            cfg[L3] = Am
            cfg[C3LO] = max(cfg[AE], 0.0)
            cfg[C3HI] = Am
            cfg[S3] = 1.0
            hint = int(res[R_HINT])
            for i in range(4):
                shape = _cruise_shape(i, hint)
                solve_shape(cfg, work, shape, pre, npre, suf, nsuf, sgn, st, lim, best, res,
                            scratch, vec[0], vec[1], vec[2], ivl, vec[3:])
                if res[R_T] < math.inf:
                    break
            for k in range(NCFG):
                cfg[k] = save[k]
            return
        mode = int(cfg[MODE])
        if stage == STAGE_HOLD2:
            if mode != M_MID:
                _hold2(cfg, work, pre, npre, suf, nsuf, sgn, st, lim, best, res, scratch)
            for end in range(2):
                if mode != M_MID and mode != M_SINGLE and mode != M_ZSINGLE and not (
                        res[R_T] < math.inf):
                    _delay_cruise(cfg, work, pre, npre, suf, nsuf, sgn, st, lim, best, res,
                                  scratch, end)
                if mode != M_MID and not (res[R_T] < math.inf):
                    _delay_step1(cfg, work, pre, npre, suf, nsuf, sgn, st, lim, best, res,
                                 scratch, end)
                if (mode == M_SINGLE or mode == M_ZERO) and not (res[R_T] < math.inf):
                    _delay_hold(cfg, work, pre, npre, suf, nsuf, sgn, st, lim, best, res,
                                scratch, end)
            return
        if stage == STAGE_EQUAL and mode == M_ZERO and (
                cfg[S3] == 0.0 or (cfg[K1] == max(lim[2], lim[4]) and cfg[K4] == cfg[K1])):
            # equal jerk on every ramp, at the tighter of both legs' limits
            save = cfg[NCFG:]
            for k in range(NCFG):
                save[k] = cfg[k]
            Km = max(lim[2], lim[4])
            Am = min(lim[1], lim[3])
            cfg[K1] = Km
            cfg[K2P] = Km
            cfg[K2N] = Km
            cfg[K4] = Km
            cfg[L1] = Am
            cfg[L3] = -Am
            cfg[SG2] = 1.0
            cfg[MODE] = M_MID
            for shape in range(S2_MH1, S2_MH4 + 1):
                solve_shape(cfg, work, shape, pre, npre, suf, nsuf, sgn, st, lim, best, res,
                            scratch, vec[0], vec[1], vec[2], ivl, vec[3:])
                if res[R_T] < math.inf:
                    break
            if not (res[R_T] < math.inf):
                cfg[MODE] = M_SINGLE
                solve_shape(cfg, work, S2_JF, pre, npre, suf, nsuf, sgn, st, lim, best, res,
                            scratch, vec[0], vec[1], vec[2], ivl, vec[3:])
            for k in range(NCFG):
                cfg[k] = save[k]
        return
    solve_vel(cfg, work, pre, npre, suf, nsuf, sgn, st, lim, best, res, scratch)
    equal = cfg[S3] == 0.0  # the template with equal jerks everywhere
    for shape in range(4):
        if res[R_STOP] > 0.0:
            return
        if shape == S_NONE and equal:
            shape = S_NONEW
        solve_shape(cfg, work, shape, pre, npre, suf, nsuf, sgn, st, lim, best, res, scratch,
                    vec[0], vec[1], vec[2], ivl, vec[3:])


# ------------------------------------------------------------------ legs
@jit_raw
def _push(buf, n, x, y, K):
    """Append an up-ramp x -> y at jerk 1/K (nothing for an infinite jerk)."""
    if K == 0.0:
        return n
    buf[n, 0] = (y - x) * K
    buf[n, 1] = 1.0 / K
    buf[n, 2] = x
    return n + 1


@jit_raw
def _az_from_start(x, v, K, sign):
    """Acceleration where an up-ramp from (v, x) at 1/K reaches v = 0 (or nan)."""
    if K == 0.0:
        return math.nan
    r = x * x - 2.0 * v / K
    if r < 0.0:
        return math.nan
    return sign * math.sqrt(r)


@jit_raw
def _az_from_end(y, ve, K, sign):
    """Acceleration where an up-ramp ending at (ve, y) at 1/K had v = 0 (or nan)."""
    if K == 0.0:
        return math.nan
    r = y * y - 2.0 * ve / K
    if r < 0.0:
        return math.nan
    return sign * math.sqrt(r)


@jit_raw
def _prefix_a(pre, p0, v0, a0, K1_, K2_):
    """The a < 0 part of ramp 1 (a0 -> 0, jerk +), exact through a reversal.

    Returns (n, p, v) at its end (a = 0).
    """
    n = 0
    if v0 > 0.0:
        az = _az_from_start(a0, v0, K2_, -1.0)
        if az == az and az > a0:
            n = _push(pre, n, a0, az, K2_)
            n = _push(pre, n, az, 0.0, K1_)
        else:
            n = _push(pre, n, a0, 0.0, K2_)
    else:
        n = _push(pre, n, a0, 0.0, K1_)
    p, v, _ = integrate(pre, 0, n, p0, v0, a0)
    return n, p, v


@jit_raw
def _suffix_d(suf, pf, vf, af, K1_, K2_):
    """The a > 0 part of ramp 4 (0 -> af, jerk +), exact through a reversal.

    Returns (n, p, v): the state (a = 0) where it starts.
    """
    n = 0
    if vf <= 0.0:
        n = _push(suf, n, 0.0, af, K2_)
    else:
        az = _az_from_end(af, vf, K1_, 1.0)
        if az == az and az > 0.0:
            n = _push(suf, n, 0.0, az, K2_)
            n = _push(suf, n, az, af, K1_)
        else:
            n = _push(suf, n, 0.0, af, K1_)
    return _before(suf, 0, n, pf, vf)


@jit_raw
def _before(buf, n0, n, pe, ve):
    """State (p, v) from which phases n0..n-1 end at (pe, ve)."""
    dv = 0.0
    for k in range(n0, n):
        t = buf[k, 0]
        dv += t * (buf[k, 2] + 0.5 * t * buf[k, 1])
    vb = ve - dv
    p, _, _ = integrate(buf, n0, n, 0.0, vb, 0.0)
    return n, pe - p, vb


@jit_raw
def _copy(dst, n0, src, m):
    for k in range(m):
        dst[n0 + k, 0] = src[k, 0]
        dst[n0 + k, 1] = src[k, 1]
        dst[n0 + k, 2] = src[k, 2]
    return n0 + m


@jit_raw
def _setcfg(cfg, ps, vs, as_, pe, ve, ae, k1, k2p, k2n, k2q, k4, mode, l1, l3, vm, c1lo, c1hi,
            c3lo, c3hi, s3, sz, k2r):
    cfg[PS] = ps
    cfg[VS] = vs
    cfg[AS] = as_
    cfg[PE] = pe
    cfg[VE] = ve
    cfg[AE] = ae
    cfg[K1] = k1
    cfg[K2P] = k2p
    cfg[K2N] = k2n
    cfg[K2Q] = k2q
    cfg[K4] = k4
    cfg[MODE] = mode
    cfg[L1] = l1
    cfg[L3] = l3
    cfg[VM] = vm
    cfg[C1LO] = c1lo
    cfg[C1HI] = c1hi
    cfg[C3LO] = c3lo
    cfg[C3HI] = c3hi
    cfg[S3] = s3
    cfg[SZ] = sz
    cfg[K2R] = k2r
    cfg[SG2] = 1.0


@jit_raw
def _c1_bound(V, vs, as_, k1):
    """Largest c1 >= 0 whose ramp from ``as_`` keeps v <= V (inf when unbounded)."""
    if not (V < math.inf) or k1 == 0.0:
        return math.inf
    x = 2.0 * (V - vs) / k1 + as_ * as_
    return math.sqrt(x) if x > 0.0 else 0.0


@jit_raw
def _c3_bound(V, ve, ae, k4):
    """Largest |c3| whose ramp to ``ae`` keeps |v| <= V before it."""
    if not (V < math.inf) or k4 == 0.0:
        return math.inf
    x = 2.0 * (V - ve) / k4 + ae * ae
    return math.sqrt(x) if x > 0.0 else 0.0


@jit_raw
def _solve(cfg, W, vec, ivl, npre, nsuf, sgn, st, lim, best, res):
    T = st[6]
    if T == T:
        if res[R_T] < math.inf:
            return  # step 2: one profile of the duration is enough
        # the template lasts what the fixed prefix and suffix leave
        for k in range(npre):
            T -= W[1][k, 0]
        for k in range(nsuf):
            T -= W[2][k, 0]
        if not (T >= 0.0):
            return
    cfg[TT] = T
    solve_template(cfg, W, vec, ivl, npre, nsuf, sgn, st, lim, best, res)



@jit_raw
def _hold_push(buf, n, a, t):
    buf[n, 0] = t
    buf[n, 1] = 0.0
    buf[n, 2] = a
    return n + 1


@jit_raw
def _down(buf, n, x, y, K):
    """Append a down-ramp x -> y at jerk -1/K (nothing for an infinite jerk)."""
    if K == 0.0:
        return n
    buf[n, 0] = (x - y) * K
    buf[n, 1] = -1.0 / K
    buf[n, 2] = x
    return n + 1


@jit_raw
def _hold_prefix(pre, npre, ps, vs, as_, A1, K1_, A2, K2_):
    """A reversal at the top of a rising run (a > 0, v < 0 -> v > 0) where the
    acceleration limit changes from ``A2`` (slowing) to ``A1`` (speeding).

    The part up to the reversal (all slowing, at ``K2``) ends at ``v = 0`` with
    ``a = min(A1, A2)``: with ``A1 >= A2`` a ramp to ``A2`` and a hold there;
    with ``A1 < A2`` a ramp up to a peak (held at ``A2`` when reached) and
    down to ``A1``. Returns (ok, n, p, a_end).
    """
    if as_ > A2 or K2_ == 0.0:
        return False, npre, ps, as_
    n0 = npre
    if A1 >= A2:
        if not (A2 < math.inf):
            return False, npre, ps, as_
        vr = vs + 0.5 * (A2 * A2 - as_ * as_) * K2_
        ta = -vr / A2
        if not (ta >= 0.0):
            return False, npre, ps, as_
        npre = _push(pre, npre, as_, A2, K2_)
        npre = _hold_push(pre, npre, A2, ta)
        aend = A2
    else:
        # peak c: vs + (c^2 - as^2) K2/2 + (c^2 - A1^2) K2/2 = 0
        c2 = 0.5 * (as_ * as_ + A1 * A1) - vs / K2_
        c = math.sqrt(c2) if c2 > 0.0 else 0.0
        if c < as_ or c < A1:
            return False, npre, ps, as_
        if c <= A2:
            npre = _push(pre, npre, as_, c, K2_)
            npre = _down(pre, npre, c, A1, K2_)
        else:
            vr = vs + 0.5 * (A2 * A2 - as_ * as_) * K2_ + 0.5 * (A2 * A2 - A1 * A1) * K2_
            ta = -vr / A2
            if not (ta >= 0.0):
                return False, npre, ps, as_
            npre = _push(pre, npre, as_, A2, K2_)
            npre = _hold_push(pre, npre, A2, ta)
            npre = _down(pre, npre, A2, A1, K2_)
        aend = A1
    p, _, _ = integrate(pre, n0, npre, ps, vs, as_)
    return True, npre, p, aend


@jit_raw
def _hold_suffix(suf, pe, ve, ae, A1, K1_, A2, K2_):
    """A reversal in a falling run (a < 0, v > 0 -> v < 0) where the
    acceleration limit changes from ``A2`` to ``A1``: the part after it (from
    ``v = 0``, all speeding, at ``K1``) ending at (ve, ae). With ``A1 >= A2`` it
    starts at ``a = -A2``, ramps down to a valley (held at ``-A1`` when
    reached) and up to ``ae``; with ``A1 < A2`` it starts at ``-A1``, holds
    there and ramps up to ``ae``. Returns (ok, n, p, a_start) of its start.
    """
    if not (A1 < math.inf) or ve >= 0.0 or ae < -A1 or K1_ == 0.0:
        return False, 0, pe, ae
    n = 0
    if A1 >= A2:
        if not (A2 < math.inf):
            return False, 0, pe, ae
        tb = (0.5 * (A2 * A2 - A1 * A1) * K1_ + 0.5 * (ae * ae - A1 * A1) * K1_ - ve) / A1
        if tb >= 0.0:
            n = _down(suf, n, -A2, -A1, K1_)
            n = _hold_push(suf, n, -A1, tb)
            n = _push(suf, n, -A1, ae, K1_)
        else:
            # valley c: (A2^2 - c^2) K1/2 + (ae^2 - c^2) K1/2 = ve
            c2 = 0.5 * (A2 * A2 + ae * ae) - ve / K1_
            c = -math.sqrt(c2) if c2 > 0.0 else 0.0
            if c > -A2 or c > ae:
                return False, 0, pe, ae
            n = _down(suf, n, -A2, c, K1_)
            n = _push(suf, n, c, ae, K1_)
        a_start = -A2
    else:
        tb = (0.5 * (ae * ae - A1 * A1) * K1_ - ve) / A1
        if not (tb >= 0.0):
            return False, 0, pe, ae
        n = _hold_push(suf, n, -A1, tb)
        n = _push(suf, n, -A1, ae, K1_)
        a_start = -A1
    _, pb, _ = _before(suf, 0, n, pe, ve)
    return True, n, pb, a_start


@jit_raw
def _front(pre, npA, pA, vA, aA, hb, A1, K1_, A2, K2_, Am, Km):
    """Run B (a > 0, v rising from vA): hypothesis ``hb`` -> (ok, npre, ps, vs, as, AB, KB,
    KB2, mode_b, vc_pos). ``mode_b``: 1 when the reversal lies in ramp 2's first half
    (then KB applies before it, KB2 after); 2 when it lies in a hold at a free ``c1``
    (ramp 1 at ``K2``, KB after it; hypothesis 5, step 2 only)."""
    ps, vs, as_ = pA, vA, aA
    npre = npA
    if vs >= 0.0:
        return hb == 0, npre, ps, vs, as_, A1, K1_, K1_, 0, True
    if hb == 0:  # vc <= 0
        return True, npre, ps, vs, as_, A2, K2_, K2_, 0, False
    if hb == 1:  # reversal in ramp 1 (exact, fixed point)
        az = _az_from_start(as_, vs, K2_, 1.0)
        if not (az == az):
            return False, npre, ps, vs, as_, A1, K1_, K1_, 0, True
        npre = _push(pre, npre, as_, az, K2_)
        ps, vs, _ = integrate(pre, npA, npre, ps, vs, as_)
        return True, npre, ps, 0.0, az, A1, K1_, K1_, 0, True
    if hb == 2:  # reversal in ramp 2's first half (c1 -> 0)
        return True, npre, ps, vs, as_, A2, K2_, K1_, 1, True
    if hb == 4:  # reversal in the hold at c1 (fixed prefix, ends at v = 0)
        ok, npre, ps, aend = _hold_prefix(pre, npA, ps, vs, as_, A1, K1_, A2, K2_)
        return ok, npre, ps, 0.0, aend, A1, K1_, K1_, 0, True
    if hb == 5:  # (step 2) reversal in a hold at a free c1: ramp 1 slowing (K2), the rest speeding
        return True, npre, ps, vs, as_, min(A1, A2), K1_, K1_, 2, True
    return True, npre, ps, vs, as_, Am, Km, Km, 0, True


@jit_raw
def _back(suf, sufd, nsD, pD, vD, aD, hc, vc_pos, A1, K1_, A2, K2_, Am, Km):
    """Run C (a < 0, v falling to vD): hypothesis ``hc`` -> (ok, nsuf, pe, ve, ae, AC, KC,
    KC2, mode_c). ``mode_c``: 1 when the reversal lies in ramp 2's second half (KC before
    it, KC2 after); 2 when it lies in a hold at a free ``c3`` (ramp 4 at KC2;
    hypothesis 5, step 2 only)."""
    pe, ve, ae = pD, vD, aD
    nsuf = 0
    ok = True
    AC, KC, KC2, mode_c = A2, K2_, K2_, 0
    if not vc_pos:
        ok = hc == 0 and ve <= 0.0
        AC, KC, KC2 = A1, K1_, K1_
    elif ve >= 0.0:
        ok = hc == 0
    elif hc == 0:
        ok = False
    elif hc == 1:  # reversal in ramp 4 (exact, fixed point)
        az = _az_from_end(ae, ve, K1_, -1.0)
        if not (az == az):
            ok = False
        else:
            nsuf = _push(suf, 0, az, ae, K1_)
            _, pe, ve = _before(suf, 0, nsuf, pe, ve)
            ae = az
    elif hc == 2:  # reversal in ramp 2's second half (0 -> c3)
        AC, KC, KC2, mode_c = A1, K2_, K1_, 1
    elif hc == 5:  # (step 2) reversal in a hold at a free c3: ramp 4 speeding (KC2)
        AC, KC, KC2, mode_c = min(A1, A2), K2_, K1_, 2
    elif hc == 4:  # reversal in the hold at c3 (fixed suffix from v = 0)
        ok, nsuf, pe, ae = _hold_suffix(suf, pe, ve, ae, A1, K1_, A2, K2_)
        ve = 0.0
        AC, KC, KC2 = A2, K2_, K2_
    else:
        AC, KC, KC2 = Am, Km, Km
    nsuf = _copy(suf, nsuf, sufd, nsD)
    return ok, nsuf, pe, ve, ae, AC, KC, KC2, mode_c


@jit_raw
def _one_run(pre, suf, sufd, npA, nsD, ps, vs, as_, pe, ve, ae, h, sign, A1, K1_, A2, K2_, Am,
             Km):
    """A single run (the acceleration keeps the sign ``sign`` between the forced
    prefix and suffix): hypothesis ``h`` -> (ok, npre, nsuf, ps, vs, as, pe, ve, ae,
    A_before, K_before, A_after, K_after, where): where the velocity reversal lies: 0 nowhere
    or no leg change, 1 in ramp 2, 2 in a hold at a free ``c1`` (ramp 1 before it), 3 in
    a hold at a free ``c3`` (ramp 4 after it); 2 and 3 for step 2 only)."""
    npre = npA
    nsuf = 0
    rising = sign > 0.0  # a > 0: v rises
    # speeding up when sign(v) == sign(a)
    v_first = vs
    v_last = ve
    if (rising and v_first >= 0.0) or (not rising and v_last >= 0.0):
        ok = h == 0
        if rising:
            A, K = A1, K1_
        else:
            A, K = A2, K2_
        nsuf = _copy(suf, 0, sufd, nsD)
        return ok, npre, nsuf, ps, vs, as_, pe, ve, ae, A, K, A, K, 0
    if (rising and v_last <= 0.0) or (not rising and v_first <= 0.0):
        ok = h == 0
        if rising:
            A, K = A2, K2_
        else:
            A, K = A1, K1_
        nsuf = _copy(suf, 0, sufd, nsD)
        return ok, npre, nsuf, ps, vs, as_, pe, ve, ae, A, K, A, K, 0
    # the velocity changes sign inside the run: slowing before, speeding after
    if h == 0:  # in the first ramp (fixed point)
        az = _az_from_start(as_, vs, K2_, sign)
        if not (az == az) or az < as_:
            return False, npre, 0, ps, vs, as_, pe, ve, ae, A1, K1_, A1, K1_, 0
        npre = _push(pre, npre, as_, az, K2_)
        ps, vs, _ = integrate(pre, npA, npre, ps, vs, as_)
        nsuf = _copy(suf, 0, sufd, nsD)
        return True, npre, nsuf, ps, 0.0, az, pe, ve, ae, A1, K1_, A1, K1_, 0
    if h == 1:  # in the last ramp (fixed point)
        az = _az_from_end(ae, ve, K1_, sign)
        if not (az == az):
            return False, npre, 0, ps, vs, as_, pe, ve, ae, A2, K2_, A2, K2_, 0
        nsuf = _push(suf, 0, az, ae, K1_)
        _, pe, ve = _before(suf, 0, nsuf, pe, ve)
        nsuf = _copy(suf, nsuf, sufd, nsD)
        return True, npre, nsuf, ps, vs, as_, pe, ve, az, A2, K2_, A2, K2_, 0
    if h == 4:  # in the hold at c1 (rising run: prefix) or at c3 (falling run: suffix)
        if rising:
            ok, npre, ps, aend = _hold_prefix(pre, npA, ps, vs, as_, A1, K1_, A2, K2_)
            nsuf = _copy(suf, 0, sufd, nsD)
            return ok, npre, nsuf, ps, 0.0, aend, pe, ve, ae, A1, K1_, A1, K1_, 0
        ok, nsuf, pe, ae = _hold_suffix(suf, pe, ve, ae, A1, K1_, A2, K2_)
        nsuf = _copy(suf, nsuf, sufd, nsD)
        return ok, npre, nsuf, ps, vs, as_, pe, 0.0, ae, A2, K2_, A2, K2_, 0
    nsuf = _copy(suf, 0, sufd, nsD)
    if h == 2:  # in ramp 2
        return True, npre, nsuf, ps, vs, as_, pe, ve, ae, A2, K2_, A1, K1_, 1
    if h == 5:  # (step 2) in a hold at a free c1: ramp 1 slowing, ramp 2 on speeding
        return True, npre, nsuf, ps, vs, as_, pe, ve, ae, min(A1, A2), K2_, A1, K1_, 2
    if h == 6:  # (step 2) in a hold at a free c3: up to ramp 2 slowing, ramp 4 speeding
        return True, npre, nsuf, ps, vs, as_, pe, ve, ae, A2, K2_, min(A1, A2), K1_, 3
    return True, npre, nsuf, ps, vs, as_, pe, ve, ae, Am, Km, Am, Km, 0


@jit_raw
def direction(sgn, st0, lim, best, res, W, vec, ivl, cfg, st):
    """Every template of one direction (``sgn``: +1 as given, -1 mirrored).

    ``st0 = (p0, v0, a0, pf, vf, af)``; positions relative to ``p0``.
    """
    p0 = 0.0
    v0 = sgn * st0[1]
    a0 = sgn * st0[2]
    D = sgn * (st0[3] - st0[0])  # NaN: the velocity interface
    vf = sgn * st0[4]
    af = sgn * st0[5]
    st[0] = p0
    st[1] = v0
    st[2] = a0
    st[3] = D
    st[4] = vf
    st[5] = af
    st[6] = st0[6]
    V, A1, K1_, A2, K2_ = lim[0], lim[1], lim[2], lim[3], lim[4]
    symmetric = A1 == A2 and K1_ == K2_
    if symmetric:
        # symmetric: one template, no split of the legs
        c1hi = min(A1, _c1_bound(V, v0, a0, K1_))
        c3lo = -min(A1, _c3_bound(V, vf, af, K1_))
        _setcfg(cfg, p0, v0, a0, D, vf, af, K1_, K1_, K1_, K1_, K1_, M_ZERO, A1, -A1, V,
                a0, c1hi, c3lo, af, 0.0, 1.0, K1_)
        _solve(cfg, W, vec, ivl, 0, 0, sgn, st, lim, best, res)
        # ... and, with both boundary accelerations of one sign, the profiles
        # whose acceleration never changes sign (e.g. a hold at a_max from -v_max
        # to +v_max): the one-run templates below
        if not ((a0 > 0.0 and af > 0.0) or (a0 < 0.0 and af < 0.0)) or res[R_STOP] > 0.0:
            return
    pre = W[1]
    suf = W[2]
    sufd = W[4]
    Am = min(A1, A2)
    Km = max(K1_, K2_)
    # forced prefix (a < 0 part of ramp 1 when c1 >= 0) and suffix (a > 0 part
    # of ramp 4 when c3 <= 0), exact through a velocity reversal
    npA = 0
    pA, vA, aA = p0, v0, a0
    if a0 < 0.0:
        npA, pA, vA = _prefix_a(pre, p0, v0, a0, K1_, K2_)
        aA = 0.0
    nsD = 0
    pD, vD, aD = D, vf, af
    if af > 0.0:
        nsD, pD, vD = _suffix_d(sufd, D, vf, af, K1_, K2_)
        aD = 0.0
    # step 2 also tries a reversal inside a hold at a free level (hypotheses 5 and 6;
    # the holds of minimum time are at a limit, where the fixed prefix/suffix take them)
    nh = 5 if st0[6] != st0[6] else 6
    # ===== sign case (+, -): c1 >= 0 >= c3; run B (a > 0: v rises to vc), run C (a < 0)
    for hb in range(0 if symmetric else nh):
        okb, npre, ps, vs, as_, AB, KB, KB2, mb, vc_pos = _front(
            pre, npA, pA, vA, aA, hb, A1, K1_, A2, K2_, Am, Km)
        if not okb:
            continue
        for hc in range(nh if not symmetric else 5):
            okc, nsuf, pe, ve, ae, AC, KC, KC2, mc = _back(
                suf, sufd, nsD, pD, vD, aD, hc, vc_pos, A1, K1_, A2, K2_, Am, Km)
            if not okc:
                continue
            if mb == 1 and mc == 1:
                mode, k2q, sz = M_ZBOTH, KB2, 1.0
            elif mb == 1:
                mode, k2q, sz = M_ZFIRST, KB2, 1.0
            elif mc == 1:
                mode, k2q, sz = M_ZSECOND, KC2, -1.0
            else:
                mode, k2q, sz = M_ZERO, KB, 1.0
            # holds: at c1 before a reversal in ramp 2 (leg of B), at c3 after one (leg of C)
            k1 = K2_ if mb == 2 else KB  # a reversal in the hold at c1: ramp 1 slowing
            c1hi = min(AB, _c1_bound(V, vs, as_, k1))
            c3lo = -min(AC, _c3_bound(V, ve, ae, KC if mc == 0 else KC2))
            k4 = KC if mc == 0 else KC2
            _setcfg(cfg, ps, vs, as_, pe, ve, ae, k1, KB, KC, k2q, k4, mode, AB, -AC, V,
                    max(as_, 0.0), c1hi, c3lo, min(ae, 0.0), -1.0, sz, KC2)
            _solve(cfg, W, vec, ivl, npre, nsuf, sgn, st, lim, best, res)
    # ===== sign case (+, +): c1 >= c3 >= 0: one run with a >= 0 (needs af >= 0)
    if af >= 0.0:
        for he in range(nh + 1 if not symmetric else 5):
            ok, npre, nsuf, ps, vs, as_, pe, ve, ae, Ab, Kb, Aa, Ka, cr = _one_run(
                pre, suf, sufd, npA, 0, pA, vA, aA, D, vf, af, he, 1.0,
                A1, K1_, A2, K2_, Am, Km)
            if not ok:
                continue
            mode = M_ZSINGLE if cr == 1 else M_SINGLE
            c1hi = min(Ab, _c1_bound(V, vs, as_, Kb))
            # (a reversal in the hold at c1: ramp 2 on speeding)
            _setcfg(cfg, ps, vs, as_, pe, ve, ae, Kb, Ka if cr == 2 else Kb, Ka, Ka, Ka, mode, Ab,
                    Aa, V, max(as_, 0.0), c1hi, 0.0, ae, 1.0, 1.0, Ka)
            _solve(cfg, W, vec, ivl, npre, nsuf, sgn, st, lim, best, res)
    # ===== sign case (-, -): 0 >= c1 >= c3: one run with a <= 0 (needs a0 <= 0)
    if a0 <= 0.0:
        for hf in range(nh + 1 if not symmetric else 5):
            ok, npre, nsuf, ps, vs, as_, pe, ve, ae, Ab, Kb, Aa, Ka, cr = _one_run(
                pre, suf, sufd, 0, nsD, p0, v0, a0, pD, vD, aD, hf, -1.0,
                A1, K1_, A2, K2_, Am, Km)
            if not ok:
                continue
            mode = M_ZSINGLE if cr == 1 else M_SINGLE
            c3lo = -min(Aa, _c3_bound(V, ve, ae, Ka))
            _setcfg(cfg, ps, vs, as_, pe, ve, ae, Kb, Ka if cr == 2 else Kb, Ka, Ka, Ka, mode, -Ab,
                    -Aa, V, as_, 0.0, c3lo, min(ae, 0.0), -1.0, -1.0, Ka)
            _solve(cfg, W, vec, ivl, npre, nsuf, sgn, st, lim, best, res)
    if symmetric:
        return
    # ===== the tighter limits of both legs on the whole profile (always valid)
    c1hi = min(Am, _c1_bound(V, v0, a0, Km))
    c3lo = -min(Am, _c3_bound(V, vf, af, Km))
    _setcfg(cfg, p0, v0, a0, D, vf, af, Km, Km, Km, Km, Km, M_ZERO, Am, -Am, V, a0, c1hi, c3lo,
            af, 0.0, 1.0, Km)
    _solve(cfg, W, vec, ivl, 0, 0, sgn, st, lim, best, res)


@jit_raw
def _vel_change_time(dv, A, K):
    """Duration of the fastest change of the velocity by ``dv`` from ``a = 0`` to
    ``a = 0`` (limits ``A``, ``K = 1/j``)."""
    dv = abs(dv)
    if K == 0.0:
        return dv / A if A < math.inf else 0.0
    if A < math.inf and dv > A * A * K:
        return dv / A + A * K
    return 2.0 * math.sqrt(dv * K)


@jit_raw
def _cruise_margins(st0, lim):
    """Where the cruise velocity ``vc`` of a profile of duration ``T = st0[6]``
    lies relative to the start and goal: ``(vc - v0', vf' - vc)``.

    ``v0'`` is the velocity where the start's acceleration, ramped straight to
    zero, leaves it; ``vf'`` the one from which a ramp straight to the goal's
    acceleration ends at the goal's velocity. ``vc`` is estimated from the
    mean velocity ``D / T``, corrected for the velocity changes at both ends
    (each taken as a straight ramp of velocity over its fastest duration). An
    estimate: it only orders the search (every family is still tried).
    """
    A = min(lim[1], lim[3])
    K = max(lim[2], lim[4])
    V = lim[0]
    v0 = st0[1] + 0.5 * st0[2] * abs(st0[2]) * K
    vf = st0[4] - 0.5 * st0[5] * abs(st0[5]) * K
    T = st0[6]
    D = st0[3] - st0[0]
    vc = min(max(D / T, -V), V)
    for _ in range(CRUISE_ESTIMATE_ROUNDS):
        t1 = _vel_change_time(vc - v0, A, K)
        t2 = _vel_change_time(vc - vf, A, K)
        x = (D + 0.5 * (vc - v0) * t1 + 0.5 * (vc - vf) * t2) / T
        if not (abs(x) < math.inf):
            break
        vc = min(max(x, -V), V)
    return vc - v0, vf - vc


@jit_raw
def _cruise_pair(up1, up2):
    """(stage, direction) of the cruise family whose velocity rises into the
    cruise (``up1``) and rises out of it (``up2``): UD|DU is UDDU, DU|UD its
    mirror, UD|UD and DU|DU the inflections."""
    if up1 and not up2:
        return STAGE_CRUISE, 1.0
    if up2 and not up1:
        return STAGE_CRUISE, -1.0
    return STAGE_INFLECTION, (1.0 if up1 else -1.0)


@jit_raw
def _peak_over(m, a, s, A, K):
    """Whether the acceleration peak of a half of a cruise (a velocity change by
    ``s m`` with ``m`` from :func:`_cruise_margins`, rising for ``s = 1``, at the
    boundary acceleration ``a``) exceeds ``A``: the half then holds at ``A``.
    Its square, from the velocity change of two ramps at jerk ``1/K``, is
    ``s m / K + (a^2 + s a |a|) / 2``."""
    if not (A < math.inf):
        return False
    if K == 0.0:
        return True
    return s * m / K + 0.5 * (a * a + s * a * abs(a)) > A * A


@jit_raw
def _cruise_hint(st0, lim, stage, sgn, m1, m2):
    """The cruise shape (S2_NN..S2_AA) of the (stage, direction) pair that the
    estimated cruise velocity predicts: which halves reach the acceleration
    limit (tried first; the others follow)."""
    if stage != STAGE_CRUISE and stage != STAGE_INFLECTION:
        return S2_NN
    A = min(lim[1], lim[3])
    K = max(lim[2], lim[4])
    s2 = -sgn if stage == STAGE_CRUISE else sgn
    h1 = _peak_over(m1, st0[2], sgn, A, K)
    h2 = _peak_over(m2, st0[5], s2, A, K)
    return S2_NN + (1 if h1 else 0) + (2 if h2 else 0)


@jit_raw
def _step2_pair(k, m1, m2):
    """The ``k``-th (stage, direction) pair searched by step 2 (``k`` in
    ``range(STEP2_PAIRS)``; each pair exactly once).

    With the margins ``(m1, m2)`` of :func:`_cruise_margins`: first the cruise
    family their signs predict, then the one with the smaller margin's sign
    flipped, the holds (both directions), the cruise with the other sign
    flipped, with both flipped, and last the equal-jerk families (the most
    expensive), then the holds of :func:`_hold2` (the last resort). The
    first valid profile ends the search, so the order changes only the
    work, never whether a profile is found.
    """
    up1 = m1 > 0.0
    up2 = m2 > 0.0
    small1 = abs(m1) < abs(m2)
    if k == 0:
        return _cruise_pair(up1, up2)
    if k == 1:
        return _cruise_pair(up1 != small1, up2 == small1)
    if k == 2:
        return STAGE_HOLD, 1.0
    if k == 3:
        return STAGE_HOLD, -1.0
    if k == 4:
        return _cruise_pair(up1 == small1, up2 != small1)
    if k == 5:
        return _cruise_pair(not up1, not up2)
    if k < STEP2_HOLD2_FIRST:
        return STAGE_EQUAL, (1.0 if k == 6 else -1.0)
    return STAGE_HOLD2, (1.0 if k == STEP2_HOLD2_FIRST else -1.0)


@jit_raw
def step1(st0, lim, best, res, W, vec, ivl, cfg, st):
    """Minimum time (``st0[6]`` NaN) or exactly ``st0[6]`` (step 2) from
    ``st0[:3]`` (inside the limits) to ``st0[3:6]``.

    Fills ``best`` (phase table of the fastest valid candidate; for step 2
    the first one found) and ``res`` (``res[R_T]`` its duration (inf if
    none), ``res[R_N]`` its phase count, ``res[R_NV]`` the number of valid
    candidates and their durations, ``res[R_SHAPE]`` its shape code).
    """
    res[R_T] = math.inf
    res[R_N] = 0.0
    res[R_NV] = 0.0
    res[R_SHAPE] = 0.0
    # a rest goal with symmetric limits has exactly one valid profile (ruckig's
    # observation, checked against ruckig by the tests): stop at the first
    symmetric = lim[1] == lim[3] and lim[2] == lim[4]
    rest_goal = st0[4] == 0.0 and st0[5] == 0.0 and st0[3] == st0[3] and st0[6] != st0[6]
    res[R_STOP] = -1.0 if (symmetric and rest_goal and res[R_ALL] == 0.0 and EARLY) else 0.0
    if st0[6] == st0[6] and st0[3] == st0[3]:
        step2_pairs(st0, lim, best, res, W, vec, ivl, cfg, st, 0)
        return
    direction(1.0, st0, lim, best, res, W, vec, ivl, cfg, st)
    if res[R_STOP] <= 0.0:
        direction(-1.0, st0, lim, best, res, W, vec, ivl, cfg, st)


@jit_raw
def step2_pairs(st0, lim, best, res, W, vec, ivl, cfg, st, k0):
    """Step 2 (exactly ``st0[6]``) by the (stage, direction) pairs ``k0 ..
    STEP2_PAIRS - 1``, the likeliest first (see :func:`_step2_pair`); ``best``
    and ``res`` as :func:`step1` fills them."""
    res[R_T] = math.inf
    res[R_N] = 0.0
    res[R_NV] = 0.0
    res[R_SHAPE] = 0.0
    res[R_STOP] = 0.0
    m1, m2 = _cruise_margins(st0, lim)
    for k in range(k0, STEP2_PAIRS):
        stage, sgn = _step2_pair(k, m1, m2)
        res[R_STAGE] = stage
        res[R_HINT] = _cruise_hint(st0, lim, stage, sgn, m1, m2)
        direction(sgn, st0, lim, best, res, W, vec, ivl, cfg, st)
        if res[R_T] < math.inf:
            break
