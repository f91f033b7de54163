"""The supported numeric range of the profile planners (``trajkit.profiles._range``).

A fuzz sweep over decimal exponents -300..300 of every input (positions,
limits, start and goal states, durations): every result a planner returns
passes ``trajkit.verify``, everything else is a typed ``TrajkitError``
(never a TypeError, an overflow, a NaN profile). Inside the documented
range the planners must succeed (only a requested duration below the
minimum, a blocked duration or an unreachable goal state may be refused).
``TRAJKIT_SWEEP=1`` runs ten times as many cases.
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

from trajkit import AxisLimits, min_duration, plan_move, plan_moves
from trajkit.errors import InfeasibleError, InvalidInputError, TrajkitError
from trajkit.profiles import _range as R
from trajkit.profiles.state import plan_state_to_state, plan_velocity
from trajkit.verify import verify_profile, verify_state_profile

SCALE = 10 if os.environ.get("TRAJKIT_SWEEP") == "1" else 1
N_REST = 6000 * SCALE
N_STATES = 3000 * SCALE


# ------------------------------------------------------------ the examples
def test_tiny_limit_is_refused_not_planned():
    # used to return a duration of 2e-311 s
    with pytest.raises(InvalidInputError, match="a_max 1e-310 is outside the supported range"):
        plan_move(0, 1, AxisLimits(1, 1e-310, 10))


def test_huge_positions_are_refused_not_nan():
    # used to return inf with NaN states
    with pytest.raises(InvalidInputError, match="start -1e\\+308 is outside the supported range"):
        plan_move(-1e308, 1e308, AxisLimits(1, 1, 1))


@pytest.mark.parametrize("bad", ["x", None, [1.0], object()])
def test_non_numbers_are_invalid_input(bad):
    lim = AxisLimits(1, 1, 1)
    with pytest.raises(InvalidInputError, match="goal must be a number"):
        plan_move(0, bad, lim)
    with pytest.raises(InvalidInputError, match="start must be a number"):
        plan_move(bad, 1, lim)
    with pytest.raises(InvalidInputError, match="distance must be a number"):
        min_duration(bad, lim)
    with pytest.raises(InvalidInputError):
        plan_state_to_state((0.0, bad, 0.0), (1.0, 0.0, 0.0), lim)


def test_the_range_edges():
    lim = AxisLimits(1, 1, 1)
    # the largest positions, the smallest resolvable distance, the extreme limits
    for s, g, L in [(R.REST_POSITION_MAX, -R.REST_POSITION_MAX, lim),
                    (0.0, R.DISTANCE_ABS_MIN, lim),
                    (1.0, 1.0 + 2.2e-16, lim),  # one ulp: planned relative to the start
                    (0.0, 1.0, AxisLimits(*(3 * [R.REST_MAGNITUDE_MIN]))),
                    (0.0, 1.0, AxisLimits(*(3 * [R.REST_MAGNITUDE_MAX]))),
                    (0.0, 1.0, AxisLimits(1.0, 1.0, 1.0, a_max_decel=1.0 / R.LEG_RATIO_MAX,
                                          j_max_decel=R.LEG_RATIO_MAX))]:
        p = plan_move(s, g, L)
        assert math.isfinite(p.duration) and p.duration > 0
        assert verify_profile(p).ok
    with pytest.raises(InvalidInputError, match="distance"):
        plan_move(0.0, 1e-101, lim)
    with pytest.raises(InvalidInputError, match="duration"):
        plan_move(0.0, 1.0, lim, duration=1e301)
    with pytest.raises(InvalidInputError, match="duration"):
        plan_state_to_state((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), lim, duration=1e51)
    with pytest.raises(InvalidInputError, match="position"):
        plan_state_to_state((1e16, 0.0, 0.0), (1.0, 0.0, 0.0), lim)
    with pytest.raises(InvalidInputError, match="a_max"):
        plan_state_to_state((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), AxisLimits(1.0, 1e-31, 1.0))
    with pytest.raises(InvalidInputError, match="decel leg"):
        plan_move(0.0, 1.0, AxisLimits(1.0, 1.0, 1.0, a_max_decel=1e-7))
    with pytest.raises(InvalidInputError, match="v_max j_max / a_max"):
        plan_state_to_state((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), AxisLimits(1e-10, 1.0, 1e-10))


# ------------------------------------------------------------ the sweep
def _x(rng, lo, hi, zero=0.08, signed=True):
    if rng.random() < zero:
        return 0.0
    x = 10.0 ** rng.uniform(lo, hi)
    return -x if signed and rng.random() < 0.5 else x


def _limits(rng, wide, span=33):
    lo, hi = (-300, 300) if wide else (-span, span)
    vals = [_x(rng, lo, hi, zero=0.0, signed=False) for _ in range(5)]
    if not wide:
        # mostly plausible ratios inside the range, sometimes anything
        if rng.random() < 0.7:
            base = 10.0 ** rng.uniform(-(span - 8), span - 8)
            vals = [base * 10.0 ** rng.uniform(-3, 3) for _ in range(5)]
    if rng.random() < 0.1:
        vals[0] = math.inf
    elif rng.random() < 0.05:
        vals[1] = math.inf
    if rng.random() < 0.4:
        vals[3], vals[4] = vals[1], vals[2]
    try:
        return AxisLimits(*vals)
    except InvalidInputError:
        return None


def _in_range_limits(lim, states):
    try:
        R.check_limits_range(lim, states=states)
    except InvalidInputError:
        return False
    return True


def _scale(lim):
    """A natural length scale of the limits (to put positions near it)."""
    V, A, J = lim.v_max, lim.a_max, lim.j_max
    if V < math.inf and A < math.inf:
        return V / A * V
    if A < math.inf and J < math.inf:
        return A / J * (A / J) * A
    return math.sqrt(V / J) * V if V < math.inf else 1.0


def test_fuzz_rest_to_rest():
    rng = np.random.default_rng(300)
    counts = dict(ok=0, invalid=0, infeasible=0)
    for i in range(N_REST):
        wide = i % 2 == 0
        lim = _limits(rng, wide, span=153)
        if lim is None:
            continue
        if wide:
            s, g = _x(rng, -300, 300), _x(rng, -300, 300)
        else:
            sc = _scale(lim)
            s = _x(rng, -300, 300) if rng.random() < 0.2 else sc * rng.uniform(-3, 3)
            g = s + sc * _x(rng, -20, 3)
        T = None
        if rng.random() < 0.3:
            T = _x(rng, -300, 300, signed=False) if wide or rng.random() < 0.3 else None
        try:
            p = plan_move(s, g, lim, duration=T)
        except InvalidInputError as err:
            counts["invalid"] += 1
            in_range = (_in_range_limits(lim, False) and abs(s) <= R.REST_POSITION_MAX
                        and abs(g) <= R.REST_POSITION_MAX and (
                            g == s or abs(g - s) >= R.DISTANCE_ABS_MIN))
            # (the duration rules: below REST_DURATION_MAX, the ratio to the
            # minimum and the cruise velocity, checked by the planner)
            assert not in_range or (T is not None and str(err).startswith("duration")), (
                s, g, lim, T, str(err))
            continue
        except InfeasibleError:
            counts["infeasible"] += 1
            assert T is not None  # only a duration below the minimum
            continue
        except TrajkitError:  # pragma: no cover - any other typed error is a finding
            raise
        counts["ok"] += 1
        assert math.isfinite(p.duration)
        rep = verify_profile(p)
        assert rep.ok, (s, g, lim, T, rep.violations[:2])
        # min_duration agrees (same range, same value)
        if T is None:
            assert min_duration(g - s, lim) == pytest.approx(p.duration, rel=1e-12, abs=0.0) or s != 0.0
    assert counts["ok"] > 0.2 * N_REST and counts["invalid"] > 0.1 * N_REST, counts


def test_fuzz_batch_same_verdicts_as_scalar():
    rng = np.random.default_rng(301)
    for _ in range(300):
        lim = _limits(rng, wide=bool(rng.random() < 0.5))
        if lim is None:
            continue
        s = np.array([_x(rng, -300, 300) for _ in range(4)])
        g = s + np.array([_x(rng, -20, 20) for _ in range(4)])
        args = (s, g, lim.v_max, lim.a_max, lim.j_max, lim.a_max_decel, lim.j_max_decel)
        scalar_ok = True
        for a, b in zip(s, g):
            try:
                plan_move(float(a), float(b), lim)
            except InvalidInputError:
                scalar_ok = False
        try:
            batch = plan_moves(*args)
        except InvalidInputError:
            assert not scalar_ok
            continue
        assert scalar_ok
        assert np.all(np.isfinite(batch.duration))


def _state(rng, lim, wide, goal):
    if wide:
        return (_x(rng, -300, 300), _x(rng, -300, 300), _x(rng, -300, 300))
    V = lim.v_max if lim.v_max < math.inf else 1e3 * _scale(lim) ** 0.5
    A = min(lim.a_max, lim.a_max_decel)
    A = A if A < math.inf else V
    k = rng.integers(0, 4)
    v = 0.0 if k == 0 else V * rng.uniform(-1.0, 1.0) * (1.5 if not goal and k == 3 else 1.0)
    a = 0.0 if k == 1 else A * rng.uniform(-1.0, 1.0) * (1.5 if not goal and k == 3 else 0.3)
    return (0.0, float(v), float(a))


def test_fuzz_states():
    rng = np.random.default_rng(302)
    counts = dict(ok=0, invalid=0, infeasible=0)
    for i in range(N_STATES):
        wide = i % 3 == 0
        lim = _limits(rng, wide)
        if lim is None:
            continue
        s = _state(rng, lim, wide, goal=False)
        g = _state(rng, lim, wide, goal=True)
        if not wide:
            sc = _scale(lim)
            p0 = sc * rng.uniform(-3, 3)
            s = (p0, s[1], s[2])
            g = (p0 + sc * _x(rng, -20, 2), g[1], g[2])
        T = None
        if rng.random() < 0.2:
            T = _x(rng, -300, 300, signed=False)
        velocity = rng.random() < 0.2
        try:
            if velocity:
                p = plan_velocity(s, g[1], g[2], limits=lim, duration=T)
            else:
                p = plan_state_to_state(s, g, lim, duration=T)
        except InvalidInputError:
            counts["invalid"] += 1
            continue
        except InfeasibleError as err:
            counts["infeasible"] += 1
            # inside the range only a duration can be infeasible (below the
            # minimum, blocked, or a profile leaving the position range)
            assert T is not None or not _in_range_limits(lim, states=True), (s, g, lim, str(err))
            continue
        counts["ok"] += 1
        assert math.isfinite(p.duration)
        rep = verify_state_profile(p)
        assert rep.ok, (s, g, lim, T, rep.violations[:2])
    assert counts["ok"] > 0.2 * N_STATES and counts["invalid"] > 0.1 * N_STATES, counts


def test_state_planner_corners_of_the_range():
    """Every combination of limits at the ends and the middle of the range,
    states at rest, moving, at the limits and beyond them, distances from tiny
    to large compared with the limits: planned and verified, or refused."""
    import itertools

    mags = (R.MAGNITUDE_MIN, 1e-10, 1.0, 1e10, R.MAGNITUDE_MAX)
    n_ok = n_refused = 0
    for V, A, J in itertools.product(mags + (math.inf,), mags, mags):
        lim = AxisLimits(V, A, J, a_max_decel=2.0 * A, j_max_decel=0.5 * J)
        try:
            R.check_limits_range(lim, states=True)
        except InvalidInputError:
            n_refused += 1
            with pytest.raises(InvalidInputError):
                plan_state_to_state((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), lim)
            continue
        Vn = V if V < math.inf else 1e3 * math.sqrt(A ** 3 / J ** 2 * A)
        ls = min(A ** 3 / J ** 2, Vn * Vn / A)
        for (v0, a0), (vf, af), f in itertools.product(
                ((0.0, 0.0), (0.5 * Vn, 0.0), (Vn, -0.3 * A), (-0.2 * Vn, 0.5 * A), (1.5 * Vn, 0.0)),
                ((0.0, 0.0), (-0.5 * Vn, 0.0)),
                (0.0, 1e-6, 1.0, 1e6)):
            d = f * ls
            if d > R.POSITION_MAX:
                continue
            try:
                p = plan_state_to_state((0.0, v0, a0), (d, vf, af), lim)
            except InvalidInputError as err:
                # only a goal that cannot be reached or a start state forcing too much speed
                assert "cannot be reached" in str(err) or "forced" in str(err) or "distance" in str(err), (
                    V, A, J, v0, a0, d, vf, af, str(err))
                continue
            rep = verify_state_profile(p)
            assert rep.ok, (V, A, J, v0, a0, d, vf, af, rep.violations[:2])
            n_ok += 1
    assert n_ok > 500 and n_refused > 0
