"""CIRC through its three points; blended corners pass without stopping, inside the zone."""

from __future__ import annotations

import numpy as np
import pytest

from trajkit.kinematics.arm6 import default_arm6
from trajkit.kinematics.base import Pose
from trajkit.paths.arc import circle_through
from trajkit.robot import CartesianTarget, Circ, Lin, run_motions

LINE_TOL = 1e-6
LIMIT_SLACK = 1e-9


@pytest.fixture(scope="module")
def arm():
    return default_arm6()


@pytest.fixture(scope="module")
def start(arm):
    q0 = np.radians([0.0, 20.0, 10.0, 0.0, 60.0, 0.0])
    return q0, arm.fk(q0)


def _check_limits(robot, smp):
    for j, lim in enumerate(robot.limits):
        assert np.abs(smp.qd[:, j]).max() <= lim.v_max * (1 + LIMIT_SLACK)
        assert np.abs(smp.qdd[:, j]).max() <= min(lim.a_max, lim.a_max_decel) * (1 + LIMIT_SLACK)


def test_circ_passes_through_its_three_points(arm, start):
    q0, p0 = start
    via = p0.position + np.array([0.08, 0.08, -0.03])
    end = p0.position + np.array([0.0, 0.16, 0.0])
    run = run_motions(arm, [Circ(CartesianTarget(Pose(via, p0.rotation)),
                                 CartesianTarget(Pose(end, p0.rotation)), 0.15, label="C")], q0)
    smp = run.sample(run.times(0.001))
    fk = np.array([arm.fk(q).position for q in smp.q])
    centre, radius, normal = circle_through(p0.position, via, end)
    r = np.linalg.norm(fk - centre, axis=1)
    assert np.abs(r - radius).max() < LINE_TOL * arm.length_scale
    assert np.abs((fk - centre) @ normal).max() < LINE_TOL * arm.length_scale
    # start and end exactly, and the via point on the way: the densely sampled
    # path comes within one sample step of it
    assert np.linalg.norm(fk[0] - p0.position) < 1e-12
    assert np.linalg.norm(fk[-1] - end) < 1e-12
    step = 0.15 * 0.001
    assert np.linalg.norm(fk - via, axis=1).min() <= step
    # the travelled length is that of the arc via the aux point (sweep * radius)
    from trajkit.paths.arc import Arc3
    travelled = np.linalg.norm(np.diff(fk, axis=0), axis=1).sum()
    assert travelled == pytest.approx(Arc3(p0.position, via, end).length, rel=1e-5)
    _check_limits(arm, smp)
    # cruising at the programmed speed (a uniform slow-down of the timing by its final
    # check may take a few parts in 1e8 off it), never above it
    assert smp.tool_speed.max() <= 0.15 * (1 + 1e-9)
    cruise = np.isclose(smp.tool_speed, 0.15, rtol=1e-6, atol=0)
    assert cruise.sum() > 100


def test_blended_corner_keeps_moving_inside_zone(arm, start):
    q0, p0 = start
    a = p0.position + np.array([0.0, 0.15, 0.0])
    b = a + np.array([0.1, 0.0, -0.1])
    zone = 0.02
    mot = [Lin(CartesianTarget(Pose(a, p0.rotation)), 0.2, zone=zone, label="L1"),
           Lin(CartesianTarget(Pose(b, p0.rotation)), 0.2, label="L2")]
    run = run_motions(arm, mot, q0)
    assert [sg.kind for sg in run.segments] == ["CP"]
    smp = run.sample(run.times(0.001))
    fk = np.array([arm.fk(q).position for q in smp.q])
    inner = (smp.t > 0.2) & (smp.t < run.duration - 0.2)
    assert smp.tool_speed[inner].min() > 0.02  # never stops at the corner
    # every sample is on one of the two lines, or inside the zone around the corner
    def dseg(p, u, v):
        d = v - u
        s = np.clip(((p - u) @ d) / (d @ d), 0, 1)
        return np.linalg.norm(p - (u + s[:, None] * d), axis=1)
    on_lines = np.minimum(dseg(fk, p0.position, a), dseg(fk, a, b)) < LINE_TOL * arm.length_scale
    in_zone = np.linalg.norm(fk - a, axis=1) <= zone * (1 + 1e-9)
    assert (on_lines | in_zone).all()
    assert (~on_lines).sum() > 10  # the blend really leaves the corner
    assert np.linalg.norm(fk - a, axis=1).min() > 1e-4  # ... and does not touch it
    _check_limits(arm, smp)
    # faster than stopping exactly at the corner
    stop = run_motions(arm, [Lin(CartesianTarget(Pose(a, p0.rotation)), 0.2),
                             Lin(CartesianTarget(Pose(b, p0.rotation)), 0.2)], q0)
    assert [sg.kind for sg in stop.segments] == ["CP", "CP"]
    assert run.duration < stop.duration


