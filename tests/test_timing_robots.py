"""Robot paths timed by the engine: real arms, independent checks, monotone speed, oracles.

Every limit is checked independently of the engine: the joints are the inverse
kinematics at samples 0.25 ms apart, their first, second and third
differences give velocity, acceleration and jerk (the third difference is the
jerk averaged over three samples, hence the small relative tolerance).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from arms import load_arm
from conftest import sweep_size

from trajkit import AxisLimits, plan_move
from trajkit.errors import UnreachableError
from trajkit.kinematics.arm6 import default_arm6
from trajkit.kinematics.base import Pose, rot_x, rot_z
from trajkit.robot import CartesianTarget, Circ, Lin, run_motions
from trajkit.timing import _ipm, _socp, engine

DT = 2.5e-4

#: Relative slack of the finite-difference checks (three-sample averages, IK round-off).
FD_RTOL = 1e-5


def fd_ratios(robot, run):
    """Largest |v|, |a|, |j| / limit per joint from differences of IK'd samples."""
    t = np.arange(0.0, run.duration + 3 * DT, DT)
    q = run.sample(t).q
    v = np.diff(q, axis=0) / DT
    a = np.diff(q, 2, axis=0) / DT**2
    j = np.diff(q, 3, axis=0) / DT**3
    V = np.array([lm.v_max for lm in robot.limits])
    A = np.array([max(lm.a_max, lm.a_max_decel) for lm in robot.limits])
    J = np.array([max(lm.j_max, lm.j_max_decel) for lm in robot.limits])
    return np.abs(v).max(0) / V, np.abs(a).max(0) / A, np.abs(j).max(0) / J, q


def _random_motion(rng, robot, q0):
    p = robot.fk(q0)
    d = rng.normal(size=3)
    d *= rng.uniform(0.05, 0.3) / np.linalg.norm(d)
    rot = rot_z(rng.uniform(-0.5, 0.5)) @ rot_x(rng.uniform(-0.3, 0.3)) @ p.rotation
    target = CartesianTarget(Pose(p.position + d, rot))
    v = float(rng.uniform(0.2, 2.0))
    if rng.random() < 0.5:
        return Lin(target, v, label="L"), target
    side = np.cross(d, rng.normal(size=3))
    side *= 0.3 * np.linalg.norm(d) / np.linalg.norm(side)
    via = CartesianTarget(Pose(p.position + 0.5 * d + side, p.rotation))
    return Circ(via, target, v, label="C"), target


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_random_paths_on_real_arms_keep_every_limit(name):
    robot = load_arm(name)
    q_home = {"ur5": [0.0, -1.2, 1.5, -1.87, -1.57, 0.0],
              "panda": [0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785]}[name]
    rng = np.random.default_rng({"ur5": 1, "panda": 2}[name])
    done = 0
    for _ in range(10 * sweep_size(2)):
        if done >= sweep_size(2):
            break
        q0 = np.array(q_home) + rng.uniform(-0.2, 0.2, robot.n_joints)
        mot, target = _random_motion(rng, robot, q0)
        try:
            run = run_motions(robot, [mot], q0)
        except Exception as exc:  # unreachable or singular: another one
            if "unreachable" in str(exc) or "singular" in str(exc):
                continue
            raise
        done += 1
        rv, ra, rj, q = fd_ratios(robot, run)
        assert (rv <= 1 + FD_RTOL).all() and (ra <= 1 + FD_RTOL).all(), (rv, ra)
        assert (rj <= 1 + FD_RTOL).all(), rj
        # the goal exactly, the tool on its path
        dp, da = robot.fk(q[-1]).distance(target.pose)
        assert dp < 1e-9 and da < 1e-9
        if isinstance(mot, Lin):
            a, b = robot.fk(q0).position, target.pose.position
            pts = np.array([robot.fk(qq).position for qq in q[::25]])
            u = np.clip((pts - a) @ (b - a) / np.dot(b - a, b - a), 0, 1)
            off = np.linalg.norm(pts - (a + u[:, None] * (b - a)), axis=1)
            assert off.max() < 1e-9  # 1e-6 mm
        # TOPP-RA-style bound: the engine's own jerk-free round (none where the path's
        # own limits hold the motion everywhere: that S-curve is the optimum itself)
        tm = run.segments[-1].chain.timing
        assert tm.info["status"] == "path limits" or tm.duration >= tm.jerk_free_time * (1 - 1e-6)
        # ... and the S-curve under the tool's own limits alone (at the programmed speed)
        tool = AxisLimits(mot.speed, robot.cartesian_accel, robot.cartesian_jerk)
        assert tm.duration >= plan_move(0.0, tm.path.length, tool).duration * (1 - 1e-9)
    assert done >= sweep_size(2)


def test_a_ur5_line_beside_its_shoulder_singularity():
    """A UR5 line of 0.8 m 16 mm beside the shoulder singularity (at the start
    pose's y, the shoulder offset, a line along x passes the base axis): the base
    joint turns by 145 degrees, at up to 10.7 rad per metre of the line. Every
    joint limit holds on differences of IK'd samples 0.25 ms apart, the tool
    stays on the line and reaches its target, and the motion takes at most 10 %
    longer than the engine's own jerk-free round (6.8 % measured)."""
    robot = load_arm("ur5")
    q_home = np.array([0.0, -1.2, 1.5, -1.87, -1.57, 0.0])
    p = robot.fk(q_home)
    a = Pose.trusted(np.array([0.4, p.position[1] + 0.016, p.position[2]]), p.rotation)
    b = Pose.trusted(np.array([-0.4, p.position[1] + 0.016, p.position[2]]), p.rotation)
    q0 = robot.ik_near(a, q_home)
    run = run_motions(robot, [Lin(CartesianTarget(b), 3.0, label="L")], q0)
    rv, ra, rj, q = fd_ratios(robot, run)
    assert (rv <= 1 + FD_RTOL).all() and (ra <= 1 + FD_RTOL).all() and (rj <= 1 + FD_RTOL).all()
    assert np.ptp(q[:, 0]) > 2.5  # the base joint's swing past the singularity
    dp, da = robot.fk(q[-1]).distance(b)
    assert dp < 1e-9 and da < 1e-9
    pts = np.array([robot.fk(qq).position for qq in q[::25]])
    assert np.abs(pts[:, 1:] - b.position[1:]).max() < 1e-9
    tm = run.segments[-1].chain.timing
    assert tm.jerk_free_time <= tm.duration <= 1.10 * tm.jerk_free_time


