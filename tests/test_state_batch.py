"""Many state-to-state moves in one call, and the compiled multi-axis synchronisation.

* ``plan_state_moves`` gives move by move what ``plan_state_to_state`` gives
  (durations to a few ulps, the same phase tables), including brake starts,
  fixed durations and asymmetric limits; errors name the first bad move.
* ``plan_ptp_states`` (compiled time synchronisation) gives what the
  per-axis Python path gives: the same common duration, every axis verified.
"""

from __future__ import annotations

import numpy as np
import pytest
from floatcmp import assert_ulp_close
from state_reference import random_brake_case, random_case

from trajkit import AxisLimits, plan_ptp_states, plan_state_moves
from trajkit.errors import InfeasibleError, InvalidInputError
from trajkit.profiles.state import feasible_durations, plan_state_to_state
from trajkit.sync import states as sync_states
from trajkit.verify import verify_state_profile, verify_trajectory

#: Compares two code paths (see floatcmp); CI runs it again with numpy SIMD off.
pytestmark = pytest.mark.codepaths


def _cases(rng, n):
    out = []
    for i in range(n):
        if i % 5 == 4:
            out.append(random_brake_case(rng, symmetric=bool(i % 2)))
        else:
            out.append(random_case(rng, symmetric=bool(i % 2)))
    return out


def test_batch_equals_one_by_one():
    rng = np.random.default_rng(8)
    cs = _cases(rng, 300)
    S = np.array([c[0] for c in cs])
    G = np.array([c[1] for c in cs])
    L = np.array([c[2] for c in cs])
    b = plan_state_moves(S, G, L[:, 0], L[:, 1], L[:, 2], L[:, 3], L[:, 4])
    assert len(b) == len(cs)
    for i, (s, g, Lc) in enumerate(cs):
        p = plan_state_to_state(s, g, AxisLimits(*Lc))
        assert_ulp_close(b.duration[i], p.duration, 4, err_msg=f"move {i}")
        q = b.profile(i)
        assert q.phase_durations == p.phase_durations
        assert q.jerks == p.jerks
        assert q.n_brake_phases == p.n_brake_phases
        assert q.family == p.family
        if i % 10 == 0:
            assert verify_state_profile(q).ok


def test_batch_fixed_durations():
    rng = np.random.default_rng(9)
    cs = [random_case(rng, symmetric=True) for _ in range(100)]
    cs = [c for c in cs if c[0] != c[1]]
    lims = [AxisLimits(*c[2]) for c in cs]
    T = np.array([feasible_durations(c[0], c[1], lim).next_feasible(
        1.5 * plan_state_to_state(c[0], c[1], lim).duration) for c, lim in zip(cs, lims)])
    T[::7] = np.nan  # the minimum for these
    S = np.array([c[0] for c in cs])
    G = np.array([c[1] for c in cs])
    L = np.array([c[2] for c in cs])
    b = plan_state_moves(S, G, L[:, 0], L[:, 1], L[:, 2], durations=T)
    for i, (c, lim) in enumerate(zip(cs, lims)):
        p = plan_state_to_state(c[0], c[1], lim, duration=None if np.isnan(T[i]) else T[i])
        assert_ulp_close(b.duration[i], p.duration, 4, err_msg=f"move {i}")
        assert b.profile(i).phase_durations == p.phase_durations


def test_batch_moves_of_many_phases():
    """Brake starts with requested durations can need more phases than the table
    the batch plans into (PHASES_MIN): those moves are planned again into a wider
    one, and every move still equals the one-move planner's."""
    from trajkit.profiles.state_batch import PHASES_MIN

    rng = np.random.default_rng(12)
    cs, T = [], []
    while len(cs) < 400:
        c = random_brake_case(rng) if len(cs) % 2 else random_case(rng)
        if c[0] == c[1]:
            continue
        fd = feasible_durations(c[0], c[1], AxisLimits(*c[2]))
        cs.append(c)
        T.append(fd.next_feasible(fd.minimum * rng.uniform(1.0, 5.0)))
    S, G, L = (np.array([c[k] for c in cs]) for k in range(3))
    b = plan_state_moves(S, G, L[:, 0], L[:, 1], L[:, 2], durations=np.array(T))
    wide = np.flatnonzero(b.n_phases > PHASES_MIN)
    assert wide.size > 0 and b.phases.shape == (len(cs), int(b.n_phases.max()), 3)
    for i in range(len(cs)):
        p = plan_state_to_state(cs[i][0], cs[i][1], AxisLimits(*cs[i][2]), duration=T[i])
        assert_ulp_close(b.duration[i], p.duration, 4, err_msg=f"move {i}")
        q = b.profile(i)
        assert q.phase_durations == p.phase_durations and q.jerks == p.jerks
        assert not b.phases[i, int(b.n_phases[i]):].any()


