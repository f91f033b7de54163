"""Path timing against TOPP-RA, side by side in one run.

For every motion of the suite, trajkit's path-timing engine and TOPP-RA
(PyPI ``toppra``, the reference time-optimal path parameterisation, which has
no jerk limit) time exactly the same geometric joint path under the same joint
velocity and acceleration limits; trajkit also keeps every joint's jerk limit.
TOPP-RA's time is therefore a lower bound of trajkit's: the ratio says what
the jerk limit costs plus how far trajkit is from its own optimum.

Two more columns separate the two for the arms:

- ``jerk bound``: every joint has to go from its start to its goal position
  starting and ending at rest within its own v, a and j, so the longest of the
  joints' one-axis time-optimal (7-phase) moves is a lower bound of any
  jerk-limited motion along the path; ``/bound`` is trajkit's time over the
  larger of the two bounds (TOPP-RA's and this one);
- ``saturated``: the share of the motion's time during which some joint runs
  within 5 % of its velocity, acceleration or jerk limit (a time-optimal
  timing has a limit active at every instant, otherwise it could go faster
  there).

Suite:

- UR5 and Panda (``example-robot-data``, through the URDF support): LIN and
  CIRC motions (long and short, near a singularity, with orientation change)
  and blended chains; joint velocity limits from the URDF, a = 5 v, j = 50 v;
  the programmed tool speed high enough that the joints limit the motion;
- the saddle machine (theta, Z) on four seams, the feed a third "joint" for
  TOPP-RA (velocity = feed, acceleration = tangential limit);
- random joint-space waypoint sets (6 axes, 5 to 20 waypoints), against
  stopping at every waypoint (ruckig rest-to-rest per segment).

Planning time (``plan [s]``) is the engine's: for an arm motion the call its
chain's planner makes, timed on its own; for a seam the engine's calls inside
the seam's plan, summed (the summary also gives the whole seam plan, with its
arc-length table, chord-error speed limit and axis verification). TOPP-RA's
(``peer [s]``) is its solve on the same number of grid points, its spline of
the joint path made beforehand. Both are the best of :data:`REPEAT` runs. A
check of many samples uses a second core where one is free.

Run::

    python benchmarks/bench_paths.py            # the whole suite (a few minutes)
    python benchmarks/bench_paths.py --quick    # one motion per group

Prints a table per group and the summary (mean and largest ratio).
"""

from __future__ import annotations

import argparse
import importlib.metadata as md
import math
import os
import statistics
import sys
import time

import numpy as np

from trajkit import AxisLimits, plan_move
from trajkit.interpolation import SaddleMachine, plan_saddle
from trajkit.interpolation.machine import SaddleAxesPath
from trajkit.kinematics.base import Pose, rot_x, rot_z
from trajkit.kinematics.urdf import UrdfRobot
from trajkit.paths import SaddleCurve
from trajkit.robot import CartesianTarget, Circ, Lin, run_motions
from trajkit.robot._cartesian import _tool_curvature
from trajkit.timing import plan_path_timing, plan_waypoints

#: Samples of the joint path handed to TOPP-RA's spline.
SPLINE_POINTS = 2001

#: TOPP-RA's grid for the bound (its time on trajkit's own grid size is what the
#: planning-time column compares).
BOUND_GRID = 2000


def _robots_dir() -> str:
    return str(md.distribution("example-robot-data").locate_file(
        "cmeel.prefix/share/example-robot-data/robots"))


def load_arm(name: str) -> UrdfRobot:
    """UR5 or Panda with v from the URDF, a = 5 v, j = 50 v, tool limits out of the way."""
    base = _robots_dir()
    path, tip = {"ur5": ("ur_description/urdf/ur5_robot.urdf", "tool0"),
                 "panda": ("panda_description/urdf/panda.urdf", "panda_hand")}[name]
    raw = UrdfRobot(os.path.join(base, path), tip)
    lims = [AxisLimits(lm.v_max, 5 * lm.v_max, 50 * lm.v_max, position_min=lm.position_min,
                       position_max=lm.position_max, name=lm.name) for lm in raw.limits]
    rob = UrdfRobot(os.path.join(base, path), tip, limits=lims, name=name)
    rob.cartesian_accel = 1e3
    rob.cartesian_jerk = 1e6
    rob.orientation_speed = 1e3
    return rob


