"""Vectorised planning of many rest-to-rest moves at once (:func:`plan_moves`).

The same closed forms as :mod:`trajkit.profiles._scalar`, written with numpy
``where`` selections instead of branches and with Newton iterations run on
whole arrays, so N moves cost a few numpy passes and no Python loop per move.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._constants import DURATION_RTOL, ROOT_MAX_ITER, ROOT_RTOL
from ..errors import InfeasibleError, InvalidInputError
from ..limits import AxisLimits
from . import _jit
from . import _range as R
from .profile import Profile

__all__ = ["MoveBatch", "plan_moves"]

#: Batches at least this large use the compiled kernel (:mod:`._jit`) when numba
#: is installed (``pip install trajkit[fast]``) and ``TRAJKIT_NO_JIT`` is unset;
#: smaller ones (and installs without numba) use the numpy formulation below.
#: Both agree with :func:`plan_move` to a few ulps (numpy may use SIMD ``pow``/``cbrt``).
JIT_MIN_MOVES = 4096

_inf = np.inf


def _threshold(a, j):
    with np.errstate(invalid="ignore", divide="ignore"):
        thr = a * a / j
    thr = np.where(np.isinf(a), _inf, thr)
    return np.where(np.isinf(j), 0.0, thr)


def _leg_time(v, a, j, thr):
    with np.errstate(invalid="ignore", divide="ignore"):
        sat = v / a + a / j
        uns = 2.0 * np.sqrt(v / j)
    return np.where(v >= thr, sat, uns)


def _leg_phases(v, a, j, thr):
    with np.errstate(invalid="ignore", divide="ignore"):
        sat = v >= thr
        tj_s = a / j
        ta_s = np.maximum(v / a - tj_s, 0.0)
        tj_u = np.sqrt(v / j)
        tj = np.where(sat, tj_s, tj_u)
        ta = np.where(sat, ta_s, 0.0)
        ap = np.where(sat, a, j * tj_u)
    zero = v <= 0.0
    return (np.where(zero, 0.0, tj), np.where(zero, 0.0, ta), np.where(zero, 0.0, ap))


def _newton_inc(c4, c3, c2, d, u):
    u = u.copy()
    active = np.ones(u.shape, dtype=bool)
    for _ in range(ROOT_MAX_ITER):
        if not active.any():
            break
        ua = u[active]
        a4, a3, a2, dd = c4[active], c3[active], c2[active], d[active]
        u2 = ua * ua
        f = ((a4 * ua + a3) * ua + a2) * u2 - dd
        df = ((4.0 * a4 * ua + 3.0 * a3) * ua + 2.0 * a2) * ua
        ok = df > 0.0
        step = np.where(ok, f / np.where(ok, df, 1.0), 0.0)
        unew = ua - step
        u[active] = unew
        still = ok & (step > ROOT_RTOL * unew)
        idx = np.flatnonzero(active)
        active[idx[~still]] = False
    return u


def _newton_dec(p, q, c, d, t, u):
    u = u.copy()
    active = np.ones(u.shape, dtype=bool)
    for _ in range(ROOT_MAX_ITER):
        if not active.any():
            break
        ua = u[active]
        pa, qa, ca, dd, ta = p[active], q[active], c[active], d[active], t[active]
        inv = 1.0 / (ua * ua)
        h = (pa * ua + ca) * ua + qa + dd * inv - ta
        dh = 2.0 * pa * ua + ca - 2.0 * dd * inv / ua
        ok = dh < 0.0
        step = np.where(ok, -h / np.where(ok, dh, -1.0), 0.0)
        unew = ua + step
        u[active] = unew
        still = ok & (step > ROOT_RTOL * unew)
        idx = np.flatnonzero(active)
        active[idx[~still]] = False
    return u


def _peak_velocity(d, vmax, a1, j1, a2, j2, thr1, thr2):
    """Vectorised :func:`trajkit.profiles._scalar.peak_velocity` (d > 0)."""
    n = d.shape[0]
    out = np.empty(n)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        dist_v = 0.5 * vmax * (_leg_time(vmax, a1, j1, thr1) + _leg_time(vmax, a2, j2, thr2))
        cruise = np.isfinite(vmax) & (dist_v <= d)
        out[cruise] = vmax[cruise]
        first = thr1 <= thr2
        lo = np.where(first, thr1, thr2)
        hi = np.where(first, thr2, thr1)
        ak = np.where(first, a1, a2)
        jk = np.where(first, j1, j2)
        jo = np.where(first, j2, j1)
        dist_lo = np.where(np.isfinite(lo),
                           0.5 * lo * (_leg_time(lo, a1, j1, thr1) + _leg_time(lo, a2, j2, thr2)), _inf)
        dist_hi = np.where(np.isfinite(hi),
                           0.5 * hi * (_leg_time(hi, a1, j1, thr1) + _leg_time(hi, a2, j2, thr2)), _inf)
        rest = ~cruise
        above_lo = rest & np.isfinite(lo) & (dist_lo < d)
        both = above_lo & np.isfinite(hi) & (dist_hi <= d)
        mixed = above_lo & ~both
        none = rest & ~above_lo
        if both.any():
            p = 0.5 * (1.0 / a1[both] + 1.0 / a2[both])
            q = 0.5 * (a1[both] / j1[both] + a2[both] / j2[both])
            db = d[both]
            out[both] = 2.0 * db / (q + np.sqrt(q * q + 4.0 * p * db))
        if mixed.any():
            dm = d[mixed]
            akm, jkm, jom, him = ak[mixed], jk[mixed], jo[mixed], hi[mixed]
            c4 = 0.5 / akm
            c3 = 1.0 / np.sqrt(jom)
            c2 = 0.5 * akm / jkm
            u = np.minimum(np.sqrt(him), np.minimum((dm / c4) ** 0.25, (dm / c3) ** (1.0 / 3.0)))
            u = np.where(c2 > 0.0, np.minimum(u, np.sqrt(dm / np.where(c2 > 0.0, c2, 1.0))), u)
            u = _newton_inc(c4, c3, c2, dm, u)
            out[mixed] = u * u
        if none.any():
            c = 1.0 / np.sqrt(j1[none]) + 1.0 / np.sqrt(j2[none])
            out[none] = (d[none] / c) ** (2.0 / 3.0)
    return out


def _cruise_velocity(d, t, vp, a1, j1, a2, j2, thr1, thr2):
    """Vectorised :func:`trajkit.profiles._scalar.cruise_velocity`."""
    n = d.shape[0]
    out = np.empty(n)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        first = thr1 <= thr2
        lo = np.where(first, thr1, thr2)
        hi = np.where(first, thr2, thr1)
        ak = np.where(first, a1, a2)
        jk = np.where(first, j1, j2)
        jo = np.where(first, j2, j1)
        u0 = np.sqrt(d / t)
        t_lo = np.where(lo == 0.0, _inf, 0.5 * (_leg_time(lo, a1, j1, thr1) + _leg_time(lo, a2, j2, thr2)) + d / lo)
        t_hi = 0.5 * (_leg_time(hi, a1, j1, thr1) + _leg_time(hi, a2, j2, thr2)) + d / hi
        above_lo = (lo < vp) & np.isfinite(lo) & (t_lo > t)
        both = above_lo & (hi < vp) & np.isfinite(hi) & (t_hi > t)
        mixed = above_lo & ~both
        none = ~above_lo
        if both.any():
            p = 0.5 * (1.0 / a1[both] + 1.0 / a2[both])
            q = 0.5 * (a1[both] / j1[both] + a2[both] / j2[both])
            b = t[both] - q
            db = d[both]
            r = 4.0 * p * db / b / b
            out[both] = 2.0 * db / (b * (1.0 + np.sqrt(np.maximum(1.0 - r, 0.0))))
        if mixed.any():
            akm = ak[mixed]
            u = _newton_dec(0.5 / akm, 0.5 * akm / jk[mixed], 1.0 / np.sqrt(jo[mixed]),
                            d[mixed], t[mixed], u0[mixed])
            out[mixed] = u * u
        if none.any():
            m = int(none.sum())
            c = 1.0 / np.sqrt(j1[none]) + 1.0 / np.sqrt(j2[none])
            u = _newton_dec(np.zeros(m), np.zeros(m), c, d[none], t[none], u0[none])
            out[none] = u * u
    return out


@dataclass(frozen=True)
class MoveBatch:
    """N rest-to-rest moves planned at once by :func:`plan_moves`.

    Attributes
    ----------
    start, goal : ndarray, shape (N,)
        Positions [unit].
    duration : ndarray, shape (N,)
        Duration of each move [s].
    min_duration : ndarray, shape (N,)
        Minimum duration of each move [s].
    phase_durations : ndarray, shape (N, 7)
        Durations of the seven phases [s] (order of :data:`PHASE_NAMES`).
    jerks : ndarray, shape (N, 7)
        Jerk of each phase, signed [unit/s^3].
    peak_velocity : ndarray, shape (N,)
        Signed peak velocity [unit/s].
    peak_acceleration, peak_deceleration : ndarray, shape (N,)
        Acceleration reached in the accel and decel legs [unit/s^2].
    v_max, a_max, j_max, a_max_decel, j_max_decel : ndarray, shape (N,)
        The (broadcast) limits.
    """

    start: np.ndarray
    goal: np.ndarray
    duration: np.ndarray
    min_duration: np.ndarray
    phase_durations: np.ndarray
    jerks: np.ndarray
    peak_velocity: np.ndarray
    peak_acceleration: np.ndarray
    peak_deceleration: np.ndarray
    v_max: np.ndarray
    a_max: np.ndarray
    j_max: np.ndarray
    a_max_decel: np.ndarray
    j_max_decel: np.ndarray

    def __len__(self) -> int:
        return int(self.duration.shape[0])

    def profile(self, i: int) -> Profile:
        """Return move ``i`` as a :class:`Profile` (same phases, for sampling)."""
        lim = AxisLimits(
            float(self.v_max[i]), float(self.a_max[i]), float(self.j_max[i]),
            float(self.a_max_decel[i]), float(self.j_max_decel[i]),
        )
        return Profile(
            float(self.start[i]), float(self.goal[i]), float(self.duration[i]),
            float(self.min_duration[i]),
            tuple(float(x) for x in self.phase_durations[i]),
            tuple(float(x) for x in self.jerks[i]),
            float(self.peak_velocity[i]), float(self.peak_acceleration[i]),
            float(self.peak_deceleration[i]), lim,
        )


def _float_array(value, name):
    try:
        return np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{name} must be a number or an array of numbers, "
                                f"got {value!r}") from None


def _limit_array(value, name, n, allow_inf=True):
    arr = _float_array(value, name)
    try:
        arr = np.broadcast_to(arr, (n,))
    except ValueError:
        raise InvalidInputError(
            f"{name} must be a scalar or have {n} entries, got shape {arr.shape}"
        ) from None
    # one pass when every entry is fine (NaN fails ``> 0``); the first bad one named
    ok = bool(np.all(arr > 0.0)) if allow_inf else bool(np.all((arr > 0.0) & (arr < np.inf)))
    if not ok:
        bad = np.isnan(arr) | (arr <= 0.0) | (~allow_inf & np.isinf(arr))
        i = int(np.flatnonzero(bad)[0])
        raise InvalidInputError(
            f"{name}[{i}] should be larger than zero, got {float(arr[i])!r}"
        )
    return np.ascontiguousarray(arr)


def _check_range(s, g, vm, a1, j1, a2, j2, T) -> None:
    """The supported numeric range (:mod:`._range`), vectorised; names the first bad move."""
    def first(mask, field, vals, bound, why):
        if mask.any():
            i = int(np.flatnonzero(mask)[0])
            raise InvalidInputError(
                f"{field}[{i}] {float(vals[i])!r} is outside the supported range: {why} {bound!r}")

    for name, x in (("starts", s), ("goals", g)):
        first(np.abs(x) > R.REST_POSITION_MAX, name, x, R.REST_POSITION_MAX,
              "|position| must be at most")
    d = np.abs(g - s)
    first((d != 0.0) & (d < R.DISTANCE_ABS_MIN), "distance", g - s, R.DISTANCE_ABS_MIN,
          "a non-zero |distance| must be at least")
    for name, x in (("v_max", vm), ("a_max", a1), ("j_max", j1), ("a_max_decel", a2),
                    ("j_max_decel", j2)):
        fin = np.isfinite(x)
        first(fin & ((x < R.REST_MAGNITUDE_MIN) | (x > R.REST_MAGNITUDE_MAX)), name, x,
              (R.REST_MAGNITUDE_MIN, R.REST_MAGNITUDE_MAX), "finite limits must lie in")
    with np.errstate(all="ignore"):
        for name, x, y in (("a_max_decel", a2, a1), ("j_max_decel", j2, j1)):
            r = x / y
            first(np.isfinite(x) & np.isfinite(y) & ((r < 1.0 / R.LEG_RATIO_MAX) | (r > R.LEG_RATIO_MAX)),
                  name, x, R.LEG_RATIO_MAX, "the decel leg must be within a factor of the accel leg:")
    if T is not None:
        first(T > R.REST_DURATION_MAX, "durations", T, R.REST_DURATION_MAX,
              "a requested duration [s] must be at most")


def _check_ratio(T, tmin, moving) -> None:
    """Requested durations at most ``REST_DURATION_RATIO_MAX`` times the minimum."""
    if T is None:
        return
    bad = moving & (T > R.REST_DURATION_RATIO_MAX * tmin)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise InvalidInputError(
            f"durations[{i}] {float(T[i])!r} is outside the supported range: a requested "
            f"duration [s] must be at most {R.REST_DURATION_RATIO_MAX!r} times the minimum "
            f"duration of the move, {float(tmin[i]) * R.REST_DURATION_RATIO_MAX!r}")


def _check_cruise(T, vc, fixed, a1, j1, a2, j2) -> None:
    """Cruise velocities of fixed durations at least ``REST_CRUISE_MIN`` times every finite limit."""
    bad = np.zeros(vc.shape, dtype=bool)
    with np.errstate(all="ignore"):
        for x in (a1, j1, a2, j2):
            bad |= fixed & np.isfinite(x) & ~(vc >= R.REST_CRUISE_MIN * x)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise InvalidInputError(
            f"durations[{i}] {float(T[i])!r} is outside the supported range: a requested "
            f"duration this long gives a cruise velocity {float(vc[i])!r} whose ratio to every "
            f"finite acceleration and jerk limit must be at least {R.REST_CRUISE_MIN!r}")


def plan_moves(
    starts: Any,
    goals: Any,
    v_max: Any,
    a_max: Any,
    j_max: Any,
    a_max_decel: Any = None,
    j_max_decel: Any = None,
    durations: Any = None,
) -> MoveBatch:
    """Plan N rest-to-rest moves at once, vectorised over numpy arrays.

    The results agree with :func:`plan_move` move by move to 1e-12 relative
    (same closed forms, same root iterations).

    Parameters
    ----------
    starts, goals : array_like, shape (N,)
        Positions [unit], finite.
    v_max, a_max, j_max : float or array_like, shape (N,)
        Limits of the accel leg (broadcast); ``inf`` as in :class:`AxisLimits`.
    a_max_decel, j_max_decel : float or array_like, shape (N,), optional
        Limits of the decel leg; ``None`` means the same as the accel leg.
    durations : float or array_like, shape (N,), optional
        Requested durations [s]; each must be >= its move's minimum.

    Returns
    -------
    MoveBatch

    Raises
    ------
    InvalidInputError
        NaN/inf positions, bad limits, mismatched shapes, values outside the
        supported range (:mod:`trajkit.profiles._range`, as :func:`plan_move`).
    InfeasibleError
        A requested duration below its minimum (the first such move is named).
    """
    from .._validate import check_array

    s = check_array(starts, "starts", ndim=1)
    g = check_array(goals, "goals", ndim=1)
    if s.shape != g.shape:
        raise InvalidInputError(
            f"starts and goals must have the same shape, got {s.shape} and {g.shape}"
        )
    n = s.shape[0]
    vm = _limit_array(v_max, "v_max", n)
    a1 = _limit_array(a_max, "a_max", n)
    j1 = _limit_array(j_max, "j_max", n)
    a2 = a1 if a_max_decel is None else _limit_array(a_max_decel, "a_max_decel", n)
    j2 = j1 if j_max_decel is None else _limit_array(j_max_decel, "j_max_decel", n)
    for (aa, jj, an, jn) in ((a1, j1, "a_max", "j_max"), (a2, j2, "a_max_decel", "j_max_decel")):
        both = np.isinf(aa) & np.isinf(jj)
        if both.any():
            i = int(np.flatnonzero(both)[0])
            raise InvalidInputError(f"{an}[{i}] and {jn}[{i}] cannot both be infinite")
    T = None
    if durations is not None:
        T = _float_array(durations, "durations")
        try:
            T = np.ascontiguousarray(np.broadcast_to(T, (n,)))
        except ValueError:
            raise InvalidInputError(
                f"durations must be a scalar or have {n} entries, got shape {T.shape}"
            ) from None
        bad = ~np.isfinite(T) | (T < 0.0)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise InvalidInputError(f"durations[{i}] must be finite and >= 0 s, got {float(T[i])!r}")

    _check_range(s, g, vm, a1, j1, a2, j2, T)
    thr1 = _threshold(a1, j1)
    thr2 = _threshold(a2, j2)
    if n >= JIT_MIN_MOVES and _jit.AVAILABLE and not os.environ.get("TRAJKIT_NO_JIT"):
        bad, dur, tmin, phases, jerks, vpk, ap1, ap2 = _jit.plan_batch(
            s, g, vm, a1, j1, a2, j2, thr1, thr2, T)
        if bad >= 0:
            assert T is not None  # a move is too short only for a requested duration
            raise InfeasibleError(
                f"durations[{bad}] = {float(T[bad])!r} s is below the minimum duration "
                f"{tmin[bad]:.15g} s",
                minimum=float(tmin[bad]),
            )
        _check_ratio(T, tmin, g != s)
        _check_cruise(T, np.abs(vpk), dur > tmin, a1, j1, a2, j2)
        return MoveBatch(
            start=s, goal=g, duration=dur, min_duration=tmin, phase_durations=phases,
            jerks=jerks, peak_velocity=vpk, peak_acceleration=ap1, peak_deceleration=ap2,
            v_max=vm, a_max=a1, j_max=j1, a_max_decel=a2, j_max_decel=j2,
        )

    diff = g - s
    sign = np.where(diff > 0, 1.0, -1.0)
    dist = np.abs(diff)
    moving = dist > 0.0

    vp = np.zeros(n)
    tmin = np.zeros(n)
    if moving.any():
        m = moving
        vpm = _peak_velocity(dist[m], vm[m], a1[m], j1[m], a2[m], j2[m], thr1[m], thr2[m])
        tl = _leg_time(vpm, a1[m], j1[m], thr1[m]) + _leg_time(vpm, a2[m], j2[m], thr2[m])
        cr = vpm == vm[m]
        tl = np.where(cr, tl + np.maximum(dist[m] - 0.5 * vpm * tl, 0.0) / vpm, tl)
        vp[m] = vpm
        tmin[m] = tl

    vc = vp.copy()
    dur = tmin.copy()
    fixed = np.zeros(n, dtype=bool)
    if T is not None:
        low = T < tmin * (1.0 - DURATION_RTOL)
        if low.any():
            i = int(np.flatnonzero(low)[0])
            raise InfeasibleError(
                f"durations[{i}] = {float(T[i])!r} s is below the minimum duration {tmin[i]:.15g} s",
                minimum=float(tmin[i]),
            )
        _check_ratio(T, tmin, moving)
        fixed = moving & (T > tmin)
        if fixed.any():
            f = fixed
            vc[f] = _cruise_velocity(dist[f], T[f], vp[f], a1[f], j1[f], a2[f], j2[f], thr1[f], thr2[f])
            _check_cruise(T, vc, fixed, a1, j1, a2, j2)
        dur = np.where(fixed | ~moving, T, tmin)

    tj1, ta1, ap1 = _leg_phases(vc, a1, j1, thr1)
    tj2, ta2, ap2 = _leg_phases(vc, a2, j2, thr2)
    ramps = 2.0 * tj1 + ta1 + 2.0 * tj2 + ta2
    tv = np.maximum(dur - ramps, 0.0)
    # built phase-major (7, N) with contiguous row writes; exposed as (N, 7) views
    phases_t = np.empty((7, n))
    phases_t[0] = tj1
    phases_t[1] = ta1
    phases_t[2] = tj1
    phases_t[3] = tv
    phases_t[4] = tj2
    phases_t[5] = ta2
    phases_t[6] = tj2
    jerks_t = np.zeros((7, n))
    np.multiply(sign, j1, out=jerks_t[0], where=tj1 > 0.0)
    np.negative(jerks_t[0], out=jerks_t[2])
    np.multiply(sign, j2, out=jerks_t[6], where=tj2 > 0.0)
    np.negative(jerks_t[6], out=jerks_t[4])
    phases, jerks = phases_t.T, jerks_t.T
    return MoveBatch(
        start=s, goal=g, duration=dur, min_duration=tmin, phase_durations=phases,
        jerks=jerks, peak_velocity=np.where(moving, sign * vc, 0.0),
        peak_acceleration=ap1, peak_deceleration=ap2,
        v_max=vm, a_max=a1, j_max=j1, a_max_decel=a2, j_max_decel=j2,
    )
