"""Other robot models in programs: the cylindrical palletizer adapter, a URDF arm."""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import numpy as np
import pytest

from trajkit.errors import UnreachableError
from trajkit.io.program import parse_program
from trajkit.kinematics.base import Pose, rot_x, rot_z
from trajkit.robot import CartesianTarget, Lin, run_motions
from trajkit.robot.models import PalletizerRobot, robot_by_name

DATA = Path(__file__).resolve().parent / "data"


def test_palletizer_round_trip_and_lin():
    pal = PalletizerRobot()
    rng = np.random.default_rng(8)
    for _ in range(200):
        q = np.array([l.position_min + (l.position_max - l.position_min) * rng.uniform(0.05, 0.95)
                      for l in pal.limits])
        pose = pal.fk(q)
        qs = pal.ik(pose, seed=q)
        dp, da = pal.fk(qs).distance(pose)
        assert dp < 1e-12 and da < 1e-12
    with pytest.raises(UnreachableError, match="cannot tilt its gripper"):
        pal.ik(Pose(np.array([1.0, 0.0, 0.5]), rot_x(0.1)))
    # a straight line in Cartesian space is a curve in (theta, r): IK at every sample
    q0 = pal.ik(Pose(np.array([1.2, -0.3, 0.6]), rot_z(0.0)))
    goal = Pose(np.array([1.2, 0.3, 0.6]), rot_z(0.0))
    run = run_motions(pal, [Lin(CartesianTarget(goal), 0.5)], q0)
    smp = run.sample(run.times(0.004))
    fk = np.array([pal.fk(q).position for q in smp.q])
    assert np.abs(fk[:, 0] - 1.2).max() < 1e-9 and np.abs(fk[:, 2] - 0.6).max() < 1e-9
    for j, lim in enumerate(pal.limits):
        assert np.abs(smp.qd[:, j]).max() <= lim.v_max * (1 + 1e-9)


def test_robot_by_name():
    assert robot_by_name("scara").name == "scara"
    assert robot_by_name("palletizer").n_joints == 4


@pytest.mark.parametrize("name", ["scara", "arm6", "palletizer"])
def test_home_is_inside_the_ranges_and_lines_start_from_it(name):
    """A robot's home (the HMI's start) lies inside every range, away from the
    singularities at 0 of the SCARA (stretched arm) and the arm (straight wrist):
    lines from it plan in every direction, also along the arm."""
    from trajkit.kinematics._jets import jacobian

    robot = robot_by_name(name)
    q = robot.home
    q.setflags(write=False)  # a fresh array per call: the caller may keep it
    assert robot.home is not q and q.shape == (robot.n_joints,)
    robot.check_joints(q)
    if hasattr(robot, "fk_jet"):
        J = jacobian(robot.fk_jet, q[None, :])[0]
        assert np.linalg.cond(J) < 100.0
    pose = robot.fk(q)
    radial = np.array([pose.position[0], pose.position[1], 0.0])
    radial /= np.linalg.norm(radial)
    # (the palletizer's Z is at the bottom of its range at home)
    down = np.array([0.0, 0.0, 1.0 if name == "palletizer" else -1.0])
    for d in (radial, -radial, np.array([0.0, 1.0, 0.0]), down):
        goal = Pose(pose.position + 0.05 * d, pose.rotation)
        run = run_motions(robot, [Lin(CartesianTarget(goal), speed=0.2)], q)
        dp, _ = robot.fk(run.sample(run.duration).q[-1]).distance(goal)
        assert dp < 1e-9


def test_urdf_program_matches_closed_form_arm():
    pytest.importorskip("pinocchio")
    text = textwrap.dedent("""\
        robot: {urdf: arm6_test.urdf, tip_link: tool0}
        points:
          home: {joints_deg: [0, 20, 10, 0, 60, 0]}
          a: {xyz_mm: [560, 120, 520], abc_deg: [0, 0, 180]}
        program:
          - PTP: home
          - LIN: a
            speed_mm_s: 200
        """)
    prog = parse_program(text, source="urdf.yaml", base_dir=DATA)
    run = prog.run()
    smp = run.sample(run.times(0.01))
    text6 = text.replace("{urdf: arm6_test.urdf, tip_link: tool0}", "arm6")
    prog6 = parse_program(text6, source="arm6.yaml")
    run6 = prog6.run()
    assert run.duration == pytest.approx(run6.duration, rel=1e-3)
    smp6 = run6.sample(run6.times(0.01))
    n = min(smp.t.size, smp6.t.size)
    # numeric IK (pinocchio FK + our seeded solver) follows the closed-form branch
    assert np.abs(smp.q[:n] - smp6.q[:n]).max() < 1e-3
    dp, da = prog.robot.fk(smp.q[-1]).distance(prog.points["a"].pose)
    assert dp < 1e-9 and da < 1e-9
    assert math.isfinite(run.duration)