def arm_suite(name: str):
    """(label, start joints, motions) of the arm's suite."""
    rob = load_arm(name)
    if name == "ur5":
        q0 = np.array([0.0, -1.2, 1.5, -1.87, -1.57, 0.0])
    else:
        q0 = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785])
    p0 = rob.fk(q0)
    pos, R = p0.position, p0.rotation
    v = 3.0
    out = []

    def lin(target, zone=0.0, label="L"):
        return Lin(CartesianTarget(target), v, zone, label=label)

    def at(d, rot=None):
        return Pose.trusted(pos + np.asarray(d, dtype=float), R if rot is None else rot @ R)

    y = np.array([0.0, 1.0, 0.0])
    out.append(("LIN 0.8 m lateral", q0, [lin(at(0.4 * y))], at(-0.4 * y)))
    out.append(("LIN 0.16 m short", q0, [lin(at([0.0, 0.15, 0.05]))], None))
    turn = rot_z(math.pi / 2) @ rot_x(math.pi / 6)
    out.append(("LIN with 90 + 30 deg turn", q0, [lin(at([0.05, 0.25, 0.0], turn))], None))
    if name == "ur5":
        # the TCP starts at the shoulder offset's y (d4): along x at that y the wrist
        # passes the base axis, the shoulder singularity (the Jacobian's smallest
        # singular value 0.006 at x = -9 mm); this line runs 16 mm beside it
        out.append(("LIN 0.8 m, 16 mm from shoulder singularity", q0,
                    [lin(at([-0.4 - pos[0], 0.016, 0.0]))], at([0.4 - pos[0], 0.016, 0.0])))
    radial = pos * np.array([1.0, 1.0, 0.0])
    out.append(("LIN radial toward reach", q0, [lin(at(0.12 * radial / np.linalg.norm(radial)))], None))
    out.append(("CIRC half circle", q0, [Circ(CartesianTarget(at([0.15, 0.15, 0.0])),
                                             CartesianTarget(at([0.0, 0.3, 0.0])), v, label="C")], None))
    out.append(("LIN-LIN-LIN, 30 mm zones", q0, [lin(at([0.0, 0.2, 0.0]), 0.03),
                                                  lin(at([0.1, 0.2, -0.1]), 0.03),
                                                  lin(at([0.1, 0.0, -0.1]))], None))
    out.append(("LIN into CIRC, 40 mm zone", q0, [lin(at([0.0, 0.15, 0.0]), 0.04),
                                                  Circ(CartesianTarget(at([0.1, 0.25, 0.0])),
                                                       CartesianTarget(at([0.2, 0.15, 0.0])), v, label="C")],
                None))
    return rob, out


#: Planning times are the best of this many runs (trajkit's and TOPP-RA's alike).
REPEAT = 3


