"""The HMI's machine session: one run at a time, played back in real time.

A :class:`Session` holds the loaded job, the current robot joints (for jog
and teach), the taught points, the event log and a background thread that
advances the run at the job's control period, ticking in real time.
Commands from the web app (start, pause, resume, stop, emergency stop,
reset, feed override) are queued with their arrival time and applied at the
first control tick whose nominal time is at or after the arrival, so an
emergency stop takes effect within one control period (the measured latency
is logged).

The motion itself comes from the runtime (:class:`RuntimeDrive` over
:class:`trajkit.runtime.Streamer` with its servo simulation); this module
only paces it in real time and reports what it does.
"""

from __future__ import annotations

import collections
import logging
import math
import threading
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import InvalidInputError, TrajkitError
from .jobs import MM, JobTable

if TYPE_CHECKING:
    from ..kinematics.base import RobotModel
    from ..runtime import Setpoint

__all__ = ["Session", "ConflictError", "STATES", "RuntimeDrive", "SNAPSHOT_PERIOD_S"]

log = logging.getLogger("trajkit")

#: Run states shown in the page.
STATES = ("idle", "running", "pausing", "paused", "stopping", "fault")
_ACTIVE = ("running", "pausing", "paused", "stopping")

#: The loop sleeps at most this long between batches of control ticks [s].
LOOP_SLEEP_S = 0.004

#: Snapshots (live values) are refreshed at least this often [s].
SNAPSHOT_PERIOD_S = 0.02

#: Events kept in the log.
MAX_EVENTS = 500

#: Points of the actual tool path kept for the path view.
TRAIL_POINTS = 4000

#: Control period of a jog when no job is loaded [s].
JOG_PERIOD_S = 0.004

#: Longest wait of a command for the run loop to apply it [s].
COMMAND_WAIT_S = 2.0

#: One actual tool point is kept every this many control periods.
TRAIL_EVERY = 5

#: After a run the loop keeps simulating the servo axes until every axis is
#: within this fraction of its in-position window of the command and moves
#: less than that per period (or the brakes have stopped it after an
#: emergency stop), so that the actual position shown is the one the axis keeps.
REST_FRACTION = 1e-3

#: Longest time the loop simulates the axes coming to rest after a run [s].
REST_MAX_S = 5.0

#: Time step of the finite difference that gives the live tool speed [s].
TOOL_SPEED_STEP_S = 1e-4


class ConflictError(TrajkitError):
    """The command is not allowed in the present state (e.g. start while a run is active)."""


