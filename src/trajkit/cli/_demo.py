"""Sub-command ``trajkit demo``: the project's main job in one command.

Runs the palletizing job of Cao et al. (2012) in its cell (conveyor, guides,
end stop, pallet) with the classic, merged and optimal planners and the cell
planner, prints the table beside the paper's table 1 and what each plan does
in the cell, and writes the figures (B-axis velocity, cycle time against
Zmax, 3-D gripper path in the cell, one 4-axis transfer move) into a folder
(``./trajkit-demo/`` by default).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

__all__ = ["register", "DEFAULT_OUT", "write_transfer_plot"]

#: Folder the demo writes into by default.
DEFAULT_OUT = "trajkit-demo"

#: File name of the 4-axis transfer-move figure.
TRANSFER_PLOT = "ptp_transfer_4axis.png"


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "demo",
        help="run the palletizing job of Cao et al. (2012) in its cell (classic PTP, merged, "
             "optimal, cell) and write its plots",
        description="Plan the palletizing job of Cao et al. (2012) (25 boxes) with the classic "
                    "PTP, the paper's merged planner, trajkit's optimal planner (B passes its "
                    "clearance heights without stopping) and the cell planner (around the "
                    "real cell's obstacles and the growing stack), verify all four, print the "
                    "table beside the paper's table 1, check every plan against the cell and "
                    "write the figures into a folder.",
    )
    p.add_argument("--out", metavar="DIR", default=DEFAULT_OUT,
                   help=f"folder for the figures (default ./{DEFAULT_OUT}/)")
    p.set_defaults(func=_cmd_demo)


def write_transfer_plot(scenario: Any, out_dir: Path, box: int = 0) -> Path | None:
    """Plot the classic plan's 4-axis transfer move of ``box``'s load trip.

    Uses :func:`trajkit.plot.profiles.plot_trajectory` when it is available;
    returns ``None`` (and writes nothing) when it is not.
    """
    try:
        from ..plot.profiles import plot_trajectory
    except ImportError:
        return None
    from ..palletizing.planners import transfer_trajectory
    from ..plot import require_matplotlib

    spec = next(s for s in scenario.trips() if s.box == box and s.kind == "load")
    traj = transfer_trajectory(scenario, spec)
    path = Path(out_dir) / TRANSFER_PLOT
    fig = plot_trajectory(
        traj, path, units=["rad", "m", "m", "rad"],
        title=f"classic PTP transfer of box {box} (P1 -> P2), joints A, B, C, D, "
              f"{traj.duration:.3f} s",
    )
    require_matplotlib().close(fig)
    return path


def _cmd_demo(args: argparse.Namespace) -> int:
    from .._atomicio import output_folder

    out = Path(args.out)
    with output_folder(out):  # checked before planning; all figures or none
        return _demo(out)


def _demo(out: Path) -> int:
    from ..io.pallet_job import seed_cell_job_path
    from ..palletizing.report import (
        CELL_COLUMNS,
        TABLE_COLUMNS,
        bound_lines,
        cell_lines,
        cell_rows,
        summarize,
        table_rows,
    )
    from ..plot.pallet import write_pallet_plots
    from ._console import print_table
    from ._pallet import run_pallet

    scenario, plans, reports = run_pallet(str(seed_cell_job_path()), progress=sys.stderr.isatty())
    summary = summarize(plans, reports=reports)
    print_table(
        f"trajkit demo - {scenario.name}: {summary['boxes']} boxes, planned cycle time "
        "(paper: Cao et al., 2012, table 1)",
        TABLE_COLUMNS, table_rows(summary),
    )
    print_table(f"{scenario.name}: in the cell (clearance, stack, gripper volume)",
                CELL_COLUMNS, cell_rows(summary))
    for line in bound_lines(summary):
        print(line)
    for line in cell_lines(summary):
        print(line)
    print("verified: " + ", ".join(f"{n} ok" for n, r in reports.items() if r.ok_without_cell)
          + " (joint limits and ranges, places reached, placing order, clearance rule); "
          + "in the cell: " + ", ".join(
              f"{n} {'clear' if r.cell.ok else 'collides'}" for n, r in reports.items()))
    written = write_pallet_plots(plans, out, reports=reports)
    tr = write_transfer_plot(scenario, out)
    if tr is not None:
        written.append(tr)
    else:
        print("skipped the 4-axis transfer figure (trajkit.plot.profiles.plot_trajectory "
              "is not available)")
    print(f"figures in {out.resolve()}/:")
    for p in written:
        print(f"  {p.name}")
    return 0
