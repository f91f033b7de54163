"""Plan the HMI's jobs with the public library and tabulate them at the control period.

No motion math here: every job is planned by the same public function a
Python user calls (:func:`trajkit.interpolation.plan_saddle`,
:func:`trajkit.palletizing.plan_cycle`, :func:`trajkit.io.program.parse_program`,
:func:`trajkit.plan_ptp`), then sampled once at the control period into a
:class:`JobTable` (SI units) that the run loop plays back.

Every job is planned with :func:`trajkit.runtime.streamer.override_limits` of
the machine's limits (the override reserve, :data:`OVERRIDE_RESERVE` of the
acceleration and jerk) and streamed against the machine's full limits, so
that the feed-override slider and pause are proven within every limit while
the job runs at its planned speed at 100 %.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import InvalidInputError
from ..limits import AxisLimits
from ..runtime.streamer import OVERRIDE_RESERVE, override_limits
from .models import PalletJob, ProgramJob, SaddleJob

__all__ = ["JobTable", "plan_job", "jog_goal", "jog_limits", "jog_table", "check_size", "summary_view", "MM",
           "PATH_PREVIEW_POINTS", "MAX_SETPOINTS"]

MM = 1e-3  # metres per millimetre

#: Points of the planned tool path sent to the page.
PATH_PREVIEW_POINTS = 600

#: Largest number of setpoints a job may have (a tiny period on a long job
#: must not fill the memory).
MAX_SETPOINTS = 2_000_000


@dataclass
class JobTable:
    """A planned job sampled at its control period.

    Attributes
    ----------
    kind : str
        ``"saddle"``, ``"pallet"``, ``"program"`` or ``"jog"``.
    title : str
    axis_names : tuple of str
    axis_units : tuple of str
        Display unit per axis, ``"deg"`` or ``"mm"``.
    axis_scale : ndarray, shape (k,)
        Display unit per SI unit (180/pi for rad, 1000 for m).
    t : ndarray, shape (n,)
        Setpoint times [s], 0, dt, ..., duration.
    q, qd : ndarray, shape (n, k)
        Axis positions [rad or m] and velocities [/s].
    xyz : ndarray, shape (n, 3)
        Tool position [m].
    period : float
        Control period [s].
    summary : dict
        JSON-ready facts shown in the page (duration, limits used ...).
    robot : str or None
        Robot model name whose joints the axes are (jog/teach follow it).
    v_max : ndarray, shape (k,), optional
        Axis velocity limits [SI].
    source : callable, optional
        ``source()`` returns the plan as a :class:`trajkit.runtime.ProgramSource`
        (what the streaming interpolator plays).
    tool_of : callable, optional
        ``tool_of(q)`` maps axis positions (k,) [SI] to the tool point (3,) [m]
        (used for the actual path from the servo simulation).
    machine_limits : tuple of AxisLimits, optional
        The machine's limits, which the runtime's monitors enforce; the job was
        planned with ``override_limits(machine_limits)``.
    """

    kind: str
    title: str
    axis_names: tuple
    axis_units: tuple
    axis_scale: np.ndarray
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    xyz: np.ndarray
    period: float
    summary: dict = field(default_factory=dict)
    robot: str | None = None
    v_max: np.ndarray | None = None
    source: Callable[[], Any] | None = None
    tool_of: Callable[[np.ndarray], np.ndarray] | None = None
    machine_limits: tuple | None = None

    @property
    def duration(self) -> float:
        """Planned duration [s]."""
        return float(self.t[-1])

    def state_at(self, tau: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions, velocities [SI] and tool point [m] at plan time ``tau`` (linear between setpoints)."""
        tau = min(max(tau, 0.0), self.duration)
        i = min(int(np.searchsorted(self.t, tau, side="right")) - 1, self.t.size - 2)
        i = max(i, 0)
        if self.t.size == 1:
            return self.q[0].copy(), self.qd[0].copy(), self.xyz[0].copy()
        w = (tau - self.t[i]) / (self.t[i + 1] - self.t[i])
        lerp = lambda a: a[i] + w * (a[i + 1] - a[i])  # noqa: E731
        return lerp(self.q), lerp(self.qd), lerp(self.xyz)

    def preview(self) -> dict:
        """The planned path and axes for the page: a few hundred points in mm/deg."""
        idx = np.unique(np.linspace(0, self.t.size - 1, PATH_PREVIEW_POINTS).round().astype(int))
        return {
            "kind": self.kind,
            "title": self.title,
            "axes": [{"name": n, "unit": u} for n, u in zip(self.axis_names, self.axis_units)],
            "duration_s": self.duration,
            "period_s": self.period,
            "path_mm": (self.xyz[idx] / MM).round(4).tolist(),
            "summary": self.summary,
            "summary_view": summary_view(self.summary, self.period),
        }


