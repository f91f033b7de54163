"""Compiled batch kernel: the scalar closed forms in a parallel loop.

:func:`trajkit.plan_moves` uses this when numba is installed
(``pip install trajkit[fast]``) and falls back to the numpy formulation in
:mod:`trajkit.profiles.batch` otherwise. The kernel is not a second
implementation: it calls the functions of :mod:`trajkit.profiles._scalar`
(their code compiled, see :func:`._compile.compiled_twins`: same operations in
the same order, IEEE arithmetic without fast-math). Its transcendental
functions (``cbrt``, ``pow``) come from LLVM rather than the C library, so each
move agrees with :func:`trajkit.plan_move` to a few ulps; the tests check that
on random and boundary cases.
"""

from __future__ import annotations

import numpy as np

from .._constants import DURATION_RTOL
from . import _scalar
from ._compile import ENABLED, compiled_twins, jit_parallel, prange

__all__ = ["AVAILABLE", "plan_batch"]

#: True when the loop is compiled (else :mod:`.batch` uses numpy).
AVAILABLE = ENABLED

_T = compiled_twins(vars(_scalar), ("leg_threshold", "leg_time", "_lt", "leg_phases",
                                    "_newton_increasing", "_newton_decreasing",
                                    "peak_velocity", "cruise_velocity"))
_lt = _T["_lt"]
leg_phases = _T["leg_phases"]
peak_velocity = _T["peak_velocity"]
cruise_velocity = _T["cruise_velocity"]

@jit_parallel
def _loop(s, g, vm, a1, j1, a2, j2, thr1, thr2, T, has_T,
         dur, tmin_out, phases, jerks, vpk, ap1o, ap2o):
    n = s.shape[0]
    bad = n
    for i in prange(n):
        diff = g[i] - s[i]
        sign = 1.0 if diff > 0 else -1.0
        d = abs(diff)
        if d == 0.0:
            tmin_out[i] = 0.0
            dur[i] = T[i] if has_T else 0.0
            for k in range(7):
                phases[i, k] = 0.0
                jerks[i, k] = 0.0
            phases[i, 3] = dur[i]
            vpk[i] = 0.0
            ap1o[i] = 0.0
            ap2o[i] = 0.0
            continue
        A1, J1, A2, J2, t1, t2, vmax = a1[i], j1[i], a2[i], j2[i], thr1[i], thr2[i], vm[i]
        vp = peak_velocity(d, vmax, A1, J1, A2, J2, t1, t2)
        tmin = _lt(vp, A1, J1, t1) + _lt(vp, A2, J2, t2)
        if vp == vmax:
            tmin += max(d - 0.5 * vp * tmin, 0.0) / vp
        tmin_out[i] = tmin
        vc = vp
        duration = tmin
        if has_T:
            Ti = T[i]
            if Ti < tmin * (1.0 - DURATION_RTOL):
                bad = min(bad, i)  # infeasible: the caller raises, naming move i
                continue
            if Ti > tmin:
                vc = cruise_velocity(d, Ti, vp, A1, J1, A2, J2, t1, t2)
                duration = Ti
        tj1, ta1, ap1 = leg_phases(vc, A1, J1, t1)
        tj2, ta2, ap2 = leg_phases(vc, A2, J2, t2)
        ramps = 2.0 * tj1 + ta1 + 2.0 * tj2 + ta2
        tv = duration - ramps
        if tv < 0.0:
            tv = 0.0
        dur[i] = duration
        phases[i, 0] = tj1
        phases[i, 1] = ta1
        phases[i, 2] = tj1
        phases[i, 3] = tv
        phases[i, 4] = tj2
        phases[i, 5] = ta2
        phases[i, 6] = tj2
        jj1 = sign * J1 if tj1 > 0.0 else 0.0
        jj2 = sign * J2 if tj2 > 0.0 else 0.0
        jerks[i, 0] = jj1
        jerks[i, 1] = 0.0
        jerks[i, 2] = -jj1
        jerks[i, 3] = 0.0
        jerks[i, 5] = 0.0
        jerks[i, 4] = -jj2
        jerks[i, 6] = jj2
        vpk[i] = sign * vc
        ap1o[i] = ap1
        ap2o[i] = ap2
    return bad if bad < n else -1


def plan_batch(s, g, vm, a1, j1, a2, j2, thr1, thr2, T):
    """Run the compiled kernel; returns the index of the first infeasible
    duration (-1 when none) and the result arrays. Compiles on first use
    (cached on disk)."""
    n = s.shape[0]
    dur = np.empty(n)
    tmin = np.empty(n)
    phases = np.empty((n, 7))
    jerks = np.empty((n, 7))
    vpk = np.empty(n)
    ap1 = np.empty(n)
    ap2 = np.empty(n)
    has_T = T is not None
    Tarr = T if has_T else np.empty(1)
    bad = _loop(s, g, vm, a1, j1, a2, j2, thr1, thr2, Tarr, has_T,
                dur, tmin, phases, jerks, vpk, ap1, ap2)
    return bad, dur, tmin, phases, jerks, vpk, ap1, ap2
