"""The compiled joint jets of a serial chain (``UrdfRobot.joint_taylor_many``)
against the numpy version (``_jets.joint_taylor`` with ``fk_jet``) and against
the joint jet that made the tool-pose jet."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from arms import load_arm

from trajkit.kinematics import _chain_jit, _jets

pytest.importorskip("pinocchio")

DATA = Path(__file__).parent / "data"

#: A SCARA as a URDF: three revolute joints and a prismatic quill (4 joints: the
#: least-squares branch of the jets, and a prismatic joint).
SCARA_URDF = """<?xml version="1.0"?>
<robot name="scara_test">
  <link name="base"/><link name="l1"/><link name="l2"/><link name="l3"/><link name="tool"/>
  <joint name="J1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.4" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-2.5" upper="2.5" velocity="3" effort="10"/></joint>
  <joint name="J2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.3 0 0" rpy="0 0 0.2"/><axis xyz="0 0 1"/>
    <limit lower="-2.5" upper="2.5" velocity="3" effort="10"/></joint>
  <joint name="J3" type="prismatic"><parent link="l2"/><child link="l3"/>
    <origin xyz="0.25 0 0" rpy="0 0 0"/><axis xyz="0 0 -1"/>
    <limit lower="0" upper="0.2" velocity="1" effort="10"/></joint>
  <joint name="J4" type="revolute"><parent link="l3"/><child link="tool"/>
    <origin xyz="0 0.01 -0.05" rpy="0.1 0 0"/><axis xyz="0 0.6 0.8"/>
    <limit lower="-3" upper="3" velocity="5" effort="10"/></joint>
