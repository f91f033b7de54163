"""Sub-commands ``trajkit move`` (one axis) and ``trajkit ptp`` (several axes).

Thin shells over :func:`trajkit.plan_move` and :func:`trajkit.plan_ptp`:
parse the options (or a YAML/JSON job file), call the library, then print a
table or JSON and optionally write samples (CSV) and a figure (PNG).
Positions are in the axis unit named by ``--unit`` (``m`` by default; the
planner itself is unit-agnostic), times in seconds.
"""

from __future__ import annotations

import argparse
import math
import os
import re
import sys
from collections.abc import Sequence
from typing import Any, Literal, overload

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from .._atomicio import atomic_write
from .._csvio import csv_text, unit_suffix
from .._sampling import MAX_SAMPLES, count_samples
from .._validate import check_finite
from ..errors import InvalidInputError
from ..io.document import Kind, plain, read_document
from ..io.schema import Real, RealOrInf, short_repr, validation_message
from ..limits import AxisLimits
from ..profiles import PHASE_NAMES, Profile, plan_move
from ..sync import plan_ptp
from ..trajectory import SYNC_MODES, Trajectory
from ._console import print_json, print_table

__all__ = ["register", "load_ptp_job", "PtpJob", "JobLimits"]

#: Largest number of CSV rows a ``--csv`` export may write (guards against a
#: typo in ``--period`` filling the disk).
MAX_CSV_ROWS = MAX_SAMPLES

#: Most axes of a ``trajkit ptp`` job (for many independent moves use ``plan_moves``).
MAX_PTP_AXES = 1024

#: Suffixes accepted by ``--file``.
_JOB_SUFFIXES: dict[str, Kind] = {".yaml": "yaml", ".yml": "yaml", ".json": "json"}

#: (option, AxisLimits field, required) for the limit options shared by both commands.
_LIMIT_OPTIONS = (
    ("--v-max", "v_max", True),
    ("--a-max", "a_max", True),
    ("--j-max", "j_max", True),
    ("--a-max-decel", "a_max_decel", False),
    ("--j-max-decel", "j_max_decel", False),
)


# --------------------------------------------------------------------- parsing
def _number(text: str, option: str) -> float:
    """Parse one number (``inf`` allowed; the library decides where it is valid)."""
    try:
        return float(text.strip())
    except (TypeError, ValueError, AttributeError):
        raise InvalidInputError(f"{option} must be a number, got {text!r}") from None


def _numbers(text: str, option: str) -> list[float]:
    """Parse a comma-separated list of numbers (``"0,1.5,-2"``)."""
    parts = [p for p in str(text).split(",")]
    if any(not p.strip() for p in parts):
        raise InvalidInputError(f"{option} must be a comma-separated list of numbers, got {text!r}")
    return [_number(p, option) for p in parts]


def _per_axis(values: Sequence[Any], n: int, option: str) -> list[Any]:
    """Broadcast one value to ``n`` axes, or check there is one per axis."""
    if len(values) == 1:
        return list(values) * n
    if len(values) != n:
        raise InvalidInputError(
            f"{option} has {len(values)} values but start/goal have {n} axes "
            "(give one value for all axes or one per axis)"
        )
    return list(values)


def _strings(text: str, option: str) -> list[str]:
    parts = [p.strip() for p in str(text).split(",")]
    if any(not p for p in parts):
        raise InvalidInputError(f"{option} must be a comma-separated list of names, got {text!r}")
    return parts


# ------------------------------------------------------------------- job file

class JobLimits(BaseModel):
    """Limits of one axis in a job file (same fields as :class:`AxisLimits`)."""

    model_config = ConfigDict(extra="forbid")
    v_max: RealOrInf
    a_max: RealOrInf
    j_max: RealOrInf
    a_max_decel: RealOrInf | None = None
    j_max_decel: RealOrInf | None = None
    position_min: RealOrInf = -math.inf
    position_max: RealOrInf = math.inf


