"""Entry point of the one-axis state-to-state kernel: one flat workspace array.

The public planners (:mod:`trajkit.profiles.state`) write the problem into a
float64 workspace (:func:`workspace`), call :func:`solve` once (one numba
dispatch) and read the result back. Layout (indices are module constants):

``IN_*``
    start state, goal state (a NaN goal position: velocity interface), the
    limits ``v_max, a_max, j_max, a_max_decel, j_max_decel`` (``inf`` allowed
    where :class:`~trajkit.limits.AxisLimits` allows it), the task and the
    requested duration.
``OUT_*``
    status, duration, minimum duration, phase count, brake phase count, the
    blocked intervals and the phase table ``(duration, jerk, start
    acceleration)`` in the caller's units.

Inside, the problem is scaled by powers of two (exact) so that the
reference jerk and acceleration are of order one, positions are taken
relative to the start, the brake (:mod:`._brake`) brings the start state
inside the limits, and step 1 / step 2 (:func:`_step2` here, the shape families
in :mod:`._shapes`, the closed forms of symmetric limits in :mod:`._symfast`)
plan the rest.
"""

from __future__ import annotations

import math

import numpy as np

from ._brake import (
    brake_bump,
    brake_hold,
    brake_natural,
    brake_path,
    brake_ruckig,
    forced_speed,
    inside,
    lingers,
    peak_speed,
)
from ._check import check
from ._compile import jit_raw
from ._phase import phase_end
from ._roots import merge_equal, sort_ascending
from ._shapes import (
    ALL_NEAREST,
    NCFG,
    NPH,
    NVALID,
    R_ALL,
    R_N,
    R_NV,
    R_SHAPE,
    R_T,
    R_TARGET,
    R_V0,
    STEP2_HOLD2_FIRST,
    integrate,
    step1,
    step2_pairs,
)
from ._symfast import C_SG, NCF, NSF, SF_SCRATCH, build_candidate, sym_applies, sym_step1, sym_step2

__all__ = [
    "NWS", "workspace", "solve",
    "TASK_MIN", "TASK_BLOCK", "TASK_FIXED", "TASK_VELOCITY", "TASK_STEP2", "IN_GENERAL",
    "ST_OK", "ST_NONE", "ST_BRAKE", "ST_BLOCKED", "ST_SHORT",
]

# tasks
TASK_MIN = 0       # minimum time
TASK_BLOCK = 1     # minimum time and the blocked intervals
TASK_FIXED = 2     # exactly IN_T
TASK_VELOCITY = 3  # velocity interface, minimum time
TASK_STEP2 = 4     # exactly IN_T, step 1 already done: its minimum duration in OUT_TMIN

# status
ST_OK = 0
ST_NONE = 1      # no profile found (a gap of the shape set: reported, never silent)
ST_BRAKE = 2     # the start state cannot be brought inside the limits
ST_BLOCKED = 3   # the requested duration lies in a blocked interval
ST_SHORT = 4     # the requested duration is below the minimum

#: Largest number of blocked intervals reported.
NBLK = 4

#: Brake candidates (see :mod:`._brake`).
NCAND = 7

#: A brake end state within this fraction of the brake's velocity (and
#: acceleration) scale outside the limits is round-off and is moved onto them.
BRAKE_SNAP_RTOL = 1e-9

#: Valid step-1 durations closer than this (relative) are one profile.
BLOCK_MERGE_RTOL = 1e-10

#: A requested duration within this (relative) of the minimum is the minimum.
DURATION_RTOL = 1e-12

#: Shape code (step 2, before the fixed-duration offset) of the cruise fallback.
SHAPE_CRUISE_FALLBACK = 15

#: Added to a step-2 shape code where the profile was found on the time-reversed
#: move (:func:`_step2_reversed`).
SHAPE_REVERSED = 64

#: The first (stage, direction) pair of step 2 tried on the time-reversed move.
REVERSED_FIRST_PAIR = STEP2_HOLD2_FIRST

#: Where in a gap between two valid step-1 durations step 2 is tried (fractions
#: of the gap, in order) when separate legs leave the blocked intervals to be
#: probed: the gap is feasible at the first profile found, blocked without one.
PROBES = (0.5, 0.25, 0.75, 0.1, 0.9)

#: Cruise velocities sampled by the step-2 fallback (then bisection).
FALLBACK_SAMPLES = 33

# layout
IN_P0, IN_V0, IN_A0, IN_PF, IN_VF, IN_AF = 0, 1, 2, 3, 4, 5
IN_V, IN_A1, IN_J1, IN_A2, IN_J2 = 6, 7, 8, 9, 10
IN_TASK, IN_T = 11, 12
OUT_STATUS, OUT_T, OUT_TMIN, OUT_N, OUT_NB, OUT_NBLK, OUT_SHAPE = 13, 14, 15, 16, 17, 18, 19
OUT_BLK = 20
OUT_PH = OUT_BLK + 2 * NBLK
_W = OUT_PH + 3 * NPH           # W: 5 x NPH x 3
_VEC = _W + 5 * NPH * 3         # vec: 19 x 16 (values, coefficients, roots, 16 x 16 scratch)
_IVL = _VEC + 19 * 16           # ivl: 8 x 2
_CFG = _IVL + 16
_ST = _CFG + 2 * NCFG
_BEST = _ST + 7
_RES = _BEST + 3 * NPH
_LIM = _RES + R_V0 + NVALID
_ST0 = _LIM + 5
_BRK = _ST0 + 7
_S1 = _BRK + 3 * 16
_BBUF = _S1 + 7
_KEEP = _BBUF + 96
_VALID = _KEEP + 3 * NPH
_TS = _VALID + NVALID
_FBA = _TS + 1                  # the cruise fallback of step 2: first velocity change
_FBS = _FBA + 3 * NPH           # ... and its velocity problem
_SFC = _FBS + 7                 # the symmetric closed-form step 1: candidates
_SFS = _SFC + NCF * NSF         # ... and its scratch
#: Input: non-zero to plan with the general step 1 only (the closed form of
#: symmetric limits off; for the tests that compare both).
IN_GENERAL = _SFS + SF_SCRATCH
#: Scratch of the correctly rounded sum of a phase table (``_batch_states``).
SUM_SCRATCH = IN_GENERAL + 1
#: The outputs kept while the blocked intervals are probed (separate legs),
#: then the intervals found.
_SAVE = SUM_SCRATCH + NPH + 1
_NSAVE = OUT_PH + 3 * NPH - OUT_STATUS
_FOUND = _SAVE + _NSAVE
#: The time-reversed move of step 2 (separate legs): its limits and its problem.
_REV = _FOUND + 2 * NBLK
#: The valid step-1 durations of every brake candidate (NCAND x NVALID, brake
#: included), their counts, and all of them merged (a start outside the limits).
_VALL = _REV + 12
_VCNT = _VALL + NCAND * NVALID
_VUNI = _VCNT + NCAND
NWS = _VUNI + NCAND * NVALID