@pytest.mark.skipif(not _ipm.AVAILABLE, reason="the interior-point method runs compiled only")
def test_rounds_after_grid_splits_are_solved_by_the_interior_point_method(monkeypatch):
    """A random Panda LIN whose limit check splits the grid three times: every
    round, the first ones on each split grid included, converges in the
    interior-point method (none is handed to the cone solver), in a few
    hundred iterations over the whole plan, and the limits hold."""
    robot = load_arm("panda")
    rng = np.random.default_rng(1)
    q0 = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785]) + rng.uniform(-0.2, 0.2, robot.n_joints)
    mot, _ = _random_motion(rng, robot, q0)
    grids, cone, its = [], [], []
    solve_grid, clarabel, solve_round = engine.solve_grid, _socp._clarabel_solve, _ipm.solve_round

    def grid(p, *args, **kw):
        grids.append((p.s.size, kw.get("near", False)))
        return solve_grid(p, *args, **kw)

    def cone_solver(*args, **kw):
        cone.append(1)
        return clarabel(*args, **kw)

    def ipm(*args, **kw):
        out = solve_round(*args, **kw)
        its.append(out[3])
        return out

    monkeypatch.setattr(engine, "solve_grid", grid)
    monkeypatch.setattr(_socp, "_clarabel_solve", cone_solver)
    monkeypatch.setattr(_ipm, "solve_round", ipm)
    run = run_motions(robot, [mot], q0)
    assert sum(1 for _, near in grids if near) >= 3, grids  # (the case: three splits)
    assert cone == [] and max(its) < _ipm.IPM_MAX_ITER, its
    assert sum(its) < 250, its
    rv, ra, rj, _ = fd_ratios(robot, run)
    assert (rv <= 1 + FD_RTOL).all() and (ra <= 1 + FD_RTOL).all() and (rj <= 1 + FD_RTOL).all()


def test_the_jerk_rows_bound_the_jerk_at_the_slower_end_of_an_interval(monkeypatch):
    """The UR5's 0.8 m lateral LIN decelerates to rest with its elbow at the jerk
    limit: at the slower end of each interval there, the jerk's node terms
    oppose the path-jerk term. The rows take the node's own speed factor there
    (a larger one would loosen the row below the node's jerk): the first
    check of the pieces finds every joint's jerk within its limit, so that no
    re-solve is needed for the jerk."""
    robot = load_arm("ur5")
    q_home = np.array([0.0, -1.2, 1.5, -1.87, -1.57, 0.0])
    p0 = robot.fk(q_home)
    y = np.array([0.0, 0.4, 0.0])
    q0 = robot.ik_near(Pose(p0.position - y, p0.rotation), q_home)
    first = []
    check = engine._check

    def spy(*args, **kw):
        out = check(*args, **kw)
        if len(args) == 7:  # (the rounds' checks: not the path-limits screen, not the final)
            first.append(out[0])
        return out

    monkeypatch.setattr(engine, "_check", spy)
    run_motions(robot, [Lin(CartesianTarget(Pose(p0.position + y, p0.rotation)), 3.0, label="L")], q0)
    assert first[0].jerk.max() <= 1.0, first[0].jerk
    assert first[0].jerk.max() > 0.99  # (at the limit: the case)


def test_raising_the_programmed_speed_never_lengthens_a_lin():
    arm = default_arm6()
    q0 = np.radians([10.0, 25.0, 5.0, 20.0, 50.0, -30.0])
    p0 = arm.fk(q0)
    goal = Pose(p0.position + np.array([0.05, 0.30, -0.12]), rot_z(0.4) @ p0.rotation)
    speeds = [0.1, 0.2, 0.4, 0.7, 1.0, 1.2, 1.5, 2.0, 2.5, 3.0]
    durations = [run_motions(arm, [Lin(CartesianTarget(goal), v, label="L")], q0).duration
                 for v in speeds]
    # never longer than at a lower speed (up to the cone solver's tolerance where the
    # joints, not the programmed speed, limit both)
    for lo, hi in zip(durations, durations[1:]):
        assert hi <= lo * (1 + 1e-6), durations
    assert durations[-1] < 0.5 * durations[0]


def test_raising_the_programmed_speed_never_lengthens_random_lins():
    """A sweep of the programmed speed (0.05-3 m/s) on random LINs of the 6-axis
    arm, under its own tool limits (5 m/s^2, 50 m/s^3) and under four times
    higher ones. Where the tool's limits hold a LIN everywhere, its timing is
    their S-curve, the optimum, whose time never grows with the speed (to
    round-off); where the joints bind (from some speed on, or near a
    singularity) the grid problem times it: never longer than at a lower speed
    by more than the rounds' tolerance (ROUND_RTOL; measured: 3.5e-5 at most over 60
    LINs x 12 speeds).
    Both kinds occur in the sweep."""
    arm = default_arm6()
    rng = np.random.default_rng(11)
    q0 = np.radians([10.0, 25.0, 5.0, 20.0, 50.0, -30.0])
    p0 = arm.fk(q0)
    speeds = np.geomspace(0.05, 3.0, 12)
    seen = set()
    for tool_limits in ((5.0, 50.0), (20.0, 200.0)):
        arm.cartesian_accel, arm.cartesian_jerk = tool_limits
        done = 0
        while done < sweep_size(3):
            d = rng.normal(size=3)
            d *= rng.uniform(0.05, 0.35) / np.linalg.norm(d)
            goal = CartesianTarget(Pose(p0.position + d, rot_z(rng.uniform(-0.3, 0.3)) @ p0.rotation))
            try:
                runs = [run_motions(arm, [Lin(goal, float(v), label="L")], q0) for v in speeds]
            except UnreachableError:  # (outside the workspace or through a singularity)
                continue
            done += 1
            held = np.array([r.segments[-1].chain.timing.info["status"] == "path limits" for r in runs])
            seen |= set(held.tolist())
            durations = np.array([r.duration for r in runs])
            tol = np.where(held[:-1] & held[1:], 1e-12, _socp.ROUND_RTOL)
            assert (durations[1:] <= durations[:-1] * (1 + tol)).all(), (durations, held)
            assert durations[-1] < durations[0]
    assert seen == {True, False}


