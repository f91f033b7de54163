"""Execute a list of motions on a robot model: plan every segment, sample at a period."""

from __future__ import annotations

import csv
import io
import math
import os
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from .._atomicio import atomic_write
from .._validate import check_positive
from ..errors import InvalidInputError, UnreachableError
from ..kinematics.base import RobotModel
from ..limits import AxisLimits
from ..trajectory import Trajectory, plan_ptp
from ._cartesian import SLOWDOWN_RTOL, VEL_USE, CartesianChain, Slowdown, plan_chain
from ._rotations import quat_from_matrix
from .motion import Circ, JointTarget, Lin, Ptp, Wait

__all__ = ["RobotRun", "RobotSamples", "Segment", "run_motions", "SAMPLE_ENDPOINT_RTOL"]

#: A sample time within this fraction of the period from the end is the end.
SAMPLE_ENDPOINT_RTOL = 1e-9


@dataclass
class Segment:
    """One planned piece of a program: a PTP move, a wait, or a Cartesian chain.

    Attributes
    ----------
    kind : {"PTP", "WAIT", "CP"}
        ``"CP"``: continuous-path chain of LIN/CIRC motions.
    t0 : float
        Start time in the program [s].
    duration : float [s]
    motions : list of int
        Indices of the motions it executes.
    q_start, q_end : ndarray, shape (n_joints,)
    """

    kind: str
    t0: float
    duration: float
    motions: list[int]
    q_start: np.ndarray
    q_end: np.ndarray
    ptp: Trajectory | None = None
    chain: CartesianChain | None = None


