"""LIN: straight tool path at the programmed speed, slerped orientation, IK at every sample."""

from __future__ import annotations

import math

import numpy as np
import pytest

from trajkit.kinematics.arm6 import default_arm6
from trajkit.kinematics.base import Pose, rot_z
from trajkit.kinematics.scara import default_scara
from trajkit.robot import CartesianTarget, JointTarget, Lin, Ptp, Wait, run_motions
from trajkit.robot._rotations import quat_from_matrix, rotation_angle

#: FK of every sample lies on the line to this fraction of the robot's reach.
LINE_TOL = 1e-6
#: Tool speed in cruise within this fraction of the programmed speed.
SPEED_RTOL = 1e-3
#: Slack on limit checks of the analytic (chain-rule) joint rates.
LIMIT_SLACK = 1e-9


@pytest.fixture(scope="module")
def arm():
    return default_arm6()


def _dist_to_segment(p, a, b):
    d = b - a
    u = np.clip(((p - a) @ d) / (d @ d), 0.0, 1.0)
    return np.linalg.norm(p - (a + u[:, None] * d), axis=1), u


def _check_limits(robot, smp):
    for j, lim in enumerate(robot.limits):
        assert np.abs(smp.qd[:, j]).max() <= lim.v_max * (1 + LIMIT_SLACK), robot.joint_names[j]
        assert np.abs(smp.qdd[:, j]).max() <= min(lim.a_max, lim.a_max_decel) * (1 + LIMIT_SLACK)


@pytest.fixture(scope="module")
def lin_case(arm):
    q0 = np.radians([10.0, 25.0, 5.0, 20.0, 50.0, -30.0])
    p0 = arm.fk(q0)
    goal = Pose(p0.position + np.array([0.05, 0.30, -0.12]), rot_z(0.4) @ p0.rotation)
    run = run_motions(arm, [Lin(CartesianTarget(goal, name="g"), 0.2, label="L1")], q0)
    smp = run.sample(run.times(0.002))
    return arm, q0, p0, goal, run, smp


def test_lin_samples_on_line_after_fk(lin_case):
    arm, q0, p0, goal, run, smp = lin_case
    fk = np.array([arm.fk(q).position for q in smp.q])
    d, _ = _dist_to_segment(fk, p0.position, goal.position)
    assert d.max() < LINE_TOL * arm.length_scale
    # exact ends
    assert np.allclose(smp.q[0], q0, atol=1e-12)
    dp, da = arm.fk(smp.q[-1]).distance(goal)
    assert dp < 1e-12 and da < 1e-9


def test_lin_orientation_is_slerp(lin_case):
    arm, q0, p0, goal, run, smp = lin_case
    qa, qb = quat_from_matrix(p0.rotation), quat_from_matrix(goal.rotation)
    total = rotation_angle(qa, qb)
    fk = [arm.fk(q) for q in smp.q]
    _, u = _dist_to_segment(np.array([f.position for f in fk]), p0.position, goal.position)
    for f, uu in zip(fk[::10], u[::10]):
        qf = quat_from_matrix(f.rotation)
        # angle from the start grows linearly with the travelled fraction, on the geodesic
        assert rotation_angle(qa, qf) == pytest.approx(uu * total, abs=1e-8)
        assert rotation_angle(qf, qb) == pytest.approx((1 - uu) * total, abs=1e-8)


def test_lin_tool_speed_in_cruise(lin_case):
    arm, q0, p0, goal, run, smp = lin_case
    cruise = np.nonzero(np.isclose(smp.tool_speed, 0.2, rtol=0, atol=1e-12))[0]
    assert cruise.size > 100  # a real cruise phase exists
    # speed measured independently: FK of the sampled joints, central differences
    fk = np.array([arm.fk(q).position for q in smp.q])
    inner = cruise[(cruise > 0) & (cruise < smp.t.size - 1)]
    v = np.linalg.norm(fk[inner + 1] - fk[inner - 1], axis=1) / (smp.t[inner + 1] - smp.t[inner - 1])
    assert np.abs(v / 0.2 - 1).max() < SPEED_RTOL
    assert run.slowdowns == []


