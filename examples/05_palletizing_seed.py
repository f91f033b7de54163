"""Example 05: the 25-box palletizing job of Cao et al. (2012), classic PTP and merged plan.

Run::

    python examples/05_palletizing_seed.py --out /tmp/trajkit-examples

Prints the planned times beside the paper's table 1, verifies both plans
(joint limits and ranges, places reached, clearance rule), shows how the
merged plan chose Zmax for the first box, and writes the figures (B-axis
velocity, cycle time against Zmax, 3-D gripper path) into ``--out``.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from trajkit.palletizing import (
    PAPER_TABLE1,
    merged_trip_times,
    plan_cycle,
    seed_scenario,
    summarize,
    verify_plan,
)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", help="directory for the figures (default: a new temp dir)")
    args = ap.parse_args(argv)
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="trajkit-ex05-"))
    out.mkdir(parents=True, exist_ok=True)

    sc = seed_scenario()
    plans = {name: plan_cycle(sc, name) for name in ("ptp", "merged")}
    for name, plan in plans.items():
        verify_plan(plan).raise_if_failed()
        paper = PAPER_TABLE1[name]["planned_s"]
        print(f"{name:7s} total {plan.total_s:8.3f} s  per box {plan.per_box_s:.3f} s  "
              f"(paper {paper:.3f} s, {100 * (plan.total_s / paper - 1):+.2f} %)")
    s = summarize(plans)
    print(f"reduction: {s['plans']['merged']['reduction_pct']:.1f} % "
          f"(paper {s['plans']['merged']['paper_reduction_pct']:.1f} %)")

    first = plans["merged"].trips[0]
    z0, z1, z2, z3 = first.spec.z_levels
    terms = merged_trip_times(sc, first.spec, first.zmax)
    print(f"box 0 load trip: Z0={z0 * 1000:.0f} Z1={z1 * 1000:.0f} Z2={z2 * 1000:.0f} "
          f"Z3={z3 * 1000:.0f} mm, best Zmax={first.zmax * 1000:.1f} mm, "
          f"f'+g'={terms['t_b'][0]:.4f} s, t1+tH+t3={terms['t_window'][0]:.4f} s")

    # the plans are full joint trajectories: sample them at 1 ms
    tl = plans["merged"].timeline
    q = tl.sample(tl.times(0.001))
    print(f"merged plan sampled: {q.position.shape[0]} x {q.position.shape[1]} joint samples")

    from trajkit.plot.pallet import write_pallet_plots

    for p in write_pallet_plots(plans, out):
        print("wrote", p)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
