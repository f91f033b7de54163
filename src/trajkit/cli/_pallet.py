"""Sub-command ``trajkit pallet [JOB.yaml]``: plan a palletizing job, print table 1.

Thin shell over :mod:`trajkit.palletizing`: load the job (the shipped seed
scenario by default), run every planner, verify each plan, then print a
table beside seed 000's table 1 (or JSON with ``--json``) and optionally
write the figures (``--plot DIR``).
"""

from __future__ import annotations

import argparse
import contextlib
import sys
from pathlib import Path
from typing import Any, Iterator

from ..errors import InvalidInputError
from ._console import print_json, print_table

__all__ = ["register", "run_pallet", "DEFAULT_PLANNERS"]

#: Planners run by default, in table order.
DEFAULT_PLANNERS = ("ptp", "merged", "optimal")


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "pallet",
        help="plan a palletizing job (classic PTP, merged, optimal), table like seed 000's table 1",
        description="Plan a palletizing job with each planner, verify the plans, and print the "
                    "total planned time, time per box and reduction beside seed 000's table 1. "
                    "Without JOB the shipped seed scenario (25 boxes) is used.",
    )
    p.add_argument("job", nargs="?", metavar="JOB.yaml",
                   help="job file (YAML; mm and deg); default: the seed scenario")
    p.add_argument("--json", action="store_true",
                   help='print {"boxes": N, "plans": {name: {"total_s", "per_box_s", ...}}}')
    p.add_argument("--plot", metavar="DIR", help="write the figures (PNG) into DIR")
    p.add_argument("--planner", action="append", metavar="NAME",
                   help="planner to run (repeatable; default: ptp, merged and optimal)")
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


def run_pallet(job: str | None, planners=DEFAULT_PLANNERS, verify: bool = True,
               progress: bool = False) -> tuple[Any, dict, dict]:
    """Load a job, plan it with each planner and verify the plans.

    Returns
    -------
    (scenario, plans, reports)
        The scenario, ``{name: CyclePlan}`` and ``{name: VerificationReport}``
        (empty when ``verify`` is false).

    Raises
    ------
    InvalidInputError
        Bad job file or unknown planner; a plan that fails verification
        raises :class:`~trajkit.palletizing.PlanVerificationError`.
    """
    from ..io.pallet_job import load_job, seed_job_path
    from ..palletizing import PLANNERS, plan_cycle, verify_plan

    scenario = load_job(Path(job) if job else seed_job_path())
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
                reports[n].raise_if_failed()
                bar.step(f"verified {n}")
    return scenario, plans, reports


def _cmd_pallet(args: argparse.Namespace) -> int:
    from ..palletizing.report import TABLE_COLUMNS, bound_lines, summarize, table_rows

    planners = args.planner or DEFAULT_PLANNERS
    scenario, plans, reports = run_pallet(
        args.job, planners, verify=not args.no_verify,
        progress=not args.json and sys.stderr.isatty(),
    )
    if not 0 <= args.box < scenario.n_boxes:
        raise InvalidInputError(
            f"--box must be in [0, {scenario.n_boxes - 1}] for this job, got {args.box}"
        )
    summary = summarize(plans)
    for n, rep in reports.items():
        summary["plans"][n]["verified"] = rep.ok
    written = []
    if args.plot:
        from ..plot.pallet import write_pallet_plots
        written = write_pallet_plots(plans, args.plot, box=args.box)
    if args.json:
        print_json(summary)
        return 0
    print_table(
        f"{scenario.name}: {summary['boxes']} boxes, planned cycle time "
        "(paper: seed 000 table 1, 25 boxes)",
        TABLE_COLUMNS, table_rows(summary),
    )
    for line in bound_lines(summary):
        print(line)
    if reports:
        print("verified: " + ", ".join(
            f"{n} ok ({r.checks['samples']} samples, {r.checks['phase_boundaries']} phase "
            f"boundaries, {r.checks['crossings']} clearance crossings)"
            for n, r in reports.items()))
    for p in written:
        print(f"wrote {p}")
    return 0