def workspace() -> np.ndarray:
    """A new workspace array for :func:`solve`."""
    return np.zeros(NWS)


#: sqrt(1/2): the mantissa where the nearest power of two (in log scale) changes.
_SQRT_HALF = math.sqrt(0.5)


@jit_raw
def _pow2(x):
    """The power of two nearest to ``x > 0`` (in log scale)."""
    if not (x > 0.0) or not (x < math.inf):
        return 1.0
    # x = m 2^e with m in [0.5, 1): the nearer of 2^(e - 1) and 2^e in log scale
    m, e = math.frexp(x)
    if m < _SQRT_HALF:
        e -= 1
    return math.ldexp(1.0, min(max(e, -1000), 1000))


@jit_raw
def _scales(ws):
    """(time, length) scales, powers of two, so that the reference jerk and
    acceleration (or velocity) are about one."""
    V = ws[IN_V]
    A = min(ws[IN_A1], ws[IN_A2])
    J = min(ws[IN_J1], ws[IN_J2])
    if J < math.inf and A < math.inf:
        ts = A / J
        ls = A * ts * ts
    elif J < math.inf and V < math.inf:
        ts = math.sqrt(V / J)
        ls = V * ts
    elif A < math.inf and V < math.inf:
        ts = V / A
        ls = V * ts
    elif A < math.inf:
        d = abs(ws[IN_PF] - ws[IN_P0]) if ws[IN_PF] == ws[IN_PF] else 0.0
        ls = max(d, ws[IN_V0] * ws[IN_V0] / A, ws[IN_VF] * ws[IN_VF] / A, 1e-300)
        ts = math.sqrt(ls / A)
    else:
        d = abs(ws[IN_PF] - ws[IN_P0]) if ws[IN_PF] == ws[IN_PF] else 0.0
        ls = max(d, 1e-300)
        ts = (ls / J) ** (1.0 / 3.0)
    ts = _pow2(ts)
    ls = _pow2(ls)
    return ts, ls


@jit_raw
def _normalise(ws, task):
    """The problem in the kernel's units (see the module text): the limits to
    ``ws[_LIM:]``, start and goal (positions relative to the start) to
    ``ws[_ST0:]``, ``ws[_TS]`` the time scale; returns the scales
    ``(time, velocity, acceleration, jerk)``."""
    ts, ls = _scales(ws)
    ws[_TS] = ts
    vs = ls / ts
    as_ = vs / ts
    js = as_ / ts
    # (the scales are powers of two: multiplying by their reciprocals is
    # division, exactly)
    ivs = 1.0 / vs
    ias = 1.0 / as_
    lim = ws[_LIM:_LIM + 5]
    lim[0] = ws[IN_V] * ivs
    lim[1] = ws[IN_A1] * ias
    lim[2] = js / ws[IN_J1] if ws[IN_J1] < math.inf else 0.0
    lim[3] = ws[IN_A2] * ias
    if ws[IN_J2] == ws[IN_J1]:
        lim[4] = lim[2]
    else:
        lim[4] = js / ws[IN_J2] if ws[IN_J2] < math.inf else 0.0
    st0 = ws[_ST0:_ST0 + 7]
    st0[0] = 0.0
    st0[1] = ws[IN_V0] * ivs
    st0[2] = ws[IN_A0] * ias
    if task == TASK_VELOCITY:
        st0[3] = math.nan
    else:
        st0[3] = (ws[IN_PF] - ws[IN_P0]) * (1.0 / ls)
    st0[4] = ws[IN_VF] * ivs
    st0[5] = ws[IN_AF] * ias
    st0[6] = math.nan
    if not (lim[0] < math.inf):
        # no velocity limit: a finite one far above any velocity the motion can use
        # (the shapes need a bounded parameter interval)
        am = max(lim[1], lim[3]) if max(lim[1], lim[3]) < math.inf else 1.0
        km = max(lim[2], lim[4])
        d = abs(st0[3]) if st0[3] == st0[3] else 0.0
        lim[0] = 8.0 * (abs(st0[1]) + abs(st0[4]) + math.sqrt(am * d) + am * am * km
                        + abs(st0[2]) * abs(st0[2]) * km + abs(st0[5]) * abs(st0[5]) * km) + 1.0
    return ts, vs, as_, js