def check_size(duration: float, period: float) -> int:
    """Number of setpoints of a ``duration`` [s] plan at ``period`` [s], refused above the cap.

    Raises
    ------
    InvalidInputError
        More than :data:`MAX_SETPOINTS` setpoints (the message gives the
        cap and the longest job the period allows).
    """
    if not (math.isfinite(duration) and duration >= 0.0):
        raise InvalidInputError(f"the planned duration must be finite, got {duration!r} s")
    n = math.ceil(duration / period) + 1
    if n > MAX_SETPOINTS:
        raise InvalidInputError(
            f"the plan lasts {duration:.3f} s: at period_s {period:g} that is {n} setpoints, more "
            f"than the {MAX_SETPOINTS} a job may have (at most {(MAX_SETPOINTS - 1) * period:.1f} s "
            f"at this period): choose a longer period or a faster job"
        )
    return n


#: Label and unit shown in the page for each summary key.
SUMMARY_LABELS = {
    "duration_s": ("Planned duration", "s"),
    "path_length_mm": ("Path length", "mm"),
    "feed_mm_s": ("Programmed feed", "mm/s"),
    "max_tool_speed_mm_s": ("Highest tool speed", "mm/s"),
    "slowdowns": ("Slowed stretches", ""),
    "override_reserve": ("Planned accel. and jerk", "% of the machine's"),
    "boxes": ("Boxes", ""),
    "per_box_s": ("Time per box", "s"),
    "planner": ("Planner", ""),
    "robot": ("Robot", ""),
    "instructions": ("Instructions", ""),
}

_LIMIT_LABELS = {"velocity": "speed", "acceleration": "acceleration", "jerk": "jerk"}


def summary_view(summary: dict, period: float) -> list[dict]:
    """The summary as rows ``{"label", "value", "unit"}`` for the page (in display units)."""
    rows = [{"label": "Control period", "value": period * 1e3, "unit": "ms"}]
    for key, value in summary.items():
        if key == "axis_limit_use_pct":
            for axis, use in value.items():
                for qty, pct in use.items():
                    rows.append({"label": f"{axis} {_LIMIT_LABELS.get(qty, qty)} limit used",
                                 "value": pct, "unit": "%"})
            continue
        label, unit = SUMMARY_LABELS.get(key, (key.replace("_", " ").capitalize(), ""))
        if key == "override_reserve":
            value = 100.0 * value
        rows.append({"label": label, "value": value, "unit": unit})
    return rows


def _times(duration: float, period: float) -> np.ndarray:
    n = check_size(duration, period) - 1
    t = np.arange(n + 1) * period
    t[-1] = min(t[-1], duration)
    if t.size > 1 and t[-1] <= t[-2]:
        t = t[:-1]
        t[-1] = duration
    return t


def _scale(kinds) -> tuple[tuple, np.ndarray]:
    units = tuple("deg" if k == "revolute" else "mm" for k in kinds)
    scale = np.array([180.0 / math.pi if k == "revolute" else 1.0 / MM for k in kinds])
    return units, scale


