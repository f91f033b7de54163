"""Palletizing around a real cell: obstacles, the growing stack, the gripper volume.

Run::

    python examples/09_palletizing_cell.py --out /tmp/trajkit-examples

A job whose cell has a conveyor with side guides and an end stop, the
pallet, and a tall post between the conveyor and the pallet. The ``cell``
planner plans every trip as one motion of the four joints around them (B
never stops between pick and place, the horizontal joints start as soon as
the swept volume clears the guides), picks the order of the boxes in each
layer and the wrist's turn, and reports how far it is from a lower bound.
The classic ``ptp`` plan of the same job is checked against the cell too.
Writes the job (``cell_job.yaml``), the cell plan's cycle as CSV
(``cell_cycle.csv``, every 10 ms) and the 3-D figure of the cell, the stack
and both gripper paths with their tightest clearance marked
(``cell_path_3d.png``). Lengths in the job are in mm, angles in deg.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from trajkit.io import load_job
from trajkit.palletizing import plan_cycle, summarize, verify_plan
from trajkit.palletizing.report import bound_lines, cell_lines, cycle_rows

JOB = """
name: cell with a post, 3 layers
pick: {x_mm: 1300, y_mm: -100, z_mm: 500, yaw_deg: 0}
pallet: {centre_mm: [100, 1500, 300], length_mm: 1000, width_mm: 1000}
box: {length_mm: 500, width_mm: 350, height_mm: 250}
pattern: {name: interlock, alternate: rotate180}
layers: 3
cell:
  clearance_mm: 10
  settle_mm: 20
  gripper: {height_mm: 120}
  obstacles:
    - {name: conveyor, x_mm: [700, 1550], y_mm: [-350, 150], z_mm: [0, 250]}
    - {name: guide +y, x_mm: [700, 1550], y_mm: [90, 110], z_mm: [250, 400]}
    - {name: guide -y, x_mm: [700, 1550], y_mm: [-310, -290], z_mm: [250, 400]}
    - {name: end stop, x_mm: [1565, 1585], y_mm: [-350, 150], z_mm: [250, 480]}
    - {name: pallet, x_mm: [-400, 600], y_mm: [1000, 2000], z_mm: [150, 300]}
    - {name: post, x_mm: [860, 960], y_mm: [860, 960], z_mm: [0, 900]}
"""


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", help="directory for the job, CSV and figure (default: a new temp dir)")
    args = ap.parse_args(argv)
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="trajkit-ex09-"))
    out.mkdir(parents=True, exist_ok=True)
    job_path = out / "cell_job.yaml"
    job_path.write_text(JOB.lstrip(), encoding="utf-8")

    sc = load_job(job_path)
    plans = {n: plan_cycle(sc, n) for n in ("ptp", "cell")}
    reports = {n: verify_plan(p) for n, p in plans.items()}
    reports["cell"].raise_if_failed()            # limits, places, order, settle, the cell
    reports["ptp"].raise_if_failed(cell=False)   # its own rule holds; the cell's need not
    s = summarize(plans, reports=reports)
    print(f"{sc.name}: {s['boxes']} boxes")
    for n, d in s["plans"].items():
        print(f"  {n:4s} {d['total_s']:8.3f} s  {d['per_box_s']:.3f} s/box  "
              f"min clearance {d['min_clearance_mm']:8.2f} mm")
    for line in bound_lines(s) + cell_lines(s):
        print(" ", line)
    cell = plans["cell"]
    print(f"  placing order {cell.info['order']}")
    peaks = [t.z_peak * 1000 for t in cell.info["trips"]]
    print(f"  B's highest point per trip: {min(peaks):.0f} .. {max(peaks):.0f} mm "
          f"(the post's top is 900 mm)")

    rows = cycle_rows(cell, 0.01)
    csv = out / "cell_cycle.csv"
    cols = ("t_s", "box", "trip", "carrying", "A_deg", "B_mm", "C_mm", "D_deg")
    lines = [",".join(cols)] + [
        ",".join(f"{rows[c][i]:.6f}" if rows[c].dtype.kind == "f" else str(rows[c][i]) for c in cols)
        for i in range(rows["t_s"].size)
    ]
    csv.write_text("\n".join(lines) + "\n", encoding="utf-8")

    from trajkit.plot import require_matplotlib
    from trajkit.plot.pallet import plot_gripper_path_3d

    png = out / "cell_path_3d.png"
    require_matplotlib().close(plot_gripper_path_3d(plans, path=png, reports=reports))
    print("wrote", job_path)
    print("wrote", csv, f"({rows['t_s'].size} rows)")
    print("wrote", png)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