@jit_raw
def solve(ws):
    """Plan the task written in ``ws`` (see the module text); results in ``ws``."""
    task = int(ws[IN_TASK])
    sym = ws[IN_GENERAL] == 0.0 and ws[IN_A1] == ws[IN_A2] and ws[IN_J1] == ws[IN_J2]
    if sym and (task == TASK_MIN or task == TASK_BLOCK) and _solve_sym(ws, task):
        return
    nblk0 = 0
    if sym and task == TASK_FIXED and _solve_sym(ws, TASK_BLOCK):
        # the minimum and the blocked intervals in closed form; then step 2
        if ws[IN_T] < ws[OUT_TMIN] * (1.0 - DURATION_RTOL):
            ws[OUT_STATUS] = ST_SHORT
            return
        if ws[IN_T] <= ws[OUT_TMIN] * (1.0 + DURATION_RTOL):
            return
        task = TASK_STEP2
        nblk0 = int(ws[OUT_NBLK])
    tmin_in = ws[OUT_TMIN]
    ts, vs, as_, js = _normalise(ws, task)
    lim = ws[_LIM:_LIM + 5]
    st0 = ws[_ST0:_ST0 + 7]
    W = ws[_W:_W + 5 * NPH * 3].reshape((5, NPH, 3))
    vec = ws[_VEC:_VEC + 19 * 16].reshape((19, 16))
    ivl = ws[_IVL:_IVL + 16].reshape((8, 2))
    cfg = ws[_CFG:_CFG + 2 * NCFG]
    st = ws[_ST:_ST + 7]
    best = ws[_BEST:_BEST + 3 * NPH].reshape((NPH, 3))
    res = ws[_RES:_RES + R_V0 + NVALID]
    brk = ws[_BRK:_BRK + 48].reshape((16, 3))
    out = ws[OUT_PH:OUT_PH + 3 * NPH].reshape((NPH, 3))
    ws[OUT_STATUS] = ST_OK
    ws[OUT_N] = 0.0
    ws[OUT_NB] = 0.0
    ws[OUT_NBLK] = nblk0
    # ---- the brake pre-phase (candidates) and step 1 from where each ends
    s1 = ws[_S1:_S1 + 7]
    bbuf = ws[_BBUF:_BBUF + 96]
    keep = ws[_KEEP:_KEEP + 3 * NPH].reshape((NPH, 3))
    valid = ws[_VALID:_VALID + NVALID]
    start_inside = inside(st0[1], st0[2], lim[0], lim[1], lim[2], lim[3], lim[4])
    if task == TASK_STEP2:
        T = ws[IN_T] / ts
        tmin = tmin_in / ts
        if T > tmin * (1.0 + DURATION_RTOL):
            _step2(ws, T, tmin, nblk0, start_inside, st0, lim, brk, bbuf, s1, best, res, W, vec,
                   ivl, cfg, st, keep, out, ts, js, as_)
            return
        task = TASK_FIXED  # the minimum itself: plan it
    best_total = math.inf
    nb_best = 0
    n_best = 0
    nvalid = 0
    res[R_ALL] = 1.0 if (task == TASK_BLOCK or task == TASK_FIXED) else 0.0
    # the goal is the start: the empty profile (duration 0) is the fastest
    trivial = (task != TASK_VELOCITY and start_inside and st0[3] == 0.0
               and st0[1] == st0[4] and st0[2] == st0[5])
    ncand = NCAND
    if trivial:
        # (the valid set of the loop still bounds the blocked durations)
        ncand = 1 if (task == TASK_BLOCK or task == TASK_FIXED) else 0
    vall = ws[_VALL:_VALL + NCAND * NVALID].reshape((NCAND, NVALID))
    vcnt = ws[_VCNT:_VCNT + NCAND]
    vcnt[:] = 0.0
    for cand in range(ncand):
        nb, tb = _brake_cand(cand, start_inside, st0, lim, brk, bbuf, s1)
        if nb < 0:
            continue
        s1[6] = math.nan
        step1(s1, lim, best, res, W, vec, ivl, cfg, st)
        if not (res[R_T] < math.inf):
            continue
        n = int(res[R_N])
        if nb + n > NPH:
            continue
        # every candidate's valid durations (the blocked intervals of a start
        # outside the limits are those that no brake candidate reaches)
        nv = int(res[R_NV])
        for k in range(nv):
            vall[cand, k] = res[R_V0 + k] + tb
        vcnt[cand] = nv
        if not (tb + res[R_T] < best_total):
            continue
        best_total = tb + res[R_T]
        ws[OUT_SHAPE] = res[R_SHAPE]
        nb_best = nb
        n_best = n
        nvalid = int(res[R_NV])
        for k in range(nvalid):
            valid[k] = res[R_V0 + k] + tb
        _copy_rows(keep, 0, brk, nb)
        _copy_rows(keep, nb, best, n)
    if trivial:
        # (a moving start reaches itself again only after a loop: the
        # durations in between are blocked, see _blocks)
        valid[nvalid] = 0.0
        nvalid += 1
        best_total = 0.0
        nb_best = 0
        n_best = 0
        ws[OUT_SHAPE] = 0.0
    if not (best_total < math.inf):
        ws[OUT_STATUS] = ST_NONE if start_inside else ST_BRAKE
        return
    _emit(ws, out, keep, nb_best + n_best, nb_best, best_total, best_total, ts, js, as_)
    if task == TASK_MIN or task == TASK_VELOCITY:
        return
    legs_equal = lim[1] == lim[3] and lim[2] == lim[4]
    if not start_inside:
        # several brakes: the valid durations of all of them bound the feasible set
        valid = ws[_VUNI:_VUNI + NCAND * NVALID]
        nvalid = _union_valid(vall, vcnt, valid)
    nblk = 0
    if legs_equal and not start_inside:
        nblk = _blocks_union(valid, nvalid, vall, vcnt, ws)
    elif legs_equal:
        nblk = _blocks(valid, nvalid, best_total, ws)
    elif task == TASK_BLOCK:
        _blocks_probed(ws, valid, nvalid, best_total, start_inside, st0, lim, brk, bbuf, s1, best,
                       res, W, vec, ivl, cfg, st, keep, out, ts, js, as_)
    if task == TASK_BLOCK:
        return
    # ---- step 2: exactly T (brake included)
    T = ws[IN_T] / ts
    if T < best_total * (1.0 - DURATION_RTOL):
        ws[OUT_STATUS] = ST_SHORT
        return
    if T <= best_total * (1.0 + DURATION_RTOL):
        return
    if legs_equal:
        _step2(ws, T, best_total, nblk, start_inside, st0, lim, brk, bbuf, s1, best, res, W, vec,
               ivl, cfg, st, keep, out, ts, js, as_)
        return
    # separate legs: step 2 first; where it finds no profile, the blocked
    # intervals (probed) say whether the duration lies in one
    ws[OUT_NBLK] = 0.0
    _step2(ws, T, best_total, 0, start_inside, st0, lim, brk, bbuf, s1, best, res, W, vec,
           ivl, cfg, st, keep, out, ts, js, as_)
    if ws[OUT_STATUS] != ST_NONE:
        return
    nblk = _blocks_probed(ws, valid, nvalid, best_total, start_inside, st0, lim, brk, bbuf, s1, best,
                          res, W, vec, ivl, cfg, st, keep, out, ts, js, as_)
    for b in range(nblk):
        if ws[OUT_BLK + 2 * b] / ts < T < ws[OUT_BLK + 2 * b + 1] / ts:
            ws[OUT_STATUS] = ST_BLOCKED


