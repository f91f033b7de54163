"""Cartesian motion chains (LIN/CIRC with blends): path, joints by inverse kinematics, timing.

Steps: build the pieces (lines, arcs, curvature-continuous Bezier corner
blends, orientation by slerp); walk the inverse kinematics along the path
(each solution seeded by the previous one, so the configuration stays pinned,
and any joint jump bisected to tell a steep stretch from a singularity that
cannot be passed); then time the joint path with the path-timing engine
(:func:`trajkit.timing.plan_path_timing`): minimum time under every joint's
velocity, acceleration and jerk limits, the programmed tool speed, the
orientation rate and the tool's acceleration (tangential and centripetal) and
jerk. Sampling solves IK at every sample.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import InvalidInputError, UnreachableError
from ..interpolation.feed import ramp_mask, stretch_speed
from ..kinematics.base import Pose, RobotModel
from ..paths._tolerances import COINCIDENT_DIST
from ..paths.arc import Arc3
from ..paths.line import Line
from ..timing import PathTiming, plan_path_timing
from ._jointpath import ChainJointPath
from ._pieces import (
    BezierBlend,
    Piece,
    angle_between_tangents,
    blended_orientation,
    constant_point,
    constant_point_derivatives,
    sub_path,
    sub_path_derivatives,
)
from ._rotations import matrix_from_quat, quat_from_matrix, rotation_angle, slerp
from .motion import Circ, JointTarget

__all__ = ["CartesianChain", "chain_stops", "plan_chain"]

#: Fraction of the velocity limit above which a joint counts as "at its velocity limit"
#: in a run's summary.
VEL_USE = 0.999

#: A stretch runs below its programmed speed (a slow-down) when its planned
#: speed is below this fraction of it.
SLOWDOWN_FRACTION = 0.999

#: A uniform slow-down of the chain's timing (time scale above 1 by more than this)
#: is reported as a stretch over the whole chain.
UNIFORM_REPORT_RTOL = 1e-12

#: Slow-down stretches are split where their limiting speed changes by this factor.
SLOWDOWN_BAND = 1.25

#: Kept for the summary's "at the velocity limit" test (relative round-off).
SLOWDOWN_RTOL = 1e-9

#: A required speed below this fraction of the programmed speed makes the
#: path impassable (a singularity on the path).
MIN_SPEED_FRACTION = 1e-3

#: Spacing of the inverse-kinematics walk along the path [m of path parameter]
#: (seeds of the solutions, and where joint jumps are looked for).
GRID_DS = 1e-3

#: Fewest grid cells per piece.
GRID_MIN_CELLS = 16

#: Most grid cells per piece.
GRID_MAX_CELLS = 20000

#: A joint change [rad or m] between grid neighbours above which the cell is
#: bisected to tell a steep stretch from a jump (singularity).
JUMP_CHECK = 0.05

#: Bisection stops at cells this short [m of path parameter]; a joint change
#: still above JUMP_CHECK there is a jump.
JUMP_DS = 1e-9

#: Difference of the tool's turn per metre [rad/m] below which two smooth
#: pieces need no blend (a collinear LIN into a LIN turning the tool at
#: another rate does: the joint velocity would step).
SMOOTH_ORIENTATION_RATE = 1e-9

#: Tangent turn below which two pieces meet smoothly (no blend needed) [rad].
SMOOTH_TURN = 1e-6

#: Change of the curvature vector [1/m] at a tangent-continuous join above
#: which the join is blended (G2) like a corner: a curvature step would step
#: the joint accelerations (unbounded joint jerk).
SMOOTH_CURVATURE = 1e-9

#: Tangent turn above which a corner cannot be blended (reversal) [rad].
MAX_BLEND_TURN = math.pi - 1e-3

#: A corner is passed as an exact stop instead where the circle tangent to both
#: pieces at the zone's distance from the corner (the blend turns tighter still)
#: has a radius below this fraction of the robot's length scale: a near reversal
#: with a small zone (179 deg and 0.1 mm: a 0.9 um circle) would make a blend
#: turning within micrometres, which the joints pass at a crawl and the path
#: timing cannot resolve.
BLEND_RADIUS_MIN = 1e-4


@dataclass
class Slowdown:
    """A stretch where the feed runs below the programmed speed because of a limit.

    Attributes
    ----------
    motion : int
        Index of the motion in the chain's program.
    label : str
    start_xyz, end_xyz : ndarray, shape (3,) [m]
    speed : float
        Feed speed there [m/s].
    programmed : float
        Programmed speed [m/s].
    reason : str
        E.g. ``"velocity of joint A4"``, ``"acceleration of joint A1"``,
        ``"orientation speed"``, ``"path curvature"``.
    """

    motion: int
    label: str
    start_xyz: np.ndarray
    end_xyz: np.ndarray
    speed: float
    programmed: float
    reason: str

    def to_dict(self) -> dict:
        return {"instruction": self.label, "start_xyz_mm": (1e3 * self.start_xyz).tolist(),
                "end_xyz_mm": (1e3 * self.end_xyz).tolist(), "speed_mm_s": 1e3 * self.speed,
                "programmed_mm_s": 1e3 * self.programmed, "reason": self.reason}


@dataclass
class CartesianChain:
    """A planned chain of LIN/CIRC motions between two stops."""

    robot: RobotModel
    pieces: list[Piece]
    offsets: np.ndarray
    path: ChainJointPath
    timing: PathTiming
    labels: list[str]
    motion_ids: list[int]
    slowdowns: list[Slowdown] = field(default_factory=list)

    @property
    def duration(self) -> float:
        return self.timing.duration

    @property
    def q_start(self) -> np.ndarray:
        return self.path.table_q[0]

    @property
    def q_end(self) -> np.ndarray:
        return self.path.table_q[-1]

    def locate(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        k = np.clip(np.searchsorted(self.offsets, s, side="right") - 1, 0, len(self.pieces) - 1)
        return k, s - self.offsets[k]

    def geometry(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Positions (n, 3), quaternions (n, 4), tool rate (n,), motion ids (n,) at parameter s."""
        k, local = self.locate(s)
        pos = np.empty((s.size, 3))
        quat = np.empty((s.size, 4))
        rate = np.empty(s.size)
        mid = np.empty(s.size, dtype=int)
        for i in np.unique(k):
            m = k == i
            pc = self.pieces[i]
            pos[m] = pc.point(local[m])
            quat[m] = pc.quat(local[m])
            rate[m] = pc.tool_rate
            mid[m] = self.motion_ids[pc.motion]
        return pos, quat, rate, mid

    def sample(self, t: np.ndarray) -> dict[str, np.ndarray]:
        """IK at every sample time ``t`` (n,) [s] (local to the chain)."""
        s, v, a, _ = self.timing.sample(t)
        pos, quat, rate, mid = self.geometry(s)
        q = self.path.joints(s)
        dq, ddq, _ = self.timing.grid_interpolated(s)
        qd = dq * v[:, None]
        qdd = dq * a[:, None] + ddq * (v * v)[:, None]
        return {"q": q, "qd": qd, "qdd": qdd, "xyz": pos, "quat": quat,
                "tool_speed": v * rate, "motion": mid}


