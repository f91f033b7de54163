"""Sub-command ``trajkit pallet [JOB.yaml]``: plan a palletizing job, print table 1.

Thin shell over :mod:`trajkit.palletizing`: load the job (by default the
shipped job ``seed``, the experiment of Cao et al., 2012), run every planner,
verify each plan, then print a table beside the paper's table 1 (or JSON
with ``--json``) and optionally
write the figures (``--plot DIR``) and one plan's cycle as CSV (``--csv FILE
--period DT``). A job with a cell also gets the ``cell`` planner, and every
plan is checked against the cell (a plan under the paper's clearance rule
that collides is reported, not an error).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import math
import os
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from ..errors import InvalidInputError
from ._console import print_json, print_table

__all__ = ["register", "run_pallet", "DEFAULT_PLANNERS", "CELL_PLANNER", "CSV_COLUMNS",
           "write_cycle_csv"]

#: Planners run by default, in table order.
DEFAULT_PLANNERS = ("ptp", "merged", "optimal")

#: Planner added to the defaults for a job with a cell.
CELL_PLANNER = "cell"

#: Columns of ``--csv``.
CSV_COLUMNS = ("t_s", "box", "trip", "carrying", "A_deg", "B_mm", "C_mm", "D_deg")

#: Largest number of rows ``--csv`` may write (a typo in ``--period`` must
#: not fill the disk).
MAX_CSV_ROWS = 10_000_000


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "pallet",
        help="plan a palletizing job (classic PTP, merged, optimal), table like table 1 of "
             "Cao et al. (2012)",
        description="Plan a palletizing job with each planner, verify the plans, and print the "
                    "total planned time, time per box and reduction beside table 1 of Cao et "
                    "al. (2012). Without JOB the shipped job 'seed' (the paper's 25 boxes) is used.",
    )
    p.add_argument("job", nargs="?", metavar="JOB.yaml",
                   help="job file (YAML; mm and deg), or a shipped job: seed (the default; the "
                        "job of Cao et al. (2012)), seed_cell (that job in its cell)")
    p.add_argument("--json", action="store_true",
                   help='print {"boxes": N, "plans": {name: {"total_s", "per_box_s", ...}}}')
    p.add_argument("--plot", metavar="DIR", help="write the figures (PNG) into DIR")
    p.add_argument("--planner", action="append", metavar="NAME",
                   help="planner to run (repeatable; default: ptp, merged and optimal, and cell "
                        "for a job with a cell)")
    p.add_argument("--csv", metavar="FILE",
                   help="write one plan's whole cycle as CSV (t_s, box, trip, carrying, A_deg, "
                        "B_mm, C_mm, D_deg): the first --planner, else cell (job with a cell) "
                        "or optimal")
    p.add_argument("--period", metavar="DT", help="CSV sample period [s] (with --csv)")
    p.add_argument("--box", type=int, default=0,
                   help="box whose cycle the velocity and Zmax figures show (default 0)")
    p.add_argument("--no-verify", action="store_true", help="skip the plan verification")
    p.set_defaults(func=_cmd_pallet)


@contextlib.contextmanager
def _progress(enabled: bool, total: int) -> Iterator[Any]:
    """A rich progress bar on stderr (or a no-op when rich is missing or disabled)."""
    if enabled:
        try:
            from rich.console import Console
            from rich.progress import Progress
        except ImportError:  # pragma: no cover - depends on the install
            enabled = False
    if not enabled:
        class _Null:
            def step(self, text: str) -> None:
                pass
        yield _Null()
        return
    console = Console(stderr=True)
    with Progress(console=console, transient=True) as prog:
        task = prog.add_task("planning", total=total)

        class _Bar:
            def step(self, text: str) -> None:
                prog.update(task, advance=1, description=text)
        yield _Bar()


def run_pallet(job: str | None, planners=None, verify: bool = True,
               progress: bool = False) -> tuple[Any, dict, dict]:
    """Load a job, plan it with each planner and verify the plans.

    Parameters
    ----------
    job : str or None
        Job file, or the name of a shipped job (``"seed"``, ``"seed_cell"``);
        ``"seed"`` when ``None``.
    planners : sequence of str, optional
        Default :data:`DEFAULT_PLANNERS`, plus :data:`CELL_PLANNER` for a
        job with a cell.

    Returns
    -------
    (scenario, plans, reports)
        The scenario, ``{name: CyclePlan}`` and ``{name: VerificationReport}``
        (empty when ``verify`` is false).

    Raises
    ------
    InvalidInputError
        Bad job file or unknown planner; a plan that fails verification
        raises :class:`~trajkit.palletizing.PlanVerificationError` (for a
        plan under the clearance rule of Cao et al. (2012), breaking the
        cell's rules is reported in its report, not raised).
    """
    from ..io.pallet_job import load_job, seed_cell_job_path, seed_job_path
    from ..palletizing import PLANNERS, plan_cycle, verify_plan

    shipped = {"seed": seed_job_path, "seed_cell": seed_cell_job_path}
    if not job:
        path = seed_job_path()
    elif job in shipped and not Path(job).exists():
        path = shipped[job]()
    else:
        path = Path(job)
    scenario = load_job(path)
    if planners is None:
        planners = DEFAULT_PLANNERS + ((CELL_PLANNER,) if scenario.cell is not None else ())
    names = list(planners)
    for n in names:
        if n not in PLANNERS:
            raise InvalidInputError(f"--planner must be one of {sorted(PLANNERS)}, got {n!r}")
    plans, reports = {}, {}
    with _progress(progress, len(names) * (2 if verify else 1)) as bar:
        for n in names:
            plans[n] = plan_cycle(scenario, n)
            bar.step(f"planned {n}")
            if verify:
                reports[n] = verify_plan(plans[n])
                reports[n].raise_if_failed(cell=plans[n].rule == "cell")
                bar.step(f"verified {n}")
    return scenario, plans, reports


def _csv_period(args: argparse.Namespace) -> float | None:
    """Validate ``--csv``/``--period`` before planning; the period or None."""
    if args.period is not None and args.csv is None:
        raise InvalidInputError("--period needs --csv FILE (it is the CSV sample period)")
    if args.csv is None:
        return None
    if args.period is None:
        raise InvalidInputError("--csv needs --period DT (the sample period in s)")
    try:
        dt = float(str(args.period).strip())
    except ValueError:
        raise InvalidInputError(f"--period must be a number, got {args.period!r}") from None
    if not (math.isfinite(dt) and dt > 0.0):
        raise InvalidInputError(f"--period must be a finite time > 0 s, got {dt!r}")
    from .._atomicio import check_target

    check_target(args.csv, "--csv")  # the folder exists and the file is not a folder
    return dt


def write_cycle_csv(path: str | os.PathLike, plan: Any, period: float) -> int:
    """Write ``plan``'s whole cycle every ``period`` s as CSV; return the row count.

    Columns :data:`CSV_COLUMNS` (see
    :func:`trajkit.palletizing.report.cycle_rows`); the file is written
    atomically.

    Raises
    ------
    InvalidInputError
        More than :data:`MAX_CSV_ROWS` rows.
    """
    from .._atomicio import atomic_write
    from ..palletizing.report import cycle_rows

    n = plan.total_s / period + 2
    if n > MAX_CSV_ROWS:
        raise InvalidInputError(
            f"--period {period!r} s gives {n:.3g} rows over {plan.total_s:.6g} s, more than the "
            f"{MAX_CSV_ROWS} allowed"
        )
    r = cycle_rows(plan, period)
    buf = io.StringIO()
    buf.write(",".join(CSV_COLUMNS) + "\n")
    for i in range(r["t_s"].size):
        buf.write(f"{r['t_s'][i]:.9f},{r['box'][i]},{r['trip'][i]},{r['carrying'][i]},"
                  f"{r['A_deg'][i]:.9f},{r['B_mm'][i]:.9f},{r['C_mm'][i]:.9f},"
                  f"{r['D_deg'][i]:.9f}\n")
    atomic_write(path, buf.getvalue())
    return int(r["t_s"].size)


def _cmd_pallet(args: argparse.Namespace) -> int:
    from ..palletizing.report import (
        CELL_COLUMNS,
        TABLE_COLUMNS,
        bound_lines,
        cell_lines,
        cell_rows,
        summarize,
        table_rows,
    )

    period = _csv_period(args)
    scenario, plans, reports = run_pallet(
        args.job, args.planner, verify=not args.no_verify,
        progress=not args.json and sys.stderr.isatty(),
    )
    if not 0 <= args.box < scenario.n_boxes:
        raise InvalidInputError(
            f"--box must be in [0, {scenario.n_boxes - 1}] for this job, got {args.box}"
        )
    summary = summarize(plans, reports=reports)
    written = []
    if args.plot:
        from ..plot.pallet import write_pallet_plots
        written = write_pallet_plots(plans, args.plot, box=args.box, reports=reports)
    if period is not None:
        which = (args.planner[0] if args.planner else
                 CELL_PLANNER if CELL_PLANNER in plans else "optimal" if "optimal" in plans
                 else next(iter(plans)))
        rows = write_cycle_csv(args.csv, plans[which], period)
        note = f"wrote {args.csv} ({which} plan, {rows} rows every {period:g} s)"
        print(note, file=sys.stderr if args.json else sys.stdout)
    if args.json:
        print_json(summary)
        return 0
    print_table(
        f"{scenario.name}: {summary['boxes']} boxes, planned cycle time "
        "(paper: Cao et al., 2012, table 1, 25 boxes)",
        TABLE_COLUMNS, table_rows(summary),
    )
    if summary.get("cell"):
        print_table(f"{scenario.name}: in the cell (clearance, stack, gripper volume)",
                    CELL_COLUMNS, cell_rows(summary))
    for line in bound_lines(summary):
        print(line)
    for line in cell_lines(summary):
        print(line)
    if reports:
        print("verified: " + ", ".join(
            f"{n} ok ({r.checks['samples']} samples, {r.checks['phase_boundaries']} phase "
            f"boundaries, {r.checks['crossings']} clearance crossings"
            + (f", cell {'clear' if r.cell.ok else 'violated'}" if r.cell is not None else "") + ")"
            for n, r in reports.items()))
    for p in written:
        print(f"wrote {p}")
    return 0
