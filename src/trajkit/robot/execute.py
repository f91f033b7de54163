"""Execute a list of motions on a robot model: plan every segment, sample at a period."""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._atomicio import atomic_write
from .._csvio import csv_text
from .._sampling import MAX_SAMPLES, period_times
from ..errors import InvalidInputError, UnreachableError
from ..kinematics.base import RobotModel
from ..limits import AxisLimits
from ..sync import plan_ptp
from ..trajectory import Trajectory
from ._cartesian import SLOWDOWN_RTOL, VEL_USE, CartesianChain, Slowdown, chain_stops, plan_chain
from ._rotations import quat_from_matrix
from .motion import Circ, JointTarget, Lin, Ptp, Wait

__all__ = ["RobotRun", "RobotSamples", "Segment", "run_motions"]

#: Joint-space step [rad or m] of the central difference that gives the
#: tool speed of a PTP motion from FK (truncation error ~ step^2).
TOOL_SPEED_STEP = 1e-6

#: Fraction of the joint velocity and acceleration limits a PTP blend may use
#: (checked on samples; the margin covers the values between them).
PTP_BLEND_USE = 0.99

#: Fraction of the jerk limit ``min(j_max, j_max_decel)`` each of two
#: blended PTP moves uses in its overlapping leg (the decel leg of the first,
#: the accel leg of the second): their sum stays within the limit.
PTP_BLEND_JERK_SHARE = 0.5

#: Samples on which a PTP blend overlap is checked.
PTP_BLEND_CHECKS = 200