@dataclass
class RobotSamples:
    """A program sampled at a fixed period.

    Attributes
    ----------
    t : ndarray, shape (n,) [s]
    q, qd, qdd : ndarray, shape (n, n_joints)
        Joint positions [rad or m], velocities [/s], accelerations [/s^2].
    xyz : ndarray, shape (n, 3)
        Tool position [m].
    quat : ndarray, shape (n, 4)
        Tool orientation (w, x, y, z).
    tool_speed : ndarray, shape (n,) [m/s]
    motion : ndarray of int, shape (n,)
        Index of the motion each sample belongs to.
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    xyz: np.ndarray
    quat: np.ndarray
    tool_speed: np.ndarray
    motion: np.ndarray


class RobotRun:
    """The plan of a program: segments in time, summary, sampling and export.

    Attributes
    ----------
    robot : RobotModel
    motions : tuple of Ptp/Lin/Circ/Wait
    segments : list of Segment
    duration : float [s]
    slowdowns : list of Slowdown
    """

    def __init__(self, robot: RobotModel, motions: Sequence[Any], segments: list[Segment],
                 slowdowns: list[Slowdown]) -> None:
        self.robot = robot
        self.motions = tuple(motions)
        self.segments = segments
        self.duration = segments[-1].t0 + segments[-1].duration if segments else 0.0
        self.slowdowns = slowdowns

    def times(self, period: float) -> np.ndarray:
        """0, dt, 2 dt, ... and the end time [s]."""
        dt = check_positive(period, "period")
        n = int(math.floor(self.duration / dt * (1 + SAMPLE_ENDPOINT_RTOL)))
        t = np.arange(n + 1) * dt
        if t[-1] < self.duration:
            t = np.append(t, self.duration)
        return t

    def sample(self, t: Any) -> RobotSamples:
        """Sample at times ``t`` (n,) [s]: IK at every Cartesian sample."""
        tt = np.atleast_1d(np.asarray(t, dtype=np.float64))
        nj = self.robot.n_joints
        n = tt.size
        q = np.empty((n, nj))
        qd = np.zeros((n, nj))
        qdd = np.zeros((n, nj))
        xyz = np.empty((n, 3))
        quat = np.empty((n, 4))
        speed = np.zeros(n)
        mot = np.zeros(n, dtype=int)
        starts = np.array([sg.t0 for sg in self.segments])
        idx = np.clip(np.searchsorted(starts, tt, side="right") - 1, 0, len(self.segments) - 1)
        for i in np.unique(idx):
            m = idx == i
            sg = self.segments[i]
            tl = np.clip(tt[m] - sg.t0, 0.0, sg.duration)
            if sg.kind == "CP":
                out = sg.chain.sample(tl)
                q[m], qd[m], qdd[m] = out["q"], out["qd"], out["qdd"]
                xyz[m], quat[m], speed[m], mot[m] = out["xyz"], out["quat"], out["tool_speed"], out["motion"]
                continue
            if sg.kind == "PTP":
                smp = sg.ptp.sample(tl)
                q[m], qd[m], qdd[m] = smp.position, smp.velocity, smp.acceleration
            else:
                q[m] = sg.q_start
            mot[m] = sg.motions[0]
            rows = np.nonzero(m)[0]
            for r in rows:
                pose = self.robot.fk(q[r])
                xyz[r] = pose.position
                quat[r] = quat_from_matrix(pose.rotation)
            if sg.kind == "PTP" and rows.size > 1:
                speed[rows] = np.linalg.norm(np.gradient(xyz[rows], tt[rows], axis=0), axis=1)
        return RobotSamples(tt, q, qd, qdd, xyz, quat, speed, mot)

    def summary(self, samples: RobotSamples | None = None) -> dict:
        """JSON-ready summary: time, per-segment info, slow-downs and limit usage.

        With ``samples``, the largest |velocity| / v_max and |acceleration| /
        a_max of each joint over the samples are included (``limits``).
        """
        out: dict[str, Any] = {
            "robot": self.robot.name,
            "duration_s": self.duration,
            "segments": [
                {"kind": sg.kind, "t0_s": sg.t0, "duration_s": sg.duration,
                 "instructions": [getattr(self.motions[i], "label", str(i)) for i in sg.motions]}
                for sg in self.segments
            ],
            "slowdowns": [sd.to_dict() for sd in self.slowdowns],
        }
        if samples is not None:
            lims = []
            for j, (nm, lim) in enumerate(zip(self.robot.joint_names, self.robot.limits)):
                vr = float(np.max(np.abs(samples.qd[:, j]))) / lim.v_max
                ar = float(np.max(np.abs(samples.qdd[:, j]))) / min(lim.a_max, lim.a_max_decel)
                lims.append({"joint": nm, "velocity_ratio": vr, "acceleration_ratio": ar,
                             "at_velocity_limit": vr >= VEL_USE * (1.0 - SLOWDOWN_RTOL)})
            out["limits"] = lims
        return out

    def to_csv(self, samples: RobotSamples, path: str | os.PathLike | None = None) -> str:
        """Samples as CSV: t [s], joints (deg for revolute, mm for prismatic), tool x/y/z [mm], speed [mm/s]."""
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        names = []
        scale = []
        for nm, kind in zip(self.robot.joint_names, self.robot.joint_kinds):
            if kind == "revolute":
                names.append(f"{nm}_deg")
                scale.append(180.0 / math.pi)
            else:
                names.append(f"{nm}_mm")
                scale.append(1e3)
        w.writerow(["t_s", *names, "x_mm", "y_mm", "z_mm", "tool_speed_mm_s", "instruction"])
        sc = np.array(scale)
        for i in range(samples.t.size):
            w.writerow([repr(float(samples.t[i])), *(repr(float(x)) for x in samples.q[i] * sc),
                        *(repr(float(x)) for x in 1e3 * samples.xyz[i]),
                        repr(float(1e3 * samples.tool_speed[i])), int(samples.motion[i])])
        text = buf.getvalue()
        if path is not None:
            atomic_write(path, text)
        return text


def _scaled_limits(robot: RobotModel, pct: float) -> list[AxisLimits]:
    f = pct / 100.0
    return [AxisLimits(lim.v_max * f, lim.a_max, lim.j_max, lim.a_max_decel, lim.j_max_decel,
                       lim.position_min, lim.position_max, lim.name) for lim in robot.limits]


def _joint_goal(robot: RobotModel, target: Any, q_cur: np.ndarray, label: str) -> np.ndarray:
    if isinstance(target, JointTarget):
        return robot.check_joints(target.q, f"{label}: joints of point {target.name}")
    cfg = robot.config_of(q_cur) if target.config is None else robot.parse_config(target.config)
    try:
        return robot.ik(target.pose, cfg, seed=q_cur)
    except UnreachableError as exc:
        raise UnreachableError(f"{label}: target {target.name}: {exc}") from None


def run_motions(robot: RobotModel, motions: Sequence[Any], start: Any) -> RobotRun:
    """Plan ``motions`` from joints ``start``.

    Consecutive LIN/CIRC motions form one continuous-path chain when each
    (but the last) has a zone > 0: the corners are blended and the feed
    does not stop; a zone of 0 stops at the point (exact stop). PTP motions
    always stop at their target.

    Parameters
    ----------
    robot : RobotModel
    motions : sequence of Ptp, Lin, Circ, Wait
    start : array_like, shape (n_joints,)
        Joints at the start [rad or m].

    Returns
    -------
    RobotRun

    Raises
    ------
    InvalidInputError
        Bad start joints, an unknown motion type, degenerate arcs.
    UnreachableError
        Unreachable targets or path points, impassable singularities (the
        message names the instruction and the point).
    """
    q = robot.check_joints(start, "start joints")
    segments: list[Segment] = []
    slowdowns: list[Slowdown] = []
    t = 0.0
    i = 0
    motions = list(motions)
    while i < len(motions):
        m = motions[i]
        if isinstance(m, Wait):
            segments.append(Segment("WAIT", t, float(m.time), [i], q, q))
            t += float(m.time)
            i += 1
        elif isinstance(m, Ptp):
            goal = _joint_goal(robot, m.target, q, m.label)
            traj = plan_ptp(q, goal, _scaled_limits(robot, m.speed_pct), sync="phase")
            segments.append(Segment("PTP", t, traj.duration, [i], q, goal, ptp=traj))
            t += traj.duration
            q = goal
            i += 1
        elif isinstance(m, (Lin, Circ)):
            j = i
            while j + 1 < len(motions) and isinstance(motions[j + 1], (Lin, Circ)) and motions[j].zone > 0:
                j += 1
            group = motions[i:j + 1]
            chain = plan_chain(robot, q, group, [g.label for g in group], list(range(i, j + 1)))
            if chain is not None:
                segments.append(Segment("CP", t, chain.duration, list(range(i, j + 1)),
                                        q, chain.q_end, chain=chain))
                for sd in chain.slowdowns:
                    sd.motion += i
                slowdowns += chain.slowdowns
                t += chain.duration
                q = chain.q_end
            i = j + 1
        else:
            raise InvalidInputError(f"motion {i} has unknown type {type(m).__name__}")
    return RobotRun(robot, motions, segments, slowdowns)