def test_an_arc_of_the_base_joint_alone_is_its_seven_phase_optimum():
    """A CIRC about the base axis moves joint 1 alone (the tool turns with it): the
    engine's time is that joint's 7-phase optimum."""
    arm = default_arm6()
    arm.cartesian_accel = 1e3
    arm.cartesian_jerk = 1e6
    arm.orientation_speed = 1e3
    q0 = np.radians([0.0, 20.0, 10.0, 0.0, 60.0, 0.0])
    q1 = q0.copy()
    q1[0] = math.radians(120.0)
    qm = q0.copy()
    qm[0] = math.radians(60.0)
    run = run_motions(arm, [Circ(CartesianTarget(arm.fk(qm)), CartesianTarget(arm.fk(q1)), 50.0,
                                 label="C")], q0)
    ref = plan_move(0.0, q1[0], arm.limits[0]).duration
    assert ref * (1 - 1e-9) <= run.duration <= ref * 1.005, (run.duration, ref)
    q = run.sample(np.linspace(0, run.duration, 200)).q
    assert np.abs(q[:, 1:] - q0[1:]).max() < 1e-9  # the other joints stand still


def test_no_crawl_at_the_ends_of_a_lin():
    """The joint path's derivatives at the ends are those of the kinematics: the tool
    leaves the start as fast as its jerk allows (no slow first millimetres)."""
    arm = default_arm6()
    q0 = np.radians([10.0, 25.0, 5.0, 20.0, 50.0, -30.0])
    p0 = arm.fk(q0)
    goal = Pose(p0.position + np.array([0.0, 0.3, 0.0]), p0.rotation)
    run = run_motions(arm, [Lin(CartesianTarget(goal), 1.0, label="L")], q0)
    tm = run.segments[-1].chain.timing
    _, d1, d2, d3 = tm.grid_derivatives
    # the third derivative at s = 0 against the kinematics on the extended line
    h = 1e-3
    ext = [arm.ik_near(Pose(p0.position + np.array([0.0, k * h, 0.0]), p0.rotation), q0)
           for k in (-2, -1, 0, 1, 2)]
    Q = np.array(ext)
    d3_ext = (Q[4] - 2 * Q[3] + 2 * Q[1] - Q[0]) / (2 * h**3)
    scale = np.abs(d3).max()
    assert np.abs(d3[0] - d3_ext).max() <= 1e-2 * scale
    # the first 2 mm take no longer than a jerk-limited start of the slowest joint allows
    t = np.linspace(0, tm.duration, 20001)
    s = tm.sample(t)[0]
    t2 = np.interp(0.002, s, t)
    jmin = min(lm.j_max / max(np.abs(d1[0, k]), 1e-12) for k, lm in enumerate(arm.limits))
    assert t2 <= 2.0 * (6 * 0.002 / jmin) ** (1 / 3)


def test_slow_downs_are_true_stretches():
    """A LIN past a slow spot: the report covers the slow stretch, not the whole line,
    and the speed it reports holds there."""
    arm = default_arm6()
    sing = arm.fk(np.array([0.0, 0.3, 0.2, 0.0, 0.0, 0.0]))
    a = Pose(sing.position + [0.0, 0.02, -0.15], sing.rotation)
    b = Pose(sing.position + [0.0, 0.02, 0.15], sing.rotation)
    q0 = arm.ik(a, "front-up-noflip")
    run = run_motions(arm, [Lin(CartesianTarget(b), 0.25, label="L")], q0)
    assert run.slowdowns
    slowest = min(run.slowdowns, key=lambda sd: sd.speed)
    length = np.linalg.norm(slowest.end_xyz - slowest.start_xyz)
    assert length < 0.5 * 0.3
    assert slowest.speed < 0.25
    smp = run.sample(np.linspace(0, run.duration, 4001))
    inside = np.linalg.norm(smp.xyz - 0.5 * (slowest.start_xyz + slowest.end_xyz), axis=1) < 0.5 * length
    assert smp.tool_speed[inside].min() == pytest.approx(slowest.speed, rel=2e-2)


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_the_final_grid_interpolates_the_derivatives_within_the_tolerance(name):
    """The first solve runs on a grid refined to FIRST_GRID_RTOL only; the grid
    of the final timing (with the nodes of the jerk phases) is refined to
    GRID_RTOL where the first grid was not already within it: refining the
    final grid again finds nothing to split (every cell's middle within the
    tolerance) on a blended chain of both arms."""
    from trajkit.robot._cartesian import _tool_curvature
    from trajkit.timing import engine, plan_path_timing

    robot = load_arm(name)
    q0 = np.array({"ur5": [0.0, -1.2, 1.5, -1.87, -1.57, 0.0],
                   "panda": [0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785]}[name])
    p0 = robot.fk(q0)

    def at(d):
        return CartesianTarget(Pose(p0.position + np.asarray(d), p0.rotation))

    run = run_motions(robot, [Lin(at([0.0, 0.2, 0.0]), 1.0, 0.03), Lin(at([0.1, 0.2, -0.1]), 1.0, 0.03),
                              Lin(at([0.1, 0.0, -0.1]), 1.0)], q0)
    path = run.segments[-1].chain.path
    tm = plan_path_timing(path, robot.limits, speed=lambda s: np.full(np.size(s), 1.0),
                          accel=robot.cartesian_accel, jerk=robot.cartesian_jerk,
                          curvature=lambda s: _tool_curvature(path, s))
    assert engine.FIRST_GRID_RTOL > engine.GRID_RTOL
    vlim = np.array([lm.v_max for lm in robot.limits])
    alim = np.array([min(lm.a_max, lm.a_max_decel) for lm in robot.limits])
    jlim = np.array([min(lm.j_max, lm.j_max_decel) for lm in robot.limits])
    breaks = np.asarray(path.breakpoints, dtype=float)
    breaks = np.unique(breaks[(breaks > 0.0) & (breaks < path.length)])
    grid, _, pending, err = engine._refine(path, tm.grid, tm.grid_derivatives, vlim, alim, jlim,
                                           lambda s: np.full(np.size(s), 1.0), breaks,
                                           engine.GRID_RTOL)
    np.testing.assert_array_equal(grid, tm.grid)
    assert pending.size == 0 and err.max() <= engine.GRID_RTOL


