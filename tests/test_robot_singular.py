"""Near a singularity the feed slows down and reports it; impassable or unreachable paths raise."""

from __future__ import annotations

import numpy as np
import pytest

from trajkit.errors import InvalidInputError, UnreachableError
from trajkit.kinematics.arm6 import default_arm6
from trajkit.kinematics.base import Pose
from trajkit.kinematics.scara import default_scara
from trajkit.robot import CartesianTarget, Circ, JointTarget, Lin, Ptp, run_motions

LIMIT_SLACK = 1e-9


@pytest.fixture(scope="module")
def arm():
    return default_arm6()


@pytest.fixture(scope="module")
def wrist_singular(arm):
    q = np.array([0.0, 0.3, 0.2, 0.0, 0.0, 0.0])  # q5 = 0: wrist singular
    return arm.fk(q)


def _line(arm, p_sing, offset):
    a = Pose(p_sing.position + np.array([0.0, offset, -0.08]), p_sing.rotation)
    b = Pose(p_sing.position + np.array([0.0, offset, 0.08]), p_sing.rotation)
    return arm.ik(a, "front-up-noflip"), b


def test_near_wrist_singularity_slows_down_and_reports(arm, wrist_singular):
    q0, goal = _line(arm, wrist_singular, 0.004)
    run = run_motions(arm, [Lin(CartesianTarget(goal), 0.25, label="LIN near")], q0)
    assert run.slowdowns, "the feed must slow down near the wrist singularity"
    sd = min(run.slowdowns, key=lambda x: x.speed)
    assert sd.label == "LIN near"
    assert "joint A4" in sd.reason or "joint A6" in sd.reason
    assert sd.speed < 0.25 * 0.5
    # the slow stretch is around the singular point
    mid = 0.5 * (sd.start_xyz + sd.end_xyz)
    assert np.linalg.norm(mid - wrist_singular.position) < 0.03
    smp = run.sample(run.times(0.002))
    for j, lim in enumerate(arm.limits):
        assert np.abs(smp.qd[:, j]).max() <= lim.v_max * (1 + LIMIT_SLACK)
        assert np.abs(smp.qdd[:, j]).max() <= lim.a_max * (1 + LIMIT_SLACK)
    # independent check of the joint speed: finite differences of the IK samples
    fd = np.abs(np.diff(smp.q, axis=0) / np.diff(smp.t)[:, None])
    assert (fd <= np.array([lim.v_max for lim in arm.limits]) * 1.01).all()
    # the slow-down is smooth: no speed jump between samples beyond the path jerk bound
    dv = np.abs(np.diff(smp.tool_speed))
    assert dv.max() <= arm.cartesian_accel * 0.002 * (1 + 1e-6)
    summary = run.summary(smp)
    assert summary["slowdowns"] and summary["slowdowns"][0]["instruction"] == "LIN near"


def test_through_wrist_singularity_is_impassable(arm, wrist_singular):
    q0, goal = _line(arm, wrist_singular, 0.0)
    with pytest.raises(UnreachableError,
                       match=r"LIN thru: the path passes through a singularity at \(615\.033, 0\.000, "
                             r"625\.681\) mm .*joint A[46] would jump by 180\.0 deg"):
        run_motions(arm, [Lin(CartesianTarget(goal), 0.25, label="LIN thru")], q0)


def test_target_outside_workspace_names_instruction_and_point(arm):
    q0 = np.radians([0.0, 20.0, 10.0, 0.0, 60.0, 0.0])
    far = Pose.from_xyz_abc([1.5, 0.0, 0.5], [0.0, 0.0, np.pi])
    with pytest.raises(UnreachableError, match=r"LIN far: point \(\d+\.\d+, .*\) mm .*unreachable"):
        run_motions(arm, [Lin(CartesianTarget(far, name="far"), 0.2, label="LIN far")], q0)
    with pytest.raises(UnreachableError, match=r"PTP far: target far: pose at \(1500\.000, 0\.000, 500\.000\) mm"):
        run_motions(arm, [Ptp(CartesianTarget(far, name="far"), label="PTP far")], q0)


def test_path_through_scara_hole_is_unreachable():
    sc = default_scara()
    # inner radius of the SCARA workspace is a1 - a2 = 50 mm: a line through (30, 0) leaves it
    a = Pose.from_xyz_abc([0.03, 0.25, 0.1])
    b = Pose.from_xyz_abc([0.03, -0.25, 0.1])
    q0 = sc.ik(a, "lefty")
    with pytest.raises(UnreachableError, match=r"L: point \(30\.000, .*\) mm of the path is unreachable"):
        run_motions(sc, [Lin(CartesianTarget(b), 0.3, label="L")], q0)


def test_lin_cannot_change_configuration(arm):
    q0 = np.radians([0.0, 20.0, 10.0, 0.0, 60.0, 0.0])
    pose = arm.fk(np.radians([0.0, 25.0, 10.0, 0.0, 55.0, 0.0]))
    with pytest.raises(UnreachableError, match="taught in configuration 'front-up-flip'.*use PTP"):
        run_motions(arm, [Lin(CartesianTarget(pose, "front-up-flip"), 0.2, label="L")], q0)


def test_bad_motion_arguments(arm):
    q0 = np.radians([0.0, 20.0, 10.0, 0.0, 60.0, 0.0])
    tgt = JointTarget(q0)
    with pytest.raises(InvalidInputError, match="L1: speed should be larger than zero, got -0.1"):
        Lin(tgt, -0.1, label="L1")
    with pytest.raises(InvalidInputError, match="L1: zone must be >= 0 m, got -0.01"):
        Lin(tgt, 0.1, zone=-0.01, label="L1")
    with pytest.raises(InvalidInputError, match="P: speed_pct must be <= 100, got 150"):
        Ptp(tgt, 150.0, label="P")
    p = arm.fk(q0).position
    with pytest.raises(InvalidInputError, match="C: arc points .* collinear"):
        run_motions(arm, [Circ(CartesianTarget(Pose(p + [0, 0.05, 0], np.eye(3) @ arm.fk(q0).rotation)),
                               CartesianTarget(Pose(p + [0, 0.1, 0], arm.fk(q0).rotation)), 0.1,
                               label="C")], q0)
    with pytest.raises(InvalidInputError, match=r"start joints: joint A2 = 171\.887 deg is outside its range \[-100, 135\] deg"):
        run_motions(arm, [], np.array([0, 3.0, 0, 0, 0, 0]))
