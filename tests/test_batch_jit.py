"""The compiled batch kernel (numba, optional) agrees with plan_move to a few ulps.

Runs only where numba is installed (it is in the test extra); both the numpy
formulation and the compiled one are compared with the scalar planner. They are
different code paths (numba compiles against libm, numpy may use SIMD ``pow``
and ``cbrt``), so they are compared in ulps (``floatcmp``), not bit for bit.
"""

from __future__ import annotations

import numpy as np
import pytest
from floatcmp import assert_ulp_close

from trajkit import AxisLimits, InfeasibleError, plan_move, plan_moves
from trajkit.profiles import batch as B

#: Compares two code paths (see floatcmp); CI runs it again with numpy SIMD off.
pytestmark = pytest.mark.codepaths

pytest.importorskip("numba")

N = 8192  # above JIT_MIN_MOVES


def _random(rng, n):
    s = rng.uniform(-1, 1, n)
    g = s + 10 ** rng.uniform(-6, 3, n) * rng.choice([-1.0, 1.0], n)
    g[::97] = s[::97]  # zero moves
    v = 10 ** rng.uniform(-2, 2, n)
    a = v * 10 ** rng.uniform(-3, 3, n)
    j = a * 10 ** rng.uniform(-3, 3, n)
    ad = a * 10 ** rng.uniform(np.log10(0.05), np.log10(20), n)
    jd = j * 10 ** rng.uniform(np.log10(0.05), np.log10(20), n)
    j[::13] = np.inf  # trapezoids
    jd[::13] = np.inf
    v[::17] = np.inf
    return s, g, v, a, j, ad, jd


@pytest.fixture(scope="module")
def cases():
    return _random(np.random.default_rng(2026), N)


def test_jit_path_is_used_and_matches_numpy_path(cases, monkeypatch):
    assert B._jit.AVAILABLE
    fast = plan_moves(*cases)
    monkeypatch.setenv("TRAJKIT_NO_JIT", "1")
    slow = plan_moves(*cases)
    scale = {"phase_durations": slow.duration[:, None], "jerks": None}
    for f in ("duration", "min_duration", "phase_durations", "jerks", "peak_velocity",
              "peak_acceleration", "peak_deceleration"):
        assert_ulp_close(getattr(fast, f), getattr(slow, f), scale=scale.get(f), err_msg=f)


def test_jit_matches_scalar_plan_move_with_durations(cases):
    s, g, v, a, j, ad, jd = cases
    tmin = plan_moves(s, g, v, a, j, ad, jd).duration
    T = tmin * 10 ** np.random.default_rng(7).uniform(0, 2, N)
    b = plan_moves(s, g, v, a, j, ad, jd, durations=T)
    for i in range(0, N, 37):
        p = plan_move(s[i], g[i], AxisLimits(v[i], a[i], j[i], ad[i], jd[i]), duration=T[i])
        assert b.duration[i] == p.duration == T[i]  # the requested duration, copied
        assert_ulp_close(b.phase_durations[i], p.phase_durations, scale=T[i], err_msg="phases")
        assert_ulp_close(b.peak_velocity[i], p.peak_velocity, err_msg="peak velocity")


def test_jit_infeasible_duration_names_the_first_move(cases):
    s, g, v, a, j, ad, jd = cases
    tmin = plan_moves(s, g, v, a, j, ad, jd).duration
    T = tmin * 2.0
    k = int(np.flatnonzero(tmin > 0)[5])
    T[k] = 0.5 * tmin[k]
    T[-1] = 0.1 * tmin[-1] if tmin[-1] > 0 else T[-1]
    with pytest.raises(InfeasibleError, match=rf"durations\[{k}\] = .* is below the minimum"):
        plan_moves(s, g, v, a, j, ad, jd, durations=T)