@jit_raw
def _solve_sym(ws, task):
    """Step 1 (minimum time, with ``TASK_BLOCK`` the blocked intervals) by the
    closed form of symmetric limits (:mod:`._symfast`), where it applies: a
    start inside the limits, finite jerk and acceleration limits, a goal that
    is not the start. True when it planned (results written as :func:`solve`
    writes them); False leaves the task to the general path."""
    ts, vs, as_, js = _normalise(ws, task)
    lim = ws[_LIM:_LIM + 5]
    if not sym_applies(lim):
        return False
    st0 = ws[_ST0:_ST0 + 7]
    if not inside(st0[1], st0[2], lim[0], lim[1], lim[2], lim[3], lim[4]):
        return False
    if st0[3] == 0.0 and st0[1] == st0[4] and st0[2] == st0[5]:
        return False  # the goal is the start (see solve)
    # (as a brake candidate of no phases: a start within round-off of the
    # boundary put onto it; within the bounds it is inside, as checked)
    v = st0[1]
    a = st0[2]
    if abs(v) > lim[0] or abs(a) > lim[1]:
        v, a, ok = _onto_boundary(v, a, lim, abs(v), abs(a))
        if not ok:
            return False
    s1 = ws[_S1:_S1 + 7]
    s1[0] = 0.0
    s1[1] = v
    s1[2] = a
    s1[3] = st0[3]
    s1[4] = st0[4]
    s1[5] = st0[5]
    s1[6] = math.nan
    res = ws[_RES:_RES + R_V0 + NVALID]
    cand = ws[_SFC:_SFC + NCF * NSF]
    ph = ws[_BEST:_BEST + 3 * NPH].reshape((NPH, 3))
    ib = sym_step1(s1, lim, res, task == TASK_BLOCK, cand, ws[_SFS:_SFS + SF_SCRATCH], ph)
    if ib < 0:
        return False
    if task == TASK_BLOCK:
        n, total, sg = build_candidate(cand, ib, s1, lim, ph)
    else:  # (the minimum alone: left built in ph)
        n = int(res[R_N])
        total = res[R_T]
        sg = cand[ib * NSF + C_SG]
    ws[OUT_STATUS] = ST_OK
    ws[OUT_NB] = 0.0
    ws[OUT_NBLK] = 0.0
    ws[OUT_SHAPE] = res[R_SHAPE]
    for k in range(n):
        o = OUT_PH + 3 * k
        ws[o] = ph[k, 0] * ts
        ws[o + 1] = sg * ph[k, 1] * js
        ws[o + 2] = sg * ph[k, 2] * as_
    ws[OUT_N] = n
    ws[OUT_T] = total * ts
    ws[OUT_TMIN] = total * ts
    if task == TASK_BLOCK:
        _blocks(ws[_RES + R_V0:_RES + R_V0 + NVALID], int(res[R_NV]), total, ws)
    return True