</robot>
"""


def _robot(name, tmp_path):
    from trajkit.kinematics.urdf import UrdfRobot

    if name == "arm6_urdf":
        return UrdfRobot(str(DATA / "arm6_test.urdf"), "tool0")
    if name == "scara_urdf":
        path = tmp_path / "scara.urdf"
        path.write_text(SCARA_URDF)
        return UrdfRobot(str(path), "tool")
    return load_arm(name)


@pytest.mark.parametrize("name", ["ur5", "arm6_urdf", "scara_urdf"])
def test_compiled_joint_jets_recover_the_joint_motion(name, tmp_path):
    if not _chain_jit.AVAILABLE:
        pytest.skip("numba is not available: the numpy version is the only one")
    robot = _robot(name, tmp_path)
    m = robot.n_joints
    rng = np.random.default_rng(11)
    n = 200
    qj = np.zeros((n, 4, m))
    qj[:, 0] = rng.uniform(-2.0, 2.0, (n, m))
    if name == "scara_urdf":
        qj[:, 0, 2] = rng.uniform(0.01, 0.19, n)
    qj[:, 1:] = rng.standard_normal((n, 3, m))
    pos, rot = robot.fk_jet(qj)
    got, sing = robot.joint_taylor_many(qj[:, 0], pos, rot)
    jac = robot.jacobian_many(qj[:, 0])
    ref, sing_ref = _jets.joint_taylor(robot.fk_jet, qj[:, 0], pos, rot, jac)
    assert got.shape == (n, 4, m)
    np.testing.assert_array_equal(sing, sing_ref)
    sv = np.linalg.svd(jac, compute_uv=False)
    good = sv[:, 0] < 1e3 * sv[:, -1]  # well-conditioned: round-off stays small
    assert good.sum() > n // 2
    for out in (got, ref):  # both recover the joint jet that made the pose jet
        err = np.abs(out[good] - qj[good]).max(axis=(1, 2)) / np.abs(qj[good]).max(axis=(1, 2))
        assert err.max() < 1e-9
    np.testing.assert_array_equal(got[:, 0], qj[:, 0])


def _redundant_motion(robot, n, seed):
    """Joint jets of a 7-joint arm that keep ``c . (q - sigma) = 0`` (order by order),
    with their pose jets: random points, directions near the null space, seeds."""
    rng = np.random.default_rng(seed)
    m = robot.n_joints
    lo, hi = robot.joint_ranges[:, 0], robot.joint_ranges[:, 1]
    qj = np.zeros((n, 4, m))
    qj[:, 0] = rng.uniform(np.maximum(lo, -2.0), np.minimum(hi, 2.0), (n, m))
    qj[:, 1:] = rng.standard_normal((n, 3, m))
    null = np.linalg.svd(robot.jacobian_many(qj[:, 0]))[2][:, -1]
    cj = np.zeros((n, 4, m))
    cj[:, 0] = null + 0.05 * rng.standard_normal((n, m))
    cj[:, 1:] = rng.standard_normal((n, 3, m))
    sj = qj + 1e-3 * rng.standard_normal((n, 4, m))
    # the seeds' coefficients made to keep the condition at every order
    for k in range(4):
        gap = sum(np.einsum("nj,nj->n", cj[:, i], qj[:, k - i] - sj[:, k - i]) for i in range(k + 1))
        sj[:, k] += (gap / np.einsum("nj,nj->n", cj[:, 0], cj[:, 0]))[:, None] * cj[:, 0]
    pos, rot = robot.fk_jet(qj)
    return qj, pos, rot, (cj, sj)


def test_compiled_joint_jets_of_a_redundant_arm_recover_the_joint_motion():
    """The seventh equation ``c . (q - sigma) = 0``: both versions give back the
    joint jet that made the pose jet and keeps it."""
    robot = load_arm("panda")
    n = 200
    qj, pos, rot, null = _redundant_motion(robot, n, 12)
    ref, sing_ref = _jets.joint_taylor(robot.fk_jet, qj[:, 0], pos, rot, None, null)
    outs = [ref]
    if _chain_jit.AVAILABLE:
        got, sing = robot.joint_taylor_many(qj[:, 0], pos, rot, null)
        np.testing.assert_array_equal(sing, sing_ref)
        outs.append(got)
    lhs = np.concatenate([robot.jacobian_many(qj[:, 0]), null[0][:, :1]], axis=1)
    sv = np.linalg.svd(lhs, compute_uv=False)
    good = sv[:, 0] < 1e3 * sv[:, -1]
    assert good.sum() > n // 2
    for out in outs:
        err = np.abs(out[good] - qj[good]).max(axis=(1, 2)) / np.abs(qj[good]).max(axis=(1, 2))
        assert err.max() < 1e-9
    with pytest.raises(ValueError, match="7 joints"):
        _jets.joint_taylor(robot.fk_jet, qj[:, 0], pos, rot)
    assert robot.joint_taylor_many(qj[:, 0], pos, rot) is None  # no resolution given


def test_the_projection_of_a_redundant_arm_compiled_and_in_numpy():
    """Newton steps onto the pose and ``c . (q - sigma) = 0`` from a nearby start:
    both versions land on the same joints, which keep both."""
    robot = load_arm("panda")
    n = 200
    qj, pos, rot, (cj, sj) = _redundant_motion(robot, n, 13)
    start = qj[:, 0] + 1e-4 * np.random.default_rng(1).standard_normal(qj[:, 0].shape)
    ref, ok_ref = _jets.project(robot.fk_jet, pos[:, 0], rot[:, 0], start, cj[:, 0], sj[:, 0])
    outs = [(ref, ok_ref)]
    if _chain_jit.AVAILABLE:
        outs.append(robot.ik_project_many(pos[:, 0], rot[:, 0], start, cj[:, 0], sj[:, 0]))
    lhs = np.concatenate([robot.jacobian_many(qj[:, 0]), cj[:, :1, :]], axis=1)
    sv = np.linalg.svd(lhs, compute_uv=False)
    good = sv[:, 0] < 1e3 * sv[:, -1]
    assert good.sum() > n // 2
    for q, ok in outs:
        assert ok[good].all()
        np.testing.assert_allclose(q[good], qj[good, 0], rtol=0, atol=1e-10)
        np.testing.assert_array_equal(q[~ok], start[~ok])  # (not converged: the start)
    far = start.copy()
    far[0] += 2.5  # another branch of the rotation: left as it is
    q, ok = _jets.project(robot.fk_jet, pos[:1, 0], rot[:1, 0], far[:1], cj[:1, 0], sj[:1, 0])
    assert not ok[0] and np.array_equal(q[0], far[0])


def test_compiled_joint_jets_flag_the_singular_points():
    if not _chain_jit.AVAILABLE:
        pytest.skip("numba is not available: the numpy version is the only one")
    robot = load_arm("ur5")
    q = np.array([[0.0, 0.0, 0.0, 0.0, 0.0, 0.0],           # stretched, wrist aligned
                  [0.0, -np.pi / 2, 0.0, -np.pi / 2, 0.0, 0.0],
                  [0.0, -1.2, 1.5, -1.87, -1.57, 0.0],       # regular
                  [0.0, -1.2, 1.5, -1.87, 1e-13, 0.0]])       # wrist singular to 1e-13
    qj = np.concatenate([q[:, None], np.full((4, 3, 6), 0.1)], axis=1)
    pos, rot = robot.fk_jet(qj)
    got, sing = robot.joint_taylor_many(q, pos, rot)
    _ref, sing_ref = _jets.joint_taylor(robot.fk_jet, q, pos, rot)
    assert sing.tolist() == sing_ref.tolist() == [True, True, False, True]
    assert np.isnan(got[sing, 1:]).all() and np.isfinite(got[~sing]).all()


@pytest.mark.parametrize("name", ["ur5", "panda", "scara_urdf"])
def test_compiled_batch_ik_equals_the_numpy_steps(name, tmp_path):
    """``ik_near_many``'s Newton steps compiled and in numpy: the same solutions
    to round-off (well-conditioned poses), the same poses left to the one-by-one
    solver (seeds too far), and every solution on its pose."""
    if not _chain_jit.AVAILABLE:
        pytest.skip("numba is not available: the numpy version is the only one")
    robot = _robot(name, tmp_path)
    rng = np.random.default_rng(4)
    lo, hi = robot.joint_ranges[:, 0], robot.joint_ranges[:, 1]
    n = 300
    qt = rng.uniform(np.maximum(lo, -2.0), np.minimum(hi, 2.0), (n, robot.n_joints))
    pos, rot, jac = robot._fk_jacobian_many(qt)
    seeds = np.clip(qt + rng.normal(0.0, 1e-8, qt.shape), lo, hi)
    seeds[::10] = np.clip(qt[::10] + 0.05, lo, hi)  # too far for the batch
    got, ok = robot.ik_near_many(pos, rot, seeds)
    arrays = robot._chain_arrays()
    robot._chain_arrays_cache = None  # the numpy steps
    try:
        ref, ok_ref = robot.ik_near_many(pos, rot, seeds)
    finally:
        robot._chain_arrays_cache = arrays
    np.testing.assert_array_equal(ok, ok_ref)
    sv = np.linalg.svd(jac, compute_uv=False)
    good = ok & (sv[:, 0] < 1e3 * sv[:, -1])
    assert good.sum() > n // 2
    np.testing.assert_allclose(got[good], ref[good], rtol=0, atol=1e-12)
    for i in np.flatnonzero(good)[:40]:
        pose = robot.fk(got[i])
        assert np.abs(pose.position - pos[i]).max() < 1e-10
        assert np.abs(pose.rotation - rot[i]).max() < 1e-10


def test_the_joint_jets_lu_solves_like_numpy():
    """The compiled jets' LU with partial pivoting (one factorisation, three solves
    per point): the solutions of random systems, one that needs row swaps (a zero
    leading entry), and a zero pivot reported for a singular matrix."""
    rng = np.random.default_rng(3)
    for m in (2, 4, 6, 7):
        for case in range(20):
            a = rng.standard_normal((m, m))
            if case == 0:
                a[0, 0] = 0.0  # the first pivot must come from another row
            b = rng.standard_normal(m)
            lu = a.copy()
            piv = np.zeros(m, dtype=np.int64)
            assert _chain_jit._lu(lu, piv)
            x = np.empty(m)
            _chain_jit._lu_solve(lu, piv, b, x)
            np.testing.assert_allclose(a @ x, b, rtol=0, atol=1e-10 * np.linalg.cond(a))
    s = rng.standard_normal((5, 5))
    s[:, 3] = 0.0  # a zero column: no pivot in it
    assert not _chain_jit._lu(s, np.zeros(5, dtype=np.int64))
