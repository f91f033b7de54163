"""The fast state-to-state kernel gives the same results as before (issue 8).

The speed work replaced the phase-list evaluations inside the family scans
by fused scalar residuals (compiled with numba when installed), checked
candidates lazily and compiled the exact verification. None of it may change
a result:

* the fused residuals equal ``integrate(profile(x))[0] - goal`` of the
  phase lists that build the returned profiles, bit for bit;
* the compiled residuals, scans and verification equal the Python ones bit
  for bit (when numba is installed);
* minimum durations equal those of the kernel before the speed-up (stored
  in ``tests/data/state_min_durations_v0.npz``) on random and corner states
  (symmetric and asymmetric limits) to 1e-12 relative;
* planning with and without the compilation (``TRAJKIT_NO_JIT=1``) gives
  identical profiles, minimum-time and fixed-duration.

Sizes: CI default (``sweep_size``); ``TRAJKIT_SWEEP=1`` runs 20x.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import sweep_size
from state_reference import random_case

from trajkit import AxisLimits
from trajkit.profiles import _state_jit as SJ
from trajkit.profiles import _state_kernel as K
from trajkit.profiles.state import (
    BlockedDurationError,
    min_state_duration,
    plan_state_to_state,
)

#: Compares two code paths (see floatcmp); CI runs it again with numpy SIMD off.
pytestmark = pytest.mark.codepaths

needs_numba = pytest.mark.skipif(not SJ.AVAILABLE, reason="numba not installed")


def _cases(seed, n, symmetric=None, corners=True):
    """Random states (tests/state_reference.random_case) plus infinite-limit variants."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        sym = bool(i % 2) if symmetric is None else symmetric
        s, g, L = random_case(rng, symmetric=sym)
        if corners and i % 9 == 4:
            L = (math.inf,) + L[1:]  # no velocity limit
        elif corners and i % 9 == 7:
            L = (L[0], L[1], math.inf, L[3], math.inf)  # trapezoidal acceleration
        out.append((s, g, L))
    return out


def _params(rng, s, g, L):
    V, A1, A2 = L[0], L[1], L[3]
    vs = V if V != math.inf else max(abs(s[1]), abs(g[1]), 1.0)
    am = max(A1, A2)
    return [float(x) for x in rng.uniform(-1.2, 1.2, 3) * vs] + [s[1], g[1], 0.0, vs, -vs], \
        [float(x) for x in rng.uniform(-1.1, 1.1, 3) * am] + [s[2], g[2], 0.0, am, -am]


def _phase_list_fixed_error(vc, T, s, g, L):
    """Position error of the fixed-duration F1 profile built as a phase list."""
    b1 = K.bump(s[1], s[2], vc, 0.0, L)
    b2 = K.bump(vc, 0.0, g[1], g[2], L)
    if b1 is None or b2 is None:
        return None
    tc = T - K.total_time(b1) - K.total_time(b2)
    if tc < -K.ROUND_RTOL * T:
        return None
    ph = b1 + [(max(tc, 0.0), 0.0, 0.0)] + b2
    return K.integrate(ph, *s)[0] - g[0]


def _as_opt(res):
    ok, r = res
    return float(r) if ok else None


def test_fused_residuals_equal_phase_lists_bit_for_bit():
    rng = np.random.default_rng(101)
    n = 0
    for s, g, L in _cases(102, sweep_size(300)):
        _, A1, J1, A2, J2 = L
        vcs, ams = _params(rng, s, g, L)
        args = (*s, *g, A1, J1, A2, J2)
        for vc in vcs:
            ph = K.f1_profile(vc, s, g, L)
            ref = None if ph is None else K.integrate(ph, *s)[0] - g[0]
            assert _as_opt(K.f1_residual(vc, *args)) == ref
            # the fused durations used to order the lazily built candidates
            assert _as_opt(K._fam_time(0, vc, (0.0, *args))) == (
                None if ph is None else K.total_time(ph))
            tc = 0.3 * abs(vc)
            ph = K.f1_profile(vc, s, g, L, cruise=tc)
            assert _as_opt(K._f1_cruise_time(vc, tc, (0.0, *args))) == (
                None if ph is None else K.total_time(ph))
            T = 0.5 + abs(vc)
            assert _as_opt(K.fixed_residual(vc, T, *args)) == _phase_list_fixed_error(vc, T, s, g, L)
            n += 1
        for am in ams:
            for first in (False, True):
                ph = K.f2_profile(am, s, g, L, first)
                ref = None if ph is None else K.integrate(ph, *s)[0] - g[0]
                assert _as_opt(K.f2_residual(am, *args, first)) == ref
                assert _as_opt(K._fam_time(2 if first else 1, am, (0.0, *args))) == (
                    None if ph is None else K.total_time(ph))
                # the F2-with-hold member: the fused residual is the phases' error
                T = 1.0 + abs(am)
                ph = K.f2_hold_profile(am, s, g, L, T, first)
                ref = None if ph is None else K.integrate(ph, *s)[0] - g[0]
                assert _as_opt(K.f2_hold_residual(am, T, *args, first)) == ref
    assert n > 1000