def _mm(p: Any) -> str:
    return "(" + ", ".join(f"{1e3 * float(x):.3f}" for x in p) + ") mm"


def _target_pose(robot: RobotModel, t: Any, label: str) -> tuple[Pose, Any]:
    if isinstance(t, JointTarget):
        q = robot.check_joints(t.q, f"{label}: joints of point {t.name}")
        return robot.fk(q), robot.config_of(q)
    return t.pose, (None if t.config is None else robot.parse_config(t.config))


def _base_pieces(robot: RobotModel, q0: np.ndarray, motions: Sequence[Any], labels: Sequence[str]):
    pose = robot.fk(q0)
    p_prev, quat_prev = pose.position, quat_from_matrix(pose.rotation)
    out = []  # (piece-spec dict) per motion
    for i, (m, lab) in enumerate(zip(motions, labels)):
        tpose, cfg = _target_pose(robot, m.target, lab)
        p_end, quat_end = tpose.position, quat_from_matrix(tpose.rotation)
        if float(np.dot(quat_prev, quat_end)) < 0:
            quat_end = -quat_end
        ang = rotation_angle(quat_prev, quat_end)
        path: Arc3 | Line | None = None
        if isinstance(m, Circ):
            vpose, _ = _target_pose(robot, m.via, lab)
            try:
                path = Arc3(p_prev, vpose.position, p_end)
            except InvalidInputError as exc:
                raise InvalidInputError(f"{lab}: {exc}") from None
        elif float(np.linalg.norm(p_end - p_prev)) > COINCIDENT_DIST:
            path = Line(p_prev, p_end)
        out.append({"path": path, "p0": p_prev, "p1": p_end, "quat0": quat_prev,
                    "quat1": quat_end, "angle": ang, "speed": float(m.speed),
                    "zone": float(m.zone), "config": cfg, "motion": i})
        p_prev, quat_prev = p_end, quat_end
    return out


