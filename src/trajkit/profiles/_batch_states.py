"""Compiled loops over the one-axis kernel: many moves, and many synchronised axes.

* :func:`solve_many` plans N independent moves between states (minimum time,
  or each a requested duration) in one call, in parallel over the cores
  (``numba.prange`` over chunks, one workspace per chunk).
* :func:`sync_time` plans the axes of one multi-axis move in time
  synchronisation (ruckig's scheme): step 1 with the blocked intervals on
  every axis, the common duration (the largest minimum, moved past every
  blocked interval), step 2 on every axis that is not at its own minimum.

Both run the same :func:`._kernel.solve` as the one-axis planner, on inputs
validated by the caller: :func:`solve_many` on the arrays of starts, goals
and limits, :func:`sync_time` on rows ``(p0, v0, a0, pf, vf, af, v_max,
a_max, j_max, a_max_decel, j_max_decel)`` and bounds (:data:`NSYNC`).
"""

from __future__ import annotations

import math

import numpy as np

from . import _kernel as K
from . import _range as R
from ._brake import inside
from ._compile import jit, jit_parallel, jit_raw, prange
from ._range import DISTANCE_ABS_MIN
from ._shapes import NPH

__all__ = ["NIN", "NSYNC", "NBLK", "ST_GOAL", "ST_WIDE", "ST_RANGE", "solve_many", "sync_time",
           "NPH", "exact_sum", "sum_partials"]

NBLK = K.NBLK

#: Columns of an input row.
NIN = 11

#: Columns of an input row of :func:`sync_time`: a row of :data:`NIN`, then the
#: bounds of a state the caller validated the limits for (position range,
#: |v|, |a|, ``1/(2 min j)``, the forced-speed bound; see ``profiles.state._fast_pair``).
NSYNC = NIN + 6

#: Status (beyond the kernel's): the goal state cannot be reached within the limits.
ST_GOAL = 9

#: Status of :func:`solve_many`: planned, but the phase table given is narrower
#: than the move's phases (``nph`` says how many; plan it again with a wider one).
ST_WIDE = 10

#: Status of :func:`solve_many`: a value of the move lies outside the supported
#: range of the state planners (see :func:`_in_range`; not planned).
ST_RANGE = 11

#: Rounds of moving the common duration past blocked intervals.
SYNC_MAX_ROUNDS = 16

#: Moves per chunk of the parallel loop (one workspace each).
CHUNK = 64

#: The unit round-off of doubles.
_U = 2.0**-53


@jit_raw
def _goal_ok(vf, af, V, A1, J1, A2, J2):
    """Whether the goal (v, a) can be reached: leaving (v, -a) backwards in time,
    legs swapped, is inside the limits."""
    K1 = 1.0 / J1 if J1 < math.inf else 0.0
    K2 = 1.0 / J2 if J2 < math.inf else 0.0
    return inside(vf, -af, V, A2, K2, A1, K1)


@jit
def _state_ok(row):
    """Whether the start and goal of a :data:`NSYNC` row lie within its bounds (the
    checks of the one-axis planner's fast path) and the distance is zero or
    resolvable; NaN fails."""
    plo = row[NIN]
    phi = row[NIN + 1]
    vb = row[NIN + 2]
    ab = row[NIN + 3]
    k2 = row[NIN + 4]
    vb2 = row[NIN + 5]
    for o in (0, 3):
        p, v, a = row[o], row[o + 1], row[o + 2]
        if not (plo <= p <= phi and abs(v) <= vb and abs(a) <= ab and abs(v) + a * a * k2 <= vb2):
            return False
    d = abs(row[3] - row[0])
    return d == 0.0 or d >= DISTANCE_ABS_MIN


@jit_raw
def _ratio_out(r, rmax):
    """Whether the ratio ``r`` is finite and outside ``[1 / rmax, rmax]``."""
    return abs(r) < math.inf and (r < 1.0 / rmax or r > rmax)