def toppra_time(jp, limits, grid, extra=None):
    """TOPP-RA's duration and planning time on the joint path ``jp`` (same grid size)."""
    import toppra as ta
    import toppra.algorithm as algo
    import toppra.constraint as constraint

    ta.setup_logging("WARNING")
    L = jp.length
    ss = np.linspace(0.0, L, SPLINE_POINTS)
    q = jp.derivatives(ss)[0]
    v = np.array([lm.v_max for lm in limits])
    a = np.array([min(lm.a_max, lm.a_max_decel) for lm in limits])
    if extra is not None:  # the path parameter itself as a joint (tool speed, tangential acc.)
        q = np.column_stack([q, ss])
        v = np.append(v, extra[0])
        a = np.append(a, extra[1])
    path = ta.SplineInterpolator(ss, q)

    def solve(n):
        inst = algo.TOPPRA([constraint.JointVelocityConstraint(np.column_stack([-v, v])),
                            constraint.JointAccelerationConstraint(np.column_stack([-a, a]))],
                           path, gridpoints=np.linspace(0.0, L, n), parametrizer="ParametrizeConstAccel")
        return inst.compute_trajectory()

    dt = math.inf
    for _ in range(REPEAT):  # planning time on trajkit's grid size (the best of REPEAT)
        t0 = time.perf_counter()
        solve(grid.size)
        dt = min(dt, time.perf_counter() - t0)
    traj = solve(BOUND_GRID)  # the bound: a fine grid (a coarse one is slow at the ends)
    return (float(traj.duration) if traj is not None else math.nan), dt


def run_arms(quick: bool):
    rows = []
    for name in ("ur5", "panda"):
        rob, suite = arm_suite(name)
        for label, q0, mots, first in suite[: 2 if quick else None]:
            if first is not None:  # move to the start of the line first (not timed)
                q0 = rob.ik_near(first, q0)
            run = run_motions(rob, mots, q0)
            chains = [sg.chain for sg in run.segments if sg.kind == "CP"]
            for ch in chains:
                tm = ch.timing
                # the call the chain's planner makes (tool speed, tangential acceleration
                # with the tool path's curvature, jerk), timed on its own
                engine_s = math.inf
                for _ in range(REPEAT):
                    t0 = time.perf_counter()
                    plan_path_timing(ch.path, rob.limits, speed=lambda s: np.full(np.size(s), 3.0),
                                     accel=rob.cartesian_accel, jerk=rob.cartesian_jerk,
                                     curvature=lambda s, p=ch.path: _tool_curvature(p, s))
                    engine_s = min(engine_s, time.perf_counter() - t0)
                tt, tt_s = toppra_time(ch.path, rob.limits, tm.grid, extra=(3.0, rob.cartesian_accel))
                jb = jerk_bound(ch.path, rob.limits)
                rows.append(dict(label=f"{name}: {label}", t=tm.duration, ref=tt, ratio=tm.duration / tt,
                                 plan=engine_s, peer=tt_s, nodes=tm.grid.size, jerk_bound=jb,
                                 to_bound=tm.duration / max(tt, jb), saturated=saturation(tm, rob.limits)))
    return rows


def jerk_bound(jp, limits) -> float:
    """The longest one-joint rest-to-rest time-optimal move between the path's ends [s]."""
    q = jp.derivatives(np.array([0.0, jp.length]))[0]
    return max(plan_move(float(q[0, k]), float(q[1, k]), lm).duration if q[0, k] != q[1, k] else 0.0
               for k, lm in enumerate(limits))


def saturation(tm, limits, samples: int = 20001, level: float = 0.95) -> float:
    """Share of the duration with some joint at ``level`` of a v, a or j limit or more."""
    t = np.linspace(0.0, tm.duration, samples)
    _, qd, qdd, qddd = tm.joint_states(t)
    v = np.array([lm.v_max for lm in limits])
    a = np.array([min(lm.a_max, lm.a_max_decel) for lm in limits])
    j = np.array([min(lm.j_max, lm.j_max_decel) for lm in limits])
    use = np.maximum.reduce([np.abs(qd) / v, np.abs(qdd) / a, np.abs(qddd) / j]).max(axis=1)
    return float(np.mean(use >= level))


SEAMS = [(0.11, 0.1, 90.0, 0.0), (0.2, 0.1, 90.0, 0.0), (0.15, 0.1, 60.0, 0.0), (0.16, 0.1, 90.0, 0.04)]