def curvature_vector(path: Any, s: float) -> np.ndarray:
    """Curvature vector (kappa times the principal normal) [1/m], shape (3,), of ``path`` at ``s``.

    Exact for :class:`~trajkit.paths.Line` (zero) and :class:`~trajkit.paths.arc.Arc3`
    (towards the centre, magnitude 1 / radius).
    """
    if isinstance(path, Arc3):
        return (path.centre - path.point(s)) / path.radius**2
    if isinstance(path, Line):
        return np.zeros(3)
    raise InvalidInputError(f"no curvature vector for a path of type {type(path).__name__}")


def _orientation_rate(spec: dict) -> np.ndarray:
    """World-frame turn of the tool per metre of path [rad/m] (constant along a slerp)."""
    path = spec["path"]
    if path is None or spec["angle"] <= 0.0 or path.length <= 0.0:
        return np.zeros(3)
    rel = matrix_from_quat(spec["quat1"]) @ matrix_from_quat(spec["quat0"]).T
    w = np.array([rel[2, 1] - rel[1, 2], rel[0, 2] - rel[2, 0], rel[1, 0] - rel[0, 1]])
    sn = 0.5 * float(np.linalg.norm(w))
    cs = 0.5 * (float(np.trace(rel)) - 1.0)
    th = math.atan2(sn, cs)
    axis = w / (2.0 * sn) if sn > 0.0 else np.zeros(3)
    if th > 0.0 and sn <= 1e-12:  # a half turn: the axis from the symmetric part
        m = 0.5 * (rel + np.eye(3))
        axis = m[int(np.argmax(np.diag(m)))]
        axis = axis / np.linalg.norm(axis)
    return axis * th / path.length


def _corner(robot: RobotModel, a: dict, b: dict) -> float | None:
    """How the chain passes from spec ``a`` into spec ``b``: the radius of their
    corner blend [m], 0 where they join smoothly (tangent, curvature and orientation
    rate continuous), None where the motion has to stop (a zone of 0, an
    orientation-only motion, a reversal, or a blend tighter than BLEND_RADIUS_MIN)."""
    if a["zone"] <= 0 or a["path"] is None or b["path"] is None:
        return None
    ta = a["path"].tangent(a["path"].length)
    tb = b["path"].tangent(0.0)
    turn = angle_between_tangents(ta, tb)
    if turn > MAX_BLEND_TURN:
        return None
    if turn < SMOOTH_TURN and np.linalg.norm(
            curvature_vector(a["path"], a["path"].length)
            - curvature_vector(b["path"], 0.0)) <= SMOOTH_CURVATURE and np.linalg.norm(
            _orientation_rate(a) - _orientation_rate(b)) <= SMOOTH_ORIENTATION_RATE:
        return 0.0
    r = min(a["zone"], 0.5 * a["path"].length, 0.5 * b["path"].length)
    # the tangent circle's radius r cot(turn / 2), below the minimum (no division:
    # a tangent-continuous join, turn 0, has none)
    if r * math.cos(0.5 * turn) < BLEND_RADIUS_MIN * robot.length_scale * math.sin(0.5 * turn):
        return None
    return r