@jit_raw
def _in_range(p0, v0, a0, pf, vf, af, vm, a1, j1, a2, j2, T):
    """Whether a move (start, goal, limits, requested duration ``T`` or NaN) lies
    in the supported range of the state planners (:mod:`._range`): the checks
    of ``state_batch._check``, which names the first bad move, with its
    arithmetic; the limits are positive and not NaN (checked before)."""
    for x in (vm, a1, j1, a2, j2):
        if x < math.inf and (x < R.MAGNITUDE_MIN or x > R.MAGNITUDE_MAX):
            return False
    if vm == math.inf and a1 == math.inf and a2 == math.inf:
        return False
    if _ratio_out(a2 / a1, R.LEG_RATIO_MAX) or _ratio_out(j2 / j1, R.LEG_RATIO_MAX):
        return False
    if (_ratio_out(vm * j1 / (a1 * a1), R.SHAPE_RATIO_MAX)
            or _ratio_out(vm * j2 / (a2 * a2), R.SHAPE_RATIO_MAX)):
        return False
    am = max(a1, a2)
    jm = min(j1, j2)
    for p, v, a in ((p0, v0, a0), (pf, vf, af)):
        if abs(p) > R.POSITION_MAX or abs(v) > R.STATE_RATIO_MAX * vm:
            return False
        if abs(a) > R.STATE_RATIO_MAX * am:
            return False
        if vm < math.inf and abs(v) + 0.5 * (a * a) / jm > R.STATE_RATIO_MAX * vm:
            return False
    d = abs(pf - p0)
    if d != 0.0 and d < R.DISTANCE_ABS_MIN:
        return False
    return not (T > R.DURATION_MAX)


@jit_raw
def _load(ws, inp, i, task, T):
    """Row ``i`` of ``inp`` (rows of :data:`NIN` or more) and the task into the
    workspace."""
    for k in range(NIN):
        ws[k] = inp[i, k]
    ws[K.IN_TASK] = task
    ws[K.IN_T] = T


@jit_raw
def _load_move(ws, s, g, vm, a1, j1, a2, j2, i, task, T):
    """Move ``i`` of :func:`solve_many`'s arrays and the task into the workspace."""
    ws[0] = s[i, 0]
    ws[1] = s[i, 1]
    ws[2] = s[i, 2]
    ws[3] = g[i, 0]
    ws[4] = g[i, 1]
    ws[5] = g[i, 2]
    ws[6] = vm[i]
    ws[7] = a1[i]
    ws[8] = j1[i]
    ws[9] = a2[i]
    ws[10] = j2[i]
    ws[K.IN_TASK] = task
    ws[K.IN_T] = T


@jit_raw
def _store(ws, i, status, dur, tmin, nph, nbr, shape, ph):
    st = int(ws[K.OUT_STATUS])
    status[i] = st
    tmin[i] = ws[K.OUT_TMIN]
    n = int(ws[K.OUT_N]) if st == K.ST_OK else 0
    nph[i] = n
    if n > ph.shape[1]:
        status[i] = ST_WIDE
        return
    nbr[i] = int(ws[K.OUT_NB])
    shape[i] = ws[K.OUT_SHAPE]
    for k in range(n):
        ph[i, k, 0] = ws[K.OUT_PH + 3 * k]
        ph[i, k, 1] = ws[K.OUT_PH + 3 * k + 1]
        ph[i, k, 2] = ws[K.OUT_PH + 3 * k + 2]
    # the duration is the sum of the phases correctly rounded: the float
    # ``math.fsum`` gives in the one-axis planner, bit for bit
    dur[i] = exact_sum(ws, K.OUT_PH, 3, n, K.SUM_SCRATCH) if st == K.ST_OK else ws[K.OUT_T]


@jit_raw
def exact_sum(ws, first, stride, n, scratch):
    """The correctly rounded sum of ``ws[first + stride * k]``, k < n (finite
    values; ``n`` <= :data:`NPH`): the same float as ``math.fsum``, which
    rounds the exact sum the same way (to nearest, ties to even).

    First the running sum with every addition's error kept exactly (TwoSum),
    the errors summed in floats with a bound on that sum's round-off: where
    both ends of the exact sum's enclosure round to the same float, that
    float is the correctly rounded sum (rounding is monotone). Otherwise (a
    sum within a few ulps of a tie, or a huge cancellation)
    :func:`sum_partials` decides.
    """
    s = 0.0
    c = 0.0
    ea = 0.0
    for k in range(n):
        x = ws[first + stride * k]
        t = s + x
        bp = t - s
        e = (s - (t - bp)) + (x - bp)
        s = t
        c += e
        ea += abs(e)
    if ea == 0.0:
        return s  # every addition exact
    # |c - sum(e)| <= (n - 1) u sum|e| (u = 2^-53); four times that margin
    # also covers the round-off of c -/+ d
    d = 4.0 * (n + 2) * _U * ea
    lo = s + (c - d)
    hi = s + (c + d)
    if lo == hi and abs(lo) < math.inf:
        return lo
    return sum_partials(ws, first, stride, n, scratch)