def plan_saddle_job(req: SaddleJob) -> JobTable:
    """Plan a saddle seam on the theta/Z machine and tabulate theta and Z at the period."""
    from ..interpolation import SaddleMachine, plan_saddle
    from ..paths import SaddleCurve

    d2r = math.pi / 180.0
    try:  # the geometry is scale-free: validate in mm so that messages name mm values
        SaddleCurve(req.main_radius_mm, req.branch_radius_mm, req.angle_deg * d2r, req.offset_mm, 0.0)
    except InvalidInputError as exc:
        raise InvalidInputError(f"{exc} [mm]") from None
    curve = SaddleCurve(req.main_radius_mm * MM, req.branch_radius_mm * MM, req.angle_deg * d2r,
                        req.offset_mm * MM, 0.0)
    machine = SaddleMachine(
        AxisLimits(req.theta_vmax_deg_s, req.theta_amax_deg_s2, req.theta_jmax_deg_s3,
                   name="theta").scaled(d2r),
        AxisLimits(req.z_vmax_mm_s, req.z_amax_mm_s2, req.z_jmax_mm_s3, name="z_axis").scaled(MM),
    )
    check_size(curve.length / (req.feed_mm_s * MM), req.period_s)  # the nominal feed, before planning
    reserved = SaddleMachine(*override_limits([machine.theta, machine.z]))
    plan = plan_saddle(curve, req.feed_mm_s * MM, req.accel_mm_s2 * MM, req.jerk_mm_s3 * MM,
                       reserved, req.tolerance_mm * MM, req.period_s)
    check_size(plan.duration, req.period_s)  # the planned (slowed) duration, before sampling
    fs, ax = plan.setpoints(req.period_s)
    units, scale = _scale(("revolute", "prismatic"))
    summary = {
        "duration_s": plan.duration,
        "path_length_mm": curve.length / MM,
        "feed_mm_s": req.feed_mm_s,
        "max_tool_speed_mm_s": plan.feed_plan.peak_speed / MM,
        "slowdowns": len(plan.slowdowns),
        "override_reserve": OVERRIDE_RESERVE,
        "axis_limit_use_pct": {
            nm: {q: round(100 * float(plan.check.ratio[i, j]), 2)
                 for j, q in enumerate(("velocity", "acceleration", "jerk"))}
            for i, nm in enumerate(("theta", "z"))
        },
    }
    r = curve.branch_radius

    def source():
        from ..runtime import ProgramSource

        def sampler(t):
            st = plan.axes(t)  # (2, 4, n): axis, order
            return st[:, 0].T, st[:, 1].T, st[:, 2].T

        return ProgramSource(sampler, plan.duration, [reserved.theta, reserved.z], ("theta", "Z"),
                             motion_labels=["seam"], path_intervals=[(0.0, plan.duration)])

    def tool_of(q):  # the torch on the branch pipe at rotary angle theta and height Z
        return np.array([r * math.sin(q[0]), r * math.cos(q[0]), q[1]])

    return JobTable("saddle", f"saddle R{req.main_radius_mm:g}/r{req.branch_radius_mm:g} mm",
                    ("theta", "Z"), units, scale, fs.t, ax[:, 0].T.copy(), ax[:, 1].T.copy(),
                    fs.points.copy(), req.period_s, summary,
                    v_max=machine.limits_array()[:, 0].copy(), source=source, tool_of=tool_of,
                    machine_limits=(machine.theta, machine.z))


def plan_pallet_job(req: PalletJob) -> JobTable:
    """Plan the reference palletizing cell (:func:`trajkit.palletizing.seed_scenario`) for ``layers`` layers."""
    from ..palletizing import plan_cycle, seed_scenario

    machine = seed_scenario(layers=req.layers).robot
    sc = seed_scenario(layers=req.layers, robot=_reserved(machine))
    plan = plan_cycle(sc, req.planner)
    tl = plan.timeline
    t = _times(tl.duration, req.period_s)
    s = tl.sample(t)
    robot = sc.robot
    pose = robot.pose_from_joints(s.position)
    units, scale = _scale(("revolute", "prismatic", "prismatic", "revolute"))
    summary = {"duration_s": plan.total_s, "boxes": plan.n_boxes,
               "per_box_s": plan.per_box_s, "planner": req.planner,
               "override_reserve": OVERRIDE_RESERVE}
    return JobTable("pallet", f"palletizing ({req.planner}, {plan.n_boxes} boxes)",
                    ("A", "B", "C", "D"), units, scale, t, s.position, s.velocity,
                    np.asarray(pose)[:, :3].copy(), req.period_s, summary, robot="palletizer",
                    v_max=np.array([lim.v_max for lim in robot.limits]),
                    source=lambda: _as_source(plan),
                    tool_of=lambda q: np.asarray(robot.pose_from_joints(q))[:3],
                    machine_limits=tuple(machine.limits))


