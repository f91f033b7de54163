"""Sub-command ``trajkit run PROGRAM.yaml --period DT``: plan and sample a robot program.

Thin shell over :func:`trajkit.io.program.load_program` and
:mod:`trajkit.robot`: prints the summary (time, segments, slow-downs, joint
limit usage) as tables or JSON, and writes the joint trajectory and tool path
as CSV and a figure on request.
"""

from __future__ import annotations

import argparse
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
    p.set_defaults(func=cmd_run)


def cmd_run(args: argparse.Namespace) -> int:
    from ..io.program import load_program

    if not MIN_PERIOD <= args.period <= MAX_PERIOD:
        raise InvalidInputError(
            f"--period must be between {MIN_PERIOD} and {MAX_PERIOD} s, got {args.period!r}"
        )
    program = load_program(args.program)
    run = program.run()
    samples = run.sample(run.times(args.period))
    summary = run.summary(samples)
    summary["program"] = args.program
    summary["period_s"] = args.period
    summary["samples"] = int(samples.t.size)
    if args.csv:
        run.to_csv(samples, args.csv)
    if args.plot:
        from ..plot.robot import plot_robot_run

        plot_robot_run(run, samples, args.plot)
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
    return 0


def _xyz(p: list) -> str:
    return "(" + ", ".join(f"{x:.1f}" for x in p) + ")"
