"""A custom palletizing job from YAML: pinwheel pattern, asymmetric B axis, gripper times.

Run::

    python examples/06_custom_pallet_job.py --out /tmp/trajkit-examples

Writes the job as ``custom_pallet_job.yaml`` into ``--out`` (run it again
with ``trajkit pallet OUT/custom_pallet_job.yaml``), plans it with the three
planners (ptp, merged, optimal), verifies them, and writes the B-velocity figure
of box 0.
Lengths in the job are in mm, angles in deg, times in s.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from trajkit.io import load_job
from trajkit.palletizing import plan_cycle, summarize, verify_plan
from trajkit.palletizing.report import bound_lines

JOB = """
name: pinwheel, 4 layers
robot:
  joints:
    # a heavier load: B brakes more gently than it accelerates
    B: {v_max: 1300, a_max: 5200, j_max: 45000, a_max_decel: 3500, j_max_decel: 25000,
        min: 0, max: 2000}
pick: {x_mm: 1300, y_mm: -200, z_mm: 500, yaw_deg: 0}
pallet: {centre_mm: [-200, 1500, 300], length_mm: 1000, width_mm: 1000}
box: {length_mm: 600, width_mm: 400, height_mm: 250}
pattern: {name: pinwheel, alternate: mirror}
layers: 4
lift_mm: 300
approach_mm: 150
gripper: {grip_s: 0.25, release_s: 0.15}
"""


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", help="directory for the job file and figure (default: a new temp dir)")
    args = ap.parse_args(argv)
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="trajkit-ex06-"))
    out.mkdir(parents=True, exist_ok=True)
    job_path = out / "custom_pallet_job.yaml"
    job_path.write_text(JOB.lstrip(), encoding="utf-8")

    sc = load_job(job_path)
    plans = {n: plan_cycle(sc, n) for n in ("ptp", "merged", "optimal")}
    for p in plans.values():
        verify_plan(p).raise_if_failed()
    s = summarize(plans)
    print(f"{sc.name}: {s['boxes']} boxes")
    for n, d in s["plans"].items():
        print(f"  {n:7s} {d['total_s']:8.3f} s  {d['per_box_s']:.3f} s/box  "
              f"reduction {d['reduction_pct']:.1f} %")
    for line in bound_lines(s):
        print(" ", line)

    from trajkit.plot import require_matplotlib
    from trajkit.plot.pallet import plot_b_velocity

    png = out / "custom_pallet_b_velocity.png"
    require_matplotlib().close(plot_b_velocity(plans, box=0, path=png))
    print("wrote", job_path)
    print("wrote", png)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