def test_batch_errors_name_the_move():
    S = np.zeros((3, 3))
    G = np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 5.0, 0.0]])  # |vf| > v_max
    with pytest.raises(InvalidInputError, match=r"goals\[2\]"):
        plan_state_moves(S, G, 1.0, 1.0, 1.0)
    with pytest.raises(InvalidInputError, match="shape"):
        plan_state_moves(np.zeros((3, 2)), np.zeros((3, 2)), 1.0, 1.0, 1.0)
    with pytest.raises(InvalidInputError, match=r"v_max\[1\]"):
        plan_state_moves(S, S, [1.0, -1.0, 1.0], 1.0, 1.0)
    with pytest.raises(InvalidInputError, match="outside the supported range"):
        plan_state_moves(S, S, 1e-40, 1.0, 1.0)
    G[2, 1] = 0.0
    with pytest.raises(InfeasibleError, match=r"durations\[1\]"):
        plan_state_moves(S, G, 1.0, 1.0, 1.0, durations=[5.0, 0.1, 5.0])


def test_compiled_range_check_is_the_vectorised_one():
    """The compiled loop's range check (``_batch_states._in_range``) flags exactly the
    moves the vectorised check (``state_batch._check``) names, on moves with one
    value pushed to or past each bound of the supported range; the error of the
    batch names the field as the vectorised check does."""
    from trajkit.profiles import _batch_states as B
    from trajkit.profiles import _range as R
    from trajkit.profiles.state_batch import _check

    rng = np.random.default_rng(5)
    pushes = [R.MAGNITUDE_MIN * 0.5, R.MAGNITUDE_MIN, R.MAGNITUDE_MAX * 2.0, np.inf, 1e-7, 1e7,
              R.POSITION_MAX * 1.5, -R.POSITION_MAX, 2e6, -3e6, 1e-101, 0.0]
    rows, Ts = [], []
    for k in range(600):
        s, g, L = random_case(rng, symmetric=bool(k % 2))
        row = np.array([*s, *g, *L])
        col = int(rng.integers(12))
        if col < 11:
            val = float(rng.choice(pushes))
            if col >= 6 and not val > 0.0:
                val = 1.0  # (limits <= 0 are refused before the range check)
            if col in (1, 2, 4, 5) and abs(val) > 1.0:
                val = float(np.sign(val) * rng.choice([0.999e6, 1.001e6, 2e6]) * row[6 if col in (1, 4) else 7])
            if col == 3:
                val = row[0] + float(rng.choice([1e-101, 1e-99, -1e-120, 0.0, R.POSITION_MAX * 2]))
            row[col] = val
        rows.append(row)
        Ts.append(float(rng.choice([np.nan, 1.0, R.DURATION_MAX * 2.0])) if col == 11 else np.nan)
    inp = np.array(rows)
    T = np.array(Ts)
    flagged = 0
    for i in range(len(inp)):
        r = inp[i:i + 1]
        try:
            _check(r[:, 0:3], r[:, 3:6], r[:, 6], r[:, 7], r[:, 8], r[:, 9], r[:, 10],
                   None if np.isnan(T[i]) else T[i:i + 1])
            ok = True
        except InvalidInputError:
            ok = False
        assert bool(B._in_range(*inp[i], T[i])) == ok, (i, inp[i].tolist(), T[i])
        flagged += not ok
    assert 100 < flagged < len(inp) - 100, flagged
    # the batch error names the field of the vectorised check
    S = np.zeros((3, 3))
    G = np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    with pytest.raises(InvalidInputError, match=r"goals position\[1\]"):
        plan_state_moves(S, np.where(np.arange(3)[:, None] == 1, [[2e15, 0.0, 0.0]], G), 1.0, 1.0, 1.0)
    with pytest.raises(InvalidInputError, match=r"durations\[2\]"):
        plan_state_moves(S, G, 1.0, 1.0, 1.0, durations=[np.nan, np.nan, 1e51])


def test_compiled_sync_equals_the_python_path(monkeypatch):
    rng = np.random.default_rng(10)
    trajs = []
    for _ in range(40):
        cs = [random_case(rng, symmetric=True) for _ in range(4)]
        S = [c[0] for c in cs]
        G = [c[1] for c in cs]
        lims = [AxisLimits(*c[2]) for c in cs]
        trajs.append((S, G, lims, plan_ptp_states(S, G, lims)))
    monkeypatch.setattr(sync_states, "_sync_time_compiled", lambda *a: None)
    for S, G, lims, fast in trajs:
        slow = plan_ptp_states(S, G, lims)
        assert_ulp_close(fast.duration, slow.duration, 4)
        assert verify_trajectory(fast).ok
        for a, b in zip(fast.axes, slow.axes):
            assert_ulp_close(a.duration, b.duration, 4)
            assert a.goal_state == b.goal_state


