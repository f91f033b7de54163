"""Cylindrical palletizer (Cao et al., 2012): FK/IK, wrist choice, ranges, unit conversion."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
from floatcmp import assert_ulp_close

from trajkit import AxisLimits
from trajkit.errors import InvalidInputError, UnreachableError
from trajkit.kinematics import DEFAULT_JOINT_TABLE, CylindricalPalletizer, default_palletizer

#: Compares two code paths (see floatcmp); CI runs it again with numpy SIMD off.
pytestmark = pytest.mark.codepaths

N = 20000 if os.environ.get("TRAJKIT_SWEEP") else 2000
DEG = math.pi / 180


@pytest.fixture(scope="module")
def robot():
    return default_palletizer()


def test_default_table_is_issue_table_in_si(robot):
    a, b, c, d = robot.limits
    assert (a.v_max, a.a_max, a.j_max) == pytest.approx((160 * DEG, 620 * DEG, 5400 * DEG), rel=1e-15)
    assert (b.v_max, b.a_max, b.j_max) == pytest.approx((1.3, 5.2, 45.0), rel=1e-15)
    assert (c.position_min, c.position_max) == pytest.approx((0.3, 2.2), rel=1e-15)
    assert (d.v_max, d.a_max, d.j_max) == pytest.approx((315 * DEG, 1550 * DEG, 13600 * DEG), rel=1e-15)
    assert robot.z_top == pytest.approx(2.0, rel=1e-15)
    assert robot.joint_ranges.shape == (4, 2)
    assert robot.joint_ranges[0] == pytest.approx([-math.pi, math.pi], rel=1e-15)
    assert [lim.name for lim in robot.limits] == ["A", "B", "C", "D"]
    assert DEFAULT_JOINT_TABLE["B"][4] == 2000.0


def test_fk_known_values(robot):
    p = robot.pose_from_joints([math.pi / 2, 0.6, 1.4, -math.pi / 2])
    assert p == pytest.approx([0.0, 1.4, 0.6, 0.0], abs=1e-15)
    p = robot.pose_from_joints([0.0, 0.4, 1.2, 0.0])
    assert p == pytest.approx([1.2, 0.0, 0.4, 0.0], abs=0)


def test_ik_fk_round_trip_batch_matches_scalar(robot):
    rng = np.random.default_rng(4)
    q = np.column_stack([
        rng.uniform(-math.pi + 1e-6, math.pi, N),
        rng.uniform(0.0, 2.0, N),
        rng.uniform(0.3, 2.2, N),
        rng.uniform(-math.pi / 2, math.pi / 2, N),
    ])
    pose = robot.pose_from_joints(q)
    # reference the true wrist angle: IK must return exactly that branch
    back = robot.joints_from_pose(pose, wrist_reference=q[:, 3])
    assert np.max(np.abs(back - q)) < 1e-12
    for i in range(0, N, N // 20):
        one = robot.joints_from_pose(pose[i], wrist_reference=q[i, 3])
        assert_ulp_close(one, back[i], scale=np.abs(q[i]) + 1.0, err_msg="scalar vs batch IK")
    assert robot.pose_from_joints(back) == pytest.approx(pose, abs=1e-12)


def test_wrist_takes_smaller_motion_for_symmetric_box(robot):
    # box yaw 0 at theta = 80 deg: d = -80 deg (not +100 deg) from the reference 0
    pose = [math.cos(80 * DEG), math.sin(80 * DEG), 1.0, 0.0]
    q = robot.joints_from_pose(pose, 0.0, yaw_period=math.pi)
    assert q[3] == pytest.approx(-80 * DEG, abs=1e-14)
    # a box yaw of 180 deg is the same box: same wrist angle
    q2 = robot.joints_from_pose([*pose[:3], math.pi], 0.0, yaw_period=math.pi)
    assert q2[3] == pytest.approx(q[3], abs=1e-14)
    # without symmetry the yaw 180 pose needs d = 100 deg
    q3 = robot.joints_from_pose([*pose[:3], math.pi], 0.0)
    assert q3[3] == pytest.approx(100 * DEG, abs=1e-14)


def test_out_of_range_joint_is_named(robot):
    with pytest.raises(UnreachableError, match=r"joint C = 250 mm is outside its range \[300, 2200\] mm"):
        robot.joints_from_pose([0.25, 0.0, 0.5, 0.0])
    with pytest.raises(UnreachableError, match=r"joint B = 2100 mm .*\[0, 2000\] mm"):
        robot.joints_from_pose([1.0, 0.0, 2.1, 0.0])
    with pytest.raises(UnreachableError, match=r"vertical axis"):
        robot.joints_from_pose([0.0, 0.0, 1.0, 0.0])
    with pytest.raises(UnreachableError, match=r"pose\[1\]: joint C"):
        robot.joints_from_pose([[1.0, 0.0, 1.0, 0.0], [0.1, 0.0, 1.0, 0.0]])


def test_check_false_skips_range(robot):
    q = robot.joints_from_pose([0.25, 0.0, 0.5, 0.0], check=False)
    assert q[2] == pytest.approx(0.25)


def test_bad_shapes_and_limits():
    rob = default_palletizer()
    with pytest.raises(InvalidInputError, match=r"shape \(4,\) or \(n, 4\), got shape \(3,\)"):
        rob.pose_from_joints([1, 2, 3])
    with pytest.raises(InvalidInputError, match=r"pose\[2\] must be finite"):
        rob.joints_from_pose([1.0, 0.0, float("nan"), 0.0])
    with pytest.raises(InvalidInputError, match="4 AxisLimits"):
        CylindricalPalletizer((AxisLimits(1, 1, 1),) * 3)
    with pytest.raises(InvalidInputError, match="joint table has no row for joint C"):
        CylindricalPalletizer.from_table({k: DEFAULT_JOINT_TABLE[k] for k in "ABD"})
    with pytest.raises(InvalidInputError, match="v_max of axis A should be larger than zero, got -1"):
        CylindricalPalletizer.from_table({**DEFAULT_JOINT_TABLE, "A": (-1, 620, 5400, -180, 180)})


def test_asymmetric_decel_from_table():
    rob = CylindricalPalletizer.from_table(DEFAULT_JOINT_TABLE, decel={"B": (2600.0, 20000.0)})
    assert rob.limits[1].a_max_decel == pytest.approx(2.6, rel=1e-15)
    assert rob.limits[1].j_max_decel == pytest.approx(20.0, rel=1e-15)
    assert rob.limits[1].a_max == pytest.approx(5.2, rel=1e-15)
    d = rob.to_dict()
    assert d["B"]["a_max_decel"] == pytest.approx(2600.0, rel=1e-12)
