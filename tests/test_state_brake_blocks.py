"""Blocked durations of a start outside the limits.

A start outside the limits has several brake candidates (``_kernel._brake_cand``),
each ending inside the limits after its own duration ``tb``; a duration ``T`` is
feasible when the move from some candidate's end has a profile of ``T - tb``.
The blocked intervals are therefore those that no candidate reaches:

* every duration the planner refuses as blocked is refused by every brake
  candidate on its own (below the minimum from its end, or inside one of that
  move's blocked intervals, computed by the planner for a start inside the
  limits);
* every profile it returns keeps the limits (independent exact check), and its
  duration lies outside the reported intervals;
* the intervals' ends are feasible durations.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import sweep_size
from state_reference import exact_check, goal_error, random_brake_case

from trajkit import AxisLimits
from trajkit.errors import InfeasibleError
from trajkit.profiles import _kernel as K
from trajkit.profiles.state import BlockedDurationError, feasible_durations, plan_state_to_state


def _check(prof, lim):
    why = exact_check(prof, lim)
    assert why is None, why
    assert goal_error(prof) < 1e-9


def _brake_ends(s, g, L):
    """``(tb, end state)`` of every brake candidate of the start ``s``."""
    V, A1, J1, A2, J2 = L
    lim = np.array([V, A1, 1.0 / J1, A2, 1.0 / J2])
    st0 = np.array([0.0, s[1], s[2], g[0] - s[0], g[1], g[2], math.nan])
    out = []
    for c in range(K.NCAND):
        brk, bbuf, s1 = np.zeros((16, 3)), np.zeros(96), np.zeros(7)
        nb, tb = K._brake_cand(c, False, st0, lim, brk, bbuf, s1)
        if nb >= 0:
            out.append((tb, (s[0] + s1[0], s1[1], s1[2])))
    return out


def _no_brake_reaches(s, g, L, T):
    """True when no brake candidate's end has a profile of ``T - tb`` to ``g``
    (by the planner's minimum and blocked intervals of that move)."""
    lim = AxisLimits(*L)
    for tb, B in _brake_ends(s, g, L):
        try:
            fd = feasible_durations(B, g, lim)
        except InfeasibleError:
            continue
        rest = T - tb
        if rest >= fd.minimum * (1.0 + 1e-9) and not any(lo < rest < hi for lo, hi in fd.blocked):
            return False
    return True


#: Requests the planner once answered with "no profile found" (from
#: ``benchmarks/state_step2_study.py --cases 4000 --seed 5 --brake``): start,
#: goal, limits, durations and the blocked interval they lie in.
BLOCKED = [
    ((4.5688687133993815, -3.1915784745814877, -4.162299402522049),
     (-11.599663965862284, -2.935899612164932, 0.0),
     (4.800217925845856, 1.3757168076118405, 5.012851379801606, 2.2064132852652594, 1.3565407809313796),
     (4.878576311412535, 7.066002095935903, 5.0992209748239), (4.761825241395899, 7.371437979439192)),
    ((-0.3661566331378077, 0.7147550898768374, -0.2901582703606616),
     (0.2769275572374628, 0.218466287436769, 0.0),
     (0.41663869653844987, 0.7948459629695132, 30.124335773819272, 1.1081293680842332, 75.86321833350532),
     (1.4231706540187004,), (1.2259289194780694, 1.4517383258169345)),
    ((1.4696823786039768, -5.506829873407579, -0.2065584966543597),
     (-46.61888400703526, -1.5935233146861378, 0.0),
     (2.8569399834083633, 1.892350831523668, 0.3036082908537631, 0.38421294974467296, 0.6488958323626277),
     (19.128148756540465, 15.725228871161319), (15.471048494009471, 22.949202170679232)),
]


@pytest.mark.parametrize("s, g, L, durations, interval", BLOCKED)
def test_durations_no_brake_reaches_are_blocked(s, g, L, durations, interval):
    """The interval is reported, every duration inside it is refused as blocked
    (not as "no profile found") and is refused by every brake on its own, and
    durations just outside it are planned."""
    lim = AxisLimits(*L)
    fd = feasible_durations(s, g, lim)
    assert any(lo == pytest.approx(interval[0], rel=1e-9) and hi == pytest.approx(interval[1], rel=1e-9)
               for lo, hi in fd.blocked), fd.blocked
    for T in durations:
        with pytest.raises(BlockedDurationError) as err:
            plan_state_to_state(s, g, lim, duration=T)
        assert err.value.interval == pytest.approx(interval, rel=1e-9)
        assert _no_brake_reaches(s, g, L, T)
    lo, hi = interval
    for T in (lo * (1.0 - 1e-6), hi * (1.0 + 1e-6)):
        q = plan_state_to_state(s, g, lim, duration=T)
        assert q.duration == pytest.approx(T, rel=1e-12)
        _check(q, lim)


#: Symmetric limits: durations that were reported blocked though another brake
#: than the minimum-time one reaches them.
REACHED = [
    ((0.16884033001057386, 0.23161372345650239, 1.347270729808743), (0.2812185539526854, 0.21388162679833056, 0.0),
     (0.21677181271477924, 4.459408699503627, 13.695875607257419, 4.459408699503627, 13.695875607257419),
     (0.6, 0.7, 0.8)),
    ((0.10790479615951712, -0.49472223927724984, 0.10168250141191774), (-0.5577760355449599, -0.20497706305240446, 0.0),
     (0.2643558346720603, 0.24295658555318286, 0.5597972143981378, 0.24295658555318286, 0.5597972143981378),
     (2.4, 4.0, 5.0)),
]


@pytest.mark.parametrize("s, g, L, durations", REACHED)
def test_durations_another_brake_reaches_are_planned(s, g, L, durations):
    lim = AxisLimits(*L)
    fd = feasible_durations(s, g, lim)
    for T in durations:
        assert not any(lo < T < hi for lo, hi in fd.blocked)
        q = plan_state_to_state(s, g, lim, duration=T)
        assert q.duration == pytest.approx(T, rel=1e-12)
        assert q.n_brake_phases > 0
        _check(q, lim)


N_BRAKE = sweep_size(300)


@pytest.mark.parametrize("symmetric", [True, False])
def test_brake_starts_blocked_or_planned(symmetric):
    """Random starts outside the limits, four durations each in [T_min, 3 T_min]:
    a profile within the limits outside every reported interval, or a blocked
    duration that no brake reaches; never "no profile found" with equal legs."""
    rng = np.random.default_rng(4242 if symmetric else 4243)
    counts = {"profile": 0, "blocked": 0, "none": 0}
    for _ in range(N_BRAKE):
        s, g, L = random_brake_case(rng, symmetric=symmetric)
        lim = AxisLimits(*L)
        try:
            fd = feasible_durations(s, g, lim)
        except InfeasibleError:
            continue
        for f in rng.uniform(1.0, 3.0, 4):
            T = fd.minimum * f
            inside = any(lo < T < hi for lo, hi in fd.blocked)
            try:
                q = plan_state_to_state(s, g, lim, duration=T)
            except BlockedDurationError:
                assert inside
                assert _no_brake_reaches(s, g, L, T), (s, g, L, T)
                counts["blocked"] += 1
                continue
            except InfeasibleError:
                assert not symmetric, (s, g, L, T)
                counts["none"] += 1
                continue
            assert not inside, (s, g, L, T, fd.blocked)
            _check(q, lim)
            counts["profile"] += 1
    assert counts["profile"] >= 3 * N_BRAKE and counts["none"] <= 0.002 * 4 * N_BRAKE, counts