@needs_numba
def test_compiled_kernels_equal_python_bit_for_bit():
    jk = SJ.kernels()
    rng = np.random.default_rng(103)
    for s, g, L in _cases(104, sweep_size(150)):
        V, A1, J1, A2, J2 = L
        vcs, ams = _params(rng, s, g, L)
        args = (*s, *g, A1, J1, A2, J2)
        for vc in vcs:
            assert _as_opt(jk["f1_residual"](vc, *args)) == _as_opt(K.f1_residual(vc, *args))
            T = 0.5 + abs(vc)
            assert (_as_opt(jk["fixed_residual"](vc, T, *args))
                    == _as_opt(K.fixed_residual(vc, T, *args)))
        for am in ams:
            for first in (False, True):
                assert (_as_opt(jk["f2_residual"](am, *args, first))
                        == _as_opt(K.f2_residual(am, *args, first)))
                T = 1.0 + abs(am)
                assert (_as_opt(jk["f2_hold_residual"](am, T, *args, first))
                        == _as_opt(K.f2_hold_residual(am, T, *args, first)))
        # whole scans (grid, edges, refinement, golden sections)
        grid = K._grid(-V if V != math.inf else -4.0, V if V != math.inf else 4.0,
                       [s[1], g[1], 0.0])
        P = (1.5, *args)
        hold = len(vcs) % 2 == 0 and rng.random() < 0.15  # the slow nested hold scans: some
        for kind in range(6 if hold else 4):
            near = kind >= 4
            assert (list(SJ.scan_family(kind, grid, P, K.EDGE_BISECT, near))
                    == K.scan_family(kind, grid, P, K.EDGE_BISECT, near))


@needs_numba
def test_compiled_verification_equals_python(monkeypatch):
    rng = np.random.default_rng(105)
    n_fail = 0
    for s, g, L in _cases(106, sweep_size(150)):
        monkeypatch.setenv("TRAJKIT_NO_JIT", "1")
        for _, _, ph in K.candidates_min_time(s, g, L):
            # the profile, and perturbed copies that break limits or the goal
            variants = [ph] + [
                [(dt * (1 + 1e-3 * rng.normal()), j * (1 + 1e-2 * rng.normal()), a)
                 for dt, j, a in ph] for _ in range(2)]
            tighter = (L[0] * 0.9, L[1] * 0.8, L[2] * 0.8, L[3] * 0.7, L[4] * 0.9)
            for q in variants:
                for LL in (L, tighter):
                    for cg in (True, False):
                        monkeypatch.setenv("TRAJKIT_NO_JIT", "1")
                        ref = K.verify(q, *s, LL, g, check_goal=cg)  # the Python code
                        monkeypatch.delenv("TRAJKIT_NO_JIT", raising=False)
                        assert K.verify(q, *s, LL, g, check_goal=cg) == ref
                        monkeypatch.setenv("TRAJKIT_NO_JIT", "1")
                        assert K.verify(q, *s, LL, g, check_goal=cg) == ref
                        n_fail += ref is not None
    assert n_fail > 100  # the failing branches were exercised too


#: Minimum durations of the pure-Python kernel before the speed-up (commit
#: 6cb7752), on the random and corner states of ``_cases(107, 700, symmetric)``
#: and ``_cases(108, 350, asymmetric)``: columns start (3), goal (3), limits
#: (5: V, A1, J1, A2, J2), duration [s], symmetric flag.
V0_DURATIONS = Path(__file__).parent / "data" / "state_min_durations_v0.npz"


@pytest.mark.parametrize("symmetric,seed,n", [(True, 107, 700), (False, 108, 350)])
def test_min_durations_equal_the_kernel_before_the_speed_up(symmetric, seed, n):
    """Random and corner states: the same minimum duration as before, to 1e-12."""
    rows = np.load(V0_DURATIONS)["cases"]
    rows = rows[rows[:, 12] == (1.0 if symmetric else 0.0)]
    cases = [(s, g, L) for s, g, L in _cases(seed, n, symmetric=symmetric) if not (s == g and s[2] == 0.0)]
    assert len(cases) == rows.shape[0]
    worst = 0.0
    for (s, g, L), row in zip(cases, rows):
        np.testing.assert_array_equal(row[:11], [*s, *g, *L])  # the same states as stored
        d = min_state_duration(s, g, AxisLimits(*L))
        worst = max(worst, abs(d - row[11]) / row[11])
        assert d == pytest.approx(row[11], rel=1e-12, abs=1e-300), (s, g, L)
    assert worst <= 1e-12


def _phases(p):
    return (p.phase_durations, p.jerks, p.phase_accelerations, p.family)


@needs_numba
def test_compiled_and_python_plans_are_identical(monkeypatch):
    """Minimum-time and fixed-duration profiles with and without numba."""
    n_fixed = 0
    for s, g, L in _cases(109, sweep_size(150)):
        lim = AxisLimits(*L)
        out = {}
        for mode in ("jit", "python"):
            if mode == "python":
                monkeypatch.setenv("TRAJKIT_NO_JIT", "1")
            else:
                monkeypatch.delenv("TRAJKIT_NO_JIT", raising=False)
            res = []
            p = plan_state_to_state(s, g, lim)
            res.append(_phases(p))
            for f in (0.01, 0.4):
                try:
                    res.append(_phases(plan_state_to_state(s, g, lim, duration=p.duration * (1 + f))))
                except BlockedDurationError as err:
                    res.append(err.interval)
            out[mode] = res
        assert out["jit"] == out["python"], (s, g, L)
        n_fixed += 2
    assert n_fixed > 0
