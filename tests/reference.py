"""Independent second formulation of rest-to-rest jerk-limited moves (test oracle).

Nothing here uses :mod:`trajkit.profiles`. The planner in ``_scalar.py``
solves the distance equation region by region with closed forms and Newton
iterations on ``sqrt(v)``; this module instead

* builds each velocity ramp (rest -> V or V -> rest) as an explicit list of
  constant-jerk phases and integrates position and velocity through them
  phase by phase (no "a ramp covers V*T/2" shortcut, no region formulas for
  the distance);
* finds the peak velocity of the minimum-time move with scipy's ``brentq`` on
  ``dist(V) - D`` over ``[0, v_max]`` (``dist`` is increasing in V), and the
  cruise velocity of a fixed-duration move with ``brentq`` on
  ``time(V) - T`` over ``[D/T, V_peak]``.

It is slow (a root search per move) and meant for tests only.
"""

from __future__ import annotations

import math

from scipy.optimize import brentq

#: brentq tolerances: relative to the root, as tight as scipy allows.
BRENT_RTOL = 4.0 * 2.220446049250313e-16
BRENT_MAXITER = 500


def ramp_phases(v: float, a: float, j: float) -> list[tuple[float, float, float]]:
    """Constant-jerk phases of the fastest ramp from rest to velocity ``v``.

    Returns ``(duration, acceleration at phase start, jerk)`` triples. The
    acceleration rises with jerk ``j`` to ``min(a, sqrt(v j))``, holds, and
    falls back to zero; ``j = inf`` gives a jump (trapezoid), ``a = inf``
    never holds.
    """
    if v <= 0.0:
        return []
    if math.isinf(j):
        return [(v / a, a, 0.0)]
    # peak acceleration of the ramp: the acceleration limit, unless the
    # velocity is reached before the acceleration can build up to it
    ap = math.sqrt(v * j)
    if ap <= a:
        tj = ap / j
        return [(tj, 0.0, j), (tj, ap, -j)]
    tj = a / j
    dv_jerk = a * tj  # velocity gained in the two jerk phases together
    return [(tj, 0.0, j), ((v - dv_jerk) / a, a, 0.0), (tj, a, -j)]


def integrate(phases, p0=0.0, v0=0.0):
    """Integrate ``(duration, a_start, jerk)`` phases; return end ``(p, v, t)``."""
    p, v, t = p0, v0, 0.0
    for dt, a0, jj in phases:
        p += dt * v + 0.5 * a0 * dt * dt + jj * dt ** 3 / 6.0
        v += a0 * dt + 0.5 * jj * dt * dt
        t += dt
    return p, v, t


def ramp(v: float, a: float, j: float) -> tuple[float, float]:
    """``(time, distance)`` of the fastest ramp between rest and ``v``."""
    p, _, t = integrate(ramp_phases(v, a, j))
    return t, p


def dist_at(v, a1, j1, a2, j2):
    """Distance covered by both ramps (accel leg to ``v``, decel leg from it)."""
    return ramp(v, a1, j1)[1] + ramp(v, a2, j2)[1]


def time_at(v, a1, j1, a2, j2):
    """Duration of both ramps around a peak velocity ``v``."""
    return ramp(v, a1, j1)[0] + ramp(v, a2, j2)[0]


def _upper_velocity(d, a1, j1, a2, j2):
    """A velocity whose two ramps certainly cover more than ``d``."""
    v = 1.0
    while dist_at(v, a1, j1, a2, j2) < d:
        v *= 4.0
    return v


def peak_velocity(d, v_max, a1, j1, a2, j2):
    """Peak velocity of the minimum-time move over ``d > 0`` (brentq)."""
    if math.isfinite(v_max) and dist_at(v_max, a1, j1, a2, j2) <= d:
        return v_max
    hi = v_max if math.isfinite(v_max) else _upper_velocity(d, a1, j1, a2, j2)
    return brentq(lambda v: dist_at(v, a1, j1, a2, j2) - d, 0.0, hi,
                  xtol=1e-300, rtol=BRENT_RTOL, maxiter=BRENT_MAXITER)


def min_duration(d, v_max, a1, j1, a2=None, j2=None):
    """Minimum duration [s] of a rest-to-rest move over ``|d|``."""
    a2 = a1 if a2 is None else a2
    j2 = j1 if j2 is None else j2
    d = abs(d)
    if d == 0.0:
        return 0.0
    vp = peak_velocity(d, v_max, a1, j1, a2, j2)
    t_ramps = time_at(vp, a1, j1, a2, j2)
    cruise = (d - dist_at(vp, a1, j1, a2, j2)) / vp
    return t_ramps + max(cruise, 0.0)


def fixed_duration(d, T, v_max, a1, j1, a2=None, j2=None):
    """Cruise velocity and phase list of the move over ``|d|`` lasting ``T``.

    Returns
    -------
    vc : float
        Cruise (= peak) velocity.
    phases : list of (duration, a_start, jerk)
        Accel ramp, cruise, decel ramp (the decel ramp is the accel-style
        ramp of the decel leg, mirrored: negated jerks and accelerations).
    """
    a2 = a1 if a2 is None else a2
    j2 = j1 if j2 is None else j2
    d = abs(d)
    vp = peak_velocity(d, v_max, a1, j1, a2, j2)

    def excess(v):
        return time_at(v, a1, j1, a2, j2) + (d - dist_at(v, a1, j1, a2, j2)) / v - T

    lo = d / T
    if excess(vp) >= 0.0:
        vc = vp
    elif excess(lo) <= 0.0:
        # the root lies at the lower bound d/T within round-off (a move that
        # is all cruise): ramps of negligible length
        vc = lo
    else:
        vc = brentq(excess, lo, vp, xtol=1e-300, rtol=BRENT_RTOL, maxiter=BRENT_MAXITER)
    up = ramp_phases(vc, a1, j1)
    down = [(dt, -a0, -jj) for dt, a0, jj in ramp_phases(vc, a2, j2)]
    cruise = T - time_at(vc, a1, j1, a2, j2)
    return vc, up + [(max(cruise, 0.0), 0.0, 0.0)] + down
