"""Scalar closed-form kernels for rest-to-rest jerk-limited profiles.

Plain float arithmetic (no numpy), so that planning one move from Python
costs a few microseconds. :mod:`._jit` compiles these same functions (their
code objects, :func:`._compile.compiled_twins`) and runs them in a parallel
loop over many moves; :mod:`trajkit.profiles.batch` implements the formulas
on numpy arrays. The tests check that all agree to a few ulps.

Notation (distance ``D > 0``, direction handled by the caller):

* one *leg* is a velocity ramp from rest to ``v`` (accel leg) or from ``v`` to
  rest (decel leg) with jerk ``J`` and acceleration limit ``A``;
* the leg *saturates* (has a constant-acceleration phase) when
  ``v >= A**2 / J``; its duration is then ``v/A + A/J``, otherwise
  ``2*sqrt(v/J)``;
* because a ramp's velocity is point-symmetric about its midpoint, the leg
  covers ``v * T_leg / 2``.

The minimum-time profile reaches the peak velocity ``min(V, Vp)`` where ``Vp``
solves ``d1(Vp) + d2(Vp) = D``; a fixed duration ``T`` lowers the cruise
velocity to the ``Vc`` that solves ``(T1(Vc) + T2(Vc))/2 + D/Vc = T``
(monotone decreasing in ``Vc``, so the root is unique).
"""

from __future__ import annotations

import math

from .._constants import ROOT_MAX_ITER, ROOT_RTOL

_sqrt = math.sqrt
_inf = math.inf


def leg_threshold(a: float, j: float) -> float:
    """Velocity ``A^2/J`` above which a leg reaches its acceleration limit."""
    if a == _inf:
        return _inf
    if j == _inf:
        return 0.0
    return a * a / j


def leg_time(v: float, a: float, j: float) -> float:
    """Duration [s] of a minimum-time ramp between rest and velocity ``v``."""
    if v >= leg_threshold(a, j):
        return v / a + a / j
    return 2.0 * _sqrt(v / j)


def _lt(v: float, a: float, j: float, thr: float) -> float:
    """:func:`leg_time` with the leg's threshold ``thr`` already known."""
    if v >= thr:
        return v / a + a / j
    return 2.0 * _sqrt(v / j)


def leg_phases(
    v: float, a: float, j: float, thr: float | None = None
) -> tuple[float, float, float]:
    """Return ``(t_jerk, t_const, a_peak)`` of the ramp between rest and ``v``.

    ``thr`` is the leg's :func:`leg_threshold` when already known.
    """
    if v <= 0.0:
        return 0.0, 0.0, 0.0
    if v >= (leg_threshold(a, j) if thr is None else thr):
        tj = a / j
        ta = v / a - tj
        if ta < 0.0:
            ta = 0.0
        return tj, ta, a
    tj = _sqrt(v / j)
    return tj, 0.0, j * tj


def _newton_increasing(c4: float, c3: float, c2: float, d: float, u: float) -> float:
    """Root of ``c4 u^4 + c3 u^3 + c2 u^2 = d`` from a start ``u`` right of it.

    The left side is convex and increasing for ``u > 0``, so Newton's method
    started on the right converges monotonically from above.
    """
    for _ in range(ROOT_MAX_ITER):
        u2 = u * u
        f = ((c4 * u + c3) * u + c2) * u2 - d
        df = ((4.0 * c4 * u + 3.0 * c3) * u + 2.0 * c2) * u
        if df <= 0.0:
            break
        step = f / df
        u -= step
        if step <= ROOT_RTOL * u:
            break
    return u


def _newton_decreasing(p: float, q: float, c: float, d: float, t: float, u: float) -> float:
    """Smallest root of ``p u^2 + q + c u + d/u^2 = t`` from a start ``u`` left of it.

    The left side is convex in ``u > 0``; started left of its smallest root,
    Newton's method converges monotonically from below.
    """
    for _ in range(ROOT_MAX_ITER):
        inv = 1.0 / (u * u)
        h = (p * u + c) * u + q + d * inv - t
        dh = 2.0 * p * u + c - 2.0 * d * inv / u
        if dh >= 0.0:
            break
        step = -h / dh
        u += step
        if step <= ROOT_RTOL * u:
            break
    return u