def chain_stops(robot: RobotModel, q0: np.ndarray, motions: Sequence[Any],
                labels: Sequence[str]) -> list[int]:
    """Indices ``i`` of the LIN/CIRC ``motions`` (all but the last with a zone > 0,
    starting at joints ``q0``) after which the motion stops exactly although the
    zone asks for a blend: an orientation-only motion next to a path, a reversal
    of the path (> MAX_BLEND_TURN), or a corner whose blend would be tighter than
    BLEND_RADIUS_MIN of the robot's length scale. The chain is planned in parts
    split there (the joint path has a kink at such a corner)."""
    specs = _base_pieces(robot, q0, motions, labels)
    return [i for i in range(len(specs) - 1) if _corner(robot, specs[i], specs[i + 1]) is None]


def _pieces(robot: RobotModel, specs: list[dict]) -> list[Piece]:
    w_max = robot.orientation_speed
    n = len(specs)
    # trims at both ends of each path spec
    trim0 = [0.0] * n
    trim1 = [0.0] * n
    blends: dict[int, float] = {}
    for i in range(n - 1):
        r = _corner(robot, specs[i], specs[i + 1])
        if not r:  # a smooth join (or a stop, which chain_stops splits the chain at)
            continue
        trim1[i] = r
        trim0[i + 1] = r
        blends[i] = r
    pieces: list[Piece] = []
    for i, sp in enumerate(specs):
        path = sp["path"]
        v = sp["speed"]
        if path is None:
            if sp["angle"] <= 0.0:
                continue
            L = sp["angle"] * robot.length_scale
            pieces.append(Piece("orient", L, constant_point(sp["p0"]), sp["quat0"], sp["quat1"],
                                w_max * robot.length_scale, i, 0.0, "orientation speed",
                                derivatives=constant_point_derivatives(sp["p0"])))
            continue
        s0, s1 = trim0[i], path.length - trim1[i]
        frac0, frac1 = s0 / path.length, s1 / path.length
        qa = slerp(sp["quat0"], sp["quat1"], frac0)
        qb = slerp(sp["quat0"], sp["quat1"], frac1)
        cap, reason = v, ""
        if sp["angle"] > 0 and w_max * path.length / sp["angle"] < v:
            cap, reason = w_max * path.length / sp["angle"], "orientation speed"
        pieces.append(Piece("path", s1 - s0, sub_path(path, s0, s1), qa, qb, cap, i, 1.0, reason, v,
                            feature=path.radius if isinstance(path, Arc3) else math.inf,
                            derivatives=sub_path_derivatives(path, s0)))
        if i in blends:
            r = blends[i]
            nxt = specs[i + 1]
            pa = path.point(s1)
            tang_a = path.tangent(s1)
            pb = nxt["path"].point(r)
            tang_b = nxt["path"].tangent(r)
            qn = slerp(nxt["quat0"], nxt["quat1"], r / nxt["path"].length)
            bz = BezierBlend(pa, tang_a, pb, tang_b, r, ka=curvature_vector(path, s1),
                             kb=curvature_vector(nxt["path"], r), corner=sp["p1"])
            cap_b = min(v, nxt["speed"])
            ori = blended_orientation(sp["quat0"], sp["quat1"], path.length, s1,
                                      nxt["quat0"], nxt["quat1"], nxt["path"].length, r, bz.length)
            pieces.append(Piece("blend", bz.length, bz.point, qb, qn, cap_b, i, 1.0, "",
                                quat_fn=ori, feature=1.0 / bz.peak_curvature
                                if bz.peak_curvature > 0.0 else math.inf, derivatives=bz.derivatives))
    return pieces


def _pose_at(pieces: list[Piece], offsets: np.ndarray, s: float) -> tuple[Pose, int]:
    i = int(np.clip(np.searchsorted(offsets, s, side="right") - 1, 0, len(pieces) - 1))
    loc = np.array([s - offsets[i]])
    p = pieces[i].point(loc)[0]
    r = matrix_from_quat(pieces[i].quat(loc)[0])
    return Pose.trusted(p, r), pieces[i].motion