@jit_raw
def sum_partials(ws, first, stride, n, scratch):
    """:func:`exact_sum` by Shewchuk's algorithm (the general case): the running
    sum is kept exactly as non-overlapping partials (``ws[scratch:]``, in
    increasing magnitude); the result is their sum from the largest down,
    with the tie case across partials decided by the sign of the rest."""
    m = 0  # partials in use
    for k in range(n):
        x = ws[first + stride * k]
        j = 0
        for i in range(m):
            y = ws[scratch + i]
            if abs(x) < abs(y):
                x, y = y, x
            hi = x + y
            lo = y - (hi - x)
            if lo != 0.0:
                ws[scratch + j] = lo
                j += 1
            x = hi
        m = j
        if x != 0.0:
            ws[scratch + m] = x
            m += 1
    if m == 0:
        return 0.0
    m -= 1
    hi = ws[scratch + m]
    lo = 0.0
    while m > 0:
        x = hi
        m -= 1
        y = ws[scratch + m]
        hi = x + y
        lo = y - (hi - x)
        if lo != 0.0:
            break
    if m > 0 and ((lo < 0.0 and ws[scratch + m - 1] < 0.0) or (lo > 0.0 and ws[scratch + m - 1] > 0.0)):
        # the exact sum lies just past the halfway point hi + lo: round away
        y = lo * 2.0
        x = hi + y
        if y == x - hi:
            hi = x
    return hi


@jit_raw
def _solve_rows(s, g, vm, a1, j1, a2, j2, T, status, dur, tmin, nph, nbr, shape, ph, ws, i0, i1):
    """Moves ``i0 .. i1 - 1`` of :func:`solve_many` with the workspace ``ws`` (no
    reference counting: the threads share the arrays' counts, and counting
    them per move would make the threads wait on each other)."""
    for i in range(i0, i1):
        ok = _in_range(s[i, 0], s[i, 1], s[i, 2], g[i, 0], g[i, 1], g[i, 2], vm[i], a1[i], j1[i],
                       a2[i], j2[i], T[i])
        if not ok or not _goal_ok(g[i, 1], g[i, 2], vm[i], a1[i], j1[i], a2[i], j2[i]):
            status[i] = ST_GOAL if ok else ST_RANGE
            nph[i] = 0
            dur[i] = math.nan
            tmin[i] = math.nan
            continue
        Ti = T[i]
        if Ti == Ti:
            _load_move(ws, s, g, vm, a1, j1, a2, j2, i, K.TASK_FIXED, Ti)
        else:
            _load_move(ws, s, g, vm, a1, j1, a2, j2, i, K.TASK_MIN, 0.0)
        K.solve(ws)
        _store(ws, i, status, dur, tmin, nph, nbr, shape, ph)


@jit_parallel
def solve_many(s, g, vm, a1, j1, a2, j2, T, status, dur, tmin, nph, nbr, shape, ph):
    """Plan every move: from ``s[i]`` to ``g[i]`` (``(N, 3)`` states) within the
    limits ``vm[i] .. j2[i]`` (``(N,)`` each, C-contiguous), minimum time where
    ``T[i]`` is NaN, else exactly ``T[i]``. Fills the output arrays (``ph``:
    ``(N, W, 3)`` phase tables, any width ``W``; a move of more phases gets the
    status :data:`ST_WIDE`, one outside the supported range :data:`ST_RANGE`)."""
    n = s.shape[0]
    nchunk = (n + CHUNK - 1) // CHUNK
    for c in prange(nchunk):
        ws = np.zeros(K.NWS)
        _solve_rows(s, g, vm, a1, j1, a2, j2, T, status, dur, tmin, nph, nbr, shape, ph, ws,
                    c * CHUNK, min(n, (c + 1) * CHUNK))


