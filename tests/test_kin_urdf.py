"""URDF robots through pinocchio: FK against the closed-form Arm6, seeded numeric IK."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pinocchio")

from trajkit.errors import InvalidInputError, UnreachableError  # noqa: E402
from trajkit.kinematics.arm6 import default_arm6  # noqa: E402
from trajkit.kinematics.base import Pose  # noqa: E402
from trajkit.kinematics.urdf import UrdfRobot  # noqa: E402

URDF = Path(__file__).parent / "data" / "arm6_test.urdf"


@pytest.fixture(scope="module")
def robots():
    return UrdfRobot(URDF, "tool0"), default_arm6()



def _assert_batch_matches_pinocchio(rob, q, pin):
    """The vectorised FK and tool-frame Jacobians equal pinocchio's, row by row."""
    pos, rot, jac = rob._fk_jacobian_many(q)
    for i in range(q.shape[0]):
        pose = rob.fk(q[i])
        ref = pin.computeFrameJacobian(rob.model, rob.data, q[i], rob.frame_id,
                                       pin.ReferenceFrame.LOCAL)
        assert np.abs(pose.position - pos[i]).max() < 1e-12
        assert np.abs(pose.rotation - rot[i]).max() < 1e-12
        assert np.abs(ref - jac[i]).max() < 1e-12

def test_structure_from_urdf(robots):
    urdf, arm = robots
    assert urdf.joint_names == arm.joint_names
    assert urdf.n_joints == 6
    for a, b in zip(urdf.limits, arm.limits):
        assert a.position_min == pytest.approx(b.position_min, abs=1e-12)
        assert a.position_max == pytest.approx(b.position_max, abs=1e-12)
        assert a.v_max == pytest.approx(b.v_max, rel=1e-12)


def test_fk_matches_closed_form_arm(robots):
    urdf, arm = robots
    rng = np.random.default_rng(3)
    for _ in range(200):
        q = np.array([rng.uniform(l.position_min, l.position_max) for l in arm.limits])
        dp, da = urdf.fk(q).distance(arm.fk(q))
        assert dp < 1e-12 and da < 1e-12


def test_seeded_ik_stays_on_branch(robots):
    urdf, arm = robots
    rng = np.random.default_rng(4)
    for _ in range(40):
        q = np.array([rng.uniform(0.8 * l.position_min, 0.8 * l.position_max) for l in arm.limits])
        pose = arm.fk(q)
        seed = q + rng.normal(0.0, 0.02, 6)
        qs = urdf.ik_near(pose, seed)
        dp, da = pose.distance(urdf.fk(qs))
        assert dp < 1e-9 * urdf.length_scale and da < 1e-9
        # near the seed, the numeric solution is the closed-form one of the same branch
        assert np.abs(qs - arm.ik(pose, arm.config_of(q), seed=q)).max() < 1e-6


def test_ik_all_finds_closed_form_solutions(robots):
    urdf, arm = robots
    pose = arm.fk(np.array([0.2, 0.3, 0.4, 0.5, 0.6, 0.7]))
    found = urdf.ik_all(pose)
    assert found
    for _, q in found:
        dp, da = pose.distance(urdf.fk(q))
        assert dp < 1e-9 and da < 1e-9


def test_errors(robots, tmp_path):
    urdf, _ = robots
    with pytest.raises(UnreachableError, match=r"\(3000\.000, 0\.000, 0\.000\) mm"):
        urdf.ik(Pose.from_xyz_abc([3.0, 0.0, 0.0]))
    with pytest.raises(InvalidInputError, match="no link named 'nope'"):
        UrdfRobot(URDF, "nope")
    with pytest.raises(InvalidInputError, match="does not exist"):
        UrdfRobot(tmp_path / "missing.urdf", "tool0")


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_vectorised_fk_and_jacobian_match_pinocchio(name):
    import pinocchio as pin
    from arms import load_arm

    rob = load_arm(name)
    rng = np.random.default_rng(11)
    lo, hi = rob.joint_ranges[:, 0], rob.joint_ranges[:, 1]
    q = lo + (hi - lo) * rng.uniform(size=(50, rob.n_joints))
    _assert_batch_matches_pinocchio(rob, q, pin)


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_ik_near_many_matches_ik_near(name):
    from arms import load_arm

    rob = load_arm(name)
    rng = np.random.default_rng(5)
    lo, hi = rob.joint_ranges[:, 0], rob.joint_ranges[:, 1]
    mid = 0.5 * (lo + hi)
    q = mid + 0.2 * (hi - lo) * rng.uniform(-1.0, 1.0, size=(40, rob.n_joints))
    poses = [rob.fk(qi) for qi in q]
    # seeds at round-off, near (batched Newton steps), far (one by one) and hopeless
    scale = np.repeat([0.0, 1e-9, 1e-4, 0.3], 10)[:, None]
    seeds = np.clip(q + scale * rng.normal(size=q.shape), lo, hi)
    seeds[-1] = lo  # far from the pose: may fail, as ik_near does
    pos = np.array([p.position for p in poses])
    rot = np.array([p.rotation for p in poses])
    got, ok = rob.ik_near_many(pos, rot, seeds)
    for i in range(q.shape[0]):
        try:
            ref = rob.ik_near(poses[i], seeds[i])
        except UnreachableError:
            assert not ok[i] and np.isnan(got[i]).all()
            continue
        assert ok[i]
        assert np.abs(got[i] - ref).max() < 1e-9  # the same solution (branch, null space)
        assert np.abs(rob.fk(got[i]).position - pos[i]).max() < 1e-12


def test_vectorised_fk_with_unaligned_and_prismatic_joints(tmp_path):
    import pinocchio as pin

    joints = [("revolute", "0.6 0.8 0", "0.1 0.2 0.3", "0.3 -0.2 0.5"),
              ("prismatic", "0 0.6 0.8", "0.2 0 0.1", "0 0 0"),
              ("revolute", "0 -1 0", "0 0.3 0", "0.1 0 0"),
              ("prismatic", "1 0 0", "0.1 0.1 0", "0 0.4 0")]
    links = "".join(f'<link name="l{i}"/>' for i in range(len(joints) + 1))
    body = "".join(
        f'<joint name="j{i}" type="{kind}"><parent link="l{i}"/><child link="l{i + 1}"/>'
        f'<origin xyz="{xyz}" rpy="{rpy}"/><axis xyz="{axis}"/>'
        f'<limit lower="-1" upper="1" velocity="1" effort="1"/></joint>'
        for i, (kind, axis, xyz, rpy) in enumerate(joints))
    path = tmp_path / "mixed.urdf"
    path.write_text(f'<robot name="mixed">{links}{body}</robot>')
    rob = UrdfRobot(path, f"l{len(joints)}")
    assert rob._chain() is not None
    rng = np.random.default_rng(2)
    q = rng.uniform(-1.0, 1.0, size=(20, rob.n_joints))
    _assert_batch_matches_pinocchio(rob, q, pin)
