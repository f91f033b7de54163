"""Step 1 in closed form for symmetric limits against the general step 1.

With ``a_max == a_max_decel``, ``j_max == j_max_decel`` and a start inside
the limits, the kernel plans the minimum time (and the blocked intervals)
from hand-derived shape polynomials (``profiles._symfast``) and runs the
general step 1 only where that finds nothing. Here:

* the shape polynomials are the stated multiples of the exact position
  residual of their profiles (the derivation, checked without a CAS);
* the degree-4 root finder finds the roots the general one finds;
* on seeded random symmetric cases (``state_reference.random_case``) the
  closed form plans almost every case, and where it does its minimum
  duration equals the general step 1's to 1e-9 and its blocked intervals
  are the same; the profiles reach the goal state and keep every limit
  (independent checks of ``state_reference``, on the public profile).

``TRAJKIT_SWEEP=1`` multiplies the case counts (``conftest.sweep_size``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import sweep_size
from state_reference import exact_check, goal_error, random_case

from trajkit import AxisLimits
from trajkit.profiles import _kernel as K
from trajkit.profiles import _roots, _symfast
from trajkit.profiles._shapes import NVALID, R_SHAPE, R_T, R_V0
from trajkit.profiles.state import feasible_durations, plan_state_to_state

#: Durations of both step-1 paths agree to this (relative).
DURATION_RTOL = 1e-9


def _rows(seed, n):
    rng = np.random.default_rng(seed)
    out = np.empty((n, 11))
    for i in range(n):
        s, g, L = random_case(rng, symmetric=True)
        out[i] = (*s, *g, *L)
    return out


def _ws(row, task, general):
    ws = K.workspace()
    ws[:11] = row
    ws[K.IN_TASK] = task
    ws[K.IN_GENERAL] = 1.0 if general else 0.0
    return ws


def _blocks(ws):
    n = int(ws[K.OUT_NBLK])
    return ws[K.OUT_BLK:K.OUT_BLK + 2 * n].copy()


# ------------------------------------------------------------------ the algebra
def _end_state(v0, a0, phases):
    """(p, v, a) after ``phases`` = [(duration, jerk)] from (0, v0, a0)."""
    p, v, a = 0.0, v0, a0
    for dt, j in phases:
        p, v, a = (p + dt * (v + dt * (a / 2 + dt * j / 6)), v + dt * (a + dt * j / 2), a + dt * j)
    return p, v, a


def _uddu(c1, t1, c3, t3, a0, af, J):
    return [((c1 - a0) / J, J), (t1, 0.0), ((c1 - c3) / J, -J), (t3, 0.0), ((af - c3) / J, J)]


def test_shape_polynomials_are_multiples_of_the_position_residual():
    rng = np.random.default_rng(5)
    for _ in range(2000):
        v0, a0, vf, af, D = rng.uniform(-2, 2, 5)
        A = 10 ** rng.uniform(-0.5, 0.5)
        J = 10 ** rng.uniform(-0.5, 0.5)
        h0, hf, g, E = _symfast.invariants(v0, a0, D, vf, af, J)
        u = rng.uniform(-2, 2)
        w = abs(u) + 0.1
        x = rng.uniform(0, 2)
        for shape in ("none", "acc0", "acc1"):
            coef = np.zeros(5)
            if shape == "none":
                _symfast.coef_none(coef, h0, hf, g, E)
                par, mult = w, 12 * J * J * w
                phases = _uddu((w + g / w) / 2, 0.0, (g / w - w) / 2, 0.0, a0, af, J)
            elif shape == "acc0":
                _symfast.coef_acc0(coef, A, h0, hf, E)
                par, mult = u, 6 * A * J * J
                phases = _uddu(A, (g - A * A + u * u) / (J * A), u, 0.0, a0, af, J)
            else:
                _symfast.coef_acc1(coef, A, h0, hf, E)
                par, mult = u, 6 * A * J * J
                phases = _uddu(u, 0.0, -A, (u * u - A * A - g) / (J * A), a0, af, J)
            p, v, a = _end_state(v0, a0, phases)
            # the velocity equation is built in: the end state is the goal's (v, a)
            assert v == pytest.approx(vf, abs=1e-9 * (abs(vf) + 10))
            assert a == pytest.approx(af, abs=1e-12 * 10)
            poly = sum(coef[k] * par ** k for k in range(5))
            scale = sum(abs(coef[k] * par ** k) for k in range(5)) + abs(mult) * (abs(D) + 10)
            assert poly == pytest.approx(mult * (p - D), abs=1e-11 * scale)
        q0, q1, q2 = _symfast.coef_acc01(A, J, h0, hf, E)
        p, v, a = _end_state(v0, a0, _uddu(A, x, -A, x - g / (J * A), a0, af, J))
        assert v == pytest.approx(vf, abs=1e-9 * (abs(vf) + 10))
        mult = 6 * A * J * J
        scale = abs(q0) + abs(q1 * x) + abs(q2 * x * x) + mult * (abs(D) + 10)
        assert q0 + q1 * x + q2 * x * x == pytest.approx(mult * (p - D), abs=1e-11 * scale)


def _distinct(x, tol=1e-6):
    x = np.sort(x)
    return x[np.concatenate(([True], np.diff(x) > tol))] if len(x) else x


def test_quartic_roots_unit_finds_the_roots_of_the_general_finder():
    rng = np.random.default_rng(9)
    out = np.zeros(8)
    tmp = np.zeros(8)
    ref = np.zeros(16)
    dtab = np.zeros((8, 8))
    for i in range(3000):
        kind = i % 3
        if kind == 0:  # four real roots, some outside [-1, 1]
            r = rng.uniform(-1.5, 1.5, 4)
        elif kind == 1:  # a double root
            x = rng.uniform(-0.9, 0.9)
            r = np.array([x, x, *rng.uniform(-1.5, 1.5, 2)])
        else:  # two real roots and a complex pair
            r = rng.uniform(-1.5, 1.5, 2)
        c = np.polynomial.polynomial.polyfromroots(r) * rng.uniform(0.1, 10)
        if kind == 2:
            re, im = rng.uniform(-1, 1), rng.uniform(0.01, 1)
            c = np.polynomial.polynomial.polymul(c, [re * re + im * im, -2 * re, 1.0])
        c = np.ascontiguousarray(c[:5], dtype=float)
        n = _roots.quartic_roots_unit(c, out, tmp)
        m = _roots.real_roots_unit(c, 4, ref, dtab)
        # (a double root may come once or as two neighbours within round-off)
        a, b = _distinct(out[:n]), _distinct(ref[:m])
        assert len(a) == len(b), (i, c, out[:n], ref[:m])
        np.testing.assert_allclose(a, b, atol=1e-6 if kind == 1 else 1e-12)
        inside = np.sort(r[(r >= -1) & (r <= 1)])
        if kind != 1 and len(inside) == n:
            np.testing.assert_allclose(out[:n], inside, atol=1e-9)


# ------------------------------------------------------------------ the kernel
@pytest.mark.parametrize("task", [K.TASK_MIN, K.TASK_BLOCK])
def test_closed_form_equals_general_step1(task):
    n = sweep_size(10_000)
    rows = _rows(31 + task, n)
    taken = 0
    blocked = 0
    for i, row in enumerate(rows):
        wf = _ws(row, task, general=False)
        if not K._solve_sym(wf, task):
            continue  # the general step 1 plans it (as below)
        taken += 1
        wg = _ws(row, task, general=True)
        K.solve(wg)
        assert wg[K.OUT_STATUS] == K.ST_OK, i
        assert wf[K.OUT_STATUS] == K.ST_OK, i
        tf, tg = wf[K.OUT_T], wg[K.OUT_T]
        assert abs(tf - tg) <= DURATION_RTOL * tg, (i, tf, tg, row.tolist())
        assert wf[K.OUT_TMIN] == tf
        if task == K.TASK_BLOCK:
            bf, bg = _blocks(wf), _blocks(wg)
            assert len(bf) == len(bg), (i, bf, bg, row.tolist())
            np.testing.assert_allclose(bf, bg, rtol=DURATION_RTOL, err_msg=str(i))
            blocked += len(bf) > 0
        # the kernel's entry takes the closed form for this task
        ws = _ws(row, task, general=False)
        K.solve(ws)
        assert ws[K.OUT_T] == tf and ws[K.OUT_N] == wf[K.OUT_N]
    print(f"\nclosed form planned {taken} of {n} symmetric cases (task {task}); "
          f"{blocked} with blocked intervals")
    assert taken >= 0.99 * n
    if task == K.TASK_BLOCK:
        assert blocked >= 0.003 * n  # the block computation is exercised


def _norm(row):
    ws = _ws(row, K.TASK_MIN, general=False)
    K._normalise(ws, K.TASK_MIN)
    return ws[K._LIM:K._LIM + 5].copy(), ws[K._ST0:K._ST0 + 7].copy()


def test_first_direction_is_the_side_of_the_velocity_change():
    """``first_direction`` is +1 exactly where the distance exceeds the displacement
    of the minimum-time velocity change, planned independently by the kernel's
    velocity task (position free) and integrated here."""
    rows = _rows(61, 3000)
    checked = 0
    for row in rows:
        lim, st0 = _norm(row)
        if not _symfast.sym_applies(lim):
            continue
        wv = _ws(row, K.TASK_VELOCITY, general=True)
        wv[K.IN_PF] = math.nan
        K.solve(wv)
        if wv[K.OUT_STATUS] != K.ST_OK or wv[K.OUT_NB] != 0:
            continue
        p, v, a = 0.0, row[1], row[2]
        for k in range(int(wv[K.OUT_N])):
            dt, j, a = wv[K.OUT_PH + 3 * k:K.OUT_PH + 3 * k + 3]
            p, v, a = p + dt * (v + dt * (0.5 * a + dt * j / 6.0)), v + dt * (a + 0.5 * dt * j), a + dt * j
        D = row[3] - row[0]
        if abs(D - p) <= 1e-9 * max(abs(D), abs(p), abs(row[0])):
            continue  # (on the boundary: either side)
        assert _symfast.first_direction(st0, lim) == (1.0 if D > p else -1.0), row.tolist()
        checked += 1
    assert checked >= 0.9 * len(rows)


def test_first_direction_search_finds_the_minimum_of_both_directions():
    """The minimum-time search of one direction first (the other only when the first
    has no valid profile) returns the fastest valid profile of both directions'
    search, and the fallback to the other direction is exercised."""
    n = sweep_size(20_000)
    rows = _rows(67, n)
    cand = np.zeros(_symfast.NCF * _symfast.NSF)
    scr = np.zeros(_symfast.SF_SCRATCH)
    ph = np.zeros((K.NPH, 3))
    res = np.zeros(R_V0 + NVALID)
    compared = 0
    other = 0
    for row in rows:
        lim, st0 = _norm(row)
        if not _symfast.sym_applies(lim):
            continue
        if _symfast.sym_step1(st0, lim, res, True, cand, scr, ph) < 0:
            continue  # (the general step 1 decides these)
        t_both = res[R_T]
        ib = _symfast.sym_step1(st0, lim, res, False, cand, scr, ph)
        assert ib >= 0, row.tolist()
        assert abs(res[R_T] - t_both) <= 1e-12 * t_both, (row.tolist(), res[R_T], t_both)
        mirrored = res[R_SHAPE] >= 16.0
        other += mirrored != (_symfast.first_direction(st0, lim) < 0.0)
        compared += 1
    print(f"\n{compared} compared, {other} found in the second direction")
    assert compared >= 0.95 * n
    assert other >= 1


def test_closed_form_profiles_reach_the_goal_within_the_limits():
    n = sweep_size(10_000)
    rows = _rows(77, n)
    checked = 0
    for i, row in enumerate(rows):
        if not K._solve_sym(_ws(row, K.TASK_MIN, general=False), K.TASK_MIN):
            continue
        s, g, L = tuple(row[0:3]), tuple(row[3:6]), row[6:9]
        lim = AxisLimits(*L)
        prof = plan_state_to_state(s, g, lim)
        why = exact_check(prof, lim)
        assert why is None, (i, why, row.tolist())
        assert goal_error(prof) < 1e-9, (i, goal_error(prof), row.tolist())
        assert prof.n_brake_phases == 0
        assert prof.family.split()[-1] in ("none", "acc0", "acc1", "acc0_acc1", "vel", "acc0_vel",
                                           "acc1_vel", "acc0_acc1_vel")
        checked += 1
    assert checked >= 0.99 * n


@pytest.mark.parametrize("start, goal, limits", [
    # a pure cruise at v_max (the minimum is isolated: an even count of valid
    # durations, the general step 1 decides)
    ((0.0, 1.0, 0.0), (3.0, 1.0, 0.0), (1.0, 1.0, 1.0)),
    ((0.0, -2.0, 0.0), (-0.5, -2.0, 0.0), (2.0, 0.7, 3.0)),
    # the goal is the start
    ((0.3, 0.2, 0.1), (0.3, 0.2, 0.1), (1.0, 1.0, 1.0)),
    # a start on the acceleration limit, a rest goal
    ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (1.0, 1.0, 1.0)),
])
def test_degenerate_cases_equal_the_general_path(start, goal, limits):
    row = np.array([*start, *goal, *limits, limits[1], limits[2]], dtype=float)
    for task in (K.TASK_MIN, K.TASK_BLOCK):
        wf = _ws(row, task, general=False)
        K.solve(wf)
        wg = _ws(row, task, general=True)
        K.solve(wg)
        assert wf[K.OUT_STATUS] == wg[K.OUT_STATUS] == K.ST_OK
        assert wf[K.OUT_T] == pytest.approx(wg[K.OUT_T], rel=DURATION_RTOL, abs=0.0)
        np.testing.assert_allclose(_blocks(wf), _blocks(wg), rtol=DURATION_RTOL)
    lim = AxisLimits(*limits)
    prof = plan_state_to_state(start, goal, lim)
    assert exact_check(prof, lim) is None
    assert prof.n_phases == 0 or goal_error(prof) < 1e-9
    fd = feasible_durations(start, goal, lim)
    assert math.isclose(fd.minimum, prof.duration, rel_tol=1e-12)


def test_equal_legs_check_is_the_general_check():
    """``check_equal_legs`` decides as ``check`` does when both legs are equal: on
    the candidates of the closed form (valid and not) and on perturbed ones."""
    from trajkit.profiles._check import check, check_equal_legs

    rng = np.random.default_rng(13)
    rows = _rows(55, 1500)
    ph = np.zeros((K.NPH, 3))
    agree = [0, 0]
    for row in rows:
        ws = _ws(row, K.TASK_BLOCK, general=False)
        K._normalise(ws, K.TASK_BLOCK)
        lim = ws[K._LIM:K._LIM + 5].copy()
        st0 = ws[K._ST0:K._ST0 + 7].copy()
        if not _symfast.sym_applies(lim):
            continue
        cand = np.zeros(_symfast.NCF * _symfast.NSF)
        scr = np.zeros(_symfast.SF_SCRATCH)
        res = np.zeros(R_V0 + NVALID)
        _symfast.sym_step1(st0, lim, res, True, cand, scr, ph)
        for i in range(_symfast.NCF):
            if cand[i * _symfast.NSF + _symfast.C_CODE] == 0.0:
                break  # (every shape code is > 0)
            n, _, sg = _symfast.build_candidate(cand, i, st0, lim, ph)
            if n == 0:
                continue
            for trial in range(3):
                q = ph[:n].copy()
                if trial == 1:
                    q[rng.integers(n), 0] *= 1.0 + rng.choice([-1, 1]) * 10 ** rng.uniform(-12, -6)
                elif trial == 2:
                    q[:, 1] *= 1.0 + 10 ** rng.uniform(-11, -8)
                args = (q, n, 0.0, sg * st0[1], sg * st0[2], sg * st0[3], sg * st0[4], sg * st0[5])
                a = check(*args, lim[0], lim[1], lim[2], lim[3], lim[4])
                b = check_equal_legs(*args, lim[0], lim[1], lim[2])
                assert a == b, (row.tolist(), i, trial, q)
                agree[int(a)] += 1
    assert agree[0] > 100 and agree[1] > 100, agree


def test_fixed_durations_after_the_closed_form_equal_the_general_path():
    """A requested duration: step 1 (minimum, blocked intervals) in closed form, then
    step 2 -- the same outcome as the general path: too short, blocked, or a profile
    of exactly the duration that keeps every limit."""
    rng = np.random.default_rng(21)
    rows = _rows(17, sweep_size(1500))
    outcomes = {}
    for row in rows:
        ws0 = _ws(row, K.TASK_BLOCK, general=True)
        K.solve(ws0)
        if ws0[K.OUT_STATUS] != K.ST_OK:
            continue
        T = ws0[K.OUT_TMIN] * float(rng.choice([0.9, 1.0, 1.0 + 1e-6, 1.02, 1.3, 3.0]))
        got = []
        for general in (True, False):
            ws = _ws(row, K.TASK_FIXED, general)
            ws[K.IN_T] = T
            K.solve(ws)
            got.append((int(ws[K.OUT_STATUS]), int(ws[K.OUT_NBLK]), _blocks(ws), ws))
        (st_g, nb_g, blk_g, _), (st_f, nb_f, blk_f, wsf) = got
        assert st_f == st_g and nb_f == nb_g
        np.testing.assert_allclose(blk_f, blk_g, rtol=DURATION_RTOL)
        outcomes[st_f] = outcomes.get(st_f, 0) + 1
        if st_f == K.ST_OK:
            n = int(wsf[K.OUT_N])
            ph = wsf[K.OUT_PH:K.OUT_PH + 3 * n].reshape(n, 3)
            assert math.fsum(ph[:, 0]) == pytest.approx(T, rel=1e-12)
    assert outcomes.get(K.ST_OK, 0) > 0.5 * len(rows) and outcomes.get(K.ST_SHORT, 0) > 0
