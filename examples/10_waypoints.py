"""Joint-space waypoints without stopping, in minimum time (``plan_waypoints``).

Run::

    python examples/10_waypoints.py --out /tmp/trajkit-examples

1. plans a 6-axis motion through 7 taught joint positions of the 6-axis arm
   four ways: a spline through every waypoint, a spline passing each
   inner waypoint within 0.05 rad, and straight lines with
   0.2 and 0.05 rad blends (blends so tight that passing them would take
   longer than stopping: the motion then stops at each waypoint, never
   slower); and, for comparison, a jerk-limited rest-to-rest move between
   every pair (stopping at each waypoint);
2. prints each motion's duration, how far it passes each waypoint, where it
   stops, and the largest |velocity|, |acceleration| and |jerk| of every
   joint over its limit on a dense sampling of the exact pieces (never
   above 1);
3. writes the joint velocities of the fastest motion to ``--out``
   (``waypoints_velocity.png`` when matplotlib is installed, and
   ``waypoints.csv``).
"""

from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path

import numpy as np

from trajkit import plan_ptp
from trajkit.robot.models import robot_by_name
from trajkit.timing import plan_waypoints

#: Seven taught joint positions of the 6-axis arm [deg].
TAUGHT_DEG = [
    [0, -30, 60, 0, 45, 0],
    [25, -20, 50, 10, 40, 20],
    [50, -35, 70, 25, 30, 45],
    [70, -15, 40, 10, 55, 60],
    [95, -25, 55, -15, 50, 90],
    [120, -40, 75, -30, 35, 100],
    [140, -30, 60, 0, 45, 120],
]


def _use(traj, lims) -> np.ndarray:
    """Largest |v|, |a|, |j| over the limit per joint, shape (3, m), on a 0.5 ms sampling."""
    t = np.linspace(0.0, traj.duration, int(traj.duration / 5e-4) + 2)
    s = traj.sample(t)
    v = np.array([lm.v_max for lm in lims])
    speeding = s.velocity * s.acceleration > 0
    a = np.where(speeding, [lm.a_max for lm in lims], [lm.a_max_decel for lm in lims])
    j = np.array([max(lm.j_max, lm.j_max_decel) for lm in lims])
    return np.array([np.max(np.abs(s.velocity) / v, axis=0), np.max(np.abs(s.acceleration) / a, axis=0),
                     np.max(np.abs(s.jerk) / j, axis=0)])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", help="directory for the figure and CSV (default: a new temp dir)")
    args = ap.parse_args(argv)
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="trajkit-ex10-"))
    out.mkdir(parents=True, exist_ok=True)

    robot = robot_by_name("arm6")
    lims = list(robot.limits)
    W = np.radians(np.array(TAUGHT_DEG, dtype=float))

    stopping = sum(plan_ptp(W[i], W[i + 1], lims).duration for i in range(len(W) - 1))
    print(f"{len(W)} waypoints of the 6-axis arm; stopping at each (rest-to-rest PTP): {stopping:.3f} s")
    plans = {
        "spline, through every waypoint": plan_waypoints(W, lims),
        "spline, within 0.05 rad": plan_waypoints(W, lims, blend=0.05),
        "lines, 0.2 rad blends": plan_waypoints(W, lims, blend=0.2, shape="lines"),
        # blends this tight would be slower than stopping: it stops at each instead
        "lines, 0.05 rad blends": plan_waypoints(W, lims, blend=0.05, shape="lines"),
    }
    for name, traj in plans.items():
        use = _use(traj, lims)
        print(f"{name:32s}: {traj.duration:.3f} s ({100 * (traj.duration / stopping - 1):+.1f} % "
              f"vs stopping), stops at waypoints {traj.stops}, passes each within "
              f"{traj.deviation.max():.4f} rad")
        print(f"{'':32s}  largest |v|/v_max {use[0].max():.4f}, |a|/a_max {use[1].max():.4f}, "
              f"|j|/j_max {use[2].max():.4f}")

    best_name = min(plans, key=lambda k: plans[k].duration)
    best = plans[best_name]
    t = np.arange(0.0, best.duration, 0.004)
    t = np.append(t, best.duration)
    s = best.sample(t)
    names = robot.joint_names
    header = "t_s," + ",".join(f"{n}_deg,{n}_velocity_deg_s" for n in names)
    rows = np.column_stack([t] + [c for k in range(len(names))
                                  for c in (np.degrees(s.position[:, k]), np.degrees(s.velocity[:, k]))])
    np.savetxt(out / "waypoints.csv", rows, delimiter=",", header=header, comments="", fmt="%.9g")
    print(f"final joints [deg]: {np.round(np.degrees(s.position[-1]), 6).tolist()}")
    written = ["waypoints.csv"]
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no figure")
    else:
        fig, ax = plt.subplots(figsize=(9, 4.5))
        for k, n in enumerate(names):
            ax.plot(t, np.degrees(s.velocity[:, k]), label=n)
        for lm in lims[:1]:
            ax.axhline(math.degrees(lm.v_max), color="0.6", lw=0.8, ls="--")
        ax.set_xlabel("t [s]")
        ax.set_ylabel("joint velocity [deg/s]")
        ax.set_title(f"{best_name}: {best.duration:.3f} s")
        ax.legend(ncol=6, fontsize=8)
        fig.tight_layout()
        fig.savefig(out / "waypoints_velocity.png", dpi=110)
        plt.close(fig)
        written.append("waypoints_velocity.png")
    for name in written:
        print(f"wrote {out / name}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
