"""Programs as the streaming interpolator sees them: joint states as a function of program time.

A :class:`ProgramSource` wraps any planned motion (a :class:`Trajectory`, a
palletizing :class:`Timeline` / :class:`CyclePlan`, a robot :class:`RobotRun`
or :class:`Program`) behind one vectorised ``sample(tau)`` that returns joint
position, velocity and acceleration at program times ``tau`` [s], plus the
structure the runtime needs: motion boundaries (progress), exact-stop
points (in-position waits) and the continuous-path intervals (where a
controlled stop must stay on the path).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..errors import InvalidInputError
from ..limits import AxisLimits

__all__ = ["ProgramSource", "as_source", "limits_envelope"]

#: Sampling step of the estimated jerk envelope of LIN/CIRC segments [s].
ENVELOPE_STEP = 5e-4

#: Margin on a velocity or jerk measured on samples (values between the samples).
ENVELOPE_MARGIN = 1.1


def limits_envelope(limits: Sequence[AxisLimits]) -> np.ndarray:
    """Envelope ``(V, A_acc, A_dec, J)`` per axis implied by planning limits.

    Parameters
    ----------
    limits : sequence of AxisLimits (n_axes)

    Returns
    -------
    ndarray, shape (4, n_axes)
        ``v_max`` [unit/s], ``a_max``, ``a_max_decel`` [unit/s^2],
        ``max(j_max, j_max_decel)`` [unit/s^3].
    """
    return np.array([[lm.v_max for lm in limits], [lm.a_max for lm in limits],
                     [lm.a_max_decel for lm in limits],
                     [max(lm.j_max, lm.j_max_decel) for lm in limits]], dtype=float).reshape(4, -1)


class ProgramSource:
    """Joint states of a planned program as a function of program time.

    Parameters
    ----------
    sampler : callable
        ``sampler(tau)`` with ``tau`` an ndarray (n,) [s] in ``[0, duration]``
        returns ``(q, qd, qdd)``, each ndarray (n, n_axes) [unit, unit/s,
        unit/s^2].
    duration : float
        Program duration [s].
    limits : sequence of AxisLimits
        Joint limits (one per axis) the program was planned for.
    names : sequence of str, optional
        Axis names.
    motion_starts : array_like, shape (m,), optional
        Start time of each motion [s] (default: one motion at 0).
    motion_labels : sequence of str, optional
    stop_points : array_like, optional
        Program times [s] where the machine stops exactly (all joints at
        rest) and waits for in-position when the streamer is asked to
        (default: the end of the program).
    path_intervals : sequence of (float, float), optional
        Program-time intervals [s] of continuous-path (LIN/CIRC) motion.
    envelope : array_like, shape (4, n_axes), optional
        Per axis upper bounds of the program over its whole duration, rows
        ``V >= |Q'|`` [unit/s], ``A_acc >= sign(Q') Q''`` (speeding up)
        [unit/s^2], ``A_dec >= -sign(Q') Q''`` (slowing down) [unit/s^2],
        ``J >= |Q'''|`` [unit/s^3]. Default: the limits the program was
        planned with, ``(v_max, a_max, a_max_decel, max(j_max, j_max_decel))``
        (exact bounds for programs that keep their limits). The streamer
        derives its override rate limits from it
        (:func:`~trajkit.runtime.streamer.override_rate_limits`).
    envelope_kind : str, optional
        ``"limits"`` (bounds from the planning limits), ``"estimated"``
        (measured on samples, e.g. the joint jerk of LIN/CIRC segments,
        which no planner bounds) or ``"given"``.

    Attributes
    ----------
    n_axes : int
    start_position : ndarray, shape (n_axes,)
    envelope : ndarray, shape (4, n_axes)
    envelope_kind : str
    """

    def __init__(self, sampler: Callable[[np.ndarray], tuple], duration: float,
                 limits: Sequence[AxisLimits], names: Sequence[str] | None = None,
                 motion_starts: Any = None, motion_labels: Sequence[str] | None = None,
                 stop_points: Any = None,
                 path_intervals: Sequence[tuple[float, float]] = (),
                 envelope: Any = None, envelope_kind: str | None = None) -> None:
        self._sampler = sampler
        self.duration = float(duration)
        if not np.isfinite(self.duration) or self.duration < 0:
            raise InvalidInputError(f"program duration must be finite and >= 0, got {duration!r}")
        self.limits = tuple(limits)
        self.n_axes = len(self.limits)
        self.names = tuple(names) if names is not None else tuple(
            str(lm.name) if lm.name is not None else f"q{k}" for k, lm in enumerate(self.limits))
        self.limits = tuple(lm.with_name(nm) if lm.name is None else lm
                            for lm, nm in zip(self.limits, self.names))
        ms = np.array([0.0] if motion_starts is None else motion_starts, dtype=float)
        self.motion_starts = ms
        self.motion_labels = tuple(motion_labels) if motion_labels is not None else tuple(
            f"motion {i}" for i in range(ms.size))
        sp = np.array([self.duration] if stop_points is None else stop_points, dtype=float)
        self.stop_points = np.unique(np.clip(sp, 0.0, self.duration))
        self.path_intervals = tuple((float(a), float(b)) for a, b in path_intervals)
        if envelope is None:
            env = limits_envelope(self.limits)
            kind = envelope_kind or "limits"
        else:
            env = np.array(envelope, dtype=float)
            if env.shape != (4, self.n_axes) or np.any(~(env >= 0.0)):
                raise InvalidInputError(
                    f"envelope must be an array (4, {self.n_axes}) of bounds >= 0 "
                    f"(V, A_acc, A_dec, J), got shape {env.shape}")
            kind = envelope_kind or "given"
        self.envelope = env
        self.envelope_kind = kind
        q, _, _ = self.sample(np.array([0.0]))
        self.start_position = q[0].copy()

    def sample(self, tau: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Joint position, velocity, acceleration at program times ``tau``.

        Parameters
        ----------
        tau : array_like, shape (n,)
            Program times [s]; clipped to ``[0, duration]``.

        Returns
        -------
        q, qd, qdd : ndarray, shape (n, n_axes)
        """
        tt = np.clip(np.atleast_1d(np.asarray(tau, dtype=np.float64)), 0.0, self.duration)
        q, qd, qdd = self._sampler(tt)
        return (np.asarray(q, dtype=float).reshape(tt.size, self.n_axes),
                np.asarray(qd, dtype=float).reshape(tt.size, self.n_axes),
                np.asarray(qdd, dtype=float).reshape(tt.size, self.n_axes))

    def motion_at(self, tau: float) -> int:
        """Index of the motion running at program time ``tau`` [s]."""
        i = int(np.searchsorted(self.motion_starts, tau, side="right")) - 1
        return max(0, min(i, self.motion_starts.size - 1))

    def on_path(self, tau: float) -> bool:
        """True when ``tau`` [s] lies in a continuous-path (LIN/CIRC) interval."""
        return any(a <= tau < b for a, b in self.path_intervals)

    def motion_ends(self) -> np.ndarray:
        """End time of each motion [s], shape (m,)."""
        return np.append(self.motion_starts[1:], self.duration)


def _from_trajectory(traj) -> ProgramSource:
    def f(t):
        s = traj.sample(t)
        return s.position, s.velocity, s.acceleration
    return ProgramSource(f, traj.duration, [p.limits for p in traj.axes], traj.names)


def _from_timeline(tl, limits, motion_starts=None, labels=None, stops=None) -> ProgramSource:
    def f(t):
        s = tl.sample(t)
        return s.position, s.velocity, s.acceleration
    return ProgramSource(f, tl.duration, limits, tl.names, motion_starts, labels, stops)


def _from_cycle_plan(plan) -> ProgramSource:
    starts = np.asarray(plan.trip_starts, dtype=float)
    ends = starts + np.array([tr.duration for tr in plan.trips])
    labels = [f"trip {i} ({'load' if i % 2 == 0 else 'return'})" for i in range(len(plan.trips))]
    limits = plan.scenario.robot.limits
    return _from_timeline(plan.timeline, limits, starts, labels, ends)


def _from_robot_run(run) -> ProgramSource:
    def f(t):
        # repeated times (a block clipped at a stop point) sampled once: RobotRun
        # differentiates the tool path over its sample times
        u, inv = np.unique(t, return_inverse=True)
        s = run.sample(u)
        return s.q[inv], s.qd[inv], s.qdd[inv]
    starts = [sg.t0 for sg in run.segments] or [0.0]
    labels = [f"{sg.kind} " + ", ".join(getattr(run.motions[i], "label", None) or str(i)
                                         for i in sg.motions) for sg in run.segments]
    ends = [sg.t0 + sg.duration for sg in run.segments]
    paths = [(sg.t0, sg.t0 + sg.duration) for sg in run.segments if sg.kind == "CP"]
    env = limits_envelope(run.robot.limits)
    kind = "limits"
    # the joint jerk of LIN/CIRC segments (IK of a Cartesian feed, bounded by the
    # planner through finite differences) and of blended PTP moves (superposed
    # S-curves) is not given by the joint limits alone: measure it
    for sg in run.segments:
        if not (sg.kind == "CP" or (sg.parts is not None and len(sg.parts) > 1)):
            continue
        n = max(math.ceil(sg.duration / ENVELOPE_STEP), 2)
        tt = sg.t0 + np.linspace(0.0, sg.duration, n + 1)
        _, qd, qdd = f(tt)
        jerk = np.max(np.abs(np.diff(qdd, axis=0)), axis=0) / (tt[1] - tt[0])
        env[3] = np.maximum(env[3], ENVELOPE_MARGIN * jerk)
        env[0] = np.maximum(env[0], ENVELOPE_MARGIN * np.max(np.abs(qd), axis=0))
        kind = "estimated"
    return ProgramSource(f, run.duration, run.robot.limits, run.robot.joint_names,
                         starts, labels or None, ends or None, paths, env, kind)


def as_source(obj: Any, limits: Sequence[AxisLimits] | None = None) -> ProgramSource:
    """Wrap a planned motion as a :class:`ProgramSource`.

    Parameters
    ----------
    obj : ProgramSource, Trajectory, Profile, CyclePlan, Timeline, RobotRun or Program
        ``Program`` (from :func:`trajkit.io.program.load_program`) is planned
        with ``program.run()``. A :class:`~trajkit.palletizing.CyclePlan`
        gives one motion per trip, with an exact stop at the end of each
        trip (pick and place).
    limits : sequence of AxisLimits, optional
        Needed for a bare :class:`Timeline` (its joint limits).

    Returns
    -------
    ProgramSource

    Raises
    ------
    InvalidInputError
        An object of another type, or a Timeline without limits.
    """
    if isinstance(obj, ProgramSource):
        return obj
    from ..palletizing import CyclePlan, Timeline
    from ..profiles import Profile
    from ..robot.execute import RobotRun
    from ..trajectory import Trajectory

    if isinstance(obj, Trajectory):
        return _from_trajectory(obj)
    if isinstance(obj, Profile):
        return _from_trajectory(Trajectory([obj]))
    if isinstance(obj, CyclePlan):
        return _from_cycle_plan(obj)
    if isinstance(obj, Timeline):
        if limits is None:
            raise InvalidInputError("as_source(Timeline) needs the joint limits (limits=...)")
        return _from_timeline(obj, limits)
    if isinstance(obj, RobotRun):
        return _from_robot_run(obj)
    if hasattr(obj, "run") and hasattr(obj, "motions"):
        return _from_robot_run(obj.run())
    raise InvalidInputError(
        f"cannot stream an object of type {type(obj).__name__}: expected a Trajectory, Profile, "
        "CyclePlan, Timeline, RobotRun or Program"
    )