#: Bisection steps when shrinking a PTP blend overlap.
PTP_BLEND_BISECT = 25


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
    parts: list[tuple[float, Trajectory]] | None = None

    def sample_ptp(self, tl: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Joint position, velocity, acceleration (n, n_joints) at local times ``tl``.

        A blended PTP group is the superposition of its moves, each started
        at its offset: ``q = q_start + sum_k (q_k(t - off_k) - q_k(0))``.
        """
        if self.parts is not None:
            parts = self.parts
        else:
            assert self.ptp is not None  # a PTP segment has its moves
            parts = [(0.0, self.ptp)]
        q = np.broadcast_to(self.q_start, (tl.size, self.q_start.size)).copy()
        qd = np.zeros_like(q)
        qdd = np.zeros_like(q)
        for off, traj in parts:
            smp = traj.sample(tl - off)
            q += smp.position - traj.start
            qd += smp.velocity
            qdd += smp.acceleration
        return q, qd, qdd


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

    def times(self, period: float, max_samples: int | None = MAX_SAMPLES) -> np.ndarray:
        """0, dt, 2 dt, ... and the end time [s]; at most ``max_samples`` samples
        (see :func:`trajkit._sampling.period_times`)."""
        return period_times(self.duration, period, end="exact", max_samples=max_samples)

    def _tool_speed(self, q: np.ndarray, qd: np.ndarray) -> float:
        """|d FK(q)/dt| [m/s] for joint velocity ``qd``: central difference of FK
        along ``qd`` (a directional derivative, independent of the sample spacing)."""
        nrm = float(np.max(np.abs(qd)))
        if nrm == 0.0:
            return 0.0
        h = TOOL_SPEED_STEP / nrm
        p1 = self.robot.fk(q + h * qd).position
        p0 = self.robot.fk(q - h * qd).position
        return float(np.linalg.norm(p1 - p0) / (2.0 * h))

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
                q[m], qd[m], qdd[m] = sg.sample_ptp(tl)
                mot[m] = _part_index(sg, tl)
            else:
                q[m] = sg.q_start
                mot[m] = sg.motions[0]
            rows = np.nonzero(m)[0]
            for r in rows:
                pose = self.robot.fk(q[r])
                xyz[r] = pose.position
                quat[r] = quat_from_matrix(pose.rotation)
                if sg.kind == "PTP":
                    speed[r] = self._tool_speed(q[r], qd[r])
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
        names = []
        cols = [samples.t]
        for k, nm in enumerate(self.robot.joint_names):
            unit, sc = self.robot.joint_unit(k)
            names.append(f"{nm}_{unit}")
            cols.append(samples.q[:, k] * sc)
        cols += [1e3 * samples.xyz[:, 0], 1e3 * samples.xyz[:, 1], 1e3 * samples.xyz[:, 2],
                 1e3 * samples.tool_speed, samples.motion]
        text = csv_text(["t_s", *names, "x_mm", "y_mm", "z_mm", "tool_speed_mm_s", "instruction"], cols)
        if path is not None:
            atomic_write(path, text)
        return text


def _scaled_limits(robot: RobotModel, pct: float, blend_in: bool = False,
                   blend_out: bool = False) -> list[AxisLimits]:
    """Joint limits of a PTP: ``v_max`` times ``pct`` / 100; the jerk of a leg
    that overlaps a blended neighbour (accel leg: ``blend_in``, decel leg:
    ``blend_out``) is PTP_BLEND_JERK_SHARE of ``min(j_max, j_max_decel)``."""
    f = pct / 100.0
    out = []
    for lim in robot.limits:
        jb = PTP_BLEND_JERK_SHARE * min(lim.j_max, lim.j_max_decel)
        out.append(AxisLimits(lim.v_max * f, lim.a_max, jb if blend_in else lim.j_max,
                              lim.a_max_decel, jb if blend_out else lim.j_max_decel,
                              lim.position_min, lim.position_max, lim.name))
    return out


def _joint_goal(robot: RobotModel, target: Any, q_cur: np.ndarray, label: str) -> np.ndarray:
    if isinstance(target, JointTarget):
        return robot.check_joints(target.q, f"{label}: joints of point {target.name}")
    cfg = robot.config_of(q_cur) if target.config is None else robot.parse_config(target.config)
    try:
        return robot.ik(target.pose, cfg, seed=q_cur)
    except UnreachableError as exc:
        raise UnreachableError(f"{label}: target {target.name}: {exc}") from None


def _part_index(sg: Segment, tl: np.ndarray) -> np.ndarray:
    """Motion index of each local time of a (blended) PTP segment: the latest started move."""
    offs = np.array([o for o, _ in sg.parts]) if sg.parts else np.zeros(1)
    k = np.clip(np.searchsorted(offs, tl, side="right") - 1, 0, len(sg.motions) - 1)
    return np.asarray(sg.motions)[k]


def _leg_times(traj: Trajectory) -> tuple[float, float]:
    """(accel leg, decel leg) durations [s] of a phase-synchronised PTP."""
    acc = max((sum(p.phase_durations[:3]) for p in traj.axes), default=0.0)
    dec = max((sum(p.phase_durations[4:]) for p in traj.axes), default=0.0)
    return acc, dec


def _phase_bounds(traj: Trajectory) -> np.ndarray:
    """Times [s] of every phase boundary of every axis of ``traj`` (sorted, unique)."""
    out = [0.0, traj.duration]
    for p in traj.axes:
        out += np.cumsum(p.phase_durations).tolist()
    return np.unique(np.array(out))


def _blend_saves_time(robot: RobotModel, q0: np.ndarray, q1: np.ndarray, q2: np.ndarray,
                      ma: Ptp, mb: Ptp) -> bool:
    """Whether blending PTP ``ma`` (q0 -> q1) into ``mb`` (q1 -> q2), with half
    the jerk in the overlapping legs, ends sooner than stopping at q1 (the pair
    on its own)."""
    a = plan_ptp(q0, q1, _scaled_limits(robot, ma.speed_pct, blend_out=True), sync="phase")
    b = plan_ptp(q1, q2, _scaled_limits(robot, mb.speed_pct, blend_in=True), sync="phase")
    blended = a.duration + b.duration - _ptp_overlap(robot, a, b, ma, mb)
    a0 = plan_ptp(q0, q1, _scaled_limits(robot, ma.speed_pct), sync="phase")
    b0 = plan_ptp(q1, q2, _scaled_limits(robot, mb.speed_pct), sync="phase")
    return blended < a0.duration + b0.duration


def _ptp_overlap(robot: RobotModel, a: Trajectory, b: Trajectory, ma: Ptp, mb: Ptp) -> float:
    """Largest overlap [s] of PTP ``b`` over the end of ``a`` that keeps the limits and the zone.

    The overlap is at most the decel leg of ``a`` and the accel leg of ``b``;
    it is shrunk (bisection) until, on PTP_BLEND_CHECKS samples of the
    overlap, every joint stays within PTP_BLEND_USE of its velocity (with the
    lower of both overrides) and acceleration limits, and the tool within
    ``ma.zone`` of ``a``'s target; and the summed jerk (piecewise constant:
    checked exactly, once between every two phase boundaries of either move)
    within ``min(j_max, j_max_decel)``. Both legs are planned with
    PTP_BLEND_JERK_SHARE of that jerk, so the jerk check holds by construction.
    """
    _, dec = _leg_times(a)
    acc, _ = _leg_times(b)
    dmax = min(dec, acc)
    if dmax <= 0.0:
        return 0.0
    f = min(ma.speed_pct, mb.speed_pct) / 100.0
    vmax = np.array([lim.v_max for lim in robot.limits]) * f * PTP_BLEND_USE
    amax = np.array([min(lim.a_max, lim.a_max_decel) for lim in robot.limits]) * PTP_BLEND_USE
    jmax = np.array([min(lim.j_max, lim.j_max_decel) for lim in robot.limits])
    corner = robot.fk(a.goal).position
    zone = float(ma.zone)
    bounds_a = _phase_bounds(a)
    bounds_b = _phase_bounds(b)

    def ok(d: float) -> bool:
        t0 = a.duration - d
        t = np.linspace(t0, a.duration, PTP_BLEND_CHECKS)
        sa = a.sample(t)
        sb = b.sample(t - t0)
        v = sa.velocity + sb.velocity
        acc_ = sa.acceleration + sb.acceleration
        if (np.abs(v) > vmax).any() or (np.abs(acc_) > amax).any():
            return False
        edges = np.union1d(np.clip(bounds_a, t0, a.duration),
                           np.clip(bounds_b + t0, t0, a.duration))
        mid = 0.5 * (edges[1:] + edges[:-1])[np.diff(edges) > 0]
        if mid.size:
            jk = a.sample(mid).jerk + b.sample(mid - t0).jerk
            if (np.abs(jk) > jmax * (1.0 + 1e-12)).any():
                return False
        q = sa.position + sb.position - b.start
        return all(np.linalg.norm(robot.fk(qq).position - corner) <= zone for qq in q)

    if ok(dmax):
        return dmax
    lo, hi = 0.0, dmax
    for _ in range(PTP_BLEND_BISECT):
        mid = 0.5 * (lo + hi)
        if ok(mid):
            lo = mid
        else:
            hi = mid
    return lo


def run_motions(robot: RobotModel, motions: Sequence[Any], start: Any) -> RobotRun:
    """Plan ``motions`` from joints ``start``.

    Consecutive LIN/CIRC motions form one continuous-path chain when each
    (but the last) has a zone > 0: the corners are blended and the feed
    does not stop; a zone of 0 stops at the point (exact stop). A PTP with a
    zone > 0 followed by a PTP blends in joint space (the next move starts
    during this one's deceleration, the tool within the zone of the target,
    limits kept, the overlapping legs at half the jerk; where that would not
    save time over an exact stop, it stops); between PTP and LIN/CIRC the
    robot always stops.

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
            j = i
            while j + 1 < len(motions) and isinstance(motions[j + 1], Ptp) and motions[j].zone > 0:
                j += 1
            goals = []
            starts = []
            for k in range(i, j + 1):
                starts.append(q)
                goals.append(_joint_goal(robot, motions[k].target, q, motions[k].label))
                q = goals[-1]
            # blend a junction only where it saves time over an exact stop
            # (the overlapping legs run at half the jerk)
            blend = [_blend_saves_time(robot, starts[k], goals[k], goals[k + 1], motions[i + k],
                                       motions[i + k + 1]) for k in range(j - i)]
            g0 = 0
            for g1 in range(j - i + 1):
                if g1 < j - i and blend[g1]:
                    continue
                parts: list[tuple[float, Trajectory]] = []
                off = 0.0
                for k in range(g0, g1 + 1):
                    mk = motions[i + k]
                    traj = plan_ptp(starts[k], goals[k], _scaled_limits(
                        robot, mk.speed_pct, blend_in=k > g0, blend_out=k < g1), sync="phase")
                    if parts:
                        prev_off, prev = parts[-1]
                        off = prev_off + prev.duration - _ptp_overlap(
                            robot, prev, traj, motions[i + k - 1], mk)
                    parts.append((off, traj))
                duration = max(o + tr.duration for o, tr in parts)
                segments.append(Segment("PTP", t, duration, list(range(i + g0, i + g1 + 1)),
                                        starts[g0], goals[g1], ptp=parts[0][1], parts=parts))
                t += duration
                g0 = g1 + 1
            i = j + 1
        elif isinstance(m, (Lin, Circ)):
            j = i
            while j + 1 < len(motions) and isinstance(motions[j + 1], (Lin, Circ)) and motions[j].zone > 0:
                j += 1
            # (split where the zone cannot be blended: the motion stops there)
            cuts = [i + c for c in chain_stops(robot, q, motions[i:j + 1],
                                               [g.label for g in motions[i:j + 1]])]
            for a, b in zip([i] + [c + 1 for c in cuts], cuts + [j]):
                group = motions[a:b + 1]
                chain = plan_chain(robot, q, group, [g.label for g in group], list(range(a, b + 1)))
                if chain is not None:
                    segments.append(Segment("CP", t, chain.duration, list(range(a, b + 1)),
                                            q, chain.q_end, chain=chain))
                    for sd in chain.slowdowns:
                        sd.motion += a
                    slowdowns += chain.slowdowns
                    t += chain.duration
                    q = chain.q_end
            i = j + 1
        else:
            raise InvalidInputError(f"motion {i} has unknown type {type(m).__name__}")
    return RobotRun(robot, motions, segments, slowdowns)
