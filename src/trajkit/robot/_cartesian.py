"""Cartesian motion chains (LIN/CIRC with blends): path, IK grid, speed limits, feed.

Steps: build the pieces (lines, arcs, Bezier corner blends, orientation by
slerp); solve IK on a dense grid of the path parameter, each seeded by the
previous one (the configuration stays pinned); get dq/ds, d2q/ds2 and
d3q/ds3; cap the feed speed and choose each run's path acceleration and jerk
so that every joint stays within its velocity, acceleration and jerk limits;
plan the jerk-limited feed (:mod:`trajkit.robot._feed`). Corners are blended
by curvature-continuous curves, so the joint accelerations never step.
Sampling then solves IK at every sample.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from ..errors import InvalidInputError, UnreachableError
from ..kinematics.base import Pose, RobotModel
from ..paths._tolerances import COINCIDENT_DIST
from ..paths.arc import Arc3
from ..paths.line import Line
from ._feed import Feed, Run, plan_feed
from ._pieces import (
    BezierBlend,
    Piece,
    angle_between_tangents,
    blended_orientation,
    constant_point,
    sub_path,
)
from ._rotations import matrix_from_quat, quat_from_matrix, rotation_angle, slerp
from .motion import Circ, JointTarget

__all__ = ["CartesianChain", "plan_chain"]

#: Fraction of each joint's velocity limit the feed may use (margin for the
#: difference between the IK grid and IK at the samples).
VEL_USE = 0.95

#: Fraction of each joint's acceleration limit used by the centripetal term
#: (d2q/ds2) v^2; the rest (ACC_PATH_USE) is left to the path acceleration.
ACC_CURVE_USE = 0.5

#: Fraction of each joint's acceleration limit used by (dq/ds) s''.
ACC_PATH_USE = 0.45

#: Joint jerk along the path: ``d3q/ds3 v^3 + 3 d2q/ds2 v a + dq/ds j`` (v, a, j:
#: path speed, acceleration, jerk). Fraction of each joint's jerk limit
#: (``min(j_max, j_max_decel)``) the three terms may use together; the rest
#: covers the finite differences (the derivatives between grid points).
JERK_USE = 0.9

#: Fraction of each joint's jerk limit used by the first term, ``|d3q/ds3| v^3``:
#: a speed cap at every grid point, like the velocity and acceleration caps.
JERK_CURVE_USE = 0.5

#: Share of what the first term leaves of JERK_USE (at the run's speed level)
#: that ``3 |d2q/ds2| v |a|`` may use at most; it bounds the run's path
#: acceleration. ``|dq/ds| |j|`` gets the rest, which bounds the run's path jerk.
JERK_ACC_SHARE = 0.5

#: The path derivatives used for the jerk bound at a grid point are the
#: largest over this many grid points on either side, so that the bound
#: holds between the grid points too.
DERIV_WINDOW = 1

#: Grid refinement for the derivatives (:func:`_refine_derivatives`): a cell
#: whose second derivative changes by more than REFINE_RTOL of its size, where
#: the jerk cap would bind if the third derivative were REFINE_D3_FACTOR times
#: the grid's, is re-sampled REFINE_FACTOR times finer.
REFINE_RTOL = 0.1
REFINE_D3_FACTOR = 1000.0
REFINE_FACTOR = 16

#: Fraction of the tool acceleration limit used by the path curvature (v^2 kappa).
CART_CURVE_USE = 0.5

#: A run capped less than this fraction below its programmed speed is not a slow-down.
SLOWDOWN_RTOL = 1e-9

#: Speed levels of the feed: the programmed speed times LEVEL_RATIO**k.
LEVEL_RATIO = 0.85

#: A required speed below this fraction of the programmed speed makes the
#: path impassable (a singularity on the path).
MIN_SPEED_FRACTION = 1e-3

#: Target spacing of the IK grid [m of path parameter].
GRID_DS = 5e-4

#: Fewest grid cells per piece.
GRID_MIN_CELLS = 16

#: Most grid cells per chain.
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
    grid_s: np.ndarray
    grid_q: np.ndarray
    grid_dq: np.ndarray
    grid_ddq: np.ndarray
    feed: Feed
    labels: list[str]
    motion_ids: list[int]
    slowdowns: list[Slowdown] = field(default_factory=list)

    @property
    def duration(self) -> float:
        return self.feed.duration

    @property
    def q_start(self) -> np.ndarray:
        return self.grid_q[0]

    @property
    def q_end(self) -> np.ndarray:
        return self.grid_q[-1]

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
        s, v, a = self.feed.sample(t)
        pos, quat, rate, mid = self.geometry(s)
        rots = matrix_from_quat(quat)
        nj = self.robot.n_joints
        q = np.empty((s.size, nj))
        seeds = np.column_stack([np.interp(s, self.grid_s, self.grid_q[:, j]) for j in range(nj)])
        for i in range(s.size):
            q[i] = self._ik(Pose.trusted(pos[i], rots[i]), seeds[i], int(mid[i]), pos[i])
        dq = np.column_stack([np.interp(s, self.grid_s, self.grid_dq[:, j]) for j in range(nj)])
        ddq = np.column_stack([np.interp(s, self.grid_s, self.grid_ddq[:, j]) for j in range(nj)])
        qd = dq * v[:, None]
        qdd = dq * a[:, None] + ddq * (v * v)[:, None]
        return {"q": q, "qd": qd, "qdd": qdd, "xyz": pos, "quat": quat,
                "tool_speed": v * rate, "motion": mid}

    def _ik(self, pose: Pose, seed: np.ndarray, motion: int, p: np.ndarray) -> np.ndarray:
        try:
            return self.robot.ik_near(pose, seed)
        except UnreachableError as exc:
            lab = self.labels[self.motion_ids.index(motion)] if motion in self.motion_ids else ""
            raise UnreachableError(f"{lab}: point {_mm(p)} is unreachable: {exc}") from None


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
        path = None
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


def _pieces(robot: RobotModel, specs: list[dict]) -> list[Piece]:
    w_max = robot.orientation_speed
    n = len(specs)
    # trims at both ends of each path spec
    trim0 = [0.0] * n
    trim1 = [0.0] * n
    blends: dict[int, float] = {}
    for i in range(n - 1):
        a, b = specs[i], specs[i + 1]
        if a["zone"] <= 0 or a["path"] is None or b["path"] is None:
            continue
        ta = a["path"].tangent(a["path"].length)
        tb = b["path"].tangent(0.0)
        turn = angle_between_tangents(ta, tb)
        if turn > MAX_BLEND_TURN:
            continue
        if turn < SMOOTH_TURN and np.linalg.norm(
                curvature_vector(a["path"], a["path"].length)
                - curvature_vector(b["path"], 0.0)) <= SMOOTH_CURVATURE and np.linalg.norm(
                _orientation_rate(a) - _orientation_rate(b)) <= SMOOTH_ORIENTATION_RATE:
            continue  # tangent, curvature and orientation rate continuous: no blend needed
        r = min(a["zone"], 0.5 * a["path"].length, 0.5 * b["path"].length)
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
                                w_max * robot.length_scale, i, 0.0, "orientation speed"))
            continue
        a, b = trim0[i], path.length - trim1[i]
        frac0, frac1 = a / path.length, b / path.length
        qa = slerp(sp["quat0"], sp["quat1"], frac0)
        qb = slerp(sp["quat0"], sp["quat1"], frac1)
        cap, reason = v, ""
        if sp["angle"] > 0 and w_max * path.length / sp["angle"] < v:
            cap, reason = w_max * path.length / sp["angle"], "orientation speed"
        pieces.append(Piece("path", b - a, sub_path(path, a, b), qa, qb, cap, i, 1.0, reason, v))
        if i in blends:
            r = blends[i]
            nxt = specs[i + 1]
            pa = path.point(b)
            tang_a = path.tangent(b)
            pb = nxt["path"].point(r)
            tang_b = nxt["path"].tangent(r)
            qn = slerp(nxt["quat0"], nxt["quat1"], r / nxt["path"].length)
            bz = BezierBlend(pa, tang_a, pb, tang_b, r, ka=curvature_vector(path, b),
                             kb=curvature_vector(nxt["path"], r), corner=sp["p1"])
            cap_b = min(v, nxt["speed"])
            ori = blended_orientation(sp["quat0"], sp["quat1"], path.length, b,
                                      nxt["quat0"], nxt["quat1"], nxt["path"].length, r, bz.length)
            pieces.append(Piece("blend", bz.length, bz.point, qb, qn, cap_b, i, 1.0, "",
                                quat_fn=ori))
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


def _window_max(x: np.ndarray, w: int) -> np.ndarray:
    """Largest value of ``x`` (n, m) over rows i - w .. i + w, per row and column."""
    out = x.copy()
    for k in range(1, w + 1):
        out[k:] = np.maximum(out[k:], x[:-k])
        out[:-k] = np.maximum(out[:-k], x[k:])
    return out


def _run_accel_jerk(robot: RobotModel, d1: np.ndarray, d2: np.ndarray, d3: np.ndarray,
                    speed: float, amax: np.ndarray, jmax: np.ndarray) -> tuple[float, float]:
    """Path acceleration [m/s^2] and path jerk [m/s^3] of a run.

    Parameters
    ----------
    d1, d2, d3 : ndarray, shape (n_joints,)
        Largest |dq/ds| [/m], |d2q/ds2| [/m^2] and |d3q/ds3| [/m^3] of each
        joint over the run.
    speed : float
        The run's speed level [m/s] (the largest path speed inside the run).
    amax, jmax : ndarray, shape (n_joints,)
        Joint acceleration [/s^2] and jerk [/s^3] limits.

    Notes
    -----
    With ``rest = JERK_USE j_max - |d3q/ds3| v^3`` (>= (JERK_USE -
    JERK_CURVE_USE) j_max, as the speed caps keep the first term within
    JERK_CURVE_USE j_max), the acceleration ``a`` obeys ``|dq/ds| a <=
    ACC_PATH_USE a_max``, ``3 |d2q/ds2| v a <= JERK_ACC_SHARE rest`` and the
    tool's ``cartesian_accel``; the jerk ``j`` is the tool's ``cartesian_jerk``
    scaled like ``a``, and at most ``(rest - 3 |d2q/ds2| v a) / |dq/ds|``. So
    every joint's jerk stays within JERK_USE j_max wherever the speed is at
    most ``v`` (the feed's speed changes happen inside the faster run).
    """
    rest = np.maximum(JERK_USE * jmax - d3 * speed**3, (JERK_USE - JERK_CURVE_USE) * jmax)
    with np.errstate(divide="ignore", invalid="ignore"):
        acc = min(robot.cartesian_accel, float(np.min(ACC_PATH_USE * amax / d1)),
                  float(np.min(JERK_ACC_SHARE * rest / (3.0 * d2 * speed))))
        jerk = min(robot.cartesian_jerk * acc / robot.cartesian_accel,
                   float(np.min((rest - 3.0 * d2 * speed * acc) / d1)))
    return acc, jerk


def _refine_derivatives(robot, pieces, offsets, s, q, ddq, a1, a2, a3, jmax, top_speed):
    """Re-estimate |dq/ds|, |d2q/ds2|, |d3q/ds3| on a finer grid where the grid misses features.

    Near a singularity the joint path can bend within one grid cell: the
    third derivative from finite differences on the grid is then too small
    (measured: 15-25x near the palletizer's axis) and so would be its jerk
    cap. A cell is re-sampled :data:`REFINE_FACTOR` times finer (IK seeded
    from the cell's start) when the second derivative changes across it by
    more than :data:`REFINE_RTOL` of its size and the jerk cap could bind
    there even if the third derivative were :data:`REFINE_D3_FACTOR` times
    the grid's. The largest derivatives found in the cell raise its two
    nodes' values (never lower them).
    """
    h = np.diff(s)
    nj = q.shape[1]
    dd = np.abs(np.diff(ddq, axis=0))  # signed: a sign change of d2q/ds2 counts
    scale = np.maximum(np.abs(ddq[:-1]), np.abs(ddq[1:]))
    g3 = np.maximum(a3[:-1], a3[1:])
    with np.errstate(divide="ignore", invalid="ignore"):
        could_bind = np.cbrt(JERK_CURVE_USE * jmax[None, :] / (REFINE_D3_FACTOR * g3)) < top_speed
        sharp = dd > REFINE_RTOL * scale
    cells = np.nonzero(np.any(could_bind & sharp, axis=1))[0]
    # not the cells at the chain's ends: one-sided differences there are not
    # derivatives of the path (the path does not go on beyond its ends)
    cells = cells[(cells >= 3) & (cells <= h.size - 4)]
    if cells.size == 0:
        return a1, a2, a3
    a1, a2, a3 = a1.copy(), a2.copy(), a3.copy()
    total = float(offsets[-1])
    for c in cells:
        hf = h[c] / REFINE_FACTOR
        sf = s[c] + hf * np.arange(-3, REFINE_FACTOR + 4)
        if sf[0] < 0.0 or sf[-1] > total:  # pragma: no cover - cells near the ends are skipped
            continue
        kk = np.clip(np.searchsorted(offsets, sf, side="right") - 1, 0, len(pieces) - 1)
        pos = np.empty((sf.size, 3))
        quat = np.empty((sf.size, 4))
        for i in np.unique(kk):
            m = kk == i
            pos[m] = pieces[i].point(sf[m] - offsets[i])
            quat[m] = pieces[i].quat(sf[m] - offsets[i])
        rots = matrix_from_quat(quat)
        qf = np.empty((sf.size, nj))
        seed = q[c]
        try:
            for i in range(sf.size):
                seed = qf[i] = robot.ik_near(Pose.trusted(pos[i], rots[i]), seed)
        except UnreachableError:  # the grid itself was reachable: keep its estimate
            continue
        f1 = np.abs(np.gradient(qf, sf, axis=0))
        f2 = np.gradient(np.gradient(qf, sf, axis=0), sf, axis=0)
        f3 = np.abs(np.gradient(f2, sf, axis=0))
        # nested differences: the one-sided ends spoil 3 points on each side
        inner = slice(3, -3)
        for arr, f in ((a1, f1), (a2, np.abs(f2)), (a3, f3)):
            m = f[inner].max(axis=0)
            arr[c] = np.maximum(arr[c], m)
            arr[c + 1] = np.maximum(arr[c + 1], m)
    return a1, a2, a3


def plan_chain(robot: RobotModel, q0: np.ndarray, motions: Sequence[Any], labels: Sequence[str],
               motion_ids: Sequence[int]) -> CartesianChain:
    """Plan LIN/CIRC ``motions`` from joints ``q0`` as one chain (rest to rest).

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
    # ---- derivatives along the path
    dq = np.gradient(q, s, axis=0)
    ddq = np.gradient(dq, s, axis=0)
    dddq = np.gradient(ddq, s, axis=0)
    vmax = np.array([lim.v_max for lim in robot.limits])
    amax = np.array([min(lim.a_max, lim.a_max_decel) for lim in robot.limits])
    jmax = np.array([min(lim.j_max, lim.j_max_decel) for lim in robot.limits])
    a1, a2, a3 = _refine_derivatives(robot, pieces, offsets, s, q, ddq, np.abs(dq), np.abs(ddq),
                                     np.abs(dddq), jmax, float(max(p.cap for p in pieces)))
    d1, d2, d3 = (_window_max(x, DERIV_WINDOW) for x in (a1, a2, a3))
    with np.errstate(divide="ignore"):
        vel_cap = VEL_USE * vmax[None, :] / np.abs(dq)
        acc_cap = np.sqrt(ACC_CURVE_USE * amax[None, :] / np.abs(ddq))
        jerk_cap = np.cbrt(JERK_CURVE_USE * jmax[None, :] / d3)
        dpos = np.gradient(pos, s, axis=0)
        ddpos = np.gradient(dpos, s, axis=0)
        curv = np.linalg.norm(ddpos, axis=1)
        cart_cap = np.sqrt(CART_CURVE_USE * robot.cartesian_accel / curv)
    prog = np.array([pieces[i].cap for i in k])
    cand = np.column_stack([prog, vel_cap.min(axis=1), acc_cap.min(axis=1), cart_cap,
                            jerk_cap.min(axis=1)])
    node_cap = cand.min(axis=1)
    programmed = np.array([pieces[i].programmed for i in k])
    worst = int(np.argmin(node_cap / programmed))
    if node_cap[worst] < MIN_SPEED_FRACTION * programmed[worst]:
        jv = int(np.argmin(vel_cap[worst]))
        raise UnreachableError(
            f"{labels[mot[worst]]}: the path passes through a singularity at {_mm(pos[worst])} "
            f"that cannot be passed: joint {robot.joint_names[jv]} would need "
            f"{np.abs(dq[worst, jv]):.4g} rad per m of path, allowing only "
            f"{1e3 * node_cap[worst]:.4g} mm/s (< {100 * MIN_SPEED_FRACTION:g} % of the programmed "
            f"{1e3 * programmed[worst]:.4g} mm/s)"
        )
    # ---- runs: cells with quantised caps
    cell_cap = np.minimum(node_cap[:-1], node_cap[1:])
    cell_piece = k[:-1]
    cell_prog = np.array([pieces[i].cap for i in cell_piece])
    # a cell at the end of a piece also obeys the next piece's programmed cap
    cell_prog = np.minimum(cell_prog, np.array([pieces[i].cap for i in k[1:]]))
    # quantise strictly downwards: a level never exceeds its cell cap
    with np.errstate(divide="ignore"):
        steps = np.ceil(np.log(cell_cap / cell_prog) / math.log(LEVEL_RATIO))
    level_speed = np.where(cell_cap >= cell_prog, cell_prog, cell_prog * LEVEL_RATIO**steps)
    runs: list[Run] = []
    run_cells: list[tuple[int, int]] = []
    i0 = 0
    ncell = s.size - 1
    for c in range(1, ncell + 1):
        if c == ncell or level_speed[c] != level_speed[i0]:
            acc, jerk = _run_accel_jerk(robot, d1[i0:c + 1].max(axis=0), d2[i0:c + 1].max(axis=0),
                                        d3[i0:c + 1].max(axis=0), float(level_speed[i0]),
                                        amax, jmax)
            runs.append(Run(float(s[i0]), float(s[c]), float(level_speed[i0]), acc, jerk))
            run_cells.append((i0, c))
            i0 = c
    feed = plan_feed(runs)
    chain = CartesianChain(robot, pieces, offsets, s, q, dq, ddq, feed, labels,
                           list(motion_ids))
    # ---- slow-downs caused by limits (not by the programmed speed)
    last_cell = -1
    for run, (c0, c1) in zip(runs, run_cells):
        prog_run = float(np.min(programmed[c0:c1 + 1]))
        if run.cap >= prog_run * (1.0 - SLOWDOWN_RTOL):
            continue
        nodes = np.arange(c0, c1 + 1)
        j = nodes[int(np.argmin(node_cap[nodes]))]
        col = int(np.argmin(cand[j]))
        if col == 0:
            reason = pieces[k[j]].cap_reason or "programmed speed"
        elif col == 1:
            reason = f"velocity of joint {robot.joint_names[int(np.argmin(vel_cap[j]))]}"
        elif col == 2:
            reason = f"acceleration of joint {robot.joint_names[int(np.argmin(acc_cap[j]))]}"
        elif col == 3:
            reason = "path curvature (tool acceleration)"
        else:
            reason = f"jerk of joint {robot.joint_names[int(np.argmin(jerk_cap[j]))]}"
        mi = int(mot[j])
        if (chain.slowdowns and chain.slowdowns[-1].motion == mi and last_cell == c0
                and chain.slowdowns[-1].reason == reason):
            sd = chain.slowdowns[-1]
            sd.end_xyz = pos[c1]
            sd.speed = min(sd.speed, run.speed)
            last_cell = c1
            continue
        last_cell = c1
        chain.slowdowns.append(Slowdown(mi, labels[mi], pos[c0], pos[c1], run.speed,
                                        float(programmed[j]), reason))
    return chain
