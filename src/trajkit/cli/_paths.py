"""Sub-commands ``trajkit saddle`` (pipe-intersection seams) and ``trajkit path``.

Thin shells over :mod:`trajkit.paths` and :mod:`trajkit.interpolation`.
Units at this boundary: lengths in mm, speeds in mm/s (mm/s^2, mm/s^3),
angles in degrees, the period in seconds; the library works in m, rad, s.
"""

from __future__ import annotations

import argparse
import math
import os
from typing import Any

import numpy as np

from .._atomicio import atomic_write
from .._csvio import csv_text
from .._sampling import count_samples
from ..errors import InvalidInputError
from ..interpolation import SaddleMachine, plan_feed, plan_saddle
from ..limits import AxisLimits
from ..paths import Arc3, CompositePath, Line, SaddleCurve, circle_through, discretize, uniform_chord_count
from ._console import print_json, print_table

__all__ = ["register", "load_path_file", "build_path"]

MM = 1e-3  # metres per millimetre

#: Default tangent jump [deg] treated as a corner by ``trajkit path``.
DEFAULT_CORNER_DEG = 0.01

_UNITS_NOTE = "Units: lengths in mm, speeds in mm/s, mm/s^2, mm/s^3, angles in deg, period in s."


# ----------------------------------------------------------------- parsing
def _num(text: Any, what: str) -> float:
    try:
        x = float(text)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{what} must be a number, got {text!r}") from None
    if not math.isfinite(x):
        raise InvalidInputError(f"{what} must be finite, got {x!r}")
    return x


def _point(value: Any, what: str) -> np.ndarray:
    """A point in mm from "x,y,z" text or a 3-list; returned in metres."""
    items = value.split(",") if isinstance(value, str) else value
    if not isinstance(items, (list, tuple)) or len(items) != 3:
        raise InvalidInputError(f"{what} must be three numbers x,y,z in mm, got {value!r}")
    return np.array([_num(v, f"{what} coordinate") for v in items]) * MM