@jit_raw
def _step2(ws, T, tmin, nblk, start_inside, st0, lim, brk, bbuf, s1, best, res, W, vec, ivl,
           cfg, st, keep, out, ts, js, as_):
    """Step 2: a profile of exactly ``T`` (normalised; brake included)."""
    for b in range(nblk if lim[1] == lim[3] and lim[2] == lim[4] else 0):
        # inside a blocked interval (away from its ends) with symmetric limits: no
        # profile has this duration (ruckig's block scheme; with separate legs the
        # intervals of step 1 may hold profiles of step 2: the search decides)
        if (ws[OUT_BLK + 2 * b] / ts * (1.0 + DURATION_RTOL) < T
                < ws[OUT_BLK + 2 * b + 1] / ts * (1.0 - DURATION_RTOL)):
            ws[OUT_STATUS] = ST_BLOCKED
            return
    for cand in range(NCAND):
        nb, tb = _brake_cand(cand, start_inside, st0, lim, brk, bbuf, s1)
        if nb < 0 or not (T - tb > 0.0):
            continue
        s1[6] = T - tb
        if nb == 0:
            # symmetric limits, a cruise at a free velocity: closed form first
            n, code = sym_step2(s1, T - tb, lim, best, ws[_SFS:_SFS + SF_SCRATCH])
            if n > 0:
                total = 0.0
                for k in range(n):
                    total += best[k, 0]
                _emit(ws, out, best, n, 0, total, tmin, ts, js, as_)
                ws[OUT_SHAPE] = code + 32
                return
        res[R_ALL] = 0.0
        step1(s1, lim, best, res, W, vec, ivl, cfg, st)
        if not (res[R_T] < math.inf):
            continue
        n = int(res[R_N])
        if nb + n > NPH:
            continue
        _copy_rows(keep, 0, brk, nb)
        _copy_rows(keep, nb, best, n)
        _emit(ws, out, keep, nb + n, nb, tb + res[R_T], tmin, ts, js, as_)
        ws[OUT_SHAPE] = res[R_SHAPE] + 32
        return
    # no family of step 2 fits: two minimum-time velocity changes around a cruise
    fba = ws[_FBA:_FBA + 3 * NPH].reshape((NPH, 3))
    sv = ws[_FBS:_FBS + 7]
    for cand in range(NCAND):
        nb, tb = _brake_cand(cand, start_inside, st0, lim, brk, bbuf, s1)
        if nb < 0 or not (T - tb > 0.0):
            continue
        n = _cruise_fallback(T - tb, s1, lim, best, res, W, vec, ivl, cfg, st, fba, sv, keep, nb)
        if n > 0:
            _copy_rows(keep, 0, brk, nb)
            total = tb
            for k in range(nb, nb + n):
                total += keep[k, 0]
            _emit(ws, out, keep, nb + n, nb, total, tmin, ts, js, as_)
            ws[OUT_SHAPE] = SHAPE_CRUISE_FALLBACK + 32
            return
    if _step1_at(ws, T, tmin, start_inside, st0, lim, brk, bbuf, s1, best, res, W, vec, ivl, cfg,
                 st, keep, out, ts, js, as_):
        return
    if lim[1] != lim[3] or lim[2] != lim[4]:
        for cand in range(NCAND):
            nb, tb = _brake_cand(cand, start_inside, st0, lim, brk, bbuf, s1)
            if nb < 0 or not (T - tb > 0.0):
                continue
            if _step2_reversed(ws, T - tb, tb, tmin, s1, nb, brk, lim, best, res, W, vec, ivl,
                               cfg, st, keep, out, ts, js, as_):
                return
    ws[OUT_STATUS] = ST_NONE
    for b in range(nblk):
        if ws[OUT_BLK + 2 * b] / ts < T < ws[OUT_BLK + 2 * b + 1] / ts:
            ws[OUT_STATUS] = ST_BLOCKED


@jit_raw
def _step2_reversed(ws, T, tb, tmin, s0, nb, brk, lim, best, res, W, vec, ivl, cfg, st, keep,
                    out, ts, js, as_):
    """Step 2's last stage (the pairs from :data:`REVERSED_FIRST_PAIR` on) on the
    time-reversed move (separate legs) from ``s0`` (the state where brake
    candidate's ``nb`` phases ``brk`` of duration ``tb`` end, the goal, as
    ``s1``) in ``T`` (after the brake); True when it emitted a profile.

    Played backwards, a motion from ``(p0, v0, a0)`` to ``(pf, vf, af)`` is one
    from ``(pf, -vf, af)`` to ``(p0, -v0, a0)`` with the jerk negated, and
    ``|v|`` grows where it shrank: the legs swap. The families are not closed
    under this reversal (a hold at a limit before a reversal maps to one after
    it), so a duration they miss forwards can be found backwards. The table found
    is turned back (phases in reverse order, each starting at the acceleration
    where its reversed phase ends) and checked exactly in forward time.
    """
    r = ws[_REV:_REV + 12]
    limr = r[0:5]
    sr = r[5:12]
    limr[0] = lim[0]
    limr[1] = lim[3]
    limr[2] = lim[4]
    limr[3] = lim[1]
    limr[4] = lim[2]
    sr[0] = 0.0
    sr[1] = -s0[4]
    sr[2] = s0[5]
    sr[3] = -(s0[3] - s0[0])
    sr[4] = -s0[1]
    sr[5] = s0[2]
    sr[6] = T
    res[R_ALL] = 0.0
    step2_pairs(sr, limr, best, res, W, vec, ivl, cfg, st, REVERSED_FIRST_PAIR)
    if not (res[R_T] < math.inf):
        return False
    n = int(res[R_N])
    if nb + n > NPH:
        return False
    total = tb
    for i in range(n):
        k = n - 1 - i
        keep[nb + i, 0] = best[k, 0]
        keep[nb + i, 1] = -best[k, 1]
        keep[nb + i, 2] = s0[2] if i == 0 else best[k + 1, 2]
        total += keep[nb + i, 0]
    if not check(keep[nb:], n, s0[0], s0[1], s0[2], s0[3], s0[4], s0[5],
                 lim[0], lim[1], lim[2], lim[3], lim[4]):
        return False
    _copy_rows(keep, 0, brk, nb)
    _emit(ws, out, keep, nb + n, nb, total, tmin, ts, js, as_)
    ws[OUT_SHAPE] = res[R_SHAPE] + 32 + SHAPE_REVERSED
    return True