class _EngineClock:
    """Inside ``with``: the time spent in the path-timing engine's calls, summed
    (the engine's share of a plan, as the arms' rows time the engine's call)."""

    def __init__(self) -> None:
        self.seconds = 0.0

    def __enter__(self):
        import trajkit.timing as timing

        self._module, self._orig = timing, timing.plan_path_timing

        def timed(*args, **kwargs):
            t0 = time.perf_counter()
            try:
                return self._orig(*args, **kwargs)
            finally:
                self.seconds += time.perf_counter() - t0

        timing.plan_path_timing = timed
        return self

    def __exit__(self, *exc) -> None:
        self._module.plan_path_timing = self._orig


def run_saddles(quick: bool):
    rows = []
    d2r = math.pi / 180
    machine = SaddleMachine(AxisLimits(180 * d2r, 720 * d2r, 7200 * d2r, name="theta"),
                            AxisLimits(0.04, 1.0, 10.0, name="z_axis"))
    feed, acc, jerk = 0.05, 0.5, 5.0
    for R, r, ang, off in SEAMS[: 1 if quick else None]:
        curve = SaddleCurve(R, r, math.radians(ang), off)
        engine_s = whole = math.inf
        for _ in range(REPEAT):
            engine = _EngineClock()
            t0 = time.perf_counter()
            with engine:
                plan = plan_saddle(curve, feed, acc, jerk, machine, 1e-5, 0.001)
            whole = min(whole, time.perf_counter() - t0)
            engine_s = min(engine_s, engine.seconds)
        tm = plan.feed_plan.profiles[0]
        grid = tm.grid if tm is not None else np.linspace(0, curve.length, 400)
        tt, tt_s = toppra_time(SaddleAxesPath(curve), [machine.theta, machine.z], grid,
                               extra=(feed, acc))
        rows.append(dict(label=f"saddle R={R * 1e3:g} r={r * 1e3:g} {ang:g} deg off {off * 1e3:g}",
                         t=plan.duration, ref=tt, ratio=plan.duration / tt, plan=engine_s,
                         peer=tt_s, nodes=grid.size, whole=whole))
    return rows


#: The waypoint sets' limits, every joint alike: v [rad/s], a [rad/s^2], j [rad/s^3].
WAYPOINT_LIMITS = (2.0, 10.0, 100.0)


def waypoint_sets(n_sets: int = 8) -> list:
    """The random 6-axis waypoint sets (5-20 waypoints, steps up to 0.6 rad per joint)."""
    rng = np.random.default_rng(2026)
    out = []
    for _ in range(n_sets):
        n = int(rng.integers(5, 21))
        out.append(np.cumsum(rng.uniform(-0.6, 0.6, (n, 6)), axis=0))
    return out


def stopping_at_each(W: np.ndarray) -> list:
    """ruckig's rest-to-rest trajectory between every two consecutive waypoints of ``W``
    (n, m) under :data:`WAYPOINT_LIMITS`."""
    from ruckig import InputParameter, Result, Ruckig, Trajectory

    m = W.shape[1]
    otg = Ruckig(m)
    out = []
    for i in range(W.shape[0] - 1):
        inp = InputParameter(m)
        inp.current_position = W[i].tolist()
        inp.target_position = W[i + 1].tolist()
        v, a, j = WAYPOINT_LIMITS
        inp.max_velocity, inp.max_acceleration, inp.max_jerk = [v] * m, [a] * m, [j] * m
        traj = Trajectory(m)
        if otg.calculate(inp, traj) not in (Result.Working, Result.Finished):
            raise RuntimeError("ruckig failed on a rest-to-rest stretch")
        out.append(traj)
    return out


def run_waypoints(quick: bool):
    lims = [AxisLimits(*WAYPOINT_LIMITS) for _ in range(6)]
    rows = []
    for W in waypoint_sets(2 if quick else 8):
        n = W.shape[0]
        stop = sum(traj.duration for traj in stopping_at_each(W))
        for blend in (0.0, 0.1):
            t0 = time.perf_counter()
            tr = plan_waypoints(W, lims, blend=blend)
            dt = time.perf_counter() - t0
            rows.append(dict(label=f"waypoints {n} x 6, blend {blend:g} rad", t=tr.duration, ref=stop,
                             ratio=tr.duration / stop, plan=dt, peer=math.nan,
                             nodes=sum(sg.grid.size for sg in tr.segments), blend=blend))
    return rows


