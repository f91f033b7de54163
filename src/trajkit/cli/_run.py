"""Sub-command ``trajkit run PROGRAM.yaml --period DT``: plan and sample a robot program.

Thin shell over :func:`trajkit.io.program.load_program` and
:mod:`trajkit.robot`: prints the summary (time, segments, slow-downs, joint
limit usage) as tables or JSON, and writes the joint trajectory and tool path
as CSV and a figure on request. ``--simulate`` runs the program through
:func:`trajkit.runtime.simulate` (servo model, exact stops) and prints planned
vs simulated time per segment; with ``--plot`` it also writes the following
error figure.
"""

from __future__ import annotations

import argparse
import math
from typing import Any

from ..errors import InvalidInputError
from ..interpolation.feed import MAX_PERIOD, MIN_PERIOD
from ._console import print_json, print_table

__all__ = ["register", "cmd_run"]


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "run",
        help="plan a robot program (PTP/LIN/CIRC/WAIT, YAML) and sample it",
        description="Plan a robot program file (YAML; mm and deg), sample the joint trajectory "
                    "at the period (inverse kinematics at every Cartesian sample) and print "
                    "the summary: time, slow-downs, joint limit usage.",
    )
    p.add_argument("program", metavar="PROGRAM.yaml", help="program file")
    p.add_argument("--period", type=float, required=True, metavar="DT",
                   help="sampling period [s], e.g. 0.004")
    p.add_argument("--csv", metavar="FILE",
                   help="write the samples (t, joints in deg/mm, tool xyz in mm, tool speed)")
    p.add_argument("--plot", metavar="FILE.png", help="write a figure (joints, speed, tool path)")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.add_argument("--simulate", action="store_true",
                   help="run the program through the servo simulation (trajkit.runtime) and "
                        "print planned vs simulated time per segment; with --plot also write "
                        "the following error to FILE-following-error.png")
    p.add_argument("--inertia-ratio", type=float, default=None, metavar="R",
                   help="with --simulate: actual / nominal load inertia (default 1)")
    p.set_defaults(func=cmd_run)


def cmd_run(args: argparse.Namespace) -> int:
    from ..io.program import load_program

    if not MIN_PERIOD <= args.period <= MAX_PERIOD:
        raise InvalidInputError(
            f"--period must be between {MIN_PERIOD} and {MAX_PERIOD} s, got {args.period!r}"
        )
    if args.inertia_ratio is not None and not args.simulate:
        raise InvalidInputError("--inertia-ratio only acts on the servo simulation: add --simulate")
    program = load_program(args.program)
    run = program.run()
    samples = run.sample(run.times(args.period))
    summary = run.summary(samples)
    summary["program"] = args.program
    summary["period_s"] = args.period
    summary["samples"] = int(samples.t.size)
    report = None
    if args.simulate:
        from ..runtime import ServoParams, simulate

        ratio = 1.0 if args.inertia_ratio is None else args.inertia_ratio
        report = simulate(run, args.period, ServoParams(inertia_ratio=ratio))
        summary["simulation"] = report.to_dict()
    if args.csv:
        run.to_csv(samples, args.csv)
    if args.plot:
        from ..plot.robot import plot_robot_run

        plot_robot_run(run, samples, args.plot)
        if report is not None:
            import os

            from ..plot.runtime import plot_following_error

            root, ext = os.path.splitext(args.plot)
            fe_path = f"{root}-following-error{ext or '.png'}"
            scale = [180.0 / math.pi if k == "revolute" else 1e3 for k in run.robot.joint_kinds]
            plot_following_error(report, fe_path, scale=scale, unit="deg | mm")
            summary["following_error_plot"] = fe_path
    if args.json:
        print_json(summary)
        return 0
    print_table(
        f"{args.program}: {summary['robot']}, {summary['duration_s']:.4f} s, "
        f"{summary['samples']} samples at {args.period:g} s",
        ["#", "kind", "t0 [s]", "duration [s]", "instructions"],
        [[i, sg["kind"], sg["t0_s"], sg["duration_s"], "; ".join(sg["instructions"])]
         for i, sg in enumerate(summary["segments"])],
    )
    if summary["slowdowns"]:
        print_table(
            "slow-downs (feed below the programmed speed because of a limit)",
            ["instruction", "from [mm]", "to [mm]", "speed [mm/s]", "programmed", "reason"],
            [[sd["instruction"], _xyz(sd["start_xyz_mm"]), _xyz(sd["end_xyz_mm"]),
              sd["speed_mm_s"], sd["programmed_mm_s"], sd["reason"]] for sd in summary["slowdowns"]],
        )
    else:
        print("no slow-downs: every Cartesian motion ran at its programmed speed")
    print_table(
        "joint limit usage (largest |value| / limit over the samples)",
        ["joint", "velocity", "acceleration"],
        [[lm["joint"], lm["velocity_ratio"], lm["acceleration_ratio"]] for lm in summary["limits"]],
    )
    if report is not None:
        print_table(
            f"planned vs simulated time (servo simulation, period {args.period:g} s): "
            f"planned {report.planned_s:.4f} s, simulated {report.simulated_s:.4f} s",
            ["#", "motion", "planned [s]", "simulated [s]", "settling [s]"],
            [[m.index, m.label, m.planned_s, m.simulated_s, m.settle_s] for m in report.motions]
            + [["", "total", report.planned_s, report.simulated_s,
                sum(m.settle_s for m in report.motions)]],
        )
        if "following_error_plot" in summary:
            print(f"following error plot: {summary['following_error_plot']}")
    return 0


def _xyz(p: list) -> str:
    return "(" + ", ".join(f"{x:.1f}" for x in p) + ")"