@pytest.mark.parametrize(("motion", "fractions"), [("lin", (0.05, 0.5, 0.7)), ("circ", (0.3, 0.7, 0.9, 0.95))])
def test_the_rest_of_a_path_is_planned_again_from_a_state_of_its_own_timing(motion, fractions,
                                                                            monkeypatch):
    """Online re-planning on the grid problem: the rest of a UR5 LIN (CIRC)
    planned again from the path state of its own timing at the given fractions
    of its duration (a state of a time-optimal timing, on its way to a limit
    at the full jerk limit; the path's own jerk limit binds). The path-limits
    S-curve is left out (the LIN is held by its path limits everywhere: that
    S-curve would be its timing, see the next test), so the grid problem
    plans both. Of the states 5 % apart, 14 of 19 on the LIN and 9 of 19 on
    the CIRC raised InfeasibleError before the relaxed rounds (those at 50 %,
    70 % and 30 %, 70 % here among them): the first jerk round, linearised at
    the jerk-free round's speeds, had no solution, and the slower retry
    cannot keep a moving start. At 5 % on the LIN the pieces next to the
    start exceed the path's full jerk limit by a fraction of a per cent:
    lowered there, not the fallback (22 % slower). At 90 % and 95 % on the
    CIRC, in its final stop with a joint's jerk binding (at 99.8 % of its
    limit in the first timing), no timing was found while the grid problem
    planned with 99.8 % of the jerk limits beyond the tenth of the path next
    to the start; with a moving state it now plans with the full limits. Each
    re-plan starts in the state, ends at the goal, keeps every limit, and
    takes the time the first timing had left to within 0.1 % (never less than
    the grid's jerk-free bound)."""
    from test_timing import LIMIT_RTOL, _dense_use

    from trajkit.robot._cartesian import _tool_curvature
    from trajkit.timing import PathRest, plan_path_timing

    monkeypatch.setattr(engine, "_path_limits_profile", lambda *args: None)
    robot = load_arm("ur5")
    q0 = np.array([0.0, -1.2, 1.5, -1.87, -1.57, 0.0])
    p0 = robot.fk(q0)

    def at(d):
        return CartesianTarget(Pose(p0.position + np.asarray(d), p0.rotation))

    mot = (Lin(at([0.0, 0.15, 0.05]), 3.0) if motion == "lin"
           else Circ(at([0.15, 0.15, 0.0]), at([0.0, 0.3, 0.0]), 3.0))
    path = run_motions(robot, [mot], q0).segments[-1].chain.path

    def plan(jp, s0=0.0, **state):
        return plan_path_timing(jp, robot.limits, speed=3.0, accel=robot.cartesian_accel,
                                jerk=robot.cartesian_jerk,
                                curvature=lambda s: _tool_curvature(path, np.asarray(s) + s0), **state)

    tm = plan(path)
    for frac in fractions:
        t0 = frac * tm.duration
        s0, v0, a0, _ = tm.sample(t0)[:, 0]
        rest = plan(PathRest(path, s0), s0, start_speed=v0, start_accel=a0)
        assert rest.info["status"] != "fallback" and rest.time_scale == 1.0
        assert rest.jerk_free_time <= rest.duration
        assert rest.duration == pytest.approx(tm.duration - t0, rel=1e-3), frac
        assert max(_dense_use(rest)) <= 1 + LIMIT_RTOL
        q, qd, qdd, _ = rest.joint_states([0.0, rest.duration])
        q_, qd_, qdd_, _ = tm.joint_states([t0, tm.duration])
        scale = np.array([lm.v_max for lm in robot.limits])
        np.testing.assert_allclose(q, q_, rtol=0, atol=1e-9)
        np.testing.assert_allclose(qd / scale, qd_ / scale, rtol=0, atol=1e-9)
        np.testing.assert_allclose(qdd[0], qdd_[0], rtol=0, atol=1e-8)
        assert np.abs(qd[1]).max() == 0.0 and np.abs(qdd[1]).max() == 0.0


