"""The HMI's machine session: one run at a time, played back in real time.

A :class:`Session` holds the loaded job, the current robot joints (for jog
and teach), the taught points, the event log and a background thread that
advances the run at the job's control period, ticking in real time.
Commands from the web app (start, pause, resume, stop, emergency stop,
reset, feed override) are queued with their arrival time and applied at the
first control tick whose nominal time is at or after the arrival, so an
emergency stop takes effect within one control period (the measured latency
is logged).

The motion itself comes from a *drive* (:class:`PlaybackDrive`): it turns
the planned table and the commands into commanded and actual axis states
each tick.
"""

from __future__ import annotations

import collections
import logging
import math
import threading
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InvalidInputError, TrajkitError
from .jobs import MM, JobTable

__all__ = ["Session", "ConflictError", "STATES", "PlaybackDrive", "SNAPSHOT_PERIOD_S"]

log = logging.getLogger("trajkit")

#: Run states shown in the page.
STATES = ("idle", "running", "pausing", "paused", "stopping", "fault")
_ACTIVE = ("running", "pausing", "paused", "stopping")

#: The loop sleeps at most this long between batches of control ticks [s].
LOOP_SLEEP_S = 0.004

#: Snapshots (live values) are refreshed at least this often [s].
SNAPSHOT_PERIOD_S = 0.02

#: Feed-rate ramp of the playback: the time scale changes by at most this
#: much per second [1/s] (pause, resume, stop, override changes).
RATE_SLEW_PER_S = 2.0

#: Events kept in the log.
MAX_EVENTS = 500

#: Points of the actual tool path kept for the path view.
TRAIL_POINTS = 4000

#: Below this the time scale counts as stopped.
RATE_EPS = 1e-9


class ConflictError(TrajkitError):
    """The command is not allowed in the present state (e.g. start while a run is active)."""