class PtpJob(BaseModel):
    """A ``trajkit ptp --file`` job (YAML or JSON).

    Attributes
    ----------
    start, goal : list of float, length n_axes
        Positions [axis unit].
    limits : JobLimits or list of n_axes JobLimits
        One mapping for every axis, or one per axis.
    names : list of str, optional
        Axis names (table, CSV header, error messages).
    sync : {"time", "phase", "none"}
    duration : float, optional
        Requested duration [s].
    unit : str or list of str
        Position unit of the axes (labels only), default ``"m"``.
    """

    model_config = ConfigDict(extra="forbid")
    start: list[Real] = Field(min_length=1, max_length=MAX_PTP_AXES)
    goal: list[Real] = Field(min_length=1, max_length=MAX_PTP_AXES)
    limits: list[JobLimits] = Field(min_length=1)
    names: list[str] | None = None
    sync: Literal["time", "phase", "none"] = "time"
    duration: Real | None = None
    unit: str | list[str] = "m"

    @field_validator("limits", mode="before")
    @classmethod
    def _one_or_many(cls, v: Any) -> Any:
        return [v] if isinstance(v, dict) else v


def load_ptp_job(path: str | os.PathLike) -> PtpJob:
    """Read and validate a ``ptp`` job file.

    Parameters
    ----------
    path : str or os.PathLike
        A ``.yaml``/``.yml`` or ``.json`` file with the fields of :class:`PtpJob`.

    Returns
    -------
    PtpJob

    Raises
    ------
    InvalidInputError
        Unknown suffix, unparsable file, or a bad field (the message names the
        file and the field, e.g. ``limits.1.v_max``).
    OSError
        The file cannot be read.
    """
    p = os.fspath(path)
    kind = _JOB_SUFFIXES.get(os.path.splitext(p)[1].lower())
    if kind is None:
        raise InvalidInputError(f"--file must end in .yaml, .yml or .json, got {p!r}")
    data = plain(read_document(p, kind=kind))
    if not isinstance(data, dict):
        raise InvalidInputError(f"{p}: expected a mapping of fields at the top level, "
                                f"got {type(data).__name__}")
    try:
        return PtpJob.model_validate(data)
    except ValidationError as exc:
        raise InvalidInputError(f"{p}: {validation_message(exc)}") from None