def test_a_motion_held_by_its_path_limits_is_their_s_curve(monkeypatch):
    """A UR5 LIN of 0.16 m programmed at 3 m/s never reaches a joint limit: its
    feed is held by the path's own acceleration and jerk everywhere. The
    minimum-time S-curve of ``s`` under the path's limits alone is a lower
    bound of every timing (it drops the joints' limits), and here it keeps
    them: it is the timing, the optimum itself (the grid problem, planning with
    JERK_MARGIN of the jerk limits, is slower by up to 0.1 %). Re-planned from
    its own states, the final stop included (where the grid problem had no
    solution or a residual excess at 80 % and 90 % of the motion, and the
    fallback could not start), the rest is the same S-curve. A CIRC, whose
    joints bind, is planned on the grid and never beats that bound; the IK'd
    samples keep every limit."""
    from test_timing import LIMIT_RTOL, _dense_use

    from trajkit.profiles.state import plan_state_to_state
    from trajkit.robot._cartesian import _tool_curvature
    from trajkit.timing import PathRest, plan_path_timing

    robot = load_arm("ur5")
    q0 = np.array([0.0, -1.2, 1.5, -1.87, -1.57, 0.0])
    p0 = robot.fk(q0)

    def at(d):
        return CartesianTarget(Pose(p0.position + np.asarray(d), p0.rotation))

    path_limits = AxisLimits(3.0, robot.cartesian_accel, robot.cartesian_jerk)
    for mot in (Lin(at([0.0, 0.15, 0.05]), 3.0), Circ(at([0.15, 0.15, 0.0]), at([0.0, 0.3, 0.0]), 3.0)):
        run = run_motions(robot, [mot], q0)
        path = run.segments[-1].chain.path

        def plan(jp, s0=0.0, path=path, **state):
            return plan_path_timing(jp, robot.limits, speed=3.0, accel=robot.cartesian_accel,
                                    jerk=robot.cartesian_jerk,
                                    curvature=lambda s: _tool_curvature(path, np.asarray(s) + s0), **state)

        tm = plan(path)
        bound = plan_move(0.0, path.length, path_limits).duration
        rv, ra, rj, _ = fd_ratios(robot, run)
        assert (rv <= 1 + FD_RTOL).all() and (ra <= 1 + FD_RTOL).all() and (rj <= 1 + FD_RTOL).all()
        assert max(_dense_use(tm)) <= 1 + LIMIT_RTOL
        if isinstance(mot, Circ):
            assert tm.info["status"] != "path limits"
            assert tm.duration > bound
            continue
        assert tm.info["status"] == "path limits" and tm.time_scale == 1.0
        assert tm.duration == pytest.approx(bound, rel=1e-12)
        assert run.segments[-1].chain.timing.info["status"] == "path limits"
        with monkeypatch.context() as mp:  # the grid problem's timing: never faster
            mp.setattr(engine, "_path_limits_profile", lambda *args: None)
            grid = plan(path)
        assert grid.info["status"] != "path limits"
        assert tm.duration <= grid.duration <= tm.duration * 1.001
        for frac in (0.2, 0.5, 0.8, 0.9, 0.97):
            t0 = frac * tm.duration
            s0, v0, a0, _ = tm.sample(t0)[:, 0]
            rest = plan(PathRest(path, s0), s0, start_speed=v0, start_accel=a0)
            assert rest.info["status"] == "path limits"
            left = plan_state_to_state((0.0, v0, a0), (path.length - s0, 0.0, 0.0), path_limits)
            assert rest.duration == pytest.approx(left.duration, rel=1e-12)
            assert rest.duration == pytest.approx(tm.duration - t0, rel=1e-9), frac
            assert max(_dense_use(rest)) <= 1 + LIMIT_RTOL
            np.testing.assert_allclose(rest.sample(0.0)[:3, 0], [0.0, v0, a0], rtol=0, atol=1e-12)
            np.testing.assert_allclose(rest.sample(rest.duration)[:3, 0], [path.length - s0, 0, 0],
                                       rtol=0, atol=1e-12)


@pytest.mark.parametrize(("motion", "frac"), [("lateral", 0.05), ("turn", 0.7)])
def test_re_plans_of_the_benchmark_lins_from_their_own_states(motion, frac):
    """Two of the benchmark's UR5 LINs re-planned from the path state of their own
    timing, each of which raised InfeasibleError:

    - the 0.8 m lateral LIN at 5 % of its duration (the elbow's acceleration
      ramping to its limit): the pieces of every attempt exceeded a joint's
      acceleration limit by 3.7e-8 of it between the check points, where only
      the final check's zoom found it; a moving state cannot take that as a
      uniform slow-down. With a moving state the rounds' check is the final
      check's (the true derivatives where it comes close, the zoom's samples
      too), so the limits are lowered where the zoom finds the excess;
    - the LIN with a 90 + 30 degree turn at 70 % (37 mm before its end): the
      first jerk round, linearised at the jerk-free round's speeds, came out
      2e8 times slower than them (its tangent planes held the speed near zero
      at a node), and no later round left that near-stop. Such a round now
      counts as without a solution (STALL_FACTOR), and the relaxed rounds
      take over.

    Each re-plan starts in the state, ends at rest at the goal, keeps every
    limit and takes the time the first timing had left to within 0.1 %."""
    from test_timing import LIMIT_RTOL, _dense_use

    from trajkit.robot._cartesian import _tool_curvature
    from trajkit.timing import PathRest, plan_path_timing

    robot = load_arm("ur5")
    q_home = np.array([0.0, -1.2, 1.5, -1.87, -1.57, 0.0])
    p0 = robot.fk(q_home)
    if motion == "lateral":
        y = np.array([0.0, 0.4, 0.0])
        q0 = robot.ik_near(Pose(p0.position - y, p0.rotation), q_home)
        goal = Pose(p0.position + y, p0.rotation)
    else:
        q0 = q_home
        goal = Pose(p0.position + np.array([0.05, 0.25, 0.0]),
                    rot_z(math.pi / 2) @ rot_x(math.pi / 6) @ p0.rotation)
    run = run_motions(robot, [Lin(CartesianTarget(goal), 3.0)], q0)
    path = run.segments[-1].chain.path

    def plan(jp, s0=0.0, **state):
        return plan_path_timing(jp, robot.limits, speed=lambda s: np.full(np.size(s), 3.0), accel=1e3,
                                jerk=1e6, curvature=lambda s: _tool_curvature(path, np.asarray(s) + s0),
                                **state)

    tm = plan(path)
    t0 = frac * tm.duration
    s0, v0, a0, _ = tm.sample(t0)[:, 0]
    rest = plan(PathRest(path, s0), s0, start_speed=v0, start_accel=a0)
    assert rest.info["status"] == "Solved" and rest.time_scale == 1.0
    assert rest.duration == pytest.approx(tm.duration - t0, rel=1e-3)
    assert max(_dense_use(rest)) <= 1 + LIMIT_RTOL
    np.testing.assert_allclose(rest.sample(0.0)[:3, 0], [0.0, v0, a0], rtol=0, atol=1e-12)
    q, qd, qdd, _ = rest.joint_states([rest.duration])
    np.testing.assert_allclose(q[0], tm.joint_states([tm.duration])[0][0], rtol=0, atol=1e-9)
    assert np.abs(qd).max() == 0.0 and np.abs(qdd).max() == 0.0