def test_lin_joint_limits_and_continuity(lin_case):
    arm, q0, p0, goal, run, smp = lin_case
    _check_limits(arm, smp)
    # the joint positions (from IK) agree with the integrated rates: finite differences
    dt = np.diff(smp.t)
    fd = np.diff(smp.q, axis=0) / dt[:, None]
    mid = 0.5 * (smp.qd[1:] + smp.qd[:-1])
    vmax = np.array([lim.v_max for lim in arm.limits])
    assert np.abs(fd - mid).max() < 1e-3 * vmax.max()
    assert (np.abs(fd) <= vmax * (1 + 1e-3)).all()


def test_scara_lin_and_wait():
    sc = default_scara()
    q0 = np.array([0.3, 1.2, 0.05, 0.0])
    p0 = sc.fk(q0)
    goal = Pose(p0.position + np.array([0.15, -0.1, -0.05]), p0.rotation)
    run = run_motions(sc, [Lin(CartesianTarget(goal), 0.5), Wait(0.25), Ptp(JointTarget(q0))], q0)
    smp = run.sample(run.times(0.002))
    seg = [sg.kind for sg in run.segments]
    assert seg == ["CP", "WAIT", "PTP"]
    fk = np.array([sc.fk(q).position for q in smp.q[smp.t <= run.segments[0].duration]])
    d, _ = _dist_to_segment(fk, p0.position, goal.position)
    assert d.max() < LINE_TOL * sc.length_scale
    w = (smp.t > run.segments[1].t0) & (smp.t < run.segments[2].t0)
    assert np.ptp(smp.q[w], axis=0).max() == 0.0  # WAIT holds still
    assert run.segments[1].duration == 0.25
    assert np.allclose(smp.q[-1], q0, atol=1e-12)
    _check_limits(sc, smp)


def test_ptp_to_cartesian_target_pins_configuration(arm):
    q0 = np.radians([0.0, 20.0, 10.0, 0.0, 60.0, 0.0])
    pose = arm.fk(np.radians([40.0, 10.0, 30.0, 10.0, -50.0, 20.0]))
    run = run_motions(arm, [Ptp(CartesianTarget(pose, "front-up-flip"), 50.0)], q0)
    q_end = run.segments[-1].q_end
    assert arm.config_of(q_end) == "front-up-flip"
    dp, da = arm.fk(q_end).distance(pose)
    assert dp < 1e-12 and da < 1e-9
    smp = run.sample(run.times(0.004))
    vmax = np.array([lim.v_max for lim in arm.limits])
    assert (np.abs(smp.qd) <= 0.5 * vmax * (1 + 1e-9)).all()  # 50 % override


def test_zero_length_lin_is_skipped(arm):
    q0 = np.radians([0.0, 20.0, 10.0, 0.0, 60.0, 0.0])
    run = run_motions(arm, [Lin(JointTarget(q0), 0.1)], q0)
    assert run.duration == 0.0 and run.segments == []
    assert math.isfinite(run.duration)


def test_rotation_angle_is_accurate_at_small_angles():
    """The angle between two orientations a tiny rotation apart, to a few 1e-16 rad
    (an arccos of the quaternions' dot product resolves only about 1e-8 rad)."""
    rng = np.random.default_rng(3)
    for _ in range(20):
        w, x, y, z = rng.normal(size=4)
        n = math.sqrt(w * w + x * x + y * y + z * z)
        q = np.array([w, x, y, z]) / n
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        for angle in (1e-10, 1e-7, 1e-4, 0.5, 3.0):
            c, s = math.cos(angle / 2), math.sin(angle / 2)
            r = np.concatenate([[c], s * axis])
            w0, x0, y0, z0 = q
            w1, x1, y1, z1 = r
            q1 = np.array([w0 * w1 - x0 * x1 - y0 * y1 - z0 * z1,
                           w0 * x1 + x0 * w1 + y0 * z1 - z0 * y1,
                           w0 * y1 - x0 * z1 + y0 * w1 + z0 * x1,
                           w0 * z1 + x0 * y1 - y0 * x1 + z0 * w1])
            for a, b in ((q, q1), (q1, q), (q, -q1)):
                assert rotation_angle(a, b) == pytest.approx(angle, rel=1e-6, abs=4e-16)