def _check_continuous(robot: RobotModel, pieces: list[Piece], offsets: np.ndarray, s0: float,
                      s1: float, q0: np.ndarray, labels: Sequence[str]) -> None:
    """Bisect the cell [s0, s1]; raise if a joint still jumps in a cell of JUMP_DS."""
    qa = q0
    while s1 - s0 > JUMP_DS:
        sm = 0.5 * (s0 + s1)
        pm, _ = _pose_at(pieces, offsets, sm)
        try:
            qm = robot.ik_near(pm, qa)
        except UnreachableError:
            return  # reported by the sampling of the grid
        pe, _ = _pose_at(pieces, offsets, s1)
        try:
            qe = robot.ik_near(pe, qm)
        except UnreachableError:
            return
        left, right = float(np.abs(qm - qa).max()), float(np.abs(qe - qm).max())
        if max(left, right) <= JUMP_CHECK:
            return  # the change shrinks with the cell: steep but continuous
        if left >= right:
            s1 = sm
        else:
            s0, qa = sm, qm
    pe, mi = _pose_at(pieces, offsets, s1)
    try:
        qe = robot.ik_near(pe, qa)
    except UnreachableError:
        return
    jump = np.abs(qe - qa)
    if jump.max() > JUMP_CHECK:
        j = int(np.argmax(jump))
        raise UnreachableError(
            f"{labels[mi]}: the path passes through a singularity at {_mm(pe.position)} that "
            f"cannot be passed in this configuration: joint {robot.joint_names[j]} would jump by "
            f"{math.degrees(float(jump[j])):.1f} deg"
        )


def plan_chain(robot: RobotModel, q0: np.ndarray, motions: Sequence[Any], labels: Sequence[str],
               motion_ids: Sequence[int]) -> CartesianChain | None:
    """Plan LIN/CIRC ``motions`` from joints ``q0`` as one chain (rest to rest).

    Returns
    -------
    CartesianChain or None
        None when nothing moves (every motion ends where it starts).

    Raises
    ------
    UnreachableError
        A point of the path is out of reach or needs a joint outside its
        range, or the path crosses a singularity that cannot be passed (the
        message names the instruction and the point).
    InvalidInputError
        Degenerate arcs.
    """
    labels = list(labels)
    specs = _base_pieces(robot, q0, motions, labels)
    pieces = _pieces(robot, specs)
    if not pieces:
        return None  # nothing moves
    lengths = np.array([p.length for p in pieces])
    offsets = np.concatenate([[0.0], np.cumsum(lengths)])
    # ---- grid
    grid = []
    for i, pc in enumerate(pieces):
        n = max(GRID_MIN_CELLS, int(math.ceil(pc.length / GRID_DS)))
        n = min(n, GRID_MAX_CELLS)
        ss = offsets[i] + np.linspace(0.0, pc.length, n + 1)
        grid.append(ss if i == 0 else ss[1:])
    s = np.concatenate(grid)
    keep = np.concatenate([[True], np.diff(s) > 0])
    s = s[keep]
    k = np.clip(np.searchsorted(offsets, s, side="right") - 1, 0, len(pieces) - 1)
    local = s - offsets[k]
    nj = robot.n_joints
    q = np.empty((s.size, nj))
    pos = np.empty((s.size, 3))
    mot = np.empty(s.size, dtype=int)
    quat = np.empty((s.size, 4))
    for i in np.unique(k):
        m = k == i
        pos[m] = pieces[i].point(local[m])
        quat[m] = pieces[i].quat(local[m])
        mot[m] = pieces[i].motion
    rots = matrix_from_quat(quat)
    seed = np.asarray(q0, dtype=np.float64)
    for idx in range(s.size):
        pc = pieces[k[idx]]
        p = pos[idx]
        r = rots[idx]
        try:
            qi = robot.ik_near(Pose.trusted(p, r), seed)
        except UnreachableError as exc:
            raise UnreachableError(
                f"{labels[pc.motion]}: point {_mm(p)} of the path is unreachable: {exc}"
            ) from None
        q[idx] = qi
        seed = qi
    # ---- continuity: a joint that jumps inside a cell however finely it is cut
    # marks a singularity the pinned configuration cannot pass
    steps = np.abs(np.diff(q, axis=0))
    for c in np.nonzero(steps.max(axis=1) > JUMP_CHECK)[0]:
        _check_continuous(robot, pieces, offsets, s[c], s[c + 1], q[c], labels)
    # ---- configuration of the targets (a LIN/CIRC cannot change configuration)
    for sp in specs:
        if sp["config"] is None:
            continue
        last = np.nonzero(mot == sp["motion"])[0]
        if last.size and robot.config_of(q[last[-1]]) != sp["config"] and robot.configs != ("numeric",):
            raise UnreachableError(
                f"{labels[sp['motion']]}: the target is taught in configuration {sp['config']!r} "
                f"but the path arrives in {robot.config_of(q[last[-1]])!r} "
                "(a LIN/CIRC cannot change configuration; use PTP)"
            )
    # ---- timing: the engine, under the joint limits and the tool's own limits
    path = ChainJointPath(robot, pieces, offsets, s, q, labels)
    caps = np.array([pc.cap for pc in pieces])

    def speed(ss: np.ndarray) -> np.ndarray:
        # at a junction the slower of the two pieces
        return np.minimum(caps[path.piece_of(ss)], caps[path.piece_of(ss, side="left")])

    def curvature(ss: np.ndarray) -> np.ndarray:
        return _tool_curvature(path, ss)

    from ..errors import InfeasibleError

    try:
        timing = plan_path_timing(path, robot.limits, speed=speed, accel=robot.cartesian_accel,
                                  jerk=robot.cartesian_jerk, curvature=curvature)
    except InfeasibleError as exc:
        raise UnreachableError(f"{labels[pieces[0].motion]}: {exc}") from None
    except InvalidInputError as exc:
        raise InvalidInputError(f"{labels[pieces[0].motion]}: {exc}") from None
    chain = CartesianChain(robot, pieces, offsets, path, timing, labels, list(motion_ids))
    chain.slowdowns = _slowdowns(chain, specs)
    return chain


