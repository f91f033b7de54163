"""Joint-path derivatives from the kinematics: forward kinematics on Taylor series.

Two independent references:

- the forward kinematics pushed through a joint polynomial ``q(e)`` must have
  the Taylor coefficients of a least-squares polynomial fitted to plain
  forward-kinematics samples of that motion;
- the derivatives of an inverse-kinematics joint path must equal those of a
  high-degree polynomial fitted to inverse kinematics solved along a few
  millimetres of the path (far from the stencils either method uses).
"""

from __future__ import annotations

import numpy as np
import pytest
from arms import load_arm

from trajkit.errors import UnreachableError
from trajkit.kinematics import _jets
from trajkit.kinematics.arm6 import default_arm6
from trajkit.kinematics.base import Pose, rot_x, rot_z
from trajkit.kinematics.scara import default_scara
from trajkit.robot import CartesianTarget, Circ, Lin, run_motions
from trajkit.robot.models import PalletizerRobot


def _robot(name):
    if name == "arm6":
        return default_arm6()
    if name == "scara":
        return default_scara()
    if name == "palletizer":
        return PalletizerRobot()
    return load_arm(name)


def _fit(e, samples, deg):
    """Taylor coefficients 0..3 at e = 0 of a polynomial fit (e scaled to [-1, 1])."""
    E = np.abs(e).max()
    c = np.polynomial.polynomial.polyfit(e / E, samples, deg)[:4]
    return c / E ** np.arange(4)[:, None]


@pytest.mark.parametrize("name", ["arm6", "scara", "ur5", "panda", "palletizer"])
def test_forward_kinematics_on_jets_has_the_taylor_coefficients_of_the_motion(name):
    robot = _robot(name)
    m = robot.n_joints
    rng = np.random.default_rng(3)
    for _ in range(3):
        qj = rng.uniform(-1.0, 1.0, size=(4, m))
        if name == "scara":
            qj[0, 2] = 0.1  # the quill inside its stroke
        if name == "palletizer":
            qj[0, 1:3] = (1.0, 1.2)  # height and reach inside their strokes
        pos, rot = robot.fk_jet(qj[None])
        e = np.linspace(-0.02, 0.02, 41)
        poses = [robot.fk(qj[0] + qj[1] * x + qj[2] * x**2 + qj[3] * x**3) for x in e]
        ref_p = _fit(e, np.array([p.position for p in poses]), 7)
        ref_r = _fit(e, np.array([p.rotation.ravel() for p in poses]), 7)
        np.testing.assert_allclose(pos[0], ref_p, rtol=0, atol=1e-7)
        np.testing.assert_allclose(rot[0].reshape(4, 9), ref_r, rtol=0, atol=1e-7)
        # fewer coefficients: the leading ones of the same series
        p2, r2 = robot.fk_jet(qj[None, :2])
        np.testing.assert_allclose(p2[0], pos[0, :2], rtol=0, atol=1e-14)
        np.testing.assert_allclose(r2[0], rot[0, :2], rtol=0, atol=1e-14)


@pytest.mark.parametrize("name", ["arm6", "ur5"])
def test_jacobian_from_jets_equals_the_robots_own(name):
    robot = _robot(name)
    rng = np.random.default_rng(5)
    q = rng.uniform(-1.0, 1.0, size=(6, robot.n_joints))
    jac = _jets.jacobian(robot.fk_jet, q)
    h = 1e-6
    for i in range(q.shape[0]):
        for j in range(robot.n_joints):
            dq = np.zeros(robot.n_joints)
            dq[j] = h
            a, b = robot.fk(q[i] + dq), robot.fk(q[i] - dq)
            dp = (a.position - b.position) / (2 * h)
            dr = (a.rotation - b.rotation) / (2 * h) @ robot.fk(q[i]).rotation.T
            w = 0.5 * np.array([dr[2, 1] - dr[1, 2], dr[0, 2] - dr[2, 0], dr[1, 0] - dr[0, 1]])
            np.testing.assert_allclose(jac[i, :, j], np.concatenate([dp, w]), rtol=0, atol=1e-8)
    if hasattr(robot, "jacobian_many"):
        np.testing.assert_allclose(robot.jacobian_many(q), jac, rtol=0, atol=1e-12)


def _chain_path(robot, q0, motions):
    run = run_motions(robot, motions, q0)
    return next(sg.chain.path for sg in run.segments if sg.kind == "CP")


def _paths():
    """(robot name, start joints, motions): a LIN with a turn of the tool, a CIRC, a zone blend."""
    out = []
    for name, q0 in (("ur5", np.array([0.0, -1.2, 1.5, -1.87, -1.57, 0.0])),
                     ("arm6", np.array([0.3, -0.4, 0.5, 0.2, 0.6, 0.1])),
                     ("panda", np.array([0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785]))):
        robot = _robot(name)
        p = robot.fk(q0)
        turn = rot_z(0.6) @ rot_x(0.3) @ p.rotation

        def at(d, rot=p.rotation, p=p):
            return CartesianTarget(Pose(p.position + np.asarray(d), rot))

        out.append((name, q0, [Lin(at([0.12, 0.2, -0.05], turn), 1.0, label="L")]))
        out.append((name, q0, [Circ(at([0.1, 0.1, 0.0]), at([0.2, 0.0, 0.0]), 1.0, label="C")]))
        out.append((name, q0, [Lin(at([0.15, 0.0, 0.0]), 1.0, zone=0.04, label="L1"),
                               Lin(at([0.15, 0.15, 0.0]), 1.0, label="L2")]))
    return out