def _table(title, rows, ref):
    print(f"\n{title}")
    bounds = "jerk_bound" in rows[0]
    head = f"{'motion':48s} {'trajkit [s]':>11s} {ref:>12s} {'ratio':>6s}"
    if bounds:
        head += f" {'jerk bound':>10s} {'/bound':>6s} {'saturated':>9s}"
    print(head + f" {'plan [s]':>9s} {'peer [s]':>9s} {'nodes':>6s}")
    for r in rows:
        line = f"{r['label']:48s} {r['t']:11.4f} {r['ref']:12.4f} {r['ratio']:6.3f}"
        if bounds:
            line += f" {r['jerk_bound']:10.4f} {r['to_bound']:6.3f} {100 * r['saturated']:8.1f}%"
        print(line + f" {r['plan']:9.3f} {r['peer']:9.3f} {r['nodes']:6d}")


def _warm_up() -> None:
    """Load (or compile) the engine's compiled code before anything is timed."""
    from trajkit.timing import LinearJointPath

    plan_path_timing(LinearJointPath([0.0, 0.0], [1.0, 0.5]),
                     [AxisLimits(1.0, 5.0, 50.0), AxisLimits(1.0, 5.0, 50.0)])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="one or two motions per group")
    args = ap.parse_args(argv)
    _warm_up()
    arms = run_arms(args.quick)
    _table("robot paths: trajkit (jerk-limited) vs TOPP-RA (no jerk limit), same path and v/a limits",
           arms, "TOPP-RA [s]")
    seams = run_saddles(args.quick)
    _table("saddle seams (theta/Z machine)", seams, "TOPP-RA [s]")
    wps = run_waypoints(args.quick)
    _table("joint-space waypoints vs stopping at every waypoint (ruckig rest-to-rest)", wps,
           "stopping [s]")
    ra = [r["ratio"] for r in arms]
    rb = [r["to_bound"] for r in arms]
    rs = [r["ratio"] for r in seams]
    sp = [r["plan"] / r["peer"] for r in arms + seams if r["peer"] > 0]
    print(f"\narms vs TOPP-RA: mean ratio {statistics.mean(ra):.3f}, largest {max(ra):.3f}")
    print(f"arms vs max(TOPP-RA, jerk bound): mean {statistics.mean(rb):.3f}, largest {max(rb):.3f}; "
          f"limit saturated {100 * min(r['saturated'] for r in arms):.1f} % of the time or more")
    print(f"saddles: mean ratio {statistics.mean(rs):.3f}, largest {max(rs):.3f}")
    for blend in (0.0, 0.1):
        rw = [r["ratio"] for r in wps if r["blend"] == blend]
        print(f"waypoints, blend {blend:g} rad: {100 * (1 - statistics.mean(rw)):.1f} % shorter than "
              f"stopping (mean), worst {100 * (1 - max(rw)):.1f} %")
    sa = [r["plan"] / r["peer"] for r in arms if r["peer"] > 0]
    ss = [r["plan"] / r["peer"] for r in seams if r["peer"] > 0]
    sw = [r["whole"] / r["peer"] for r in seams if r["peer"] > 0]
    print(f"planning time / TOPP-RA's on the same grid: median {statistics.median(sp):.1f}x "
          f"(arm motions {statistics.median(sa):.1f}x, range {min(sa):.1f}-{max(sa):.1f}x; "
          f"seams {statistics.median(ss):.1f}x, the whole seam plan with its arc-length table, "
          f"chord limit and axis verification {statistics.median(sw):.1f}x)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