@jit_raw
def _step1_at(ws, T, tmin, start_inside, st0, lim, brk, bbuf, s1, best, res, W, vec, ivl, cfg, st,
              keep, out, ts, js, as_):
    """Step 2 where its families found nothing: the valid step-1 profile (brake
    included) whose duration lies within :data:`DURATION_RTOL` of ``T``, if
    there is one. The ends of the blocked intervals are such durations (a
    time-synchronised plan moves its common duration onto them), and step 2's
    families can miss them by round-off. True when it emitted one."""
    for cand in range(NCAND):
        nb, tb = _brake_cand(cand, start_inside, st0, lim, brk, bbuf, s1)
        if nb < 0 or not (T - tb > 0.0):
            continue
        s1[6] = math.nan
        res[R_ALL] = ALL_NEAREST
        res[R_TARGET] = T - tb
        step1(s1, lim, best, res, W, vec, ivl, cfg, st)
        res[R_ALL] = 0.0
        n = int(res[R_N])
        if not (abs(tb + res[R_T] - T) <= DURATION_RTOL * T) or nb + n > NPH:
            continue
        _copy_rows(keep, 0, brk, nb)
        _copy_rows(keep, nb, best, n)
        _emit(ws, out, keep, nb + n, nb, tb + res[R_T], tmin, ts, js, as_)
        ws[OUT_SHAPE] = res[R_SHAPE]  # a step-1 shape, named as one
        return True
    return False


@jit_raw
def _vel_move(sv, v0, a0, vt, at, lim, best, res, W, vec, ivl, cfg, st):
    """Minimum-time velocity change ``(v0, a0) -> (vt, at)``, position free (step 1,
    phases in ``best``): (duration (inf if none), displacement, phase count)."""
    sv[0] = 0.0
    sv[1] = v0
    sv[2] = a0
    sv[3] = math.nan
    sv[4] = vt
    sv[5] = at
    sv[6] = math.nan
    res[R_ALL] = 0.0
    step1(sv, lim, best, res, W, vec, ivl, cfg, st)
    t = res[R_T]
    if not (t < math.inf):
        return math.inf, 0.0, 0
    n = int(res[R_N])
    p, _, _ = integrate(best, 0, n, 0.0, v0, a0)
    return t, p, n


@jit_raw
def _cruise_resid(T, s1, vc, lim, best, res, W, vec, ivl, cfg, st, sv):
    """Position residual of the cruise fallback at cruise velocity ``vc`` (NaN where
    the two velocity changes take longer than ``T``)."""
    ta, da, _ = _vel_move(sv, s1[1], s1[2], vc, 0.0, lim, best, res, W, vec, ivl, cfg, st)
    if not (ta < math.inf):
        return math.nan
    tb, db, _ = _vel_move(sv, vc, 0.0, s1[4], s1[5], lim, best, res, W, vec, ivl, cfg, st)
    if not (tb < math.inf):
        return math.nan
    tc = T - ta - tb
    if not (tc >= 0.0):
        return math.nan
    return da + vc * tc + db - (s1[3] - s1[0])


@jit_raw
def _cruise_fallback(T, s1, lim, best, res, W, vec, ivl, cfg, st, fba, sv, keep, n0):
    """Step 2 when no family fits: the fastest velocity change from ``s1[:3]`` to a
    cruise ``(vc, 0)``, the cruise, the fastest velocity change to the goal's
    ``(vf, af)``; ``vc`` in ``[-v_max, v_max]`` such that the duration is ``T``
    and the position the goal's (sampled, then bisection). The phases go to
    ``keep[n0:]``; returns their count (0 when none passes the exact check)."""
    V = lim[0]
    ns = FALLBACK_SAMPLES
    x0 = -V
    f0 = _cruise_resid(T, s1, x0, lim, best, res, W, vec, ivl, cfg, st, sv)
    for i in range(1, ns):
        x1 = -V + 2.0 * V * i / (ns - 1)
        f1 = _cruise_resid(T, s1, x1, lim, best, res, W, vec, ivl, cfg, st, sv)
        if f0 == f0 and f1 == f1 and (f0 == 0.0 or f0 * f1 < 0.0 or f1 == 0.0):
            lo = x0
            hi = x1
            flo = f0
            for _ in range(200):
                if flo == 0.0:
                    hi = lo
                    break
                mid = 0.5 * (lo + hi)
                if not (lo < mid < hi):
                    break
                fm = _cruise_resid(T, s1, mid, lim, best, res, W, vec, ivl, cfg, st, sv)
                if not (fm == fm):
                    break
                if fm * flo > 0.0:
                    lo = mid
                    flo = fm
                else:
                    hi = mid
            for vc in (lo, hi):
                n = _cruise_build(T, s1, vc, lim, best, res, W, vec, ivl, cfg, st, fba, sv,
                                  keep, n0)
                if n > 0:
                    return n
        x0 = x1
        f0 = f1
    return 0


@jit_raw
def _cruise_build(T, s1, vc, lim, best, res, W, vec, ivl, cfg, st, fba, sv, keep, n0):
    """The cruise fallback's phases at ``vc`` into ``keep[n0:]``, exactly checked:
    the phase count, 0 when it fails the check."""
    ta, _, na = _vel_move(sv, s1[1], s1[2], vc, 0.0, lim, best, res, W, vec, ivl, cfg, st)
    if not (ta < math.inf):
        return 0
    _copy_rows(fba, 0, best, na)
    tb, _, nb = _vel_move(sv, vc, 0.0, s1[4], s1[5], lim, best, res, W, vec, ivl, cfg, st)
    if not (tb < math.inf):
        return 0
    tc = T - ta - tb
    if not (tc >= 0.0) or n0 + na + nb + 1 > NPH:
        return 0
    _copy_rows(keep, n0, fba, na)
    n = n0 + na
    keep[n, 0] = tc
    keep[n, 1] = 0.0
    keep[n, 2] = 0.0
    n += 1
    _copy_rows(keep, n, best, nb)
    n += nb
    if not check(keep[n0:], n - n0, s1[0], s1[1], s1[2], s1[3], s1[4], s1[5], lim[0], lim[1],
                 lim[2], lim[3], lim[4]):
        return 0
    return n - n0


