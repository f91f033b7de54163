"""Example 02: several axes, one point-to-point move, three synchronisations.

A 4-axis cylindrical palletizing robot (Cao et al., 2012) moves its joints from the
pick to above the stack: waist theta [rad], vertical Z [m], reach R [m] and
gripper rotation D [rad]. Angles are given in degrees at the I/O boundary
and converted to radians for the planner.

* ``sync="none"``: every joint at its own minimum time (they arrive apart);
* ``sync="time"``: all joints arrive together at the slowest joint's
  minimum time (the synchronisation of Jiang, 1987, with S-curves);
* ``sync="phase"``: all joints follow one normalised profile, a straight
  line in joint space.

Prints durations and peak velocities, writes a CSV of samples at 4 ms and
one figure per synchronisation.

Run::

    python examples/02_multi_axis_ptp.py --out /tmp/trajkit-examples
"""

from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path

import numpy as np

from trajkit import AxisLimits, plan_ptp


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", help="directory for figures and CSV (default: a new temp dir)")
    args = ap.parse_args(argv)
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="trajkit-ex02-"))
    out.mkdir(parents=True, exist_ok=True)

    names = ["theta", "Z", "R", "D"]
    units = ["rad", "m", "m", "rad"]
    # Pick (theta 0 deg, Z 0.8 m, R 1.2 m, D 0 deg)
    # -> above the stack (theta 90 deg, Z 1.0 m, R 1.4 m, D 180 deg).
    start_deg_or_m = [0.0, 0.8, 1.2, 0.0]
    goal_deg_or_m = [90.0, 1.0, 1.4, 180.0]
    rad = math.radians
    start = [rad(start_deg_or_m[0]), start_deg_or_m[1], start_deg_or_m[2], rad(start_deg_or_m[3])]
    goal = [rad(goal_deg_or_m[0]), goal_deg_or_m[1], goal_deg_or_m[2], rad(goal_deg_or_m[3])]
    limits = [
        AxisLimits(v_max=rad(120), a_max=rad(300), j_max=rad(1500), name="theta",
                   position_min=rad(-170), position_max=rad(170)),
        AxisLimits(v_max=1.0, a_max=4.0, j_max=40.0, a_max_decel=3.0, j_max_decel=20.0,
                   name="Z", position_min=0.0, position_max=1.8),
        AxisLimits(v_max=1.2, a_max=5.0, j_max=50.0, name="R",
                   position_min=0.5, position_max=2.0),
        AxisLimits(v_max=rad(360), a_max=rad(1200), j_max=rad(6000), name="D"),
    ]

    from trajkit.plot.profiles import plot_trajectory

    for sync in ("none", "time", "phase"):
        traj = plan_ptp(start, goal, limits, sync=sync)
        durations = ", ".join(f"{n} {p.duration:.4f}" for n, p in zip(names, traj.axes))
        peaks = ", ".join(f"{n} {abs(p.peak_velocity):.4f} {u}/s"
                          for n, p, u in zip(names, traj.axes, units))
        print(f"sync={sync:<5}: T = {traj.duration:.6f} s  (per axis [s]: {durations})")
        print(f"             peak |v|: {peaks}")
        png = out / f"02_ptp_{sync}.png"
        plot_trajectory(traj, png, units=units, title=f"palletizer joints, sync={sync}")
        print(f"             wrote {png}")

    # Straight line in joint space with sync="phase": every sample's progress
    # (q - start) / (goal - start) is the same for all axes.
    traj = plan_ptp(start, goal, limits, sync="phase")
    t = traj.times(0.004)
    s = traj.sample(t)
    progress = (s.position - np.array(start)) / (np.array(goal) - np.array(start))
    spread = float(np.ptp(progress, axis=1).max())
    print(f"\nsync=phase: {t.size} samples at 4 ms, largest spread of the normalised "
          f"progress across axes {spread:.3e}")
    csv_path = out / "02_ptp_phase.csv"
    traj.to_csv(csv_path, period=0.004)
    print(f"wrote {csv_path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
