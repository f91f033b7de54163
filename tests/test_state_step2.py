"""Step 2 of the state-to-state planner (a profile of exactly ``T``): its search
order and its speed-ups never change whether a profile is found.

* the (stage, direction) pairs and the cruise shapes are searched in a
  predicted order: every pair and every shape is still tried (a permutation);
* the template's duration without integrating positions equals the walk's;
* long durations, as time synchronisation asks for (``T`` up to 20 times the
  minimum): exactly ``T``, every limit kept (independent exact check), and
  every duration outside the blocked intervals of step 1 is filled (symmetric
  limits; those intervals are checked against ruckig in test_state_sweep.py;
  ruckig 0.19 itself crashes on some of these starts at the limits);
  asymmetric limits stay within the known gap (docs/state-profiles.md).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from conftest import sweep_size
from floatcmp import assert_ulp_close
from state_reference import (
    exact_check,
    goal_error,
    random_brake_case,
    random_case,
)

from trajkit import AxisLimits
from trajkit.errors import InfeasibleError
from trajkit.profiles import _shapes as S
from trajkit.profiles.state import BlockedDurationError, feasible_durations, plan_state_to_state

#: Long durations of the sweep, in multiples of the minimum (sync asks for a
#: median of about 8 between random 6-axis states).
FACTORS = (1.02, 1.7, 4.0, 19.0)


def _check(prof, lim):
    why = exact_check(prof, lim)
    assert why is None, why
    err = goal_error(prof)
    assert err < 1e-9, err


def test_search_order_tries_every_pair_once():
    all_pairs = {(stage, sgn) for stage in range(S.STAGE_HOLD2 + 1) for sgn in (1.0, -1.0)}
    margins = (0.0, -0.0, 1e-12, -1e-12, 0.3, -0.3, 2.0, -2.0, 1e300)
    for m1, m2 in itertools.product(margins, repeat=2):
        order = [tuple(S._step2_pair(k, m1, m2)) for k in range(S.STEP2_PAIRS)]
        assert len(order) == len(all_pairs) and set(order) == all_pairs, (m1, m2, order)
        # the equal-jerk families (the most expensive polynomials) come next to last,
        # the sampled holds last
        assert {p[0] for p in order[-4:-2]} == {S.STAGE_EQUAL}
        assert {p[0] for p in order[-2:]} == {S.STAGE_HOLD2}
        # the first pair is a cruise, of the class the margins' signs give
        stage, sgn = order[0]
        if m1 > 0.0 and not m2 > 0.0:
            assert (stage, sgn) == (S.STAGE_CRUISE, 1.0)
        elif m2 > 0.0 and not m1 > 0.0:
            assert (stage, sgn) == (S.STAGE_CRUISE, -1.0)
        else:
            assert stage == S.STAGE_INFLECTION and sgn == (1.0 if m1 > 0.0 else -1.0)


def test_cruise_shapes_hint_first_then_every_other():
    shapes = list(range(S.S2_NN, S.S2_AA + 1))
    for hint in shapes:
        order = [S._cruise_shape(i, hint) for i in range(4)]
        assert order[0] == hint and sorted(order) == shapes


def test_cruise_hint_from_the_peak_acceleration():
    # a rest-to-rest half that changes the velocity by dv peaks at sqrt(dv / K):
    # below A it is a plain ramp pair (N), above it holds at A
    lim = np.array([10.0, 1.0, 1.0, 1.0, 1.0])
    st0 = np.zeros(7)
    for m1, m2, want in ((0.5, -0.5, S.S2_NN), (1.5, -0.5, S.S2_AN),
                         (0.5, -1.5, S.S2_NA), (1.5, -1.5, S.S2_AA)):
        assert S._cruise_hint(st0, lim, S.STAGE_CRUISE, 1.0, m1, m2) == want
        # the mirrored problem: the same halves
        assert S._cruise_hint(st0, lim, S.STAGE_CRUISE, -1.0, -m1, -m2) == want
    # a start acceleration carried into the rise adds a^2 to the squared peak
    st0[2] = 0.8
    assert S._cruise_hint(st0, lim, S.STAGE_CRUISE, 1.0, 0.5, -0.5) == S.S2_AN
    assert S._cruise_hint(st0, lim, S.STAGE_CRUISE, -1.0, -0.5, 0.5) == S.S2_NN


def test_durations_equal_the_walk():
    rng = np.random.default_rng(5)
    for _ in range(2000):
        cfg = np.zeros(2 * S.NCFG)
        cfg[:S.NCFG] = rng.uniform(-2.0, 2.0, S.NCFG)
        for k in (S.K1, S.K2P, S.K2N, S.K2Q, S.K4, S.K2R):
            cfg[k] = 0.0 if rng.random() < 0.2 else rng.uniform(0.0, 3.0)
        cfg[S.MODE] = rng.integers(0, 7)
        cfg[S.SG2] = rng.choice((1.0, -1.0))
        c1, t1, z, c3, t3 = rng.uniform(-2.0, 2.0, 5)
        if rng.random() < 0.3:
            t1 = 0.0
        want = S.walk(cfg, c1, t1, z, c3, t3, 0.0)[1]
        got = S._durations(cfg, cfg, c1, t1, z, c3, t3)
        assert_ulp_close(got, want, 4, err_msg=str(cfg))


N_LONG = sweep_size(250)


def test_long_durations_symmetric():
    """Every long duration outside the blocked intervals is filled, exactly, within
    the limits (brake starts included)."""
    rng = np.random.default_rng(21)
    n_ok = n_blocked = 0
    for i in range(N_LONG):
        s, g, L = random_brake_case(rng, symmetric=True) if i % 5 == 4 else random_case(rng)
        if s == g:
            continue
        lim = AxisLimits(*L)
        fd = feasible_durations(s, g, lim)
        for f in FACTORS:
            T = fd.minimum * f
            try:
                q = plan_state_to_state(s, g, lim, duration=T)
            except BlockedDurationError as err:
                lo, hi = err.interval
                assert lo <= T <= hi and (lo, hi) in [tuple(b) for b in fd.blocked]
                n_blocked += 1
                continue
            assert q.duration == pytest.approx(T, rel=1e-12)
            _check(q, lim)
            n_ok += 1
    assert n_ok >= 0.9 * len(FACTORS) * N_LONG


def test_long_durations_asymmetric():
    rng = np.random.default_rng(22)
    n_req = n_none = 0
    for _ in range(N_LONG):
        s, g, L = random_case(rng, symmetric=False)
        if s == g:
            continue
        lim = AxisLimits(*L)
        t_min = plan_state_to_state(s, g, lim).duration
        for f in FACTORS:
            T = t_min * f
            try:
                q = plan_state_to_state(s, g, lim, duration=T)
            except BlockedDurationError:
                continue
            except InfeasibleError as err:
                assert "a longer duration may be feasible" in str(err)
                n_req += 1
                n_none += 1
                continue
            n_req += 1
            assert q.duration == pytest.approx(T, rel=1e-12)
            _check(q, lim)
    assert n_none <= 0.01 * n_req


def _proven_gap(s, g, L):
    """Durations no profile from ``s`` to ``g`` can have, proven without the
    planner by a relaxation (jerk limits dropped), or None: for a start and
    goal moving the same way as the distance, a motion that does not reverse
    covers at least ``M(T) = int max(|v0| - A2 t, |vf| - A1 (T - t), 0) dt``
    (the speed shrinks at most at ``a_max_decel`` and grows at most at
    ``a_max``), which exceeds ``|D|`` beyond ``Ta``; one that reverses must
    first stop (``|v0| / A2``), give back the travel above ``|D|`` on the other
    side (an excursion of duration ``tau`` covers at most ``tau^2 / (2 (1/A1 +
    1/A2))``) and speed up to ``|vf|`` (``|vf| / A1``): ``T >= Tb``. Every
    duration in ``(Ta, Tb)`` is infeasible."""
    from scipy.optimize import brentq

    D = g[0] - s[0]
    if not (s[1] * D > 0.0 and g[1] * D > 0.0):
        return None
    u0, uf = abs(s[1]), abs(g[1])
    A1, A2 = L[1], L[3]
    slowest = u0 * u0 / (2.0 * A2) + uf * uf / (2.0 * A1)
    if not slowest > abs(D):
        return None

    def travel(T):  # M(T): piecewise linear integrand, exact by trapezoids
        def f(t):
            return max(u0 - A2 * t, uf - A1 * (T - t), 0.0)
        pts = sorted({0.0, T} | {p for p in (u0 / A2, T - uf / A1, (u0 - uf + A1 * T) / (A1 + A2))
                                 if 0.0 < p < T})
        return sum((b - a) * (f(a) + f(b)) / 2.0 for a, b in zip(pts[:-1], pts[1:]))

    Ta = brentq(lambda T: travel(T) - abs(D), 1e-12, u0 / A2 + uf / A1, xtol=1e-14)
    tau = (2.0 * (slowest - abs(D)) * (1.0 / A1 + 1.0 / A2)) ** 0.5
    return Ta, u0 / A2 + uf / A1 + tau


def test_blocked_intervals_of_separate_legs():
    """Separate legs: step 1 also finds valid profiles whose durations lie inside
    the feasible set (an acceleration held through a velocity reversal, where
    the leg's bound changes), so the valid durations do not pair into blocked
    intervals as with equal legs; each gap between them is decided by step 2.
    Three moves whose gap is proven by :func:`_proven_gap` (the weak decel leg
    makes every reversal slow): the one blocked interval holds the proven gap,
    its ends and the durations outside it are planned, the inside refused."""
    cases = [
        ((-0.37060783406439646, -0.540875349469885, 0.04914176271392083),
         (-3.220893541416452, -0.8468465473234723, -0.06935750650130823),
         (0.8468465473234723, 0.3302788257239121, 19.796658314532166, 0.06935750650130823,
          11.102447246912389)),
        ((6.220500308668942, -2.6126255959589475, 0.0),
         (-113.52906333434463, -6.162369594996322, 0.02071853790567764),
         (8.376393706029004, 0.15393424413602913, 9.087823738523289, 0.03390842382205555,
          7.10812088807166)),
        ((-2.648890489719474, -7.7646196783710035, 0.24433205399875788),
         (-171.94600790671177, -7.7646196783710035, -0.24433205399875788),
         (7.7646196783710035, 0.3682662595737506, 0.7676909009054991, 0.24433205399875788,
          0.48682172704386745)),
    ]
    for s, g, L in cases:
        lim = AxisLimits(*L)
        Ta, Tb = _proven_gap(s, g, L)
        fd = feasible_durations(s, g, lim)
        (lo, hi), = fd.blocked
        assert fd.minimum < lo <= Ta < Tb <= hi
        # (the relaxation drops the jerk: the true gap is a little wider)
        assert Ta - lo <= 0.01 * (Tb - Ta) and hi - Tb <= 0.01 * (Tb - Ta)
        for T in (0.5 * (fd.minimum + lo), lo, hi, 1.001 * hi, 1.5 * hi):
            q = plan_state_to_state(s, g, lim, duration=T)
            assert q.duration == pytest.approx(T, rel=1e-12)
            _check(q, lim)
        for T in np.linspace(lo, hi, 9)[1:-1]:
            with pytest.raises(BlockedDurationError) as err:
                plan_state_to_state(s, g, lim, duration=T)
            assert err.value.interval == (lo, hi)


#: Moves with separate legs whose fixed durations need a hold at a free level where the
#: velocity reverses, a second cruise, or a cruise where the start's acceleration has
#: been ramped to zero: (start, goal, limits, durations, family). Before those
#: families each duration was reported blocked (the first move's from its minimum up
#: to 16.507 s) or raised "no profile found" (the last); a mixed-integer oracle (a
#: time grid, the leg of each step by binaries) found motions at 14.0, 15.0 and
#: 16.15 s for the first.
REVERSAL_HOLDS = [
    ((-7.5819, 6.9015, -0.9094), (-10.9409, 0.1484, 1.8614),
     (7.8765, 2.4022, 1.1439, 4.1584, 0.3493), (12.98, 13.2, 14.0, 15.0, 15.94, 16.15, 16.3),
     ("hold1_acc1", "hold3")),
    ((0.041607372320091894, -0.237104985766932, 0.0),
     (0.041607372320091894, 0.19389004644125424, 0.133435692666076),
     (0.273053606119807, 3.0720242027919946, 0.3294044135755663, 9.627592901076335,
      0.8993501658285952), (1.7636, 1.78), ("hold1",)),
    ((-0.3028801458259431, -0.48820339913741484, -0.10484711658468232),
     (-0.3028801458259431, 0.11892347211995313, -0.33973149134677566),
     (0.5275623987114426, 0.8750339644784393, 0.3248979706937659, 4.197393377882646,
      0.17094791701833906), (6.89, 7.28, 7.77), ("cruise_cruise",)),
    ((7.004951893634527, -1.9254256051452598, -0.265897342596525),
     (7.004951893634527, 4.956530470493023, 2.1110668419945946),
     (8.63068925516632, 4.584218390260918, 0.3676630578374718, 4.163557235420162,
      0.9388338172283597), (5.67, 6.0, 6.595), ("cruise_shape",)),
]


@pytest.mark.parametrize("s, g, L, durations, families", REVERSAL_HOLDS)
def test_fixed_durations_through_a_reversal_with_separate_legs(s, g, L, durations, families):
    """A hold at a free acceleration while the velocity reverses (the leg, and
    with it the jerk limit, changes inside the hold or the ramp next to it), a
    hold at a free level together with one at the limit, a cruise at the
    start's velocity before the cruise of ramp 2, and a cruise where the
    start's acceleration has been ramped to zero before a shape of step 1:
    step 2 finds each such motion of exactly the duration asked for (checked
    by the independent exact check), and no duration between the minimum and
    them is reported blocked."""
    lim = AxisLimits(*L)
    fd = feasible_durations(s, g, lim)
    assert all(hi < durations[0] or lo > durations[-1] for lo, hi in fd.blocked), fd
    seen = set()
    for T in durations:
        assert fd.contains(T)
        q = plan_state_to_state(s, g, lim, duration=T)
        assert q.duration == pytest.approx(T, rel=1e-12)
        _check(q, lim)
        seen.add(q.family.split()[-1])
    assert seen & set(families), seen


#: Fixed durations with separate legs that the earlier families missed ("no profile
#: found"; the grid oracle of ``benchmarks/state_step2_study.py`` found a motion at
#: each), all from the study's random moves: (start, goal, limits, duration, the
#: family's last word, whether only the time-reversed move's families find it).
MIDDLE_HOLDS = [
    # the reversal inside a hold at the smaller acceleration limit, after a hold at a
    # free level
    ((-0.1080128503531773, 0.3712077372569841, -0.15079724472027783),
     (-0.10801277946732947, -0.27661867945532237, 0.0),
     (0.6558944471915301, 0.1589438576652786, 0.865854524973261, 0.32759319818162236,
      0.6867099583709829), 3.2939970368940195, "hold1_acc1", False),
    # a hold at a free level through the reversal
    ((0.013106282919973077, -0.12431536598332057, 0.1040581404287947),
     (0.013106282919973077, 0.14233498229845165, 0.20035047812037415),
     (0.16432005755827378, 0.3915938399868019, 0.23434830086728042, 0.8118321565155231,
      0.06696431925870687), 1.9174031865764225, "hold_mid", False),
    ((-0.10237676445254386, 0.11167298404460657, -0.3943344910328354),
     (-0.10237676445254386, -0.13633380382266674, -0.7906968694558592),
     (0.13633380382266674, 2.312852583726923, 3.1075587962233513, 0.7906968694558592,
      1.6751919437468983), 0.4913465400294499, "hold_mid", False),
    # a cruise at the start's (goal's) velocity with a hold at a free level through the
    # reversal
    ((-1.4643535558870662, -3.3441680305520682, -1.2274371921750928),
     (4.606391894375869, 7.547331274926791, 0.0),
     (7.547331274926791, 5.21569699527284, 2.965120271410355, 1.502957552461593,
      1.7032114731679555), 6.61755218373325, "cruise_shape", False),
    ((0.012104600983959652, 0.1498053884048595, 0.0),
     (0.012104579874499484, -0.1498053884048595, 0.0),
     (0.1498053884048595, 0.2835575506452661, 2.088429185609405, 0.28249069738213345,
      0.9731445129598802), 1.3506152571129977, "cruise_shape", False),
    # the same families on the time-reversed move
    ((5.004105724838268, -5.072551100393745, 0.0), (12.477758997789861, 5.072551100393745, 0.0),
     (5.072551100393745, 1.3751014423359054, 0.458301907068435, 5.906115401825305,
      0.5893086545184211), 10.691788947274611, "cruise_shape", True),
    ((-5.469828229300064, 6.750492161338357, -0.22826495033725333),
     (-5.469828229300064, -3.8640862480543583, -0.12617054195239152),
     (6.750492161338357, 0.47877573911394755, 0.8836133743772189, 1.954766192423431,
      2.823558040199294), 12.54478437643983, "cruise_shape", True),
    ((0.5043130381950653, -1.7365610249579935, 2.315659831101669),
     (0.5043126892054148, 1.7365610249579935, 0.5172964050876196),
     (1.7365610249579935, 7.588289710874881, 17.122700584585534, 3.0423448401455127,
      72.22367932979876), 1.0710688350436606, "hold1_acc1", True),
]


@pytest.mark.parametrize("s, g, L, T, family, backwards", MIDDLE_HOLDS)
def test_fixed_durations_with_a_hold_through_the_reversal(s, g, L, T, family, backwards):
    """A hold at a level between the corners of ramp 2 with the velocity
    reversal inside it (the jerk limit changes there), alone, after a hold at a
    free level or after a cruise, and the motions only the time-reversed move's
    families find: step 2 plans each duration exactly, within the limits by the
    independent exact check, and the duration is not reported blocked."""
    lim = AxisLimits(*L)
    assert feasible_durations(s, g, lim).contains(T)
    q = plan_state_to_state(s, g, lim, duration=T)
    assert q.duration == pytest.approx(T, rel=1e-12)
    _check(q, lim)
    assert q.n_brake_phases == 0
    assert q.family.split()[-1] == family, q.family
    assert ("reversed" in q.family) == backwards, q.family


N_ENDS = sweep_size(400)


def test_duration_at_the_end_of_a_blocked_interval():
    """Both ends of a blocked interval are durations of valid step-1 profiles: a
    request of exactly that duration (as time synchronisation makes, moving the
    common duration onto an end) gets a profile, exact and within the limits,
    even where step 2's families miss it by round-off (the case below)."""
    s = (5.660906860336608, 7.394213336416643, -0.022783838984972427)
    g = (219.3798951397145, 5.873891416520788, 0.02777760339156456)
    lim = AxisLimits(8.283724118243203, 0.10683197825495558, 7.34973754695728)
    (lo, hi), = feasible_durations(s, g, lim).blocked
    for T in (lo, hi):
        q = plan_state_to_state(s, g, lim, duration=T)
        assert q.duration == pytest.approx(T, rel=1e-12)
        _check(q, lim)
    rng = np.random.default_rng(23)
    n_ends = 0
    for i in range(N_ENDS):
        sym = i % 3 != 2
        s, g, L = random_brake_case(rng, symmetric=sym) if i % 4 == 3 else random_case(rng, sym)
        if s == g:
            continue
        lim = AxisLimits(*L)
        for lo, hi in feasible_durations(s, g, lim).blocked:
            for T in (lo, hi):
                q = plan_state_to_state(s, g, lim, duration=T)
                assert q.duration == pytest.approx(T, rel=1e-12)
                _check(q, lim)
                n_ends += 1
            # inside, away from the ends: refused as blocked (symmetric limits;
            # with separate legs an interval is where step 2 found no profile at
            # the probes, and it may still fill a duration next to an end)
            eps = max(1e-6 * (hi - lo), 1e-11 * hi)
            if sym and hi - lo > 4.0 * eps:
                for T in (lo + eps, 0.5 * (lo + hi), hi - eps):
                    with pytest.raises(BlockedDurationError):
                        plan_state_to_state(s, g, lim, duration=T)
    assert n_ends >= 0.02 * N_ENDS  # (measured: 12 ends in 400 cases, 198 in 8,000)


N_CLOSED = sweep_size(1500)


def _table_ok(ph, n, s, g, V, A, J):
    """Independent check of a phase table from state ``s``: jerks 0 or +-J, the
    accelerations continuous and within A, the velocity within V at every phase
    end and in-phase extremum, the goal state ``g`` reached."""
    p, v, a = s
    scale = abs(g[0] - s[0]) + V * sum(ph[k, 0] for k in range(n)) + 1e-300
    for k in range(n):
        dt, j, a_k = ph[k]
        assert dt >= 0.0
        assert abs(a_k - a) <= 1e-9 * A
        assert j == 0.0 or abs(abs(j) - J) <= 1e-12 * J
        if j != 0.0 and 0.0 < -a / j < dt:
            t = -a / j
            assert abs(v + a * t + 0.5 * j * t * t) <= V * (1 + 1e-9)
        p += dt * (v + dt * (0.5 * a + dt * j / 6.0))
        v += dt * (a + 0.5 * dt * j)
        a += dt * j
        assert abs(a) <= A * (1 + 1e-9) and abs(v) <= V * (1 + 1e-9)
    assert abs(p - g[0]) <= 1e-9 * scale
    assert abs(v - g[1]) <= 1e-9 * V and abs(a - g[2]) <= 1e-9 * A


def test_closed_form_cruise_family_of_symmetric_limits():
    """Step 2 with symmetric limits tries the cruise family in closed form first
    (``_symfast.sym_step2``): on random requests of the durations time
    synchronisation asks for it finds a profile in >= 95 % of them, each of
    exactly ``T``, within the limits and at the goal (independent check); the
    planner's result equals it."""
    from trajkit.profiles import _symfast as F

    rng = np.random.default_rng(31)
    ph = np.zeros((16, 3))
    scr = np.zeros(F.SF_SCRATCH)
    n_req = n_found = 0
    for _ in range(N_CLOSED):
        s, g, L = random_case(rng, symmetric=True)
        if s == g:
            continue
        V, A, J = L[0], L[1], L[2]
        lim = AxisLimits(V, A, J)
        fd = feasible_durations(s, g, lim)
        T = fd.next_feasible(fd.minimum * float(rng.choice(FACTORS)))
        if T <= fd.minimum * (1.0 + 1e-12):
            continue
        n_req += 1
        s1 = np.array([*s, *g, np.nan])
        n, code = F.sym_step2(s1, T, np.array([V, A, 1.0 / J, A, 1.0 / J]), ph, scr)
        if n == 0:
            continue
        n_found += 1
        assert ph[:n, 0].sum() == pytest.approx(T, rel=1e-12)
        _table_ok(ph, n, s, g, V, A, J)
        q = plan_state_to_state(s, g, lim, duration=T)
        assert q.phase_durations == pytest.approx(tuple(ph[:n, 0]), rel=1e-12, abs=1e-12 * T)
        assert q.family.startswith("fixed") and "cruise" in q.family
    assert n_found >= 0.95 * n_req and n_req >= 0.8 * N_CLOSED


#: Fixed durations the shape families and the time-reversed search miss (from
#: ``benchmarks/state_step2_study.py --cases 3000 --seed 20 --seeds 40``): start,
#: goal, limits, duration and the state between the two halves found.
SPLIT = [
    ((3.7576421700115556, 3.4827378955439263, -1.285837259795132),
     (3.7576421700115556, -5.611217688122037, -3.8458311536005083),
     (5.611217688122037, 3.8458311536005083, 0.9783522813574893, 13.386484013821715, 3.1493946945042555),
     3.58299250242889, 'split_at_velocity_extremum'),
    ((-0.04557438395698044, 0.4568264452424138, -0.03787361761037154),
     (0.35388565288298707, -0.7788523956030566, -0.25919661137707256),
     (0.7788523956030566, 0.8652032049723586, 0.5194326365567639, 0.37020709397327606, 0.16467706133337606),
     4.761820298833784, 'split_at_reversal'),
    ((-2.0211022739474624, 5.2472361838398545, -0.1045323440631481),
     (6.400410422009994, -5.2472361838398545, -0.45652979174020203),
     (5.2472361838398545, 0.6503180478214451, 0.1894344249613898, 0.5350384773081455, 0.22230724468163515),
     19.07019091657255, 'split_at_reversal'),
    ((-2.4146927006313703, 1.1814264193488113, -0.37108552578093396),
     (-2.4146927006313703, -2.4266244189859156, -1.648360890106777),
     (2.6157537032032137, 2.9403798000020274, 0.8704058612159771, 2.2819732525505954, 0.37057493451106366),
     4.441135942983648, 'split_at_reversal'),
    ((0.9609667634999397, -1.1433398078180743, 0.04051314985678465),
     (-2.9555785440634237, 0.887215680078552, 0.10151356395202647),
     (1.1468558296030626, 0.7006707274388636, 0.5459890207355447, 0.1635097233147258, 0.10900295083282749),
     10.11648295356341, 'split_at_reversal'),
    ((-0.5637679866725168, -0.3839408035948737, 0.19809901191056511),
     (-0.5637679866725168, 0.656926830906539, 0.3148309860506993),
     (0.656926830906539, 0.9852792847760087, 1.002632791158017, 0.36414525170815465, 0.38890653801709246),
     2.9238578312863353, 'split_at_reversal'),
    ((0.6250464482956484, -0.8394696828424577, 0.2014401203913498),
     (0.6250464482956484, 0.8394696828424577, 0.015159247101582464),
     (0.8394696828424577, 0.3602470753091162, 0.17654069298348832, 0.23916750103893622, 0.38111736213779174),
     7.3017169253622365, 'split_at_reversal'),
    ((-0.04869001028446794, -0.019879929187501796, 0.01353881373384062),
     (-0.007248092382059743, 0.08450917776225578, 0.0911863764067133),
     (0.12065349033813619, 0.15144779098653247, 0.11128878660762728, 0.20204535623013045, 0.02952898432634326),
     2.0750936456373172, 'split_at_reversal'),
    ((2.371755561560229, -1.1070913899688444, 4.531042932017537),
     (11.073489119734852, 4.05867995686406, 0.1601564475179121),
     (5.42938268644296, 5.435916474251384, 2.027630671460224, 9.492394088208904, 3.670467396164427),
     3.40776767271941, 'split_at_velocity_extremum'),
    ((-1.1190921082463732, -0.7899774647994787, 0.006921084482070048),
     (-1.1190919859235027, 1.443760685420434, 0.6569377980549636),
     (1.451785612808186, 7.164323443448838, 0.11355399838957037, 7.957824956657893, 0.23970956717252273),
     5.002207618354767, 'split_at_reversal'),
    ((-1.6702867945232325, 0.7626636182625894, -0.16563659315824272),
     (-1.6702996260978171, -0.5716811067502934, -0.015106085624514334),
     (2.102108888777601, 0.17195556530247394, 0.6262720366175643, 0.38771412101162783, 0.12781662207246336),
     6.534875727783268, 'split_at_reversal'),
]


@pytest.mark.parametrize("s, g, L, T, where", SPLIT)
def test_fixed_durations_split_in_two_halves(s, g, L, T, where):
    """Where every family misses a duration, the profile is found as two
    halves through a velocity reversal ``(p, 0, a)`` or a velocity extremum
    ``(p, v, 0)``: exactly the duration, within the limits by the independent
    exact check, and passing that state at a phase boundary."""
    lim = AxisLimits(*L)
    q = plan_state_to_state(s, g, lim, duration=T)
    assert q.duration == pytest.approx(T, rel=1e-12)
    assert q.family == f"fixed {where}", q.family
    _check(q, lim)
    st = q.sample(np.cumsum(q.phase_durations)[:-1])
    if where == "split_at_reversal":  # at rest, with an acceleration within both legs
        at = np.abs(st.velocity) <= 1e-9 * lim.v_max
        assert at.any()
        assert (np.abs(st.acceleration[at]) <= min(lim.a_max, lim.a_max_decel)).all()
    else:  # no acceleration, the velocity within v_max
        at = np.abs(st.acceleration) <= 1e-9 * max(lim.a_max, lim.a_max_decel)
        assert at.any()
        assert (np.abs(st.velocity[at]) <= lim.v_max).all()


def test_split_fixed_durations_in_a_batch():
    """The batch planner finds the same profiles as the one-move planner."""
    from trajkit.profiles.state_batch import plan_state_moves

    starts = np.array([c[0] for c in SPLIT])
    goals = np.array([c[1] for c in SPLIT])
    L = np.array([c[2] for c in SPLIT]).T
    T = np.array([c[3] for c in SPLIT])
    b = plan_state_moves(starts, goals, *L, durations=T)
    np.testing.assert_allclose(b.duration, T, rtol=1e-12)
    for i, (s, g, lims, dur, where) in enumerate(SPLIT):
        q = b.profile(i)
        one = plan_state_to_state(s, g, AxisLimits(*lims), duration=dur)
        assert q.family == one.family == f"fixed {where}"
        assert q.min_duration == pytest.approx(one.min_duration, rel=1e-12)
        np.testing.assert_allclose(q.phase_durations, one.phase_durations, rtol=1e-12, atol=1e-12 * dur)
        _check(q, AxisLimits(*lims))


#: Fixed durations that the families and both splits above miss (the same
#: study): start, goal, limits, duration. The grid oracle of the study
#: (``grid_feasible``) finds motions at both.
SPLIT_ALONG = [
    ((0.6187550785149055, -0.27456421657591734, 0.02564325945629974),
     (0.6187550785149055, 0.49612463890246916, 0.4189994001738286),
     (0.7164173192714507, 4.765936629726697, 0.10460399919917958, 18.055150802606523, 0.2735280483655923),
     3.3737563630588183),
    ((0.1732567002296881, -1.5351027606498149, 1.237627938595218),
     (0.1732567002296881, 0.8587389431775003, 0.24595813825826812),
     (1.6089338623966496, 3.968520670774027, 0.5690007632352301, 1.6465346660623077, 0.376124796584371),
     3.2393195706185844),
]


@pytest.mark.parametrize("s, g, L, T", SPLIT_ALONG)
def test_fixed_durations_split_along_the_minimum(s, g, L, T):
    """The last stage: two halves through a state of the minimum-time profile.
    Exactly the duration, within the limits by the independent exact check,
    and one phase boundary of the profile lies on the minimum-time profile."""
    lim = AxisLimits(*L)
    q = plan_state_to_state(s, g, lim, duration=T)
    assert q.duration == pytest.approx(T, rel=1e-12)
    assert q.family == "fixed split_along_minimum", q.family
    _check(q, lim)
    fast = plan_state_to_state(s, g, lim)
    path = fast.sample(np.linspace(0.0, fast.duration, 200001))
    bounds = q.sample(np.cumsum(q.phase_durations)[:-1])
    scale = (abs(g[0] - s[0]) + lim.v_max * fast.duration, lim.v_max, max(lim.a_max, lim.a_max_decel))
    gap = [min(np.max(np.abs(np.array([path.position - b_p, path.velocity - b_v, path.acceleration - b_a]))
                      / np.array(scale)[:, None], axis=0))
           for b_p, b_v, b_a in zip(bounds.position, bounds.velocity, bounds.acceleration)]
    assert min(gap) < 1e-4, gap


def test_split_along_in_a_batch():
    from trajkit.profiles.state_batch import plan_state_moves

    L = np.array([c[2] for c in SPLIT_ALONG]).T
    T = np.array([c[3] for c in SPLIT_ALONG])
    b = plan_state_moves(np.array([c[0] for c in SPLIT_ALONG]), np.array([c[1] for c in SPLIT_ALONG]),
                         *L, durations=T)
    np.testing.assert_allclose(b.duration, T, rtol=1e-12)
    for i, case in enumerate(SPLIT_ALONG):
        q = b.profile(i)
        assert q.family == "fixed split_along_minimum"
        _check(q, AxisLimits(*case[2]))