@jit_raw
def _copy_rows(dst, n0, src, m):
    for k in range(m):
        dst[n0 + k, 0] = src[k, 0]
        dst[n0 + k, 1] = src[k, 1]
        dst[n0 + k, 2] = src[k, 2]


@jit_raw
def _emit(ws, out, keep, n, nb, total, tmin, ts, js, as_):
    for k in range(n):
        out[k, 0] = keep[k, 0] * ts
        out[k, 1] = keep[k, 1] * js
        out[k, 2] = keep[k, 2] * as_
    ws[OUT_N] = n
    ws[OUT_NB] = nb
    ws[OUT_T] = total * ts
    ws[OUT_TMIN] = tmin * ts


@jit_raw
def _onto_boundary(v, a, lim, vsc, asc):
    """A brake's end state ``(v, a)``, which lies on the boundary of the inside set up
    to the round-off of the brake's velocity and acceleration scales ``vsc``,
    ``asc``, put onto it: ``(v, a, inside)``."""
    # a velocity a few ulps beyond the limit is put on it (the shapes of step 1
    # start within it)
    if abs(v) > lim[0] and abs(v) - lim[0] <= BRAKE_SNAP_RTOL * vsc:
        v = lim[0] if v > 0.0 else -lim[0]
    # ... and an acceleration a few ulps beyond its leg's bound is put on it
    al = lim[3] if v * a < 0.0 else lim[1]
    if abs(a) > al and abs(a) - al <= BRAKE_SNAP_RTOL * asc:
        a = al if a > 0.0 else -al
    if not inside(v, a, lim[0], lim[1], lim[2], lim[3], lim[4]):
        # ... and of its acceleration scale
        am = max(lim[1], lim[3])
        if abs(a) > am and abs(a) - am <= BRAKE_SNAP_RTOL * asc:
            a = am if a > 0.0 else -am
        if abs(a) <= BRAKE_SNAP_RTOL * asc and not inside(v, a, lim[0], lim[1], lim[2], lim[3],
                                                            lim[4]):
            a = 0.0
        # a brake cut at a velocity reversal ends at v = 0 up to round-off (the
        # leg, hence the acceleration bound, changes there)
        if abs(v) <= BRAKE_SNAP_RTOL * vsc and not inside(v, a, lim[0], lim[1], lim[2], lim[3],
                                                           lim[4]):
            v = 0.0
        # a slowing acceleration whose velocity, through the reversal, lands a
        # few ulps beyond v_max (an end on two bounds at once, e.g. a bump onto
        # (v_max, 0) on the far side cut where |v| meets v_max)
        if v * a < 0.0 and lim[2] > 0.0 and lim[4] > 0.0:
            az2 = a * a - 2.0 * abs(v) / lim[4]
            over = 0.5 * az2 * lim[2] - lim[0]
            if 0.0 < over <= BRAKE_SNAP_RTOL * vsc:
                a2 = math.copysign(math.sqrt(2.0 * lim[0] / lim[2] + 2.0 * abs(v) / lim[4]), a)
                if inside(v, a2, lim[0], lim[1], lim[2], lim[3], lim[4]):
                    a = a2
        return v, a, inside(v, a, lim[0], lim[1], lim[2], lim[3], lim[4])
    return v, a, True


@jit_raw
def _brake_cand(cand, start_inside, st0, lim, brk, bbuf, s1):
    """Brake candidate ``cand`` (0, 1: paths; 2, 3: bumps to +-v_max; 4: natural;
    5: hold; 6: ruckig's rule; only 0 = none when the start is inside): (phase count or -1,
    duration); ``s1[:6]`` gets the problem from its end."""
    if start_inside:
        if cand > 0:
            return -1, 0.0
        nb = 0
    elif cand < 2:
        nb = brake_path(1.0 if cand == 0 else -1.0, st0[1], st0[2], lim[0], lim[1], lim[2],
                        lim[3], lim[4], brk, bbuf[:78])
    elif cand < 4:
        nb = brake_bump(lim[0] if cand == 2 else -lim[0], st0[1], st0[2], lim[0], lim[1],
                        lim[2], lim[3], lim[4], brk, bbuf)
    elif cand == 4:
        nb = brake_natural(st0[1], st0[2], lim[0], lim[1], lim[2], lim[3], lim[4], brk, bbuf)
    elif cand == 5:
        nb = brake_hold(st0[1], st0[2], lim[0], lim[1], lim[2], lim[3], lim[4], brk, bbuf)
    else:
        nb = brake_ruckig(st0[1], st0[2], lim[0], lim[1], lim[2], lim[3], lim[4], brk, bbuf)
    if nb < 0:
        return -1, 0.0
    # a brake exceeds the velocity limit no more than the start state forces (in
    # each direction)
    if nb > 0:
        pa, pb = peak_speed(brk, nb, st0[1], st0[2])
        fa, fb = forced_speed(st0[1], st0[2], lim[0], lim[1], lim[2], lim[3], lim[4])
        if pa > fa * (1.0 + BRAKE_SNAP_RTOL) or pb > fb * (1.0 + BRAKE_SNAP_RTOL):
            return -1, 0.0
    # ... nor an acceleration beyond its leg's bound longer than it forces
    if nb > 0 and lingers(brk, nb, st0[1], st0[2], lim[1], lim[2], lim[3], lim[4]):
        return -1, 0.0
    p = 0.0
    v = st0[1]
    a = st0[2]
    tb = 0.0
    vsc = abs(v)
    asc = abs(a)
    for k in range(nb):
        p, v, a = phase_end(p, v, brk[k, 2], brk[k, 1], brk[k, 0])
        tb += brk[k, 0]
        vsc = max(vsc, abs(v))
        asc = max(asc, abs(a), abs(brk[k, 2]))
    v, a, ok = _onto_boundary(v, a, lim, vsc, asc)
    if not ok:
        return -1, 0.0
    s1[0] = p
    s1[1] = v
    s1[2] = a
    s1[3] = st0[3]
    s1[4] = st0[4]
    s1[5] = st0[5]
    return nb, tb