def _tool_curvature(path: ChainJointPath, s: np.ndarray) -> np.ndarray:
    """Curvature [1/m] of the tool path at ``s`` (0 on orientation-only pieces): second
    differences of the piece's own points (one-sided at its ends)."""
    k = path.piece_of(s)
    lo, hi = path.offsets[k], path.offsets[k + 1]
    h = np.minimum(1e-4 * float(path.robot.length_scale), (hi - lo) / 4.0)
    a = np.clip(s - h, lo, hi - 2 * h)
    out = np.zeros(s.size)
    for i in np.unique(k):
        pc = path.pieces[i]
        m = k == i
        if pc.tool_rate == 0.0:
            continue
        loc = a[m] - path.offsets[i]
        hh = h[m]
        p0, p1, p2 = pc.point(loc), pc.point(loc + hh), pc.point(loc + 2 * hh)
        out[m] = np.linalg.norm(p0 - 2 * p1 + p2, axis=1) / hh**2
    return out


def _slowdowns(chain: CartesianChain, specs: list[dict]) -> list[Slowdown]:
    """Stretches whose planned speed is below the programmed one because of a limit.

    At every grid node the static speed limits are compared with the
    programmed speed: the joints' velocity (``v_max / |q'|``), acceleration
    (``sqrt(a / |d2q/ds2|)``) and jerk (``cbrt(j / |d3q/ds3|)``) limits at constant
    speed, the orientation rate and the tool's centripetal acceleration. Nodes
    whose planned speed is below the programmed one where such a limit is
    below it too form the reported stretches, split wherever the limit's level
    changes by more than :data:`SLOWDOWN_BAND` (neighbours of the same reason
    whose speeds stay within that band are one stretch again); each reports
    the slowest planned speed inside it, off the ramps from and to rest.
    """
    tm = chain.timing
    robot = chain.robot
    path = chain.path
    s = tm.grid
    v = tm.grid_speed
    _, d1, d2, d3 = tm.grid_derivatives
    k = path.piece_of(s)
    prog = np.array([chain.pieces[i].programmed for i in k])
    piece_cap = np.array([chain.pieces[i].cap for i in k])
    vmax = np.array([lm.v_max for lm in robot.limits])
    amax = np.array([min(lm.a_max, lm.a_max_decel) for lm in robot.limits])
    jmax = np.array([min(lm.j_max, lm.j_max_decel) for lm in robot.limits])
    kap = _tool_curvature(path, s)
    with np.errstate(divide="ignore"):
        caps = np.column_stack([
            np.where(piece_cap < prog, piece_cap, np.inf),
            np.min(vmax / np.abs(d1), axis=1),
            np.min(np.sqrt(amax / np.abs(d2)), axis=1),
            np.min(np.cbrt(jmax / np.abs(d3)), axis=1),
            np.sqrt(robot.cartesian_accel / kap),
        ])
    cap = caps.min(axis=1)
    col = np.argmin(caps, axis=1)
    ramp = ramp_mask(v)
    limited = cap < SLOWDOWN_FRACTION * prog
    # bands of the limiting speed: a stretch is split where its cap changes by
    # more than SLOWDOWN_BAND, so each reports a speed that holds over it
    band = np.floor(np.log(np.maximum(cap, 1e-300) / prog) / math.log(SLOWDOWN_BAND))

    def reason_at(i: int) -> str:
        c = int(col[i])
        if c == 0:
            return chain.pieces[k[i]].cap_reason or "programmed speed"
        if c == 4:
            return "path curvature (tool acceleration)"
        with np.errstate(divide="ignore"):
            ratio = (vmax / np.abs(d1[i]), np.sqrt(amax / np.abs(d2[i])),
                     np.cbrt(jmax / np.abs(d3[i])))
            j = int(np.argmin(ratio[c - 1]))
        return f"{('velocity', 'acceleration', 'jerk')[c - 1]} of joint {robot.joint_names[j]}"

    pos, _, _, _ = chain.geometry(s)
    out: list[tuple[int, int, Slowdown]] = []
    i = 0
    while i < s.size:
        if not limited[i]:
            i += 1
            continue
        j = i
        while (j + 1 < s.size and limited[j + 1] and band[j + 1] == band[i]
               and chain.pieces[k[j + 1]].motion == chain.pieces[k[i]].motion):
            j += 1
        seg = slice(i, j + 1)
        speed = stretch_speed(v[seg], ramp[seg])
        # the reason that holds over the longest part of the stretch
        lo = np.concatenate([[s[i]], 0.5 * (s[i:j] + s[i + 1:j + 1])])
        hi = np.concatenate([0.5 * (s[i:j] + s[i + 1:j + 1]), [s[j]]])
        weight: dict[str, float] = {}
        for n, ln in zip(range(i, j + 1), hi - lo):
            nm = reason_at(n)
            weight[nm] = weight.get(nm, 0.0) + float(ln)
        reason = max(weight, key=weight.__getitem__)
        mi = chain.motion_ids[chain.pieces[k[i]].motion]
        lab = chain.labels[chain.pieces[k[i]].motion]
        if speed < SLOWDOWN_FRACTION * float(prog[i]):
            prev = out[-1] if out else None
            # a neighbouring stretch of the same instruction and reason whose speed is
            # within one band of this one's: one stretch (its cap changed, the speed not)
            if (prev is not None and prev[1] == i - 1 and prev[2].motion == mi
                    and prev[2].reason == reason
                    and max(prev[2].speed, speed) <= SLOWDOWN_BAND * min(prev[2].speed, speed)):
                z = prev[2]
                out[-1] = (prev[0], j, Slowdown(mi, lab, z.start_xyz, pos[j].copy(), min(z.speed, speed),
                                                z.programmed, reason))
            else:
                out.append((i, j, Slowdown(mi, lab, pos[i].copy(), pos[j].copy(), speed, float(prog[i]),
                                           reason)))
        i = j + 1
    result = [z for _, _, z in out]
    k_uniform = float(getattr(tm, "time_scale", 1.0))
    if k_uniform > 1.0 + UNIFORM_REPORT_RTOL:
        # the final check found a limit exceeded between the grid nodes and the whole
        # motion was slowed down by this factor: every cruise runs 1/k slower too
        top = int(np.argmax(prog))
        mi = chain.motion_ids[chain.pieces[k[top]].motion]
        lab = chain.labels[chain.pieces[k[top]].motion]
        result.append(Slowdown(mi, lab, pos[0].copy(), pos[-1].copy(), float(prog[top]) / k_uniform,
                               float(prog[top]),
                               f"whole chain slowed down uniformly by {k_uniform - 1.0:.3g} "
                               "(a limit exceeded between the grid nodes)"))
    return result