class PlaybackDrive:
    """Plays a :class:`JobTable` back with a slewed time scale (feed override).

    The plan time ``tau`` advances by ``rate * dt`` per tick; ``rate`` moves
    towards its target (override, or 0 to pause/stop) by at most
    ``RATE_SLEW_PER_S * dt`` per tick. The commanded velocity is the planned
    one times ``rate``. An emergency stop sets ``rate = 0`` in the tick it
    is applied (the command holds the last position).
    """

    def __init__(self, table: JobTable) -> None:
        self.table = table
        self.tau = 0.0
        self.rate = 0.0
        self.target = 1.0

    def tick(self, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Advance one control period; return commanded q, qd [SI] and tool xyz [m]."""
        step = RATE_SLEW_PER_S * dt
        self.rate += max(-step, min(step, self.target - self.rate))
        self.tau = min(self.table.duration, self.tau + self.rate * dt)
        q, qd, xyz = self.table.state_at(self.tau)
        return q, qd * self.rate, xyz

    def halt(self) -> None:
        """Emergency stop: the time scale drops to zero now."""
        self.rate = 0.0
        self.target = 0.0

    @property
    def finished(self) -> bool:
        return self.tau >= self.table.duration


@dataclass
class _Command:
    name: str
    arrival: float  # perf_counter
    value: Any = None


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
        self._cmds: collections.deque[_Command] = collections.deque()
        self._wake = threading.Event()
        self._thread: threading.Thread | None = None
        self._closing = False
        self.state = "idle"
        self.job: JobTable | None = None
        self.drive: PlaybackDrive | None = None
        self.override = 1.0
        self.events: list[dict] = []
        self._event_id = 0
        self.run_id = 0
        self.ticks = 0
        self.last_estop_latency_s: float | None = None
        self.trail: collections.deque = collections.deque(maxlen=TRAIL_POINTS)
        self._trail_total = 0
        self._snap: dict = {}
        # jog and teach
        self.robot_name = "scara"
        self.robot = None
        self.q = None
        self.points: dict[str, np.ndarray] = {}
        self.set_robot("scara", log_event=False)
        self._publish(None, None, None)

    # ------------------------------------------------------------------ events
    def event(self, level: str, text: str) -> None:
        """Append to the event log (``level`` info, warning or fault)."""
        with self._lock:
            self._event_id += 1
            self.events.append({"id": self._event_id, "time": time.time(), "level": level, "text": text})
            del self.events[:-MAX_EVENTS]
        log.info("hmi %s: %s", level, text)

    def events_since(self, last_id: int) -> list[dict]:
        with self._lock:
            return [e for e in self.events if e["id"] > last_id]

    # ------------------------------------------------------------------ robot / teach
    def set_robot(self, name: str, log_event: bool = True) -> None:
        """Choose the jog/teach robot; its joints go to the middle of their ranges (or 0)."""
        from ..robot.models import robot_by_name

        with self._lock:
            self._require_inactive("change the robot")
            robot = robot_by_name(name)
            q = np.zeros(robot.n_joints)
            for k, lim in enumerate(robot.limits):
                if not lim.position_min <= 0.0 <= lim.position_max:
                    q[k] = 0.5 * (lim.position_min + lim.position_max)
            self.robot_name, self.robot, self.q = name, robot, q
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
    def _require_inactive(self, what: str) -> None:
        if self.state in _ACTIVE:
            raise ConflictError(f"cannot {what} while a run is {self.state}: stop it first")
        if self.state == "fault":
            raise ConflictError(f"cannot {what} during an emergency stop: reset first")

    def load(self, table: JobTable) -> None:
        """Make ``table`` the job that the next start runs."""
        with self._lock:
            self._require_inactive("load a job")
            self.job = table
        self.event("info", f"loaded {table.title}: {table.duration:.3f} s, "
                           f"{table.t.size} setpoints every {table.period * 1e3:g} ms")

    def start(self, table: JobTable | None = None) -> int:
        """Start the loaded job (or ``table``, e.g. a jog, without loading it); returns the run id."""
        with self._lock:
            self._require_inactive("start")
            if table is None and self.job is None:
                raise ConflictError("no job loaded: plan a job first")
            table = table or self.job
            self.run_id += 1
            self.drive = PlaybackDrive(table)
            self.drive.target = self.override
            self.trail.clear()
            self._trail_total = 0
            self.ticks = 0
            self.state = "running"
            self._ensure_thread()
            self._wake.set()
        self.event("info", f"run {self.run_id} started: {table.title}")
        return self.run_id

    def command(self, name: str, value: Any = None) -> None:
        """Queue a run command: pause, resume, stop, estop, reset, override."""
        with self._lock:
            st = self.state
            if name == "estop":
                if st not in _ACTIVE:  # latch the fault even at rest
                    self.state = "fault"
                    self.drive = None
                    self.last_estop_latency_s = 0.0
                    self.event("fault", "EMERGENCY STOP (machine at rest)")
                    self._publish(None, None, None)
                    return
            elif name == "pause":
                if st != "running":
                    raise ConflictError(f"cannot pause: the run is {st}")
            elif name == "resume":
                if st not in ("paused", "pausing"):
                    raise ConflictError(f"cannot resume: the run is {st}")
            elif name == "stop":
                if st not in ("running", "pausing", "paused"):
                    raise ConflictError(f"cannot stop: the run is {st}")
            elif name == "reset":
                if st != "fault":
                    raise ConflictError(f"nothing to reset: the state is {st}")
                self.state = "idle"
                self.drive = None
                self.event("info", "emergency stop reset")
                self._publish(None, None, None)
                return
            elif name == "override":
                self.override = float(value)
                if st not in _ACTIVE:
                    self._publish(None, None, None)
                    return
            else:  # pragma: no cover - the app only sends known names
                raise InvalidInputError(f"unknown command {name!r}")
            self._cmds.append(_Command(name, self._clock(), value))
            self._wake.set()

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
            with self._lock:
                active = self.state in _ACTIVE
            if not active:
                self._wake.wait(0.1)
                self._wake.clear()
                continue
            self._run_active()

    def _run_active(self) -> None:
        with self._lock:
            drive = self.drive
            dt = drive.table.period
        t0 = self._clock()
        k = 0
        q = qd = xyz = None
        last_pub = -math.inf
        while not self._closing:
            now = self._clock()
            due = int((now - t0) / dt)
            with self._lock:
                while k < due:
                    k += 1
                    nominal = t0 + k * dt
                    self._apply_commands(drive, nominal, dt)
                    if self.state not in _ACTIVE:
                        break
                    q, qd, xyz = drive.tick(dt)
                    self.ticks += 1
                    if self.ticks % max(1, int(round(SNAPSHOT_PERIOD_S / dt / 2))) == 0:
                        self.trail.append((xyz / MM).round(4).tolist())
                        self._trail_total += 1
                    self._after_tick(drive, q)
                    if self.state not in _ACTIVE:
                        break
                if self.state not in _ACTIVE:
                    self._finish_run(drive, q)
                    return
                if now - last_pub >= SNAPSHOT_PERIOD_S and q is not None:
                    self._publish(q, qd, xyz)
                    last_pub = now
            time.sleep(min(LOOP_SLEEP_S, dt))

    def _apply_commands(self, drive: PlaybackDrive, nominal: float, dt: float) -> None:
        while self._cmds and self._cmds[0].arrival <= nominal:
            c = self._cmds.popleft()
            if c.name == "estop":
                if self.state in _ACTIVE:
                    drive.halt()
                    self.state = "fault"
                    self.last_estop_latency_s = nominal - c.arrival
                    self.event("fault", f"EMERGENCY STOP at t = {drive.tau:.3f} s of the plan: "
                                        f"output cleared, axes braked (applied "
                                        f"{1e3 * (nominal - c.arrival):.2f} ms after the request, "
                                        f"period {dt * 1e3:g} ms)")
            elif c.name == "pause" and self.state == "running":
                drive.target = 0.0
                self.state = "pausing"
                self.event("info", "pause: slowing down")
            elif c.name == "resume" and self.state in ("paused", "pausing"):
                drive.target = self.override
                self.state = "running"
                self.event("info", "resumed")
            elif c.name == "stop" and self.state in ("running", "pausing", "paused"):
                drive.target = 0.0
                self.state = "stopping"
                self.event("info", "controlled stop")
            elif c.name == "override":
                if self.state == "running":
                    drive.target = self.override
                self.event("info", f"feed override {100 * c.value:.0f} %")

    def _after_tick(self, drive: PlaybackDrive, q: np.ndarray) -> None:
        if self.state == "pausing" and drive.rate <= RATE_EPS:
            self.state = "paused"
            self.event("info", f"paused at t = {drive.tau:.3f} s of the plan")
        elif self.state == "stopping" and drive.rate <= RATE_EPS:
            self.state = "idle"
            self.event("info", f"stopped at t = {drive.tau:.3f} s of the plan (run aborted)")
        elif self.state == "running" and drive.finished:
            self.state = "idle"
            self.event("info", f"run {self.run_id} complete: {drive.table.duration:.3f} s planned")

    def _finish_run(self, drive: PlaybackDrive, q) -> None:
        if q is not None and drive.table.robot is not None:
            if drive.table.robot != self.robot_name:
                from ..robot.models import robot_by_name

                self.robot_name, self.robot, self.points = drive.table.robot, robot_by_name(drive.table.robot), {}
            self.q = np.array(q, dtype=float)
        self._publish(q, None if q is None else np.zeros_like(q), None if q is None else
                      drive.table.state_at(drive.tau)[2], keep_values=True)

    # ------------------------------------------------------------------ snapshot
    def _publish(self, q, qd, xyz, keep_values: bool = False) -> None:
        job, drive = self.job, self.drive
        snap = {
            "state": self.state,
            "run_id": self.run_id,
            "override_pct": 100.0 * self.override,
            "job": None if job is None else job.title,
            "server_time": time.time(),
        }
        if drive is not None:
            snap["plan_time_s"] = drive.tau
            snap["duration_s"] = drive.table.duration
            snap["progress"] = drive.tau / drive.table.duration if drive.table.duration > 0 else 1.0
            snap["rate"] = drive.rate
        if q is not None and drive is not None:
            tb = drive.table
            snap["axes"] = [{"name": n, "unit": u, "position": float(p * s), "velocity": float(v * s)}
                            for n, u, p, v, s in zip(tb.axis_names, tb.axis_units, q, qd, tb.axis_scale)]
            snap["tool_mm"] = (np.asarray(xyz) / MM).tolist()
        elif keep_values and self._snap.get("axes"):
            snap["axes"] = [dict(a, velocity=0.0) for a in self._snap["axes"]]
            snap["tool_mm"] = self._snap.get("tool_mm")
        elif self._snap.get("axes") and self.state in ("fault", "idle"):
            snap["axes"] = [dict(a, velocity=0.0) for a in self._snap["axes"]]
            snap["tool_mm"] = self._snap.get("tool_mm")
        self._snap = snap

    def snapshot(self) -> dict:
        """The latest live values (JSON-ready)."""
        with self._lock:
            snap = dict(self._snap)
            snap["state"] = self.state
            snap["override_pct"] = 100.0 * self.override
            snap["estop_latency_s"] = self.last_estop_latency_s
            return snap

    def trail_since(self, run_id: int, n_seen: int) -> tuple[list, int, bool]:
        """Actual tool points [mm] of the current run not yet seen.

        Returns the new points, the new count and whether the reader must
        drop what it has (another run began since ``run_id``).
        """
        with self._lock:
            pts = list(self.trail)
            total = self._trail_total
            fresh = run_id != self.run_id
        if fresh:
            return pts, total, True
        new = max(0, total - n_seen)
        return (pts[len(pts) - min(new, len(pts)):] if new else []), total, False