@jit_raw
def _blocks_probed(ws, valid, nvalid, tmin, start_inside, st0, lim, brk, bbuf, s1, best, res, W, vec,
                   ivl, cfg, st, keep, out, ts, js, as_):
    """Blocked intervals with separate legs: between two consecutive valid
    step-1 durations a duration is feasible throughout or nowhere (every end
    of a blocked interval is a valid step-1 duration), but with separate legs
    step 1 also finds valid profiles whose durations lie inside the feasible
    set (an acceleration held through a velocity reversal, where the leg's
    bound changes), so the parity rule of :func:`_blocks` does not hold.
    Each gap is decided by step 2 at the points :data:`PROBES`: feasible at
    the first profile found, blocked where it finds none (its families miss
    some durations with separate legs, see the docs' known limits). The
    outputs written before (the minimum's profile) are kept; the intervals
    go to ``OUT_BLK`` (their count returned)."""
    sort_ascending(valid, nvalid)
    m = merge_equal(valid, nvalid, BLOCK_MERGE_RTOL)
    for k in range(_NSAVE):
        ws[_SAVE + k] = ws[OUT_STATUS + k]
    found = ws[_FOUND:_FOUND + 2 * NBLK]
    nblk = 0
    for i in range(m - 1):
        if nblk >= NBLK:
            break
        lo = valid[i]
        hi = valid[i + 1]
        blocked = True
        for f in PROBES:
            ws[OUT_STATUS] = ST_OK
            _step2(ws, lo + f * (hi - lo), tmin, 0, start_inside, st0, lim, brk, bbuf, s1, best,
                   res, W, vec, ivl, cfg, st, keep, out, ts, js, as_)
            if ws[OUT_STATUS] != ST_NONE:
                blocked = False
                break
        if blocked:
            found[2 * nblk] = lo * ts
            found[2 * nblk + 1] = hi * ts
            nblk += 1
    for k in range(_NSAVE):
        ws[OUT_STATUS + k] = ws[_SAVE + k]
    for k in range(2 * nblk):
        ws[OUT_BLK + k] = found[k]
    ws[OUT_NBLK] = nblk
    return nblk


@jit_raw
def _union_valid(vall, vcnt, out):
    """Sort and merge every brake candidate's valid durations (``vall[c,
    :vcnt[c]]``, in place, counts updated) and all of them into ``out``;
    returns the count in ``out``."""
    m = 0
    for c in range(vcnt.size):
        nc = int(vcnt[c])
        if nc == 0:
            continue
        sort_ascending(vall[c], nc)
        nc = merge_equal(vall[c], nc, BLOCK_MERGE_RTOL)
        vcnt[c] = nc
        for k in range(nc):
            out[m] = vall[c, k]
            m += 1
    sort_ascending(out, m)
    return merge_equal(out, m, BLOCK_MERGE_RTOL)


@jit_raw
def _blocks_union(uni, m, vall, vcnt, ws):
    """Blocked intervals of a start outside the limits with equal legs: the gaps
    between consecutive durations of ``uni[:m]`` (every candidate's valid
    durations, merged) where no brake candidate has a feasible duration. For
    one candidate, with ``k`` of its ``n`` valid durations below a point of a
    gap, the point is feasible where ``k`` and ``n`` are both odd or both even
    and ``k > 0`` (the parity rule of :func:`_blocks`). The intervals go to
    ``OUT_BLK`` (their count returned)."""
    nblk = 0
    for i in range(m - 1):
        if nblk >= NBLK:
            break
        x = 0.5 * (uni[i] + uni[i + 1])
        feasible = False
        for c in range(vcnt.size):
            nc = int(vcnt[c])
            k = 0
            while k < nc and vall[c, k] < x:
                k += 1
            if k > 0 and k % 2 == nc % 2:
                feasible = True
                break
        if not feasible:
            ws[OUT_BLK + 2 * nblk] = uni[i] * ws[_TS]
            ws[OUT_BLK + 2 * nblk + 1] = uni[i + 1] * ws[_TS]
            nblk += 1
    ws[OUT_NBLK] = nblk
    return nblk


@jit_raw
def _blocks(valid, nvalid, tmin, ws):
    """Blocked intervals from the durations of the valid step-1 profiles.

    Between moving states the feasible durations are ``[t_min, inf)`` minus
    intervals whose ends are durations of valid profiles (ruckig's *block*):
    with ``t_min < t1 < t2 < ...`` (equal durations merged), the blocked
    intervals are ``(t1, t2)``, ``(t3, t4)``. An even count means that the
    minimum is an isolated feasible duration (a degenerate profile, e.g. a
    pure cruise at ``v_max``, whose neighbours merged with it): the intervals
    are then ``(t_min, t1)``, ``(t2, t3)``.
    """
    sort_ascending(valid, nvalid)
    m = merge_equal(valid, nvalid, BLOCK_MERGE_RTOL)
    nblk = 0
    i = 1 if m % 2 == 1 else 0
    while i + 1 < m and nblk < NBLK:
        ws[OUT_BLK + 2 * nblk] = valid[i] * ws[_TS]
        ws[OUT_BLK + 2 * nblk + 1] = valid[i + 1] * ws[_TS]
        nblk += 1
        i += 2
    ws[OUT_NBLK] = nblk
    return nblk
