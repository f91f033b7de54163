"""The fast path of the state planners is the general path.

``plan_state_to_state`` checks and plans its common call (tuples of floats,
validated limits, no duration) inline, on bounds cached on the limits;
``plan_ptp_states`` does the same per axis. Anything else (lists, numpy
floats, an unusual value) goes the general way. Both must give the same
profile to the bit (same kernel, same inputs) and the same errors, and the
cached goal check must agree with the one that writes the messages.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import sweep_size
from state_reference import random_brake_case, random_case

from trajkit import AxisLimits, plan_ptp_states
from trajkit.errors import InvalidInputError, TrajkitError
from trajkit.profiles.state import _check_limits, _goal_ok, _goal_violation, plan_state_to_state

FIELDS = ("duration", "phase_durations", "jerks", "phase_accelerations", "min_duration",
          "n_brake_phases", "family", "start_state", "goal_state")


def _fields(p):
    return tuple(getattr(p, f) for f in FIELDS)


def _outcome(start, goal, limits):
    try:
        return ("ok", _fields(plan_state_to_state(start, goal, limits)))
    except TrajkitError as err:
        return (type(err).__name__, str(err))


def _cases(seed, n):
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        gen = random_brake_case if i % 4 == 3 else random_case
        s, g, L = gen(rng, symmetric=i % 2 == 0)
        out.append((tuple(float(x) for x in s), tuple(float(x) for x in g), L))
    return out


def test_fast_and_general_path_agree_bit_for_bit():
    n_ok = 0
    for s, g, L in _cases(21, sweep_size(120)):
        lim = AxisLimits(*L)
        ranged = AxisLimits(*L, position_min=min(s[0], g[0]) - 0.01,
                            position_max=max(s[0], g[0]) + 0.01)
        for lm in (lim, ranged):
            fast = _outcome(s, g, lm)
            # a list (and numpy floats) take the general path
            slow = _outcome(list(s), list(g), lm)
            npf = _outcome(tuple(np.float64(x) for x in s), tuple(np.float64(x) for x in g), lm)
            assert fast == slow == npf
            n_ok += fast[0] == "ok"
    assert n_ok > 100


@pytest.mark.parametrize("goal, match", [
    ((1.0, 1.0, -1.5), "goal state"),           # at v_max, slowing down: above it before
    ((1.0, 2.0, 0.0), "goal state"),            # above v_max
    ((1.0, 0.5, 3.0), "goal state"),            # above a_max
    ((1e-120, 0.0, 0.0), "distance"),           # below the smallest distance
    ((math.nan, 0.0, 0.0), "finite"),
    ((2e15, 0.0, 0.0), "position"),
])
def test_fast_path_errors_are_the_general_ones(goal, match):
    lim = AxisLimits(1.0, 2.0, 10.0)
    msgs = []
    for gg in (goal, list(goal)):
        with pytest.raises(InvalidInputError, match=match) as err:
            plan_state_to_state((0.0, 0.0, 0.0), gg, lim)
        msgs.append(str(err.value))
    assert msgs[0] == msgs[1]


def test_cached_goal_check_agrees_with_the_messages():
    rng = np.random.default_rng(5)
    n_bad = 0
    for i in range(sweep_size(3000)):
        V, A, J = 10.0 ** rng.uniform(-1, 1, 3)
        Ad = A * 10.0 ** rng.uniform(-1, 1) if i % 2 else A
        Jd = J * 10.0 ** rng.uniform(-1, 1) if i % 2 else J
        if i % 7 == 0:
            J = math.inf
        lim = _check_limits(AxisLimits(V, A, J, Ad, Jd))
        # around the boundary of the reachable set, and exactly on it
        v = V * rng.choice([rng.uniform(-1.2, 1.2), 1.0, -1.0, 1.0 + 1e-12, 1.0 + 2e-12])
        a = max(A, Ad) * rng.choice([rng.uniform(-1.2, 1.2), 1.0, -1.0, 0.0])
        ok = _goal_ok(v, a, lim)
        assert ok == (_goal_violation(v, a, lim) is None), (v, a, lim)
        n_bad += not ok
    assert n_bad > 100


def test_ptp_states_fast_and_general_inputs_agree():
    rng = np.random.default_rng(8)
    for _ in range(sweep_size(20)):
        cs = [random_case(rng, symmetric=True) for _ in range(4)]
        S = [tuple(float(x) for x in c[0]) for c in cs]
        G = [tuple(float(x) for x in c[1]) for c in cs]
        lims = [AxisLimits(*c[2]) for c in cs]
        outs = []
        # (rows of numpy arrays take the general path)
        for s_in, g_in in ((S, G), (np.array(S), np.array(G)), ([list(x) for x in S], tuple(G)),
                           ([np.array(x) for x in S], [np.array(x) for x in G])):
            try:
                traj = plan_ptp_states(s_in, g_in, lims)
                outs.append(("ok", traj.names, [_fields(p) for p in traj.axes]))
            except TrajkitError as err:
                outs.append((type(err).__name__, str(err)))
        assert all(o == outs[0] for o in outs)
