"""``trajkit.verify``: it passes correct profiles and catches every kind of fault.

Faulty profiles are built by hand with the public ``Profile`` constructor, so
each test knows exactly which check must fire, the value and the time.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from trajkit import (
    AxisLimits,
    InvalidInputError,
    Profile,
    TrajkitError,
    plan_move,
    plan_ptp,
)
from trajkit.trajectory import Trajectory
from trajkit.verify import (
    QUANTITIES,
    VerificationError,
    verify_profile,
    verify_trajectory,
)

SYM = AxisLimits(1.0, 2.0, 10.0, name="B")
EXACT = 1e-12


def _rebuild(p, limits=None, **changes):
    """Copy of ``p`` with some fields replaced."""
    f = dict(start=p.start, goal=p.goal, duration=p.duration, min_duration=p.min_duration,
             phase_durations=p.phase_durations, jerks=p.jerks, peak_velocity=p.peak_velocity,
             peak_acceleration=p.peak_acceleration, peak_deceleration=p.peak_deceleration,
             limits=p.limits if limits is None else limits)
    f.update(changes)
    return Profile(**f)


def _quantities(rep):
    return {v.quantity for v in rep.violations}


def test_correct_profile_reaches_every_limit_exactly():
    p = plan_move(0.0, 5.0, AxisLimits(1.0, 2.0, 10.0, 3.0, 20.0))
    rep = verify_profile(p)
    assert rep.ok and rep.violations == ()
    assert set(rep.ratios) == set(QUANTITIES)
    for q in ("velocity", "acceleration", "deceleration", "jerk", "jerk_decel"):
        assert rep.ratios[q] == pytest.approx(1.0, rel=1e-12), q
    assert rep.ratios["position"] == 0.0
    assert rep.goal_error <= 1e-15 and rep.duration_error <= 1e-15
    assert rep.raise_if_failed() is rep


def test_velocity_violation_names_axis_value_limit():
    p = plan_move(0.0, 5.0, SYM)
    bad = _rebuild(p, limits=AxisLimits(0.9, 2.0, 10.0, name="B"))
    rep = verify_profile(bad)
    assert not rep.ok and "velocity" in _quantities(rep)
    assert rep.ratios["velocity"] == pytest.approx(1.0 / 0.9, rel=EXACT)
    with pytest.raises(VerificationError,
                       match=r"^velocity 1\.0 of axis B exceeds the limit 0\.9 at t = ") as ei:
        rep.raise_if_failed()
    assert isinstance(ei.value, TrajkitError)
    assert ei.value.violations == rep.violations


@pytest.mark.parametrize("goal", [5.0, -5.0])
def test_asymmetric_semantics_accel_while_speeding_up(goal):
    """A decel leg harder than the accel leg is fine, unless the limits are swapped."""
    lim = AxisLimits(1.0, 1.0, 10.0, a_max_decel=3.0, j_max_decel=20.0, name=0)
    p = plan_move(0.0, goal, lim)
    assert verify_profile(p).ok
    swapped = AxisLimits(1.0, 3.0, 20.0, a_max_decel=1.0, j_max_decel=10.0, name=0)
    rep = verify_profile(_rebuild(p, limits=swapped))
    assert _quantities(rep) >= {"deceleration", "jerk_decel"}
    assert "acceleration" not in _quantities(rep) and "jerk" not in _quantities(rep)
    assert rep.ratios["deceleration"] == pytest.approx(3.0, rel=EXACT)
    assert rep.ratios["jerk_decel"] == pytest.approx(2.0, rel=EXACT)


def test_velocity_extremum_inside_a_phase_found_analytically():
    """Jerk-down phase too long: a crosses 0 inside it, v peaks there (0.4 at t = 0.4)."""
    lim = AxisLimits(0.38, 2.0, 10.0, name="X")
    p = Profile(0.0, 1.0, 0.5, 0.5, (0.2, 0.0, 0.3, 0.0, 0.0, 0.0, 0.0),
                (10.0, 0.0, -10.0, 0.0, 0.0, 0.0, 0.0), 0.4, 2.0, 1.0, lim)
    # the boundaries alone only show v = 0.2 and 0.35 (< 0.38)
    bs = p.boundary_states()
    assert np.all(np.abs(bs[:, 1]) < 0.38)
    rep = verify_profile(p, n_samples=0)
    v = next(x for x in rep.violations if x.quantity == "velocity")
    assert v.value == pytest.approx(0.4, rel=EXACT)
    assert v.time == pytest.approx(0.4, rel=EXACT)
    assert rep.ratios["velocity"] == pytest.approx(0.4 / 0.38, rel=EXACT)
    # past a = 0 the speed shrinks: the -1 of acceleration is a deceleration
    assert rep.ratios["deceleration"] == pytest.approx(1.0 / 2.0, rel=EXACT)


def test_position_overshoot_inside_a_phase_found_analytically():
    """Const-decel phase too long: v crosses 0 inside it, p peaks there."""
    p = plan_move(0.0, 5.0, SYM)
    d = list(p.phase_durations)
    d[5] += 0.15  # v: 0.8 -> 0.8 - 2 * 0.45 = -0.1, zero after 0.4 s
    # analytic overshoot: p at the start of phase 5 plus 0.8 * 0.4 - 2 * 0.4^2 / 2
    p5 = p.boundary_states()[5, 0]
    peak = p5 + 0.8 * 0.4 - 0.16                 # 4.99667 at the v = 0 root
    end5 = p5 + 0.8 * 0.45 - 0.45 ** 2           # 4.99417 at the phase end
    pmax = 4.995
    assert end5 < pmax < peak
    bad = _rebuild(p, limits=AxisLimits(1.0, 2.0, 10.0, position_max=pmax, name="B"),
                   phase_durations=tuple(d), duration=sum(d))
    assert np.all(bad.boundary_states()[:7, 0] < pmax)  # no phase start shows it
    rep = verify_profile(bad, n_samples=0)
    v = next(x for x in rep.violations if x.quantity == "position")
    assert v.value == pytest.approx(peak, rel=EXACT)
    assert v.limit == pmax
    assert v.time == pytest.approx(sum(d[:5]) + 0.4, rel=EXACT)
    assert "goal" in _quantities(rep)


def test_acceleration_jump_allowed_only_with_infinite_jerk():
    trap_lim = AxisLimits(1.0, 2.0, math.inf)
    p = plan_move(0.0, 5.0, trap_lim)
    assert verify_profile(p).ok
    rep = verify_profile(_rebuild(p, limits=AxisLimits(1.0, 2.0, 10.0)))
    assert "continuity_acceleration" in _quantities(rep)
    # accel leg jerk-free, decel leg jerk-limited: only the decel jumps count
    p2 = plan_move(0.0, 5.0, AxisLimits(1.0, 2.0, math.inf, 2.0, 10.0))
    assert verify_profile(p2).ok
    rep = verify_profile(_rebuild(p, limits=AxisLimits(1.0, 2.0, math.inf, 2.0, 10.0)))
    v = next(x for x in rep.violations if x.quantity == "continuity_acceleration")
    assert v.time == pytest.approx(p.phase_times[5], rel=EXACT)


def test_goal_duration_and_end_velocity_faults():
    p = plan_move(0.0, 5.0, SYM)
    assert "goal" in _quantities(verify_profile(_rebuild(p, goal=5.0 + 1e-7)))
    assert "duration" in _quantities(verify_profile(_rebuild(p, duration=p.duration + 1e-6)))
    d = list(p.phase_durations)
    d[1] += 1e-6  # gains velocity the decel leg does not remove
    rep = verify_profile(_rebuild(p, phase_durations=tuple(d), duration=sum(d)))
    assert {"end_velocity", "goal"} <= _quantities(rep)
    rep = verify_profile(p, expected_duration=p.duration * (1 + 1e-6))
    assert "expected_duration" in _quantities(rep)


def test_wrong_jerk_in_declared_leg():
    """Phases 4-6 are the decel leg: a jerk above j_max_decel fails even at rest."""
    lim = AxisLimits(1.0, 2.0, 10.0, j_max_decel=5.0)
    p = plan_move(0.0, 5.0, SYM)
    rep = verify_profile(_rebuild(p, limits=lim))
    v = next(x for x in rep.violations if x.quantity == "jerk_decel")
    assert abs(v.value) == 10.0 and v.limit == 5.0


def test_sample_inconsistent_with_phases_is_caught():
    class Shifted(Profile):
        __slots__ = ()

        def sample(self, t):
            s = super().sample(t)
            return type(s)(s.position + 1e-6, s.velocity, s.acceleration, s.jerk)

    p = plan_move(0.0, 5.0, SYM)
    bad = Shifted(p.start, p.goal, p.duration, p.min_duration, p.phase_durations, p.jerks,
                  p.peak_velocity, p.peak_acceleration, p.peak_deceleration, p.limits)
    assert "sample_position" in _quantities(verify_profile(bad))
    assert verify_profile(bad, n_samples=0).ok  # only the samples are wrong


def test_far_from_origin_tiny_move_is_fine():
    """Round-off of |start| is not charged to a tiny distance."""
    p = plan_move(1e4, 1e4 + 1e-6, SYM)
    rep = verify_profile(p)
    assert rep.ok, rep.violations


def test_zero_move():
    p = plan_move(2.0, 2.0, SYM, duration=1.0)
    rep = verify_profile(p)
    assert rep.ok and rep.worst_ratio == 0.0


@pytest.mark.parametrize("kw,match", [
    (dict(rtol=-1.0), r"rtol must be finite and >= 0, got -1\.0"),
    (dict(rtol=math.nan), r"rtol must be finite and >= 0, got nan"),
    (dict(n_samples=1), r"n_samples must be 0 or >= 2, got 1"),
])
def test_bad_arguments(kw, match):
    with pytest.raises(InvalidInputError, match=match):
        verify_profile(plan_move(0.0, 1.0, SYM), **kw)


# ------------------------------------------------------------ trajectories
def test_trajectory_report_collects_axes():
    tr = plan_ptp([0.0, 0.0], [1.0, -3.0], [AxisLimits(1, 2, 10), AxisLimits(2, 1, 5, 3, 8)])
    rep = verify_trajectory(tr)
    assert rep.ok and len(rep.axes) == 2 and rep.sync_error == 0.0
    assert rep.ratios["velocity"] == max(r.ratios["velocity"] for r in rep.axes)
    assert rep.raise_if_failed() is rep


def test_trajectory_unsynchronised_axes_fail_time_sync():
    a = plan_move(0.0, 1.0, SYM)
    b = plan_move(0.0, 3.0, SYM.with_name("C"))
    rep = verify_trajectory(Trajectory([a, b], sync="time"))
    assert [v.quantity for v in rep.violations] == ["sync_duration"]
    assert rep.violations[0].axis == "B"
    assert verify_trajectory(Trajectory([a, b], sync="none")).ok


def test_trajectory_off_the_line_fails_phase_sync():
    tr = plan_ptp([0.0, 0.0], [1.0, 3.0], [SYM, AxisLimits(1.0, 2.0, 10.0, name="C")],
                  sync="time")
    rep = verify_trajectory(Trajectory(tr.axes, sync="phase"))
    assert "joint_space_line" in {v.quantity for v in rep.violations}
    assert rep.line_error > 1e-3
    with pytest.raises(VerificationError, match=r"^joint_space_line"):
        rep.raise_if_failed()


def test_reports_to_dict_are_json():
    import json

    tr = plan_ptp([0.0, 0.0], [1.0, 3.0], [SYM, AxisLimits(1.0, 2.0, 10.0, name="C")])
    doc = json.loads(json.dumps(verify_trajectory(tr).to_dict()))
    assert doc["ok"] is True and [a["axis"] for a in doc["axes"]] == ["B", "C"]
    bad = _rebuild(plan_move(0.0, 5.0, SYM), limits=AxisLimits(0.9, 2.0, 10.0, name="B"))
    doc = json.loads(json.dumps(verify_profile(bad).to_dict()))
    assert doc["ok"] is False
    assert doc["violations"][0]["quantity"] == "velocity"
    assert doc["violations"][0]["limit"] == 0.9