class RuntimeDrive:
    """One job on the runtime: a :class:`trajkit.runtime.Streamer` with the servo simulation.

    The streamer does the motion (jerk-limited feed-rate law for override,
    pause and controlled stop, emergency stop, monitors, servo axes); this
    class only forwards commands, steps it once per control period and
    translates its state for the page.
    """

    def __init__(self, table: JobTable) -> None:
        from ..runtime import ServoParams, Streamer

        self.table = table
        if table.source is None:
            raise InvalidInputError(f"job {table.title!r} has no program source to run")
        src = table.source()
        # the jobs are planned with the override reserve (hmi.jobs) and the monitors
        # enforce the machine's full limits: at 100 % a job runs at its planned
        # speed, and the slider and pause are proven (velocity, acceleration, jerk)
        self.streamer = Streamer(src, table.period, servo=ServoParams(),
                                 limits=table.machine_limits)
        self._seen = 0
        self.last: Setpoint | None = None
        #: where a jog run is going [SI] (the last target), None for a job
        self.jog_goal: np.ndarray | None = None

    def command(self, name: str, value: Any = None) -> None:
        """Queue a command for the next control period."""
        st = self.streamer
        if name == "override":
            st.set_override(100.0 * value)
        elif name == "target":
            goal, limits = value
            st.set_target(goal, sync="none", limits=limits)
        else:
            getattr(st, {"estop": "estop", "start": "start", "pause": "pause", "resume": "resume",
                         "stop": "stop", "reset": "reset"}[name])()

    def step(self) -> Setpoint:
        """Run one control period; return the streamer's setpoint."""
        sp = self.last = self.streamer.step()
        return sp

    @property
    def state(self) -> str:
        """The HMI state: idle, running, pausing, paused, stopping or fault."""
        st = self.streamer
        if st.state == "running" and st.paused:
            return "paused" if st.s == 0.0 and st.sd == 0.0 else "pausing"
        if st.state == "reset":
            return "fault"
        return st.state

    @property
    def finished(self) -> bool:
        """True when the program ran to its end."""
        return bool(self.streamer.finished)

    @property
    def braking(self) -> bool:
        """True while the holding brakes are still stopping an axis after an emergency stop."""
        sv = self.streamer.servo
        return sv is not None and sv.braking and bool(np.any(sv.v))

    def at_rest(self) -> bool:
        """True when the simulated axes stand still where they will stay.

        Braked axes are at rest once they stopped; driven axes once each is
        within :data:`REST_FRACTION` of its in-position window of the command
        and moves less than that per period.
        """
        sv = self.streamer.servo
        sp = self.last
        if sv is None or sp is None:
            return True
        if sv.braking:
            return not np.any(sv.v)
        tol = REST_FRACTION * sv.window
        return bool(np.all(np.abs(sp.position - sv.measured) <= tol)
                    and np.all(np.abs(sv.v) * self.table.period <= tol))

    @property
    def tau(self) -> float:
        """Program time [s]."""
        return float(self.streamer.tau)

    def new_events(self) -> list:
        evs = self.streamer.events[self._seen:]
        self._seen += len(evs)
        return evs


@dataclass
class _Command:
    name: str
    arrival: float  # perf_counter
    value: Any = None
    done: threading.Event = field(default_factory=threading.Event)