def test_compiled_sync_requested_duration_and_errors():
    lim = AxisLimits(1.0, 1.0, 1.0)
    S = [(0.0, 0.5, 0.0), (0.0, 0.0, 0.0)]
    G = [(0.5, 0.5, 0.0), (0.01, 0.0, 0.0)]
    t = plan_ptp_states(S, G, lim)
    assert verify_trajectory(t).ok
    t2 = plan_ptp_states(S, G, lim, duration=t.duration * 2 + 3.0)
    assert t2.duration == pytest.approx(t.duration * 2 + 3.0, rel=1e-12)
    with pytest.raises(InfeasibleError, match="below the minimum"):
        plan_ptp_states(S, G, lim, duration=0.5 * t.duration)
    # axis 0 has a blocked interval (1.078 s, 3.350 s): a duration inside it is refused
    with pytest.raises(InfeasibleError, match="blocked interval"):
        plan_ptp_states(S, G, lim, duration=2.0)


def test_sync_takes_the_end_of_a_blocked_interval_of_separate_legs(caplog):
    """Separate legs: axis 1 cannot take any duration in (6.879, 13.867) s (to
    lose its excess travel it must reverse twice, each time waiting for its
    weak decel leg; proven in test_state_step2.py), and the minimum 10 s of
    axis 0 lies in that interval. The compiled synchronisation finds it when
    the axis' step 2 fails there, and the common duration is the interval's
    end, without the search in 1 % steps of a step-2 failure."""
    S = [(0.0, 0.0, 0.0), (-0.37060783406439646, -0.540875349469885, 0.04914176271392083)]
    G = [(8.0, 0.0, 0.0), (-3.220893541416452, -0.8468465473234723, -0.06935750650130823)]
    lims = [AxisLimits(1.0, 1.0, 1.0),
            AxisLimits(0.8468465473234723, 0.3302788257239121, 19.796658314532166,
                       0.06935750650130823, 11.102447246912389)]
    (lo, hi), = feasible_durations(S[1], G[1], lims[1]).blocked
    assert lo == pytest.approx(6.8787155, abs=1e-6) and hi == pytest.approx(13.8674460, abs=1e-6)
    with caplog.at_level("WARNING", logger="trajkit.sync"):
        t = plan_ptp_states(S, G, lims)
    assert verify_trajectory(t).ok
    assert feasible_durations(S[0], G[0], lims[0]).minimum == pytest.approx(10.0)
    assert t.duration == pytest.approx(hi, rel=1e-12)
    assert "step 2 found no profile" not in caplog.text
    # a requested duration inside it is refused with the interval
    with pytest.raises(InfeasibleError, match="blocked interval"):
        plan_ptp_states(S, G, lims, duration=12.0)


def test_phase_sums_are_correctly_rounded():
    """The compiled loops' durations are ``math.fsum`` of the phase table (the
    correctly rounded sum), on sums that cancel, tie and span 40 decades."""
    import math

    from trajkit.profiles import _batch_states as B
    from trajkit.profiles import _kernel as K

    rng = np.random.default_rng(5)
    ws = K.workspace()
    tricky = [1.0, 2.0**-53, 2.0**-54, 2.0**-106, -(2.0**-106), 3.0, 1e16, -1e16, 0.1]
    for trial in range(20000):
        n = int(rng.integers(0, K.NPH + 1))
        kind = trial % 3
        if kind == 0:
            x = rng.random(n) * 10.0 ** rng.uniform(-6, 3, n)
        elif kind == 1:
            x = rng.standard_normal(n) * 10.0 ** rng.integers(-20, 20, n)
        else:
            x = rng.choice(tricky, n)
        ws[K.OUT_PH:K.OUT_PH + 3 * n:3] = x
        want = math.fsum(x.tolist())
        # the enclosure's fast answer with its fallback, and the fallback alone
        assert B.exact_sum(ws, K.OUT_PH, 3, n, K.SUM_SCRATCH) == want, x.tolist()
        assert B.sum_partials(ws, K.OUT_PH, 3, n, K.SUM_SCRATCH) == want, x.tolist()
    b = plan_state_moves([(0.0, 0.3, -1.0), (2.0, 0.0, 0.0)], [(1.0, 0.0, 0.0), (-1.0, 0.2, 0.1)],
                         1.0, 2.0, 7.0)
    for i in range(2):
        assert b.duration[i] == math.fsum(b.phases[i, :b.n_phases[i], 0].tolist())