@pytest.mark.parametrize(("model", "seed", "index", "frac", "binds", "longer"),
                         [("scara", 952, 6, 0.5, True, 1e-3), ("ur5", 901, 6, 0.7, True, 1e-3),
                          ("panda", 951, 2, 0.3, False, 2e-3), ("arm6", 900, 2, 0.1, False, 1e-3),
                          ("ur5", 901, 1, 0.5, False, 1e-3)])
def test_re_plans_of_random_sharp_corner_chains(model, seed, index, frac, binds, longer):
    """Chains through sharp corners (the random chains of ``test_robot_jerk``, drawn
    from ``seed``) re-planned from their own state at ``frac`` of the duration; each
    raised InfeasibleError (28 of 275 such re-plans of 54 random chains on five
    arms did):

    - where the tool's acceleration (tangential and normal) binds (``binds``):
      between two nodes it went over its limit by 5e-5 of it. With a moving
      state that cannot be a uniform slow-down, and the path's acceleration was
      not lowered locally, so every round found the same excess (14 of the 28).
      Now that limit is lowered at the nodes of the pieces above it;
    - an excess of the path's jerk of 2e-9 of its limit (Panda), of a joint's
      jerk of 8.5e-8 (arm6), left after the last round: lowered locally, such
      an excess, the round-off of the linearised rows, turned up in another
      piece in the next round. Now it lowers that limit everywhere by ten times
      itself, and a moving state gets eight rounds (were six);
    - a timing within the limits found in a later round, passed over for an
      earlier, shorter one 0.32 % above a joint's jerk limit (UR5), which a
      moving state cannot slow down uniformly. With a moving state a timing
      within the limits now comes before any other (6 of the 28).

    The re-plan keeps every joint limit and the tool's acceleration limit (on
    the exact derivatives at 40 points of every piece), is at most ``longer``
    (a fraction) longer than the time the first timing had left and at most
    0.2 % shorter (the first timing planned with 99.8 % of the jerk limits)."""
    from trajkit.timing import PathRest

    plan, path, a_tool, left, (s0, v0, a0) = _sharp_chain_state(model, seed, index, frac)
    rest = plan(PathRest(path, s0), s0, start_speed=v0, start_accel=a0)
    tool = _check_sharp_re_plan(rest, path, s0, (v0, a0), left, longer, a_tool)
    assert (tool >= 0.999 * a_tool) == binds


def _sharp_chain_state(model, seed, index, frac, legs=False):
    """The ``index``-th random sharp-corner chain of ``seed`` on ``model`` (the
    chains of ``test_robot_jerk``), planned from rest: ``(plan, path, a_tool, left,
    (s0, v0, a0))`` with ``plan(jp, s0=0.0, **state)`` the chain's planning call on
    ``jp`` (a re-plan from ``s0``), the tool's acceleration limit, the time left after
    ``frac`` of the duration and the path state there. ``legs``: the robot with
    separate legs (``test_robot_jerk._with_legs``)."""
    from test_robot_jerk import _nth_chain, _robot, _with_legs

    from trajkit.robot._cartesian import _tool_curvature
    from trajkit.timing import plan_path_timing

    robot = _with_legs(_robot(model)) if legs else _robot(model)
    q0, mots = _nth_chain(robot, model, seed, index)
    path = run_motions(robot, mots, q0).segments[0].chain.path

    def plan(jp, s0=0.0, **state):
        return plan_path_timing(jp, robot.limits, speed=mots[0].speed, accel=robot.cartesian_accel,
                                jerk=robot.cartesian_jerk,
                                curvature=lambda s: _tool_curvature(path, np.asarray(s) + s0), **state)

    tm = plan(path)
    t0 = frac * tm.duration
    s0, v0, a0, _ = tm.sample(t0)[:, 0]
    return plan, path, robot.cartesian_accel, tm.duration - t0, (s0, v0, a0)


def _check_sharp_re_plan(rest, path, s0, start, left, longer, a_tool, shorter=2e-3):
    """A re-plan from ``s0`` in the state ``start`` (speed, acceleration) is solved
    without a uniform slow-down, keeps every joint limit and the tool's acceleration
    limit ``a_tool`` (on the exact derivatives at 40 points of every piece), starts in
    that state and takes between ``1 - shorter`` and ``1 + longer`` times ``left``;
    returns the tool's largest acceleration."""
    from test_timing import LIMIT_RTOL, _dense_use

    from trajkit.robot._cartesian import _tool_curvature

    assert rest.info["status"] == "Solved" and rest.time_scale == 1.0
    assert (1 - shorter) * left <= rest.duration <= (1 + longer) * left
    assert max(_dense_use(rest, 40)) <= 1 + LIMIT_RTOL
    t = (rest.t[:-1, None] + np.diff(rest.t)[:, None] * np.linspace(0.0, 1.0, 40)[None, :]).ravel()
    ss, sd, sdd, _ = rest.sample(t)
    tool = np.hypot(sdd, _tool_curvature(path, ss + s0) * sd * sd)
    assert tool.max() <= a_tool * (1 + LIMIT_RTOL)
    np.testing.assert_allclose(rest.sample(0.0)[:3, 0], [0.0, *start], rtol=0, atol=1e-12)
    return float(tool.max())