# ------------------------------------------------------------------- outputs
def _jsonable(obj: Any) -> Any:
    """Replace non-finite floats by the strings "inf"/"-inf"/"nan" (strict JSON)."""
    if isinstance(obj, float):
        if math.isfinite(obj):
            return obj
        return "nan" if math.isnan(obj) else ("inf" if obj > 0 else "-inf")
    if isinstance(obj, dict):
        return {k: _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
    if isinstance(obj, np.floating):
        return _jsonable(float(obj))
    return obj


def _limits_dict(lim: AxisLimits) -> dict:
    return {
        "v_max": lim.v_max, "a_max": lim.a_max, "j_max": lim.j_max,
        "a_max_decel": lim.a_max_decel, "j_max_decel": lim.j_max_decel,
        "position_min": lim.position_min, "position_max": lim.position_max,
    }


def _phase_end_states(profile: Profile) -> np.ndarray:
    """State at the END of each phase, shape (7, 4): time, position, velocity, acceleration.

    The acceleration is the value the phase ends with (its left limit), which
    differs from the value entering the next phase only for infinite jerk.
    """
    tb = profile.phase_times
    bs = profile.boundary_states()
    out = np.empty((7, 4))
    out[:, 0] = tb[1:]
    out[:, 1] = bs[1:, 0]
    out[:, 2] = bs[1:, 1]
    out[:, 3] = bs[:7, 2] + np.asarray(profile.jerks) * np.asarray(profile.phase_durations)
    return out


def _profile_json(profile: Profile, name: str | None, unit: str) -> dict:
    d = profile.to_dict()
    if name is not None:
        d = {"name": name, **d}
    end = _phase_end_states(profile)
    for ph, row in zip(d["phases"], end):
        ph["t_end_s"] = float(row[0])
        ph["end_state"] = {"position": float(row[1]), "velocity": float(row[2]),
                           "acceleration": float(row[3])}
    d["unit"] = unit
    d["limits"] = _limits_dict(profile.limits)
    return d


def _reached_text(profile: Profile) -> str:
    r = sorted(profile.reached)
    return ", ".join(r) if r else "none"


def _print_phases(title: str, profile: Profile, unit: str) -> None:
    end = _phase_end_states(profile)
    rows = []
    for k, name in enumerate(PHASE_NAMES):
        rows.append([k + 1, name, profile.phase_durations[k], profile.jerks[k],
                     end[k, 0], end[k, 1], end[k, 2], end[k, 3]])
    print_table(
        title,
        ["#", "phase", "duration [s]", f"jerk [{unit}/s^3]", "t_end [s]",
         f"pos [{unit}]", f"vel [{unit}/s]", f"acc [{unit}/s^2]"],
        rows,
    )


def _check_out_path(path: str | None, option: str) -> None:
    """Fail before planning when an output file's directory does not exist."""
    if path is None:
        return
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise InvalidInputError(f"{option} {path!r}: directory {folder!r} does not exist")


def _check_outputs(args: argparse.Namespace) -> None:
    _check_out_path(args.csv, "--csv")
    _check_out_path(args.plot, "--plot")
    if args.plot is not None:
        from ..plot.profiles import _check_path

        _check_path(args.plot)
        try:
            from ..plot import require_matplotlib

            require_matplotlib()
        except ImportError as exc:  # one line, exit 2, instead of a traceback
            from . import UsageError

            raise UsageError(f"--plot: {exc}") from None


def _check_sampling(args: argparse.Namespace, duration: float) -> float | None:
    """Validate the ``--csv``/``--period`` pair; return the period or None."""
    if args.period is not None and args.csv is None:
        raise InvalidInputError("--period needs --csv FILE (it is the CSV sample period)")
    if args.csv is None:
        return None
    if args.period is None:
        raise InvalidInputError("--csv needs --period DT (the sample period in s)")
    dt = _number(args.period, "--period")
    if not (math.isfinite(dt) and dt > 0.0):
        raise InvalidInputError(f"--period must be a finite time > 0 s, got {dt!r}")
    count_samples(duration, dt, MAX_CSV_ROWS, what="CSV rows")
    return dt


def _write_csv(path: str, traj: Trajectory, names: Sequence[str], units: Sequence[str],
               period: float, single: bool) -> int:
    """Write samples with a header row naming quantity and unit; return the row count."""
    t = traj.times(period, max_samples=MAX_CSV_ROWS)
    s = traj.sample(t)
    header = ["t_s"]
    cols = [t]
    for k, (nm, u) in enumerate(zip(names, units)):
        pre = "" if single else f"{nm}_"
        header += [f"{pre}{q}_{unit_suffix(u, d)}"
                   for d, q in enumerate(("position", "velocity", "acceleration", "jerk"))]
        cols += [s.position[:, k], s.velocity[:, k], s.acceleration[:, k], s.jerk[:, k]]
    atomic_write(path, csv_text(header, cols))
    return int(t.size)


def _note(args: argparse.Namespace, text: str) -> None:
    """Progress notes go to stderr with --json (stdout stays pure JSON)."""
    print(text, file=sys.stderr if args.json else sys.stdout)


@overload
def _limits_from_options(args: argparse.Namespace, n: None) -> AxisLimits: ...


@overload
def _limits_from_options(args: argparse.Namespace, n: int,
                         names: Sequence[str] | None = None) -> list[AxisLimits]: ...


def _limits_from_options(
    args: argparse.Namespace, n: int | None, names: Sequence[str] | None = None
) -> list[AxisLimits] | AxisLimits:
    """AxisLimits from the limit options: one (``n=None``) or one per axis."""
    # keyword arguments of AxisLimits: a number or None (n=None), else a list of them
    values: dict[str, Any] = {}
    for opt, field, required in _LIMIT_OPTIONS:
        raw = getattr(args, field)
        if raw is None:
            if required:
                raise InvalidInputError(f"{opt} is required")
            values[field] = None if n is None else [None] * n
            continue
        if n is None:
            values[field] = _number(raw, opt)
        else:
            values[field] = _per_axis(_numbers(raw, opt), n, opt)
    if n is None:
        return AxisLimits(**values)
    fields = [fl for _, fl, _ in _LIMIT_OPTIONS]
    return [AxisLimits(**{f: values[f][k] for f in fields}, name=names[k] if names else k)
            for k in range(n)]


# ------------------------------------------------------------------ commands
def _cmd_move(args: argparse.Namespace) -> int:
    start = _number(args.start, "--start")
    goal = _number(args.goal, "--goal")
    limits = _limits_from_options(args, None)
    duration = None if args.duration is None else _number(args.duration, "--duration")
    _check_outputs(args)
    profile = plan_move(start, goal, limits, duration=duration)
    period = _check_sampling(args, profile.duration)
    unit = args.unit
    if args.json:
        print_json(_jsonable(_profile_json(profile, None, unit)))
    else:
        print_table(
            f"move {start:g} -> {goal:g} {unit}",
            ["duration [s]", "min duration [s]", "shape", "reached limits",
                   f"peak vel [{unit}/s]", f"peak acc [{unit}/s^2]",
                   f"peak dec [{unit}/s^2]"],
            [[profile.duration, profile.min_duration, profile.shape, _reached_text(profile),
              profile.peak_velocity, profile.peak_acceleration, profile.peak_deceleration]],
        )
        _print_phases("phases (state at the end of each phase)", profile, unit)
    if period is not None:
        rows = _write_csv(args.csv, Trajectory([profile], names=["x"]), ["x"], [unit],
                          period, single=True)
        _note(args, f"wrote {args.csv} ({rows} samples every {period:g} s)")
    if args.plot is not None:
        from ..plot.profiles import plot_profile

        plot_profile(profile, args.plot, unit=unit)
        _note(args, f"wrote {args.plot}")
    return 0


_UNIT = re.compile(r"^[A-Za-z][A-Za-z0-9]*$")


def _check_axes(names: Sequence[str], units: Sequence[str], where: str) -> None:
    """Refuse duplicate axis names, too many axes and units that are not plain words."""
    if len(names) > MAX_PTP_AXES:
        raise InvalidInputError(f"{where or ''}start has {len(names)} axes, more than the "
                                f"{MAX_PTP_AXES} a ptp job may have (plan_moves plans many "
                                "independent moves at once)")
    seen: dict[str, int] = {}
    for k, nm in enumerate(names):
        if nm in seen:
            raise InvalidInputError(f"{where or '--'}names: axes {seen[nm]} and {k} are both "
                                    f"called {short_repr(nm)}; axis names must be unique")
        seen[nm] = k
    for u in units:
        if not _UNIT.match(u):
            raise InvalidInputError(f"{where or '--'}unit: {short_repr(u)} is not a unit name "
                                    "(letters and digits, e.g. m, rad, deg, mm)")


def _ptp_inputs(args: argparse.Namespace):
    """Return start, goal, limits list, names, units, sync, duration from options or --file."""
    if args.file is not None:
        given = [opt for opt, attr in (("--start", "start"), ("--goal", "goal"),
                                       ("--names", "names"))
                 if getattr(args, attr) is not None]
        given += [opt for opt, field, _ in _LIMIT_OPTIONS if getattr(args, field) is not None]
        if given:
            raise InvalidInputError(
                f"--file cannot be combined with {', '.join(given)} (put them in the file)"
            )
        job = load_ptp_job(args.file)
        n = len(job.start)
        if len(job.goal) != n:
            raise InvalidInputError(
                f"{args.file}: field goal has {len(job.goal)} values but start has {n}"
            )
        lims = _per_axis(job.limits, n, f"{args.file}: field limits")
        names = job.names
        units_raw = [job.unit] if isinstance(job.unit, str) else job.unit
        sync = job.sync
        duration = job.duration
        if names is not None and len(names) != n:
            raise InvalidInputError(
                f"{args.file}: field names has {len(names)} entries but start has {n} axes"
            )
        limits = [
            AxisLimits(**lm.model_dump(), name=(names[k] if names else k))
            for k, lm in enumerate(lims)
        ]
        if args.unit is not None:
            units_raw = _strings(args.unit, "--unit")
        units = _per_axis(units_raw, n, f"{args.file}: field unit")
    else:
        if args.start is None or args.goal is None:
            raise InvalidInputError("ptp needs --start and --goal (or --file JOB.yaml)")
        start = _numbers(args.start, "--start")
        goal = _numbers(args.goal, "--goal")
        n = len(start)
        if len(goal) != n:
            raise InvalidInputError(f"--goal has {len(goal)} values but --start has {n}")
        names = None if args.names is None else _strings(args.names, "--names")
        if names is not None and len(names) != n:
            raise InvalidInputError(f"--names has {len(names)} entries but --start has {n} axes")
        limits = _limits_from_options(args, n, names)
        units = _per_axis(_strings(args.unit or "m", "--unit"), n, "--unit")
        sync = "time"
        duration = None
    if args.file is not None:
        start, goal = job.start, job.goal
    if args.sync is not None:
        sync = args.sync
    if args.duration is not None:
        duration = _number(args.duration, "--duration")
    if names is None:
        names = [f"q{k}" for k in range(n)]
    where = "" if args.file is None else f"{args.file}: field "
    _check_axes(names, units, where)
    start = [check_finite(x, f"{where}start", names[k]) for k, x in enumerate(start)]
    goal = [check_finite(x, f"{where}goal", names[k]) for k, x in enumerate(goal)]
    return start, goal, limits, list(names), list(units), sync, duration


def _cmd_ptp(args: argparse.Namespace) -> int:
    start, goal, limits, names, units, sync, duration = _ptp_inputs(args)
    _check_outputs(args)
    traj = plan_ptp(start, goal, limits, sync=sync, duration=duration)
    traj = Trajectory(traj.axes, traj.sync, names=names)
    period = _check_sampling(args, traj.duration)
    if args.json:
        print_json(_jsonable({
            "duration_s": traj.duration,
            "sync": traj.sync,
            "axes": [_profile_json(p, nm, u) for p, nm, u in zip(traj.axes, names, units)],
        }))
    else:
        print_table(
            f"ptp, {traj.n_axes} axes, sync={traj.sync}: duration {traj.duration:.6g} s",
            ["axis", "start", "goal", "unit", "duration [s]", "min duration [s]",
                   "shape", "reached limits", "peak vel [unit/s]"],
            [[nm, p.start, p.goal, u, p.duration, p.min_duration, p.shape, _reached_text(p),
              p.peak_velocity] for p, nm, u in zip(traj.axes, names, units)],
        )
        for p, nm, u in zip(traj.axes, names, units):
            _print_phases(f"axis {nm}: phases (state at the end of each phase)", p, u)
    if period is not None:
        rows = _write_csv(args.csv, traj, names, units, period, single=False)
        _note(args, f"wrote {args.csv} ({rows} samples every {period:g} s)")
    if args.plot is not None:
        from ..plot.profiles import plot_trajectory

        plot_trajectory(traj, args.plot, units=units)
        _note(args, f"wrote {args.plot}")
    return 0


# ------------------------------------------------------------------ register
def _add_outputs(p: argparse.ArgumentParser) -> None:
    p.add_argument("--duration", metavar="T",
                   help="stretch the motion to exactly T s (>= the minimum duration)")
    p.add_argument("--json", action="store_true", help="print machine-readable JSON")
    p.add_argument("--csv", metavar="FILE", help="write samples to FILE (needs --period)")
    p.add_argument("--period", metavar="DT", help="CSV sample period [s]")
    p.add_argument("--plot", metavar="FILE.png",
                   help="write the stacked position/velocity/acceleration/jerk figure")


def register(subparsers: Any) -> None:
    """Add the ``move`` and ``ptp`` sub-commands to ``subparsers``."""
    mv = subparsers.add_parser(
        "move", help="plan a time-optimal jerk-limited move of one axis",
        description="Plan a rest-to-rest, jerk-limited move of one axis and print its "
                    "duration, shape and phases. Negative numbers: --start=-1.",
    )
    mv.add_argument("--start", required=True, metavar="S", help="start position [unit]")
    mv.add_argument("--goal", required=True, metavar="G", help="goal position [unit]")
    for opt, field, required in _LIMIT_OPTIONS:
        mv.add_argument(opt, dest=field, required=required, metavar="X",
                        help=f"{field} [unit/s^k]; 'inf' for none where allowed"
                        + ("" if required else " (default: same as the accel leg)"))
    mv.add_argument("--unit", default="m", help="position unit for labels (default m)")
    _add_outputs(mv)
    mv.set_defaults(func=_cmd_move)

    pt = subparsers.add_parser(
        "ptp", help="plan a synchronised point-to-point move of several axes",
        description="Plan a jerk-limited point-to-point move of several axes. Values are "
                    "comma lists, one per axis (limits: one value for all axes or one per "
                    "axis); or give everything in --file JOB.yaml|JOB.json. Negative "
                    "numbers: --start=-1,2.",
    )
    pt.add_argument("--start", metavar="S1,S2,..", help="start positions [unit]")
    pt.add_argument("--goal", metavar="G1,G2,..", help="goal positions [unit]")
    for opt, field, _ in _LIMIT_OPTIONS:
        pt.add_argument(opt, dest=field, metavar="X[,X..]",
                        help=f"{field}: one value or one per axis")
    pt.add_argument("--names", metavar="A,B,..", help="axis names (default q0, q1, ...)")
    pt.add_argument("--unit", metavar="U[,U..]",
                    help="position unit(s) for labels (default m, or the job file's)")
    pt.add_argument("--sync", metavar="|".join(SYNC_MODES),
                    help="synchronisation: time (default), phase or none")
    pt.add_argument("--file", metavar="JOB.yaml",
                    help="read start, goal, limits, names, sync, duration, unit from a "
                         "YAML or JSON file")
    _add_outputs(pt)
    pt.set_defaults(func=_cmd_ptp)