def plan_program_job(req: ProgramJob, source: str = "program", urdf_dirs=()) -> JobTable:
    """Plan a PTP/LIN/CIRC program text and tabulate its joints at the period.

    ``urdf_dirs``: folders whose URDF files the program may name (none by default).
    """
    from ..io.program import parse_program
    from ..robot.execute import run_motions

    prog = parse_program(req.text, source=source, urdf_dirs=urdf_dirs)
    run = run_motions(_reserved(prog.robot), prog.motions, prog.start)
    t = _times(run.duration, req.period_s)
    smp = run.sample(t)
    robot = prog.robot
    units, scale = _scale(robot.joint_kinds)
    summary = {"duration_s": run.duration, "robot": robot.name,
               "instructions": len(prog.motions), "slowdowns": len(run.slowdowns),
               "override_reserve": OVERRIDE_RESERVE}
    return JobTable("program", f"program on {robot.name}", tuple(robot.joint_names), units, scale,
                    smp.t, smp.q, smp.qd, smp.xyz, req.period_s, summary,
                    robot=robot.name if robot.name in ("arm6", "scara", "palletizer") else None,
                    v_max=np.array([lim.v_max for lim in robot.limits]),
                    source=lambda: _as_source(run), tool_of=lambda q: np.asarray(robot.fk(q).position),
                    machine_limits=tuple(robot.limits))


def plan_job(req, urdf_dirs=()) -> JobTable:
    """Plan a validated job request (:mod:`trajkit.hmi.models`).

    ``urdf_dirs``: folders whose URDF files a program may name (none by default).
    """
    if isinstance(req, SaddleJob):
        return plan_saddle_job(req)
    if isinstance(req, PalletJob):
        return plan_pallet_job(req)
    if isinstance(req, ProgramJob):
        return plan_program_job(req, urdf_dirs=urdf_dirs)
    raise InvalidInputError(f"unknown job type {type(req).__name__}")


def jog_goal(robot, base: np.ndarray, joint: int, step_si: float) -> np.ndarray:
    """Where a jog of ``joint`` by ``step_si`` [rad or m] from ``base`` goes.

    Raises
    ------
    InvalidInputError
        When the goal leaves the joint's range (nothing is clamped).
    """
    lim = robot.limits[joint]
    goal = np.array(base, dtype=float)
    goal[joint] += step_si
    units, scale = _scale(robot.joint_kinds)
    lo, hi = lim.position_min, lim.position_max
    if not lo <= goal[joint] <= hi:
        raise InvalidInputError(
            f"jog of joint {robot.joint_names[joint]} to {goal[joint] * scale[joint]:.3f} "
            f"{units[joint]} leaves its range [{lo * scale[joint]:.3f}, {hi * scale[joint]:.3f}] "
            f"{units[joint]}"
        )
    return goal


def jog_limits(robot, joint: int, speed_pct: float) -> list[AxisLimits]:
    """The limits a jog of ``joint`` moves with: its speed at ``speed_pct`` %, the rest as the machine's."""
    limits = [dataclasses.replace(lm) for lm in robot.limits]
    lim = limits[joint]
    limits[joint] = dataclasses.replace(lim, v_max=lim.v_max * speed_pct / 100.0)
    return limits


def jog_table(robot, q_now: np.ndarray, period: float) -> JobTable:
    """The run a jog drives: the robot standing at ``q_now``, moved by online targets.

    Every jog step is a target of the streamer
    (:meth:`trajkit.runtime.Streamer.set_target`): a step while the joint still
    moves re-plans from the commanded state in the same control period.
    """
    from ..runtime import as_source
    from ..trajectory import plan_ptp

    q = np.array(q_now, dtype=float)
    units, scale = _scale(robot.joint_kinds)
    hold = plan_ptp(q, q, list(robot.limits))
    xyz = np.array([robot.fk(q).position])
    return JobTable("jog", f"jog {robot.name}", tuple(robot.joint_names), units, scale,
                    np.zeros(1), q[None, :], np.zeros((1, q.size)), xyz, period, {"duration_s": 0.0},
                    robot=robot.name, v_max=np.array([lm.v_max for lm in robot.limits]),
                    source=lambda: as_source(hold), tool_of=lambda q: np.asarray(robot.fk(q).position),
                    machine_limits=tuple(robot.limits))


def _reserved(robot):
    """A copy of ``robot`` whose joint limits keep the override reserve."""
    import copy
    import dataclasses

    limits = tuple(override_limits(robot.limits))
    if dataclasses.is_dataclass(robot):  # the palletizing robot (frozen, validated)
        return dataclasses.replace(robot, limits=limits)
    rb = copy.copy(robot)
    rb.limits = limits
    return rb


def _as_source(obj):
    from ..runtime import as_source

    return as_source(obj)