def test_a_re_plan_with_separate_legs_past_a_corner_blend():
    """An arm6 chain through sharp corners with separate legs (deceleration 0.6 of
    the acceleration limit, its jerk 0.5), re-planned from its state at half its
    duration, raised InfeasibleError for two reasons:

    - ``PathRest`` shifts the engine's points by the start, and the sum
      rounded the point just before a corner blend's breakpoint onto the
      breakpoint: the derivatives the engine takes from the piece that ends
      there came from the blend after it (a joint's third derivative 400221
      instead of -3021), and the check with the true derivatives found that
      joint's jerk 25 % over its limit, in every attempt;
    - with that mended, an attempt 0.25 % above a limit was followed by
      attempts twice over the joint's braking jerk limit, which the rounds of
      local lowering lowered by at most 1 % each (1.05 left after eight).
      That bound now grows with every attempt in a row above the least excess.

    The re-plan keeps every limit and takes the time the first timing had
    left to within 0.2 % (0.9996 of it)."""
    from trajkit.timing import PathRest

    plan, path, a_tool, left, (s0, v0, a0) = _sharp_chain_state("arm6", 900, 7, 0.5, legs=True)
    assert np.any(np.abs(np.asarray(path.breakpoints) - s0 - 0.018) < 1e-3)
    rest = plan(PathRest(path, s0), s0, start_speed=v0, start_accel=a0)
    _check_sharp_re_plan(rest, path, s0, (v0, a0), left, 2e-3, a_tool)


def test_a_re_plan_whose_first_solve_on_the_fine_grid_ends_relaxed():
    """A palletizer chain through sharp corners with separate legs, re-planned from
    its state at half its duration (braking hard: 0.26 m/s, -3.2 m/s^2): the grid
    problem's first solve found a timing on the coarse grid, but on the fine grid,
    started from that solution, its first jerk round had no solution and the
    relaxed rounds did not reach one either; the fallback cannot start in such a
    state, and InfeasibleError was raised. That solve now starts again from the
    jerk-free round, as the coarse grid's did. The re-plan keeps every limit and
    takes 0.4 % less than the time the first timing had left to 0.1 % more
    (0.9976 of it: with separate legs the rest of a timing from rest is not
    always the shortest from one of its states)."""
    from trajkit.timing import PathRest

    plan, path, a_tool, left, (s0, v0, a0) = _sharp_chain_state("palletizer", 950, 2, 0.5, legs=True)
    assert v0 > 0.25 and a0 < -3.0
    rest = plan(PathRest(path, s0), s0, start_speed=v0, start_accel=a0)
    _check_sharp_re_plan(rest, path, s0, (v0, a0), left, 1e-3, a_tool, shorter=4e-3)


def test_a_re_plan_whose_split_grid_ends_relaxed_again():
    """A Panda chain through sharp corners with separate legs, re-planned from
    its state at 70 % of its duration (0.07 m/s, braking): on the second grid
    the solve from the first grid's solution ended relaxed and its restart
    from the jerk-free round stalled (1e7 s); the check split the grid there,
    the split grid's solve from that stalled solution ended relaxed, and the
    stalled solution (4600 times over a jerk limit) was the only attempt left:
    InfeasibleError. Until an attempt comes within 1 % of the limits, a solve
    that ends relaxed or stalls is solved again from its jerk-free round,
    whatever was tried before. The re-plan keeps every limit and takes the
    time the first timing had left to within 0.1 %."""
    from trajkit.timing import PathRest

    plan, path, a_tool, left, (s0, v0, a0) = _sharp_chain_state("panda", 951, 1, 0.7, legs=True)
    assert v0 < 0.1 and a0 < -0.4
    rest = plan(PathRest(path, s0), s0, start_speed=v0, start_accel=a0)
    _check_sharp_re_plan(rest, path, s0, (v0, a0), left, 1e-3, a_tool, shorter=1e-3)


def test_a_re_plan_from_a_near_stop_braking_start():
    """A palletizer chain through sharp corners with separate legs, re-planned from
    its state at 70 % of its duration: 0.033 m/s braking at -1.2 m/s^2, on its way
    to a near-stop (the first timing's speed dips to 0.0165 m/s). The first jerk
    round is linearised at the start's recovery: at the jerk of the start alone
    it came to 0.00015 m/s, every solve on every grid ended relaxed and
    InfeasibleError was raised; node by node, at the jerk the joints allow in
    each cell's state, the recovery ends at 0.018 m/s. The re-plan keeps every
    limit and takes 0.5 % less than the time the first timing had left to 0.1 %
    more (0.995 of it: with separate legs the rest of a timing from rest is not
    always the shortest from one of its states)."""
    from trajkit.timing import PathRest

    plan, path, a_tool, left, (s0, v0, a0) = _sharp_chain_state("palletizer", 950, 8, 0.7, legs=True)
    assert v0 < 0.04 and a0 < -1.0
    rest = plan(PathRest(path, s0), s0, start_speed=v0, start_accel=a0)
    _check_sharp_re_plan(rest, path, s0, (v0, a0), left, 1e-3, a_tool, shorter=6e-3)


def test_a_re_plan_just_before_a_speed_dip():
    """A Panda chain through sharp corners, re-planned from its state 3 ms before a
    speed minimum (0.026 m/s braking at -0.089 m/s^2): one cell's jerk excess
    (0.16 %, below the split threshold) stayed the same through every local
    lowering of the limits, and the last attempt ended 0.0093 % over a joint's
    jerk limit: InfeasibleError. A cell whose excess a lowering does not halve is
    now split. The re-plan keeps every limit and takes the time the first timing
    had left to within 0.3 % less and 0.1 % more (0.9981 of it)."""
    from trajkit.timing import PathRest

    plan, path, a_tool, left, (s0, v0, a0) = _sharp_chain_state("panda", 951, 3, 0.7030015304568528)
    assert v0 < 0.03 and a0 < -0.05
    rest = plan(PathRest(path, s0), s0, start_speed=v0, start_accel=a0)
    _check_sharp_re_plan(rest, path, s0, (v0, a0), left, 1e-3, a_tool, shorter=3e-3)