@pytest.mark.parametrize("case", range(9))
def test_joint_path_derivatives_equal_those_of_the_inverse_kinematics(case):
    name, q0, motions = _paths()[case]
    robot = _robot(name)
    jp = _chain_path(robot, q0, motions)
    assert jp._fk_jet is not None  # the derivatives come from the kinematics
    rng = np.random.default_rng(case)
    for k, piece in enumerate(jp.pieces):
        lo, hi = jp.offsets[k], jp.offsets[k + 1]
        if hi - lo < 0.02:
            continue
        s = rng.uniform(lo + 0.005, hi - 0.005, 3)
        q, d1, d2, d3 = jp.derivatives(s)
        for i, si in enumerate(s):
            E = 0.004
            e = np.linspace(-E, E, 61)
            qs = jp.ik(si + e, np.full(e.size, k), jp.seeds(si + e))
            ref = _fit(e, qs, 10)
            for order, got in enumerate((q[i], d1[i], d2[i] / 2.0, d3[i] / 6.0)):
                scale = max(1.0, np.abs(ref[order]).max())
                np.testing.assert_allclose(got, ref[order], rtol=0, atol=5e-5 * scale,
                                           err_msg=f"{name} piece {k} ({piece.kind}) order {order}")


@pytest.mark.parametrize("name", ["arm6", "ur5", "panda"])
@pytest.mark.parametrize("turn", [120.0, 150.0, 170.0])
def test_joint_path_derivatives_in_a_tight_corner_blend(name, turn):
    """A sharp corner with a 10 mm zone gets a blend of 0.1-1.3 mm radius: the
    derivatives there equal those of the inverse kinematics (Richardson-extrapolated
    central differences on steps of a twentieth of the radius and half that)."""
    robot = _robot(name)
    q0 = {"arm6": np.array([0.3, -0.4, 0.5, 0.2, 0.6, 0.1]),
          "ur5": np.array([0.0, -1.2, 1.5, -1.87, -1.57, 0.0]),
          "panda": np.array([0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785])}[name]
    p = robot.fk(q0)
    a = p.position + np.array([0.1, 0.0, 0.0])
    th = np.radians(180.0 - turn)
    b = a + 0.1 * np.array([-np.cos(th), np.sin(th), 0.0])
    jp = _chain_path(robot, q0, [Lin(CartesianTarget(Pose(a, p.rotation)), 0.5, zone=0.01, label="A"),
                                 Lin(CartesianTarget(Pose(b, p.rotation)), 0.5, label="B")])
    k = next(i for i, pc in enumerate(jp.pieces) if pc.kind == "blend")
    radius = jp.pieces[k].feature
    assert 1e-4 < radius < 2e-3  # a tight blend
    lo, hi = jp.offsets[k], jp.offsets[k + 1]
    s = lo + (hi - lo) * np.array([0.25, 0.4, 0.5, 0.6, 0.75])
    q, d1, d2, d3 = jp.derivatives(s)

    def central(h):
        e = h * np.arange(-2.0, 3.0)
        qs = np.stack([jp.ik(si + e, np.full(e.size, k), jp.seeds(si + e)) for si in s])
        return ((qs[:, 3] - qs[:, 1]) / (2 * h),
                (qs[:, 3] - 2 * qs[:, 2] + qs[:, 1]) / h**2,
                (qs[:, 4] - 2 * qs[:, 3] + 2 * qs[:, 1] - qs[:, 0]) / (2 * h**3))

    h = radius / 20.0
    coarse, fine = central(h), central(h / 2.0)
    for order, got in enumerate((d1, d2, d3)):
        ref = fine[order] + (fine[order] - coarse[order]) / 3.0  # the h^2 term removed
        scale = np.abs(ref).max()
        np.testing.assert_allclose(got, ref, rtol=0, atol=1e-4 * scale,
                                   err_msg=f"{name}, {turn} deg: derivative {order + 1}")