class Session:
    """State of one HMI: loaded job, run loop, robot joints, taught points, events.

    Parameters
    ----------
    programs_dir : str or None
        Folder of saved program files (used by the web app).
    clock : callable
        Monotonic clock [s] (``time.perf_counter``).
    """

    def __init__(self, programs_dir: str | None = None, clock=time.perf_counter) -> None:
        self.programs_dir = programs_dir
        self._clock = clock
        self._lock = threading.RLock()
        # events and the actual-path trail have their own short lock: the live stream
        # reads them without waiting for the run loop (which holds _lock while it ticks)
        self._feed_lock = threading.Lock()
        self._cmds: collections.deque[_Command] = collections.deque()
        self._wake = threading.Event()
        self._thread: threading.Thread | None = None
        self._closing = False
        self.state = "idle"
        self.job: JobTable | None = None
        self.drive: RuntimeDrive | None = None
        self.override = 1.0
        self.events: list[dict] = []
        self._event_id = 0
        self.run_id = 0
        self.ticks = 0
        self.last_estop_latency_s: float | None = None
        self.job_id = 0  # counts loads and unloads: the page refreshes its job view on a change
        #: held while a job is planned: one plan at a time (a second request answers 409)
        self.plan_lock = threading.Lock()
        self.trail: collections.deque = collections.deque(maxlen=TRAIL_POINTS)
        self._trail_total = 0
        self._snap: dict = {}
        # jog and teach
        self.robot_name = "scara"
        self.robot: RobotModel  # the jog/teach robot and its joints [SI], set by set_robot
        self.q: np.ndarray
        self.points: dict[str, np.ndarray] = {}
        self.set_robot("scara", log_event=False)
        self._publish()

    # ------------------------------------------------------------------ events
    def event(self, level: str, text: str) -> None:
        """Append to the event log (``level`` info, warning or fault)."""
        with self._feed_lock:
            self._event_id += 1
            self.events.append({"id": self._event_id, "time": time.time(), "level": level, "text": text})
            del self.events[:-MAX_EVENTS]
        log.info("hmi %s: %s", level, text)

    def events_since(self, last_id: int) -> list[dict]:
        """Events with an id above ``last_id`` (never waits for the run loop)."""
        with self._feed_lock:
            return [e for e in self.events if e["id"] > last_id]

    # ------------------------------------------------------------------ robot / teach
    def set_robot(self, name: str, log_event: bool = True) -> None:
        """Choose the jog/teach robot; its joints go to its ready configuration
        (``RobotModel.home``: away from singularities, inside the ranges)."""
        from ..robot.models import robot_by_name

        with self._lock:
            self._require_inactive("change the robot")
            robot = robot_by_name(name)
            self.robot_name, self.robot, self.q = name, robot, robot.home
            self.points = {}
        if log_event:
            self.event("info", f"robot {name}: joints at home, taught points cleared")

    def joint_info(self) -> dict:
        """Current joints in display units, and the tool position [mm]."""
        with self._lock:
            rb, q = self.robot, self.q.copy()
        units = ["deg" if k == "revolute" else "mm" for k in rb.joint_kinds]
        scale = [180.0 / math.pi if k == "revolute" else 1.0 / MM for k in rb.joint_kinds]
        return {
            "robot": self.robot_name,
            "joints": [{"name": n, "unit": u, "value": float(v * s),
                        "min": float(lim.position_min * s), "max": float(lim.position_max * s)}
                       for n, u, v, s, lim in zip(rb.joint_names, units, q, scale, rb.limits)],
            "tool_mm": (np.asarray(rb.fk(q).position) / MM).tolist(),
            "points": {k: [float(x * s) for x, s in zip(v, scale)] for k, v in self.points.items()},
        }

    def teach(self, name: str) -> None:
        with self._lock:
            self._require_inactive("teach a point")
            self.points[name] = self.q.copy()
        self.event("info", f"taught point {name}")

    def program_text(self, steps, speed_mm_s: float) -> str:
        """YAML program text (``trajkit run`` format) from taught points."""
        import yaml

        rb = self.robot
        names = []
        for st in steps:
            for p in (st.point, st.via):
                if p is not None and p not in self.points:
                    raise InvalidInputError(
                        f"point {p!r} is not taught (taught: {', '.join(self.points) or 'none'})")
                if p is not None and p not in names:
                    names.append(p)
            if st.op == "CIRC" and st.via is None:
                raise InvalidInputError(f"CIRC to {st.point} needs a via point")
        pts = {}
        for p in names:
            joints = {}
            for nm, kind, v in zip(rb.joint_names, rb.joint_kinds, self.points[p]):
                if kind == "revolute":
                    joints[f"{nm}_deg"] = round(math.degrees(float(v)), 9)
                else:
                    joints[f"{nm}_mm"] = round(float(v) / MM, 9)
            pts[p] = {"joints": joints}
        prog = []
        for st in steps:
            ins: dict[str, Any] = {st.op: st.point}
            if st.op == "CIRC":
                ins["via"] = st.via
            if st.speed_pct is not None and st.op == "PTP":
                ins["speed_pct"] = st.speed_pct
            if st.speed_mm_s is not None and st.op != "PTP":
                ins["speed_mm_s"] = st.speed_mm_s
            prog.append(ins)
        doc = {"robot": self.robot_name, "defaults": {"speed_mm_s": speed_mm_s},
               "points": pts, "program": prog}
        return yaml.safe_dump(doc, sort_keys=False, default_flow_style=None)

    # ------------------------------------------------------------------ run control
    def check_idle(self, what: str) -> np.ndarray:
        """Raise :class:`ConflictError` unless nothing runs; return the current joints."""
        with self._lock:
            self._require_inactive(what)
            return self.q.copy()

    def _require_inactive(self, what: str) -> None:
        if self.state in _ACTIVE:
            raise ConflictError(f"cannot {what} while a run is {self.state}: stop it first")
        if self.state == "fault":
            raise ConflictError(f"cannot {what} during an emergency stop: reset first")

    def load(self, table: JobTable) -> None:
        """Make ``table`` the job that the next start runs.

        The simulated machine is placed at the job's start: the live values
        (axes, progress, job title) show the new job from now on.
        """
        with self._lock:
            self._require_inactive("load a job")
            self.job = table
            self.drive = None
            self.job_id += 1
            self._publish()
        self.event("info", f"loaded {table.title}: {table.duration:.3f} s, "
                           f"{table.t.size} setpoints every {table.period * 1e3:g} ms")

    def disarm(self, reason: str) -> None:
        """Unload the job after a failed plan: Start then has nothing to run.

        Does nothing while a run is active (the running job stays loaded).
        """
        with self._lock:
            if self.state in _ACTIVE:
                return
            old = self.job
            self.job = None
            self.drive = None
            self.job_id += 1
            self._publish()
        self.event("warning", f"plan failed: {reason}" + (f"; {old.title} unloaded" if old else ""))

    def start(self, table: JobTable | None = None) -> int:
        """Start the loaded job (or ``table``, e.g. a jog, without loading it); returns the run id.

        After a controlled stop or a reset fault of the same job, start
        continues it where it stopped (the runtime first moves back to the
        path if the machine left it); otherwise the job starts from its
        beginning.
        """
        with self._lock:
            self._require_inactive("start")
            if table is None:
                if self.job is None:
                    raise ConflictError("no job loaded: plan a job first")
                table = self.job
            drive = self.drive
            resume = drive is not None and drive.table is table and not drive.finished
            if not resume:
                drive = self._new_drive(table)
            cmd = _Command("start", self._clock())
            self._cmds.append(cmd)
            self.state = "running"
            self._ensure_thread()
            self._wake.set()
        self.event("info", f"run {self.run_id} {'continued' if resume else 'started'}: {table.title}")
        cmd.done.wait(COMMAND_WAIT_S)
        return self.run_id

    def jog(self, joint: int, step_si: float, speed_pct: float) -> None:
        """Jog ``joint`` of the jog robot by ``step_si`` [rad or m] at ``speed_pct`` % of its speed.

        At rest a jog run starts; while a jog moves, the step is added to its
        goal and the streamer re-plans from the commanded state in the next
        control period (online target), so repeated steps chain without
        stopping. The goal must stay in the joint's range.

        Raises
        ------
        ConflictError
            While a job runs or during an emergency stop.
        InvalidInputError
            A goal outside the joint's range.
        """
        from .jobs import jog_goal, jog_limits, jog_table

        with self._lock:
            drive = self.drive
            jogging = (drive if self.state == "running" and drive is not None
                       and drive.table.robot == self.robot_name else None)
            base = jogging.jog_goal if jogging is not None else None  # None: no jog moves
            moving = base is not None
            if jogging is not None and base is not None:
                goal = jog_goal(self.robot, base, joint, step_si)
                target = (goal, jog_limits(self.robot, joint, speed_pct))
                cmd = _Command("target", self._clock(), target)
                self._cmds.append(cmd)
                jogging.jog_goal = goal
                self._wake.set()
            else:
                self._require_inactive("jog")
                goal = jog_goal(self.robot, self.q, joint, step_si)
                target = (goal, jog_limits(self.robot, joint, speed_pct))
                period = self.job.period if self.job is not None else JOG_PERIOD_S
                drive = self._new_drive(jog_table(self.robot, self.q, period))
                drive.jog_goal = goal
                now = self._clock()
                self._cmds.append(_Command("start", now))
                cmd = _Command("target", now, target)
                self._cmds.append(cmd)
                self.state = "running"
                self._ensure_thread()
                self._wake.set()
        if not moving:
            self.event("info", f"run {self.run_id} started: jog {self.robot.joint_names[joint]}")
        cmd.done.wait(COMMAND_WAIT_S)

    def _new_drive(self, table: JobTable) -> RuntimeDrive:
        """A fresh run of ``table`` as the session's drive (called with the session lock held)."""
        drive = RuntimeDrive(table)
        drive.command("override", self.override)
        with self._feed_lock:
            self.run_id += 1
            self.trail.clear()
            self._trail_total = 0
        self.ticks = 0
        self.drive = drive
        return drive

    def command(self, name: str, value: Any = None, wait: bool = True) -> None:
        """Queue a run command (pause, resume, stop, estop, reset, override) for the next period.

        With ``wait`` it returns once the run loop has applied it (at most
        :data:`COMMAND_WAIT_S`). An emergency stop for a running machine is
        queued without waiting for the session lock (the run loop may hold
        it for a batch of periods), so its arrival time is exact.
        """
        arrival = self._clock()
        if name == "estop":
            cmd = self.request_estop(arrival)
            if wait and cmd is not None:
                cmd.done.wait(COMMAND_WAIT_S)
            return
        with self._lock:
            st = self.state
            if name == "pause" and st != "running":
                raise ConflictError(f"cannot pause: the run is {st}")
            elif name == "resume" and st not in ("paused", "pausing"):
                raise ConflictError(f"cannot resume: the run is {st}")
            elif name == "stop" and st not in ("running", "pausing", "paused"):
                raise ConflictError(f"cannot stop: the run is {st}")
            elif name == "reset" and st != "fault":
                raise ConflictError(f"nothing to reset: the state is {st}")
            elif name == "override":
                self.override = float(value)
            if self.drive is None:
                if name == "reset":
                    self.state = "idle"
                    self.event("info", "emergency stop reset")
                self._publish()
                return
            cmd = _Command(name, arrival, value)
            self._cmds.append(cmd)
            self._ensure_thread()
            self._wake.set()
        if wait:
            cmd.done.wait(COMMAND_WAIT_S)

    def request_estop(self, arrival: float | None = None) -> _Command | None:
        """Queue an emergency stop without waiting for anything; return its command.

        A machine with a run (or the rest of one) gets the stop in the first
        control period that starts after ``arrival`` (by default the time the
        command is queued; the command's ``done``
        is set then); a machine at rest without one latches the fault at once
        (returns None). Never blocks on the session lock, so no other request
        can hold it up.
        """
        if self.drive is not None:
            cmd = _Command("estop", math.nan)
            # (stamped as it is queued: building the command, with its event, is not
            # part of the wait for a control period)
            cmd.arrival = self._clock() if arrival is None else arrival
            self._cmds.append(cmd)  # deque.append is atomic
            self._wake.set()
            return cmd
        arrival = self._clock() if arrival is None else arrival
        with self._lock:
            if self.drive is None:
                self.state = "fault"
                self.last_estop_latency_s = 0.0
                self._publish()
                latched = True
            else:
                latched = False
        if latched:
            self.event("fault", "EMERGENCY STOP (machine at rest)")
            return None
        return self.request_estop(arrival)

    def _ensure_thread(self) -> None:
        if self._thread is None or not self._thread.is_alive():
            self._closing = False
            self._thread = threading.Thread(target=self._loop, name="trajkit-hmi-run", daemon=True)
            self._thread.start()

    def close(self) -> None:
        """Stop the loop thread (the app calls it on shutdown)."""
        self._closing = True
        self._wake.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)

    # ------------------------------------------------------------------ loop
    def _loop(self) -> None:
        while not self._closing:
            latched = False
            with self._lock:
                drive = self.drive
                if drive is None and self._cmds:
                    # the run was unloaded after these were queued (a new job): an
                    # emergency stop still latches the fault; other commands lapse
                    while self._cmds:
                        c = self._cmds.popleft()
                        if c.name == "estop" and self.state != "fault":
                            self.state = "fault"
                            self.last_estop_latency_s = max(self._clock() - c.arrival, 0.0)
                            latched = True
                        c.done.set()
                    self._publish()
                busy = drive is not None and (self._cmds or self.state in _ACTIVE)
            if latched:
                self.event("fault", "EMERGENCY STOP (machine at rest)")
            if drive is None or not busy:
                self._wake.wait(0.1)
                self._wake.clear()
                continue
            try:
                self._run(drive)
            except Exception as exc:  # a runtime error must not kill the HMI
                log.exception("hmi run loop")
                with self._lock:
                    self.state = "fault"
                    for c in self._cmds:
                        c.done.set()
                    self._cmds.clear()
                self.event("fault", f"run aborted by an internal error: {exc}")

    def _run(self, drive: RuntimeDrive) -> None:
        """Tick ``drive`` in real time until it rests with no command pending.

        Returns early when another drive replaced it (a new job or run) or
        when the axes have not come to rest within :data:`REST_MAX_S`.
        """
        dt = drive.table.period
        t0 = self._clock()
        k = 0
        last_pub = -math.inf
        resting = 0  # periods ticked since the run itself ended
        rested = False
        while not self._closing:
            now = self._clock()
            due = int((now - t0) / dt)
            with self._lock:
                if self.drive is not drive:
                    return
                if self.state not in _ACTIVE and not self._cmds:
                    resting += max(due - k, 0)
                    if resting * dt > REST_MAX_S:
                        return
                while k < due:
                    k += 1
                    nominal = t0 + k * dt
                    # commands that arrived before this period starts are applied in it
                    applied = []
                    while self._cmds and self._cmds[0].arrival <= nominal:
                        if self._cmds[0].name == "reset" and drive.braking:
                            break  # a reset waits until the brakes have stopped every axis
                        c = self._cmds.popleft()
                        drive.command(c.name, c.value)
                        applied.append(c)
                        if c.name == "estop":
                            self.last_estop_latency_s = nominal - c.arrival
                    sp = drive.step()
                    self.ticks += 1
                    self.state = drive.state
                    if applied:
                        self._publish()
                        for c in applied:
                            c.done.set()
                    self._log_runtime_events(drive)
                    if self.ticks % TRAIL_EVERY == 0 or self.state not in _ACTIVE:
                        self._add_trail(drive, sp)
                    if self.state not in _ACTIVE and (not rested or applied):
                        self._rest(drive)  # the jog joints follow the command at once
                        rested = True
                    elif self.state in _ACTIVE:
                        rested = False
                    if self.state not in _ACTIVE and not self._cmds and drive.at_rest():
                        break
                if now - last_pub >= SNAPSHOT_PERIOD_S or self.state not in _ACTIVE:
                    self._publish()
                    last_pub = now
                if self.state not in _ACTIVE and not self._cmds and drive.at_rest():
                    return
            time.sleep(min(LOOP_SLEEP_S, dt))

    def _add_trail(self, drive: RuntimeDrive, sp) -> None:
        q = sp.actual if sp.actual is not None else sp.position
        tool = drive.table.tool_of(q) if drive.table.tool_of is not None else None
        if tool is not None:
            pt = (np.asarray(tool) / MM).round(4).tolist()
            with self._feed_lock:
                self.trail.append(pt)
                self._trail_total += 1

    def _log_runtime_events(self, drive: RuntimeDrive) -> None:
        for ev in drive.new_events():
            if ev.kind in ("override",):
                continue
            level = "fault" if ev.kind in ("estop", "fault") else "warning" if ev.kind == "rejected" else "info"
            text = ev.message
            if ev.kind == "estop":
                lat = self.last_estop_latency_s
                text = (f"EMERGENCY STOP at t = {drive.streamer.tau:.3f} s of the plan: output cleared, "
                        f"brakes engaged (applied {1e3 * (lat or 0.0):.2f} ms after the request, "
                        f"period {drive.table.period * 1e3:g} ms)")
            elif ev.kind == "finished":
                text = f"run {self.run_id} complete: {drive.table.title}, {drive.table.duration:.3f} s planned"
            self.event(level, text)

    def _rest(self, drive: RuntimeDrive) -> None:
        """The run rests: the jog/teach joints follow the machine (same robot)."""
        sp = drive.last
        if sp is None or drive.table.robot is None:
            return
        if drive.table.robot != self.robot_name:
            from ..robot.models import robot_by_name

            self.robot_name, self.robot, self.points = drive.table.robot, robot_by_name(drive.table.robot), {}
        q = np.array(sp.position, dtype=float)
        if drive.finished and drive.jog_goal is None:
            # the streamer's last setpoint is Q(duration - period), one period short of
            # the goal (reported to the runtime's owner); the machine ends at the goal
            q = drive.streamer.source.sample(np.array([drive.streamer.source.duration]))[0][0]
        self.q = np.array(q, dtype=float)

    # ------------------------------------------------------------------ snapshot
    def _publish(self) -> None:
        """Refresh the live values (called with the session lock held)."""
        drive = self.drive
        job = self.job
        snap: dict[str, Any] = {
            "state": self.state,
            "run_id": self.run_id,
            "override_pct": 100.0 * self.override,
            "job": None if job is None else job.title,
            "job_id": self.job_id,
            "server_time": time.time(),
        }
        if (drive is not None and job is not None and drive.table is not job
                and drive.table.kind == "jog" and self.state == "idle"):
            drive = None  # a finished jog: the views show the job that Start will run
        if drive is not None:
            st = drive.streamer
            tb = drive.table
            snap["run_title"] = tb.title
            snap["cycle"] = st.cycle
            snap["plan_time_s"] = st.tau
            online = st.target_motion
            if online is not None:  # a jog: the motion to its current target
                snap["plan_time_s"], T = online
                snap["motion"] = "online target"
            else:
                T = st.source.duration
                snap["motion"] = st.source.motion_labels[st.source.motion_at(st.tau)]
            snap["duration_s"] = T
            snap["progress"] = snap["plan_time_s"] / T if T > 0 else 1.0
            snap["rate"] = st.s
            snap["fault"] = None if st.fault is None else str(st.fault)
            sp = drive.last
            if sp is not None:
                act = sp.actual if sp.actual is not None else sp.position
                self._axes_view(snap, tb, sp.position, act, sp.velocity)
            else:  # started, first period not yet run: the machine is at the start
                self._axes_view(snap, tb, tb.q[0], tb.q[0], np.zeros_like(tb.q[0]))
        elif job is not None:  # a job loaded, not started: the machine waits at its start
            snap["plan_time_s"] = 0.0
            snap["duration_s"] = job.duration
            snap["progress"] = 0.0
            q0 = job.q[0]
            self._axes_view(snap, job, q0, q0, np.zeros_like(q0))
        self._snap = snap

    @staticmethod
    def _axes_view(snap: dict, tb: JobTable, pos, act, vel) -> None:
        snap["axes"] = [
            {"name": n, "unit": u, "position": float(p * s), "actual": float(a * s),
             "velocity": float(v * s), "following_error": float((p - a) * s)}
            for n, u, p, a, v, s in zip(tb.axis_names, tb.axis_units, pos, act, vel, tb.axis_scale)]
        if tb.tool_of is not None:
            snap["tool_mm"] = (np.asarray(tb.tool_of(act)) / MM).tolist()
            # commanded tool speed: the tool point's rate of change along the axis velocities
            h = TOOL_SPEED_STEP_S
            pos = np.asarray(pos, dtype=float)
            vel = np.asarray(vel, dtype=float)
            if np.any(vel):
                d = np.asarray(tb.tool_of(pos + h * vel)) - np.asarray(tb.tool_of(pos - h * vel))
                snap["tool_speed_mm_s"] = float(np.linalg.norm(d) / (2.0 * h) / MM)
            else:
                snap["tool_speed_mm_s"] = 0.0

    def snapshot(self) -> dict:
        """The latest live values (JSON-ready); never waits for the run loop."""
        snap = dict(self._snap)  # replaced as a whole by the loop: reading it is atomic
        snap["state"] = self.state
        snap["override_pct"] = 100.0 * self.override
        snap["estop_latency_s"] = self.last_estop_latency_s
        return snap

    def trail_since(self, run_id: int, n_seen: int) -> tuple[list, int, bool]:
        """Actual tool points [mm] of the current run not yet seen.

        Returns the new points, the new count and whether the reader must
        drop what it has (another run began since ``run_id``).
        """
        with self._feed_lock:
            pts = list(self.trail)
            total = self._trail_total
            fresh = run_id != self.run_id
        if fresh:
            return pts, total, True
        new = max(0, total - n_seen)
        return (pts[len(pts) - min(new, len(pts)):] if new else []), total, False