def test_a_re_plan_whose_last_attempt_ends_at_the_round_off():
    """A Panda chain with separate legs, re-planned from its state at a tenth of its
    duration (0.20 m/s speeding up at 1.5 m/s^2): its eight local lowerings went
    astray (32 % over a joint's jerk limit) and came back, and the last one ended
    4e-8 over a limit: at the round-off of the linearised rows, but with a moving
    start there is no uniform slow-down, and the re-plan raised InfeasibleError.
    Such an excess now gets up to two more attempts (the limit lowered everywhere
    by ten times the excess): the re-plan keeps every limit and takes the time
    the first timing had left to within 0.2 % less."""
    from trajkit.timing import PathRest

    plan, path, a_tool, left, (s0, v0, a0) = _sharp_chain_state("panda", 951, 0, 0.1, legs=True)
    assert v0 > 0.15 and a0 > 1.0
    rest = plan(PathRest(path, s0), s0, start_speed=v0, start_accel=a0)
    _check_sharp_re_plan(rest, path, s0, (v0, a0), left, 1e-3, a_tool)


def test_a_chain_whose_last_line_is_short_reaches_its_target():
    """An arm6 chain of a 300 mm line and a 1.5 mm one, with a 0.5 mm zone: the
    blend's last breakpoint lies 1 mm before the path's end, within a quarter of
    the grid's regular spacing, and the end node was dropped with the regular
    nodes that close to it: the timing ended at the breakpoint and the tool
    stopped 1 mm short of its target. It now ends at the path's end, the tool at
    its target, within every joint limit."""
    robot = default_arm6()
    q0 = np.array([0.0, 0.3, 0.5, 0.0, 0.6, 0.0])
    p0 = robot.fk(q0)

    def at(d):
        return Pose.trusted(p0.position + np.asarray(d, dtype=float), p0.rotation)

    target = at([0.0, 0.3, 0.0015])
    run = run_motions(robot, [Lin(CartesianTarget(at([0.0, 0.3, 0.0])), 1.0, 0.0005),
                              Lin(CartesianTarget(target), 1.0, 0.0)], q0)
    (seg,) = [sg for sg in run.segments if sg.kind == "CP"]
    path, tm = seg.chain.path, seg.chain.timing
    assert path.length - path.breakpoints[-1] < 0.25 * path.length / engine.GRID_START
    assert tm.grid[-1] == path.length
    assert tm.sample(tm.duration)[0, 0] == pytest.approx(path.length, rel=1e-12)
    q_end = seg.chain.sample(np.array([seg.duration]))["q"][-1]
    np.testing.assert_allclose(robot.fk(q_end).position, target.position, rtol=0, atol=1e-9)
    assert tm.limit_use.worst <= 1 + 1e-9


def test_a_re_plan_that_starts_just_before_a_corner_blend():
    """A palletizer chain through sharp corners with separate legs, re-planned
    from its state at 30 % of its duration, 0.47 mm before a corner blend's
    breakpoint (braking hard at low speed: 0.10 m/s, -2.2 m/s^2). The grid's
    regular nodes within a quarter of its spacing of a breakpoint are dropped,
    and the start node was one of them: the grid problem started the motion at
    the breakpoint's twin node, a start its rounds could not keep (InfeasibleError
    after every relaxed round). The re-plan keeps every limit and takes the time
    the first timing had left to within 0.1 %."""
    from trajkit.timing import PathRest

    plan, path, a_tool, left, (s0, v0, a0) = _sharp_chain_state("palletizer", 950, 6, 0.3, legs=True)
    assert np.any(np.abs(np.asarray(path.breakpoints) - s0 - 4.7e-4) < 1e-5)
    rest = plan(PathRest(path, s0), s0, start_speed=v0, start_accel=a0)
    assert rest.grid[0] == 0.0
    _check_sharp_re_plan(rest, path, s0, (v0, a0), left, 1e-3, a_tool)


def test_re_plans_from_start_states_a_round_off_apart_agree():
    """A re-plan of a sharp-corner chain (UR5, the one of the test above whose
    timing within the limits came after a shorter one above them) from its state
    at half its duration, and from two states that differ from it by about 1e-13
    (relative, in speed and acceleration): within the limits, no more than 0.1 %
    longer than the time left, and the same to 1e-6. Their rounds of local
    lowering differed: the second one's timing was 10 % longer (1.101 of the
    time left; the others 1.006 and 1.0034; the state with 20 such offsets:
    1.0034 to 1.101), after an attempt whose linearised rounds went astray (a
    joint's jerk 4.35 times its limit) had its limits lowered by that ratio;
    with a moving state no limit is now lowered in one round by more than the
    least excess of the attempts before (1.0022 to 1.0115 over those 20).
    ``PathRest`` evaluated the point just before a corner's breakpoint on the
    piece after it, as the shift by the start rounded onto the breakpoint: with
    that mended, all 20 give 0.99809 of the time left."""
    from trajkit.timing import PathRest

    plan, path, a_tool, left, (s0, v0, a0) = _sharp_chain_state("ur5", 901, 1, 0.5)
    durations = []
    for dv, da in ((0.0, 0.0), (-2.71116248e-13, -1.88901325e-13), (9.05355867e-14, 4.46374572e-14)):
        start = (v0 * (1 + dv), a0 * (1 + da))
        rest = plan(PathRest(path, s0), s0, start_speed=start[0], start_accel=start[1])
        _check_sharp_re_plan(rest, path, s0, start, left, 1e-3, a_tool)
        durations.append(rest.duration)
    assert max(durations) <= min(durations) * (1 + 1e-6), durations