def test_a_redundant_arm_keeps_the_seeds_part_along_its_null_direction():
    """The Panda (7 joints): the joints along a path are the inverse kinematics
    from the walked seeds, resolved exactly by ``c . (q - seeds) = 0`` with ``c``
    the Jacobian's null direction interpolated along the walk; the table's
    joints keep it, the inverse kinematics from the seeds alone lands on the same
    joints, and ``c`` stays close to the null space between the table's points."""
    robot = _robot("panda")
    q0 = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785])
    p = robot.fk(q0)
    turn = rot_z(0.6) @ rot_x(0.3) @ p.rotation
    jp = _chain_path(robot, q0, [Lin(CartesianTarget(Pose(p.position + np.array([0.1, 0.05, 0.0]),
                                                          turn)), 1.0, label="L")])
    assert jp._fk_jet is not None and jp._null is not None  # from the kinematics
    s = np.linspace(0.0, jp.length, 801)
    q = jp.joints(s)
    c, seeds = jp._null(s), jp.seeds(s)
    assert np.abs(np.einsum("ij,ij->i", c, q - seeds)).max() < 1e-12
    pos, rot = jp.poses(s, jp.piece_of(s))
    for i in range(0, s.size, 40):
        pose = robot.fk(q[i])
        assert np.abs(pose.position - pos[i]).max() < 1e-12
        assert np.abs(pose.rotation - rot[i]).max() < 1e-12
        plain = robot.ik_near(Pose(pos[i], rot[i]), seeds[i])
        assert np.abs(plain - q[i]).max() < 1e-9
    np.testing.assert_allclose(jp.joints(jp.table_s), jp.table_q, rtol=0, atol=1e-12)
    jac = robot.jacobian_many(q)
    cn = c / np.linalg.norm(c, axis=1)[:, None]
    assert np.abs(np.einsum("nij,nj->ni", jac, cn)).max() < 1e-3 * np.abs(jac).max()
    with pytest.raises(ValueError, match="7 joints"):
        _jets.joint_taylor(robot.fk_jet, np.zeros((1, 7)), np.zeros((1, 4, 3)), np.zeros((1, 4, 3, 3)))
    with pytest.raises(ValueError, match="one redundant joint"):
        z = np.zeros((1, 4, 8))
        _jets.joint_taylor(robot.fk_jet, np.zeros((1, 8)), np.zeros((1, 4, 3)),
                           np.zeros((1, 4, 3, 3)), None, (z, z))


def test_a_singular_jacobian_is_flagged_and_the_path_falls_back_to_differences():
    robot = _robot("scara")
    q = np.array([[0.3, 0.0, 0.05, 0.1], [0.3, 0.8, 0.05, 0.1]])  # stretched, bent
    pos, rot = robot.fk_jet(np.concatenate([q[:, None], np.zeros((2, 3, 4))], axis=1))
    pos[:, 1] = [[0.0, -1.0, 0.0], [0.0, -1.0, 0.0]]  # some motion of the tool
    qj, singular = _jets.joint_taylor(robot.fk_jet, q, pos, rot)
    assert singular.tolist() == [True, False]
    assert np.isnan(qj[0, 1:]).all() and np.isfinite(qj[1]).all()
    # the arm stretched: a vertical line (the quill alone) can be followed, and gets
    # differences of the inverse kinematics on the singularity ...
    q0 = np.array([0.0, 0.0, 0.05, 0.0])
    p = robot.fk(q0)
    jp = _chain_path(robot, q0, [Lin(CartesianTarget(Pose(p.position - np.array([0.0, 0.0, 0.05]),
                                                          p.rotation)), 0.5, label="L")])
    q, d1, d2, d3 = jp.derivatives(np.array([0.0, 0.5 * jp.length]))
    np.testing.assert_allclose(d1, [[0.0, 0.0, 1.0, 0.0]] * 2, atol=1e-6)
    assert np.abs(d2).max() < 1e-3 and np.abs(d3).max() < 1e-1
    # ... a line along the arm cannot: the elbow's speed would be unbounded
    with pytest.raises(UnreachableError, match=r"L: the path meets a singularity of scara at "
                                               r"\(600\.000, 0\.000, 150\.000\) mm .* cannot follow"):
        _chain_path(robot, q0, [Lin(CartesianTarget(Pose(p.position - np.array([0.2, 0.05, 0.0]),
                                                         p.rotation)), 0.5, label="L")])


def test_a_redundant_arm_with_a_singular_walk_falls_back_to_differences(monkeypatch):
    """Where the walked joints pass a point whose Jacobian is singular (its null space
    wider than one direction), the path keeps the differences of the inverse
    kinematics along the pose's Taylor polynomial: still the derivatives of its
    inverse kinematics (forced here by a condition-number bound no point meets)."""
    robot = _robot("panda")
    q0 = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785])
    p = robot.fk(q0)
    monkeypatch.setattr(_jets, "COND_MAX", 1.0)
    jp = _chain_path(robot, q0, [Lin(CartesianTarget(Pose(p.position + np.array([0.1, 0.05, 0.0]),
                                                          p.rotation)), 1.0, label="L")])
    assert jp._fk_jet is None and jp._null is None
    monkeypatch.undo()
    s = np.array([0.03, 0.06, 0.09])
    q, d1, d2, d3 = jp.derivatives(s)
    for i, si in enumerate(s):
        e = np.linspace(-0.004, 0.004, 61)
        ref = _fit(e, jp.ik(si + e, np.zeros(e.size, dtype=int), jp.seeds(si + e)), 10)
        for order, got in enumerate((q[i], d1[i], d2[i] / 2.0, d3[i] / 6.0)):
            scale = max(1.0, np.abs(ref[order]).max())
            np.testing.assert_allclose(got, ref[order], rtol=0, atol=5e-5 * scale)
