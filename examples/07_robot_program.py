"""Example 07: robot motion programs (Jiang, 1987): PTP, LIN, CIRC, blending, singularities.

1. Loads the shipped weld program for the 6-axis arm (``examples/data/arm6_weld.yaml``),
   plans it, samples it at a 4 ms period (inverse kinematics at every
   Cartesian sample) and prints the summary: segment times, slow-downs,
   joint limit usage; checks the LIN samples lie on their line (after FK).
2. Builds a LIN in Python that passes 4 mm from the arm's wrist singularity:
   the feed slows down there and the summary says why; the same line through
   the singular point is refused with an ``UnreachableError``.
3. Writes the samples (CSV) and the figure (PNG).

Run::

    python examples/07_robot_program.py --out /tmp/trajkit-examples
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from trajkit.errors import UnreachableError
from trajkit.io.program import load_program
from trajkit.kinematics.arm6 import default_arm6
from trajkit.kinematics.base import Pose
from trajkit.robot import CartesianTarget, Lin, run_motions

HERE = Path(__file__).resolve().parent


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=tempfile.gettempdir(), help="output folder")
    ap.add_argument("--period", type=float, default=0.004, help="sampling period [s]")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    # 1. the shipped program
    prog = load_program(HERE / "data" / "arm6_weld.yaml")
    run = prog.run()
    smp = run.sample(run.times(args.period))
    summary = run.summary(smp)
    print(f"program {prog.source}: {summary['duration_s']:.3f} s, {smp.t.size} samples")
    for sg in summary["segments"]:
        print(f"  {sg['kind']:4s} t0={sg['t0_s']:7.3f} s  {sg['duration_s']:6.3f} s  "
              f"{'; '.join(sg['instructions'])}")
    for sd in summary["slowdowns"]:
        a, b = (", ".join(f"{c:.0f}" for c in sd[k]) for k in ("start_xyz_mm", "end_xyz_mm"))
        print(f"  slow-down in {sd['instruction']}: ({a}) to ({b}) mm at {sd['speed_mm_s']:.1f} of "
              f"{sd['programmed_mm_s']:.0f} mm/s ({sd['reason']})")
    for lm in summary["limits"]:
        print(f"  joint {lm['joint']}: |v|/v_max {lm['velocity_ratio']:.3f}, "
              f"|a|/a_max {lm['acceleration_ratio']:.3f}")
    arm = prog.robot
    c1, c2 = prog.points["c1"].pose.position, prog.points["c2"].pose.position
    # the stretch of LIN c2 before its blend zone (20 mm): y from -150 to 130 mm
    fk = np.array([arm.fk(q).position for q in smp.q])
    on = (smp.motion == 3) & (fk[:, 1] < c2[1] - 0.02)
    d = np.linalg.norm(np.cross(fk[on] - c1, c2 - c1), axis=1) / np.linalg.norm(c2 - c1)
    print(f"  LIN c2: {on.sum()} samples, largest distance from the line {d.max():.2e} m")

    # 2. a line near / through the wrist singularity (q5 = 0)
    arm = default_arm6()
    sing = arm.fk(np.array([0.0, 0.3, 0.2, 0.0, 0.0, 0.0]))
    for offset in (0.004, 0.0):
        a = Pose(sing.position + [0.0, offset, -0.08], sing.rotation)
        b = Pose(sing.position + [0.0, offset, 0.08], sing.rotation)
        q0 = arm.ik(a, "front-up-noflip")
        try:
            r = run_motions(arm, [Lin(CartesianTarget(b), 0.25, label=f"LIN {offset * 1e3:g} mm off")], q0)
        except UnreachableError as exc:
            print(f"  refused: {exc}")
            continue
        worst = min(r.slowdowns, key=lambda s: s.speed)
        print(f"  {worst.label}: {r.duration:.3f} s, slows to {worst.speed * 1e3:.1f} mm/s "
              f"({worst.reason})")

    # 3. files
    csv_path = out / "07_robot_program.csv"
    run.to_csv(smp, csv_path)
    print(f"wrote {csv_path}")
    try:
        from trajkit.plot.robot import plot_robot_run
    except ImportError:  # pragma: no cover
        return 0
    png = out / "07_robot_program.png"
    plot_robot_run(run, smp, png)
    print(f"wrote {png}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