class _SegmentAction(argparse.Action):
    """Collect --line/--arc/--circle in command-line order."""

    def __call__(self, parser, namespace, values, option_string=None):
        segs = list(getattr(namespace, "segments", None) or [])
        segs.append((self.const, values))
        namespace.segments = segs


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``saddle`` and ``path`` to the ``trajkit`` parser."""
    p = sub.add_parser(
        "saddle",
        help="constant-feed pass along a pipe-intersection (saddle) seam on a theta/Z machine",
        description=(
            "Plan the torch along the seam where a branch pipe (radius r, axis = z) meets a main "
            "pipe (radius R): coarse chords within --tolerance, a jerk-limited feed that slows "
            "down where an axis limit would break, and setpoints every --period. " + _UNITS_NOTE
        ),
    )
    p.add_argument("--main-radius", type=float, required=True, metavar="R", help="main pipe radius [mm]")
    p.add_argument("--branch-radius", type=float, required=True, metavar="r", help="branch pipe radius [mm]")
    p.add_argument("--angle", type=float, default=90.0, metavar="DEG",
                   help="angle between branch and main axes [deg] (default 90: orthogonal)")
    p.add_argument("--offset", type=float, default=0.0, metavar="D",
                   help="distance between the axes [mm] (default 0: the axes meet)")
    p.add_argument("--theta-start", type=float, default=0.0, metavar="DEG", help="start angle [deg]")
    _motion_options(p)
    g = p.add_argument_group("machine axis limits")
    g.add_argument("--theta-vmax", type=float, default=180.0, metavar="DEG/S", help="[deg/s] (default 180)")
    g.add_argument("--theta-amax", type=float, default=720.0, metavar="DEG/S2", help="[deg/s^2] (default 720)")
    g.add_argument("--theta-jmax", type=float, default=7200.0, metavar="DEG/S3", help="[deg/s^3] (default 7200)")
    g.add_argument("--z-vmax", type=float, default=100.0, metavar="MM/S", help="[mm/s] (default 100)")
    g.add_argument("--z-amax", type=float, default=1000.0, metavar="MM/S2", help="[mm/s^2] (default 1000)")
    g.add_argument("--z-jmax", type=float, default=10000.0, metavar="MM/S3", help="[mm/s^3] (default 10000)")
    _output_options(p)
    p.set_defaults(func=_run_saddle)

    q = sub.add_parser(
        "path",
        help="constant-feed motion along lines and 3-point arcs (options or a YAML file)",
        description=(
            "Plan the tool along straight lines and spatial arcs through three points, given "
            "with --start and, in order, --line / --arc / --circle, or in a YAML file "
            "(keys: start, segments: [{line: [x,y,z]}, {arc: {via: [...], end: [...]}}, "
            "{circle: {via: [...], via2: [...]}}], and optionally feed, tolerance, period, "
            "accel, jerk). The feed stops at corners. " + _UNITS_NOTE
        ),
    )
    q.add_argument("--file", metavar="JOB.yaml", help="YAML file with start and segments [mm]")
    q.add_argument("--start", metavar="X,Y,Z", help="start point [mm]")
    q.add_argument("--line", dest="segments", action=_SegmentAction, const="line", metavar="X,Y,Z",
                   help="straight line to this point [mm] (repeatable)")
    q.add_argument("--arc", dest="segments", action=_SegmentAction, const="arc", metavar="VIA:END",
                   help="arc from the current point via VIA to END, each X,Y,Z [mm] (repeatable)")
    q.add_argument("--circle", dest="segments", action=_SegmentAction, const="circle",
                   metavar="VIA:VIA2", help="full circle through the current point, VIA and VIA2 [mm]")
    q.add_argument("--corner-angle", type=float, default=None, metavar="DEG",
                   help="tangent jumps above this are corners where the feed stops [deg] "
                        "(default 0.01; smaller jumps from rounded points are passed through)")
    _motion_options(q, required=False)
    _output_options(q)
    q.set_defaults(func=_run_path, segments=None)


def _motion_options(p, required: bool = True) -> None:
    p.add_argument("--feed", type=float, required=required, metavar="V", help="tool speed [mm/s]")
    p.add_argument("--tolerance", type=float, required=required, metavar="E",
                   help="chord tolerance [mm]: coarse chords and lines between setpoints stay within it")
    p.add_argument("--period", type=float, required=required, metavar="DT",
                   help="control period [s], 0.0001 to 0.1")
    p.add_argument("--accel", type=float, default=None, metavar="A",
                   help="tangential acceleration limit [mm/s^2] (default 500)")
    p.add_argument("--jerk", type=float, default=None, metavar="J",
                   help="tangential jerk limit [mm/s^3] (default 5000)")


def _output_options(p) -> None:
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    p.add_argument("--csv", metavar="FILE",
                   help="write setpoints: t_s, x_mm, y_mm, z_mm (saddle: and theta_deg, z_axis_mm)")
    p.add_argument("--plot", metavar="FILE.png", help="write a figure: path with chords, axes against time")


# ------------------------------------------------------------------ saddle
def _run_saddle(args: argparse.Namespace) -> int:
    geo = (_num(args.main_radius, "--main-radius"), _num(args.branch_radius, "--branch-radius"),
           math.radians(_num(args.angle, "--angle")), _num(args.offset, "--offset"),
           math.radians(_num(args.theta_start, "--theta-start")))
    try:  # the geometry is scale-free: validate in mm so that messages name mm values
        SaddleCurve(*geo)
    except InvalidInputError as exc:
        raise InvalidInputError(f"{exc} [mm]") from None
    curve = SaddleCurve(geo[0] * MM, geo[1] * MM, geo[2], geo[3] * MM, geo[4])
    feed, tol, period, acc, jerk = _motion_values(args)
    d2r = math.pi / 180.0
    machine = SaddleMachine(
        AxisLimits(args.theta_vmax, args.theta_amax, args.theta_jmax, name="theta").scaled(d2r),
        AxisLimits(args.z_vmax, args.z_amax, args.z_jmax, name="z_axis").scaled(MM),
    )
    _check_rows(curve.length / feed, period)
    chords = discretize(curve, tol)
    plan = plan_saddle(curve, feed, acc, jerk, machine, tol, period)
    fs, ax = plan.setpoints(period)
    th_deg = np.degrees(ax[0, 0] - curve.theta_start) + math.degrees(curve.theta_start)
    summary = {
        "path_length_mm": curve.length / MM,
        "chords": chords.count,
        "chords_uniform_theta": uniform_chord_count(curve, tol, start=chords.count),
        "max_chord_error_mm": chords.max_error / MM,
        "tolerance_mm": tol / MM,
        "duration_s": plan.duration,
        "setpoints": int(fs.t.size),
        "period_s": period,
        "feed_mm_s": feed / MM,
        "max_tool_speed_mm_s": plan.feed_plan.peak_speed / MM,
        "tangential_accel_used_mm_s2": plan.feed_plan.a_max / MM,
        "tangential_jerk_used_mm_s3": plan.feed_plan.j_max / MM,
        "max_axis_speed": {
            "theta_deg_s": math.degrees(float(plan.check.peaks[0, 0])),
            "z_axis_mm_s": float(plan.check.peaks[1, 0]) / MM,
        },
        "axis_limit_use": {
            nm: dict(zip(("velocity", "acceleration", "jerk"), map(float, plan.check.ratio[i])))
            for i, nm in enumerate(("theta", "z_axis"))
        },
        "slowdowns": [
            {"s_start_mm": z["s_start"] / MM, "s_end_mm": z["s_end"] / MM,
             "theta_start_deg": z["theta_start_deg"], "theta_end_deg": z["theta_end_deg"],
             "speed_mm_s": z["speed"] / MM, "reason": z["reason"]}
            for z in plan.report()
        ],
    }
    if args.csv:
        _write_csv(args.csv, fs.t, fs.points, {"theta_deg": th_deg, "z_axis_mm": ax[1, 0] / MM})
    if args.plot:
        from ..plot.paths import plot_saddle_plan

        plot_saddle_plan(plan, chords, path=args.plot)
    if args.json:
        print_json(summary)
    else:
        _print_summary("saddle seam", summary)
    return 0


# -------------------------------------------------------------------- path
def load_path_file(filename: str) -> dict:
    """Read a path job (YAML) into a dict with ``start`` and ``segments`` (mm)."""
    from ..io.document import plain, read_document

    data = plain(read_document(filename))
    if not isinstance(data, dict):
        raise InvalidInputError(f"{filename}: expected a mapping with 'start' and 'segments'")
    unknown = set(data) - {"start", "segments", "feed", "tolerance", "period", "accel", "jerk", "units",
                           "corner_angle"}
    if unknown:
        raise InvalidInputError(f"{filename}: unknown key(s) {sorted(unknown)}")
    if data.get("units", "mm") != "mm":
        raise InvalidInputError(f"{filename}: units must be 'mm', got {data.get('units')!r}")
    segs = data.get("segments")
    if not isinstance(segs, list) or not segs:
        raise InvalidInputError(f"{filename}: 'segments' must be a non-empty list")
    out = []
    for i, sg in enumerate(segs):
        if not isinstance(sg, dict) or len(sg) != 1:
            raise InvalidInputError(f"{filename}: segment {i} must be one of line/arc/circle, got {sg!r}")
        (kind, val), = sg.items()
        if kind == "line":
            out.append(("line", val))
        elif kind == "arc" and isinstance(val, dict) and set(val) == {"via", "end"}:
            out.append(("arc", (val["via"], val["end"])))
        elif kind == "circle" and isinstance(val, dict) and set(val) == {"via", "via2"}:
            out.append(("circle", (val["via"], val["via2"])))
        else:
            raise InvalidInputError(
                f"{filename}: segment {i} must be {{line: [x,y,z]}}, {{arc: {{via, end}}}} or "
                f"{{circle: {{via, via2}}}}, got {sg!r}"
            )
    return {**data, "segments": out}


def build_path(start: Any, segments: list, corner_angle_deg: float = DEFAULT_CORNER_DEG) -> CompositePath:
    """Build a composite path from a start point and (kind, value) segments [mm]."""
    cur = _point(start, "start")
    segs: list[Line | Arc3] = []
    for i, (kind, val) in enumerate(segments):
        what = f"segment {i} ({kind})"
        if kind == "line":
            end = _point(val, f"{what} end")
            if np.array_equal(end, cur):
                raise InvalidInputError(f"{what} has zero length: it ends where it starts, "
                                        f"{(cur / MM).tolist()} mm")
            segs.append(Line(cur, end))
        else:
            if isinstance(val, str):
                parts = val.split(":")
                if len(parts) != 2:
                    raise InvalidInputError(f"{what} must be two points X,Y,Z:X,Y,Z [mm], got {val!r}")
            else:
                parts = list(val)
            a = _point(parts[0], f"{what} via point")
            b = _point(parts[1], f"{what} {'end' if kind == 'arc' else 'second via'} point")
            try:  # validate in mm so that the message names the points as given
                circle_through(cur / MM, a / MM, b / MM)
            except InvalidInputError as exc:
                raise InvalidInputError(f"{what}: {exc} [mm]") from None
            arc = Arc3(cur, a, b, full_circle=(kind == "circle"))
            segs.append(arc)
            end = arc.end_point
        cur = end
    if not segs:
        raise InvalidInputError("path needs at least one --line, --arc or --circle (or --file)")
    ca = _num(corner_angle_deg, "--corner-angle")
    if not 0.0 <= ca < 180.0:
        raise InvalidInputError(f"--corner-angle must lie in [0, 180) deg, got {ca!r}")
    return CompositePath(segs, corner_angle=math.radians(ca))


def _run_path(args: argparse.Namespace) -> int:
    job: dict = {}
    if args.file:
        job = load_path_file(args.file)
    for key in ("feed", "tolerance", "period", "accel", "jerk", "corner_angle"):
        if getattr(args, key) is None and key in job:
            setattr(args, key, job[key])
    for key in ("feed", "tolerance", "period"):
        if getattr(args, key) is None:
            raise InvalidInputError(f"--{key} is required (on the command line or in the file)")
    start = args.start if args.start is not None else job.get("start")
    if start is None:
        raise InvalidInputError("--start is required (on the command line or in the file)")
    segments = (args.segments or []) if args.segments else job.get("segments", [])
    path = build_path(start, segments,
                      DEFAULT_CORNER_DEG if args.corner_angle is None else args.corner_angle)
    feed, tol, period, acc, jerk = _motion_values(args)
    _check_rows(path.length / feed, period)
    chords = discretize(path, tol)
    plan = plan_feed(path, feed, acc, jerk, tolerance=tol, period=period)
    fs = plan.setpoints(period)
    vel = np.diff(fs.points, axis=0) / period
    summary = {
        "path_length_mm": path.length / MM,
        "segments": len(path.segments),
        "corners": len(path.corners()),
        "chords": chords.count,
        "max_chord_error_mm": chords.max_error / MM,
        "tolerance_mm": tol / MM,
        "duration_s": plan.duration,
        "setpoints": int(fs.t.size),
        "period_s": period,
        "feed_mm_s": feed / MM,
        "max_tool_speed_mm_s": plan.peak_speed / MM,
        "max_axis_speed": {nm: float(np.max(np.abs(vel[:, i]), initial=0.0)) / MM
                           for i, nm in enumerate(("x_mm_s", "y_mm_s", "z_mm_s"))},
        "slowdowns": [
            {"s_start_mm": z.s_start / MM, "s_end_mm": z.s_end / MM, "speed_mm_s": z.speed / MM,
             "reason": z.reason}
            for z in plan.slowdowns
        ],
    }
    if args.csv:
        _write_csv(args.csv, fs.t, fs.points, {})
    if args.plot:
        from ..plot.paths import plot_path_plan

        plot_path_plan(plan, chords, path=args.plot)
    if args.json:
        print_json(summary)
    else:
        _print_summary("path", summary)
    return 0


# ----------------------------------------------------------------- helpers
def _motion_values(args) -> tuple[float, float, float, float, float]:
    feed = _num(args.feed, "--feed") * MM
    tol = _num(args.tolerance, "--tolerance") * MM
    period = _num(args.period, "--period")
    acc = _num(500.0 if args.accel is None else args.accel, "--accel") * MM
    jerk = _num(5000.0 if args.jerk is None else args.jerk, "--jerk") * MM
    for name, v in (("--feed", feed), ("--tolerance", tol), ("--accel", acc), ("--jerk", jerk)):
        if v <= 0:
            raise InvalidInputError(f"{name} must be larger than zero, got {v / MM!r}")
    return feed, tol, period, acc, jerk


def _check_rows(duration_floor: float, period: float) -> None:
    """Refuse early when even the nominal duration (a lower bound) gives too many setpoints;
    the planned duration is checked again before sampling."""
    count_samples(duration_floor, period, what="setpoints")


def _write_csv(filename: str, t, points, axes: dict) -> None:
    """Setpoints: ``t_s, x_mm, y_mm, z_mm`` and the machine axes (names carry their units)."""
    cols = [t, points[:, 0] / MM, points[:, 1] / MM, points[:, 2] / MM, *axes.values()]
    atomic_write(os.fspath(filename), csv_text(["t_s", "x_mm", "y_mm", "z_mm", *axes.keys()], cols))


def _print_summary(title: str, summary: dict) -> None:
    rows = []
    for k, v in summary.items():
        if isinstance(v, dict):
            for k2, v2 in v.items():
                rows.append((f"{k}.{k2}", v2 if not isinstance(v2, dict) else ", ".join(
                    f"{a}={b:.3g}" for a, b in v2.items())))
        elif isinstance(v, list):
            rows.append((k, len(v)))
            for z in v:
                rows.append(("", ", ".join(f"{a}={b:.4g}" if isinstance(b, float) else f"{a}={b}"
                                           for a, b in z.items())))
        else:
            rows.append((k, v))
    print_table(title, ("quantity", "value"), rows)