def peak_velocity(
    d: float, v_max: float, a1: float, j1: float, a2: float, j2: float,
    t1: float | None = None, t2: float | None = None,
) -> float:
    """Peak velocity of the minimum-time rest-to-rest move over distance ``d > 0``.

    ``t1``, ``t2``: the legs' :func:`leg_threshold` values when already known.
    """
    if t1 is None:
        t1 = leg_threshold(a1, j1)
    if t2 is None:
        t2 = leg_threshold(a2, j2)
    if v_max != _inf:
        dist_v = 0.5 * v_max * (_lt(v_max, a1, j1, t1) + _lt(v_max, a2, j2, t2))
        if dist_v <= d:
            return v_max
    if t1 <= t2:
        lo, hi, ak, jk, jo = t1, t2, a1, j1, j2
    else:
        lo, hi, ak, jk, jo = t2, t1, a2, j2, j1
    if lo != _inf and 0.5 * lo * (_lt(lo, a1, j1, t1) + _lt(lo, a2, j2, t2)) < d:
        if hi != _inf and 0.5 * hi * (_lt(hi, a1, j1, t1) + _lt(hi, a2, j2, t2)) <= d:
            # both legs reach their acceleration limits: p v^2 + q v = d
            p = 0.5 * (1.0 / a1 + 1.0 / a2)
            q = 0.5 * (a1 / j1 + a2 / j2)
            return 2.0 * d / (q + _sqrt(q * q + 4.0 * p * d))
        # leg k saturated, leg o not: with u = sqrt(v):
        # u^4/(2 ak) + u^3/sqrt(jo) + u^2 ak/(2 jk) = d
        c4 = 0.5 / ak
        c3 = 1.0 / _sqrt(jo)
        c2 = 0.5 * ak / jk
        u = _inf if hi == _inf else _sqrt(hi)
        u = min(u, (d / c4) ** 0.25, (d / c3) ** (1.0 / 3.0))
        if c2 > 0.0:
            u = min(u, _sqrt(d / c2))
        u = _newton_increasing(c4, c3, c2, d, u)
        return u * u
    # neither leg saturates: (1/sqrt(j1) + 1/sqrt(j2)) v^1.5 = d
    c = 1.0 / _sqrt(j1) + 1.0 / _sqrt(j2)
    return (d / c) ** (2.0 / 3.0)


def cruise_velocity(
    d: float, t: float, v_peak: float, a1: float, j1: float, a2: float, j2: float,
    t1: float | None = None, t2: float | None = None,
) -> float:
    """Cruise velocity ``Vc <= v_peak`` for which the move lasts exactly ``t``.

    Solves ``(T1(Vc) + T2(Vc))/2 + d/Vc = t`` (a decreasing function of
    ``Vc``), region by region.
    """
    t1 = leg_threshold(a1, j1)
    t2 = leg_threshold(a2, j2)
    if t1 <= t2:
        lo, hi, ak, jk, jo = t1, t2, a1, j1, j2
    else:
        lo, hi, ak, jk, jo = t2, t1, a2, j2, j1
    u0 = _sqrt(d / t)  # Vc >= d/t always: a universal start left of the root
    if lo < v_peak and lo != _inf and (
        lo == 0.0 or 0.5 * (_lt(lo, a1, j1, t1) + _lt(lo, a2, j2, t2)) + d / lo > t
    ):
        if hi < v_peak and hi != _inf and (
            hi == 0.0 or 0.5 * (_lt(hi, a1, j1, t1) + _lt(hi, a2, j2, t2)) + d / hi > t
        ):
            # both saturated: p v^2 - (t - q) v + d = 0, smaller root
            p = 0.5 * (1.0 / a1 + 1.0 / a2)
            q = 0.5 * (a1 / j1 + a2 / j2)
            b = t - q
            # 2d / (b + sqrt(b^2 - 4pd)), scaled by b so that b^2 cannot overflow
            r = 4.0 * p * d / b / b
            return 2.0 * d / (b * (1.0 + _sqrt(max(1.0 - r, 0.0))))
        u = _newton_decreasing(0.5 / ak, 0.5 * ak / jk, 1.0 / _sqrt(jo), d, t, u0)
        return u * u
    u = _newton_decreasing(0.0, 0.0, 1.0 / _sqrt(j1) + 1.0 / _sqrt(j2), d, t, u0)
    return u * u