@jit
def sync_time(inp, Treq, status, dur, tmin, nph, nbr, shape, ph, blk, nblk):
    """Time-synchronised plan of the axes in ``inp`` (rows of :data:`NSYNC`).

    ``Treq``: the requested common duration, NaN for the minimum. Returns
    ``(code, T)``: code 0 and the common duration when every axis is planned
    (outputs filled per axis), else a negative code (-1: an axis' step 1
    failed, see ``status``; -2: the requested duration is below the
    synchronised minimum; -3: it lies in a blocked interval of an axis; -4:
    step 2 failed on an axis, which the caller plans again in Python; -5: a
    state of an axis is outside its row's bounds, which the caller checks
    again with its messages) and the axis index in ``T``'s place.

    The blocked intervals of an axis with separate legs are probed by step 2
    (see ``_kernel._blocks_probed``), which costs a step 2 per gap: they are
    computed only for an axis whose step 2 fails at the common duration.
    """
    n = inp.shape[0]
    for i in range(n):
        if not _state_ok(inp[i]):
            return -5, float(i)
    ws = np.zeros(K.NWS)
    pending = np.zeros(n, dtype=np.bool_)
    # step 1 on every axis, with its blocked intervals (separate legs: later)
    for i in range(n):
        row = inp[i]
        if not _goal_ok(row[4], row[5], row[6], row[7], row[8], row[9], row[10]):
            status[i] = ST_GOAL
            return -1, float(i)
        pending[i] = row[7] != row[9] or row[8] != row[10]
        _load(ws, inp, i, K.TASK_MIN if pending[i] else K.TASK_BLOCK, 0.0)
        K.solve(ws)
        _store(ws, i, status, dur, tmin, nph, nbr, shape, ph)
        if status[i] != K.ST_OK:
            return -1, float(i)
        nblk[i] = 0
        if not pending[i]:
            _keep_blocks(ws, i, blk, nblk)
    T0 = 0.0
    for i in range(n):
        T0 = max(T0, tmin[i])
    if Treq == Treq and Treq < T0 * (1.0 - K.DURATION_RTOL):
        return -2, T0
    for _ in range(n + 1):  # (each pass resolves the blocks of one more axis)
        if Treq == Treq:
            for i in range(n):
                for b in range(nblk[i]):
                    if blk[i, b, 0] < Treq < blk[i, b, 1]:
                        return -3, float(i)
            T = max(Treq, T0)
        else:
            # the smallest duration feasible for every axis
            T = T0
            for _ in range(SYNC_MAX_ROUNDS):
                T2 = T
                for i in range(n):
                    for b in range(nblk[i]):
                        if blk[i, b, 0] < T2 < blk[i, b, 1]:
                            T2 = blk[i, b, 1]
                if T2 == T:
                    break
                T = T2
        # step 2 on every axis not at its own minimum
        failed = -1
        for i in range(n):
            if T <= tmin[i] * (1.0 + K.DURATION_RTOL):
                continue
            _load(ws, inp, i, K.TASK_STEP2, T)
            ws[K.OUT_TMIN] = tmin[i]
            K.solve(ws)
            _store(ws, i, status, dur, tmin, nph, nbr, shape, ph)
            if status[i] != K.ST_OK:
                failed = i
                break
        if failed < 0:
            return 0, T
        if not pending[failed]:
            return -4, float(failed)
        # the failed axis' blocked intervals: does T lie in one?
        pending[failed] = False
        _load(ws, inp, failed, K.TASK_BLOCK, 0.0)
        K.solve(ws)
        if ws[K.OUT_STATUS] != K.ST_OK:
            return -4, float(failed)
        _keep_blocks(ws, failed, blk, nblk)
        inside = False
        for b in range(nblk[failed]):
            if blk[failed, b, 0] < T < blk[failed, b, 1]:
                inside = True
        if not inside:
            return -4, float(failed)
    return -4, 0.0


@jit_raw
def _keep_blocks(ws, i, blk, nblk):
    """The blocked intervals of the solve in ``ws`` as axis ``i``'s."""
    nb = int(ws[K.OUT_NBLK])
    nblk[i] = nb
    for b in range(nb):
        blk[i, b, 0] = ws[K.OUT_BLK + 2 * b]
        blk[i, b, 1] = ws[K.OUT_BLK + 2 * b + 1]