def test_blend_lin_into_circ(arm, start):
    q0, p0 = start
    a = p0.position + np.array([0.0, 0.12, 0.0])
    via = a + np.array([0.06, 0.06, 0.0])
    c = a + np.array([0.12, 0.0, 0.0])
    run = run_motions(arm, [Lin(CartesianTarget(Pose(a, p0.rotation)), 0.2, zone=0.01),
                            Circ(CartesianTarget(Pose(via, p0.rotation)),
                                 CartesianTarget(Pose(c, p0.rotation)), 0.1)], q0)
    smp = run.sample(run.times(0.002))
    assert len(run.segments) == 1
    inner = (smp.t > 0.2) & (smp.t < run.duration - 0.2)
    assert smp.tool_speed[inner].min() > 0.01
    assert np.linalg.norm(arm.fk(smp.q[-1]).position - c) < 1e-12
    _check_limits(arm, smp)


def test_blend_orientation_is_smooth(arm, start):
    from trajkit.kinematics.base import rot_z
    from trajkit.robot._rotations import quat_from_matrix, rotation_angle

    q0, p0 = start
    a = Pose(p0.position + np.array([0.0, 0.12, 0.0]), p0.rotation)
    b = Pose(a.position + np.array([0.1, 0.0, 0.0]), rot_z(0.5) @ p0.rotation)
    run = run_motions(arm, [Lin(CartesianTarget(a), 0.2, zone=0.03), Lin(CartesianTarget(b), 0.2)], q0)
    dt = 0.001
    smp = run.sample(run.times(dt))
    quats = [quat_from_matrix(arm.fk(q).rotation) for q in smp.q]
    rate = np.array([rotation_angle(quats[i], quats[i + 1]) for i in range(len(quats) - 1)]) / dt
    # the tool's angular speed changes gradually (no step at the blend ends): bounded
    # angular acceleration, well below what a 0.1 rad/s step in one sample would give
    assert np.abs(np.diff(rate)).max() / dt < 30.0
    assert rate.max() <= arm.orientation_speed * (1 + 1e-6)
    _check_limits(arm, smp)
    dp, da = arm.fk(smp.q[-1]).distance(b)
    assert dp < 1e-12 and da < 1e-9


@pytest.mark.parametrize("zone", [0.05, 0.02])
def test_ptp_blend_superposition(arm, zone):
    from trajkit.robot import JointTarget, Ptp

    q0 = np.radians([0, 20, 10, 0, 60, 0])
    q1 = np.radians([40, 10, 30, 10, 50, 20])
    q2 = np.radians([80, 25, 5, 0, 60, -20])
    stop = run_motions(arm, [Ptp(JointTarget(q1)), Ptp(JointTarget(q2))], q0)
    run = run_motions(arm, [Ptp(JointTarget(q1), zone=zone, label="P1"), Ptp(JointTarget(q2))], q0)
    assert len(run.segments) == 1 and len(stop.segments) == 2
    assert run.duration < stop.duration
    (o0, a), (o1, b) = run.segments[0].parts
    assert o0 == 0.0 and 0.0 < o1 < a.duration  # b starts before a ends
    smp = run.sample(np.union1d(run.times(0.0005), [o1, a.duration]))
    _check_limits(arm, smp)
    assert np.allclose(smp.q[-1], q2, atol=1e-12)
    # no stop at the corner: some joint moves at every instant between the two moves
    mid = (smp.t > 0.5 * a.duration) & (smp.t < o1 + 0.5 * b.duration)
    assert np.abs(smp.qd[mid]).max(axis=1).min() > 0.05
    # during the overlap the tool stays within the zone of the corner point
    corner = arm.fk(q1).position
    ov = (smp.t >= o1) & (smp.t <= a.duration)
    d = np.array([np.linalg.norm(arm.fk(q).position - corner) for q in smp.q[ov]])
    assert d.max() <= zone * (1 + 1e-9)
    # the joint-space superposition is exact: q(t) = a(t) + b(t - o1) - q1
    t = smp.t[ov]
    ref = a.sample(t).position + b.sample(t - o1).position - q1
    assert np.abs(smp.q[ov] - ref).max() < 1e-12
    # the summed jerk is piecewise constant: exact at the middle of every
    # interval between two phase boundaries of either move, within the limit
    jmax = np.array([min(lim.j_max, lim.j_max_decel) for lim in arm.limits])
    edges = np.unique(np.concatenate(
        [[0.0, o1 + b.duration]]
        + [off + np.cumsum(p.phase_durations) for off, tr in ((0.0, a), (o1, b)) for p in tr.axes]))
    mid = 0.5 * (edges[1:] + edges[:-1])
    jk = a.sample(mid).jerk + b.sample(mid - o1).jerk
    assert (np.abs(jk) <= jmax * (1 + 1e-12)).all()


def test_ptp_blend_that_saves_no_time_stops_exactly(arm):
    """With half the jerk in the overlapping legs, a 4 mm zone is slower than an
    exact stop on this pair: the moves stop at the point (like zone 0)."""
    from trajkit.robot import JointTarget, Ptp

    q0 = np.radians([0, 20, 10, 0, 60, 0])
    q1 = np.radians([40, 10, 30, 10, 50, 20])
    q2 = np.radians([80, 25, 5, 0, 60, -20])
    stop = run_motions(arm, [Ptp(JointTarget(q1)), Ptp(JointTarget(q2))], q0)
    run = run_motions(arm, [Ptp(JointTarget(q1), zone=0.004), Ptp(JointTarget(q2))], q0)
    assert len(run.segments) == 2
    assert run.duration == stop.duration
    assert np.array_equal(run.segments[0].q_end, q1)
