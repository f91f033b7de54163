"""The joint path of a Cartesian chain, ``q(s)`` by inverse kinematics, with its derivatives.

The chain's pieces (lines, arcs, corner blends, orientation-only turns) give
the tool pose at every path parameter ``s``; the joints are the inverse
kinematics of that pose, on the branch the chain started on (each solution
seeded from a table of joints walked along the path).

The tool pose's own derivatives at a point are in closed form: the
positions' on lines, arcs, corner blends and turns on the spot, the
orientations' of every slerp (a constant rate about an axis fixed in the
tool frame: lines, arcs, turns) and of a corner blend's cross-fade of two
slerps (by Taylor series through its formula, :mod:`._orient_jets`). A
piece without them would get differences of its closed-form poses on a
small stencil (step :data:`STENCIL_STEP` times the robot's length scale)
inside the piece, never across a junction of two pieces (a one-sided
stencil there).

A robot that offers its forward kinematics on Taylor series (``fk_jet``, see
:mod:`trajkit.kinematics._jets`) gets the joints' derivatives from the
kinematics: one inverse kinematics per point, then the joints' Taylor
coefficients order by order through the Jacobian and the exact higher-order
terms of the forward kinematics. An arm with one redundant joint (7 joints)
has its null-space motion from the seeds: its joints keep
``c . (q - seeds) = 0``, with ``c`` the Jacobian's null direction at the
walked joints, interpolated as the seeds are (a spline through them). That
is the seventh equation of the inverse kinematics (Newton steps from the
seeded solution, which already lies on it to round-off where the seeds lie
on the path) and of every Taylor order. Another robot (more redundant
joints, or no ``fk_jet``) gets central
differences of the inverse kinematics along the tool pose's cubic Taylor
polynomial at the point: the joints along it have the path's first three
derivatives, and the stencil's truncation error comes from the kinematics
alone, not from the path's higher derivatives (a tight corner blend's change
over micrometres). A point where the Jacobian is singular (a stretched arm)
gets differences of the inverse kinematics on the path itself.
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from ..errors import UnreachableError
from ..kinematics import _jets
from ..kinematics.base import Pose, RobotModel
from ._rotations import matrix_from_quat

__all__ = ["ChainJointPath", "STENCIL_STEP"]

#: Step of the derivative stencils, as a fraction of the robot's length scale.
STENCIL_STEP = 1e-4

#: ... and, for the differences of the inverse kinematics on the path at a
#: singular point, at most this fraction of the radius of the piece's tightest
#: curvature: their truncation error goes with the fourth power of the step over
#: that radius (the joints' third derivative in a corner blend of 0.76 mm
#: radius: 0.6 % off at an eighth of it, within 2e-5 at a fiftieth, where the
#: round-off over the cube of the step is not yet felt; at a hundredth it is).
FEATURE_STEP = 0.02

#: At a singular configuration, the path's rate (tool velocity and angular
#: velocity per path unit) must lie in the range of the Jacobian to this
#: relative residual, else the joints cannot follow the path there.
FOLLOW_RTOL = 1e-6

# central (offsets -3..3) and one-sided forward (offsets 0..6) weights, order
# 6 and 5 in the step, for the 1st, 2nd and 3rd derivative
_CENTRAL = (
    np.array([-1.0, 9.0, -45.0, 0.0, 45.0, -9.0, 1.0]) / 60.0,
    np.array([2.0, -27.0, 270.0, -490.0, 270.0, -27.0, 2.0]) / 180.0,
    np.array([1.0, -8.0, 13.0, 0.0, -13.0, 8.0, -1.0]) / 8.0,
)
_FORWARD = (
    np.array([-147.0, 360.0, -450.0, 400.0, -225.0, 72.0, -10.0]) / 60.0,
    np.array([812.0, -3132.0, 5265.0, -5080.0, 2970.0, -972.0, 137.0]) / 180.0,
    np.array([-49.0, 232.0, -461.0, 496.0, -307.0, 104.0, -15.0]) / 8.0,
)


class ChainJointPath:
    """``q(s)`` of a chain of pieces (a :class:`trajkit.timing.JointPath`).

    Parameters
    ----------
    robot : RobotModel
    pieces : list of Piece
    offsets : ndarray, shape (k + 1,)
        Start of every piece in ``s``, then the total length.
    table_s, table_q : ndarray, shapes (n,), (n, m)
        Joints along the path (the walked branch) used to seed the inverse kinematics.
    labels : list of str
        Instruction labels (for messages), indexed by the pieces' ``motion``.
    """

    def __init__(self, robot: RobotModel, pieces: list, offsets: np.ndarray, table_s: np.ndarray,
                 table_q: np.ndarray, labels: list) -> None:
        self.robot = robot
        self.pieces = pieces
        self.offsets = np.asarray(offsets, dtype=float)
        self.length = float(self.offsets[-1])
        self.n_joints = robot.n_joints
        self.breakpoints = self.offsets[1:-1].copy()
        self.table_s = table_s
        self.table_q = table_q
        self.labels = labels
        self.h = STENCIL_STEP * float(robot.length_scale)
        self._features = np.array([getattr(p, "feature", np.inf) for p in pieces], dtype=float)
        self._fk_jet = self._jet_kinematics(robot)
        # seeds from a quintic spline through the walked joints: for a redundant arm
        # the inverse kinematics keeps the seed's null-space part, so the path is as
        # smooth as its seeds (a linear interpolation would put kinks in it)
        from scipy.interpolate import make_interp_spline

        k = min(5, table_s.size - 1)
        self._seed = make_interp_spline(table_s, table_q, k=k) if k >= 1 else None
        # one redundant joint: the direction of the Jacobian's null space along the
        # walked joints, as a spline of the same kind (see _null_direction)
        self._null = None
        if self._fk_jet is not None and self.n_joints == 7:
            self._null = self._null_direction(k) if k >= 3 else None
            if self._null is None:
                self._fk_jet = None

    # ---- geometry
    def piece_of(self, s: np.ndarray, side: Literal["left", "right"] = "right") -> np.ndarray:
        k = np.searchsorted(self.offsets, s, side=side) - 1
        return np.clip(k, 0, len(self.pieces) - 1)

    def poses(self, s: np.ndarray, k: np.ndarray):
        """Positions (n, 3) and rotation matrices (n, 3, 3) at ``s`` on pieces ``k``."""
        pos = np.empty((s.size, 3))
        quat = np.empty((s.size, 4))
        for i in np.unique(k):
            m = k == i
            loc = s[m] - self.offsets[i]
            pos[m] = self.pieces[i].point(loc)
            quat[m] = self.pieces[i].quat(loc)
        return pos, matrix_from_quat(quat)

    def seeds(self, s: np.ndarray) -> np.ndarray:
        if self._seed is None:
            return np.broadcast_to(self.table_q[0], (np.size(s), self.n_joints)).copy()
        return self._seed(np.clip(s, self.table_s[0], self.table_s[-1]))

    def ik(self, s: np.ndarray, k: np.ndarray, seeds: np.ndarray) -> np.ndarray:
        """The path's joints (n, m) at ``s`` (n,) on pieces ``k`` (n,), the inverse
        kinematics started from ``seeds`` (n, m) (a redundant arm's then resolved
        as the path resolves it)."""
        pos, rot = self.poses(s, k)
        return self._ik_at(pos, rot, k, seeds, s)

    def joints(self, s: np.ndarray) -> np.ndarray:
        """The path's joints (n, m) at ``s`` (n,) [path unit]."""
        s = np.clip(np.atleast_1d(np.asarray(s, dtype=np.float64)), 0.0, self.length)
        return self.ik(s, self.piece_of(s), self.seeds(s))

    def _null_direction(self, k: int):
        """Spline of degree ``k`` through the unit null vectors of the Jacobian at the
        walked joints (one sign along the path), or None where the table has a
        singular point (a null space of more than one dimension)."""
        from scipy.interpolate import make_interp_spline

        many = getattr(self.robot, "jacobian_many", None)
        jac = many(self.table_q) if many is not None else _jets.jacobian(self._fk_jet, self.table_q)
        _u, sv, vt = np.linalg.svd(jac)
        if not (sv[:, -1] * _jets.COND_MAX > sv[:, 0]).all():
            return None
        c = vt[:, -1, :]
        sign = np.cumprod(np.where(np.einsum("ij,ij->i", c[1:], c[:-1]) < 0.0, -1.0, 1.0))
        c[1:] *= sign[:, None]
        return make_interp_spline(self.table_s, c, k=k)

    def _resolution(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Taylor coefficients (n, 4, m) of the direction ``c`` and of the seeds along
        the path at ``s`` (n,): a redundant arm's joints keep ``c . (q - seeds) = 0``."""
        assert self._null is not None and self._seed is not None
        at = np.clip(s, self.table_s[0], self.table_s[-1])
        fact = (1.0, 1.0, 2.0, 6.0)
        cj = np.stack([self._null(at, nu) / fact[nu] for nu in range(_jets.ORDER + 1)], axis=1)
        sj = np.stack([self._seed(at, nu) / fact[nu] for nu in range(_jets.ORDER + 1)], axis=1)
        return cj, sj

    def _project(self, pos: np.ndarray, rot: np.ndarray, s: np.ndarray, q: np.ndarray) -> np.ndarray:
        """A redundant arm's joints at the poses ``pos`` (n, 3), ``rot`` (n, 3, 3) of
        ``s`` (n,): Newton steps from ``q`` (n, m) (the inverse kinematics from the
        seeds) onto ``c . (q - seeds) = 0``, the seeds' part along the null
        direction (a point where they do not converge keeps ``q``)."""
        at = np.clip(s, self.table_s[0], self.table_s[-1])
        assert self._null is not None and self._seed is not None
        c, sig = self._null(at), self._seed(at)
        many = getattr(self.robot, "ik_project_many", None)
        got = None if many is None else many(pos, rot, q, c, sig)
        if got is None:
            got = _jets.project(self._fk_jet, pos, rot, q, c, sig)
        return got[0]

    def _solve(self, pos: np.ndarray, rot: np.ndarray, k: np.ndarray, seeds: np.ndarray) -> np.ndarray:
        """IK of the poses ``pos`` (n, 3), ``rot`` (n, 3, 3) on pieces ``k`` from ``seeds``
        (n, m), one by one."""
        out = np.empty((pos.shape[0], self.n_joints))
        ik_near = self.robot.ik_near
        trusted = Pose.trusted
        for i in range(pos.shape[0]):
            try:
                out[i] = ik_near(trusted(pos[i], rot[i]), seeds[i])
            except UnreachableError as exc:
                lab = self.labels[self.pieces[int(k[i])].motion]
                p = pos[i]
                raise UnreachableError(
                    f"{lab}: point ({1e3 * p[0]:.3f}, {1e3 * p[1]:.3f}, {1e3 * p[2]:.3f}) mm "
                    f"of the path is unreachable: {exc}") from None
        return out

    def _ik_at(self, pos: np.ndarray, rot: np.ndarray, k: np.ndarray, seeds: np.ndarray,
               s: np.ndarray | None = None) -> np.ndarray:
        """IK of the poses ``pos`` (n, 3), ``rot`` (n, 3, 3) on pieces ``k`` (n,) from
        ``seeds`` (n, m), all at once where the robot offers it (``ik_near_many``);
        with the poses' path parameters ``s`` (n,), a redundant arm's joints are
        then resolved as the path resolves them (:meth:`_project`)."""
        many = getattr(self.robot, "ik_near_many", None)
        if many is None:
            q = self._solve(pos, rot, k, seeds)
        else:
            q, ok = many(pos, rot, seeds)
            if not ok.all():  # raises at the first failure, with the robot's message
                q[~ok] = self._solve(pos[~ok], rot[~ok], k[~ok], seeds[~ok])
        if s is not None and self._null is not None:
            q = self._project(pos, rot, s, q)
        return q

    def _stencil_ik(self, pts: np.ndarray, k: np.ndarray) -> np.ndarray:
        """Joints (n, 7, m) at the stencil points ``pts`` (n, 7) on pieces ``k`` (n,), each
        seeded from the walked branch."""
        n = pts.shape[0]
        kk = np.repeat(k, 7)
        flat = pts.ravel()
        pos, rot = self.poses(flat, kk)
        at = np.clip(flat, 0.0, self.length)
        return self._ik_at(pos, rot, kk, self.seeds(at), at).reshape(n, 7, self.n_joints)

    @staticmethod
    def _jet_kinematics(robot: RobotModel):
        """The robot's ``fk_jet`` when it covers this robot (at most one redundant
        joint, chain supported)."""
        fk_jet = getattr(robot, "fk_jet", None)
        if fk_jet is None or robot.n_joints > 7:
            return None
        probe = np.zeros((1, _jets.ORDER + 1, robot.n_joints))
        return fk_jet if fk_jet(probe) is not None else None

    def _stencil(self, s: np.ndarray, h: float, tight: bool = True):
        """7-point stencils at ``s`` (n,) of step ``h`` (or less) inside each point's piece
        (``tight``: at most :data:`FEATURE_STEP` of the piece's tightest radius).

        Returns the stencil points (n, 7), the pieces (n,), the local steps (n,),
        the forward / backward masks (n,) and the index of ``s`` in each stencil."""
        k = self.piece_of(s)
        lo = self.offsets[k]
        hi = self.offsets[k + 1]
        # a one-sided stencil (6 steps) starts within 3 steps of an end: 9 steps fit;
        # a tight curve gets its steps from its radius
        hk = np.minimum(h, (hi - lo) / 9.0)
        if tight:
            hk = np.minimum(hk, FEATURE_STEP * self._features[k])
        # stencil direction: central where it fits inside the piece, one-sided otherwise
        fwd = s - 3 * hk < lo
        bwd = ~fwd & (s + 3 * hk > hi)
        off = np.arange(-3, 4)
        pts = np.where(fwd[:, None], s[:, None] + hk[:, None] * (off + 3),
                       np.where(bwd[:, None], s[:, None] - hk[:, None] * (off + 3),
                                s[:, None] + hk[:, None] * off))
        centre = np.where(fwd | bwd, 0, 3)
        return pts, k, hk, fwd, bwd, centre

    @staticmethod
    def _differences(vals: np.ndarray, hk: np.ndarray, fwd: np.ndarray, bwd: np.ndarray) -> list:
        """First, second and third derivatives (each (n, ...)) from stencil values (n, 7, ...)."""
        out = []
        shape = (-1,) + (1,) * (vals.ndim - 2)
        for order in range(3):
            cen = np.tensordot(vals, _CENTRAL[order], axes=([1], [0]))
            one = np.tensordot(vals, _FORWARD[order], axes=([1], [0]))
            sign_b = (-1.0) ** (order + 1)  # backward stencil: mirrored offsets
            val = np.where(fwd.reshape(shape), one, np.where(bwd.reshape(shape), sign_b * one, cen))
            out.append(val / hk.reshape(shape) ** (order + 1))
        return out

    def _check_followable(self, idx: np.ndarray, q: np.ndarray, pj: np.ndarray, rj: np.ndarray,
                          k: np.ndarray) -> None:
        """Raise where the path leaves a singular configuration ``q[idx]`` in a direction
        outside the range of the Jacobian: the joints' speed would be unbounded there
        (e.g. a SCARA or an elbow stretched and the tool moving along the arm)."""
        jac = _jets.jacobian(self._fk_jet, q[idx])
        rate = np.concatenate([pj[idx, 1], _jets.vee(rj[idx, 1] @ np.swapaxes(rj[idx, 0], -1, -2))],
                              axis=1)
        for i, row in enumerate(idx):
            x = np.linalg.lstsq(jac[i], rate[i], rcond=None)[0]
            miss = float(np.linalg.norm(jac[i] @ x - rate[i]))
            if miss > FOLLOW_RTOL * max(float(np.linalg.norm(rate[i])), 1e-300):
                p = pj[row, 0]
                lab = self.labels[self.pieces[int(k[row])].motion]
                raise UnreachableError(
                    f"{lab}: the path meets a singularity of {self.robot.name} at "
                    f"({1e3 * p[0]:.3f}, {1e3 * p[1]:.3f}, {1e3 * p[2]:.3f}) mm in a direction the "
                    "joints cannot follow (their speed would be unbounded): move the point off "
                    "the singularity or use PTP")

    # ---- the JointPath protocol
    def derivatives(self, s: np.ndarray):
        s = np.clip(np.atleast_1d(np.asarray(s, dtype=np.float64)), 0.0, self.length)
        if self._fk_jet is not None:
            return self._jet_derivatives(s)
        return self._taylor_differences(s)

    def _pose_taylor(self, s: np.ndarray):
        """Taylor coefficients 0..3 of the tool pose along the path at ``s`` (n,): the
        pieces ``k`` (n,), positions (n, 4, 3) and rotations (n, 4, 3, 3). In
        closed form where the piece has them (every piece of a chain: lines, arcs,
        corner blends and orientation-only turns); else by differences of the
        closed-form poses on stencils of :data:`STENCIL_STEP` (they turn over the
        piece's length)."""
        n = s.size
        k = self.piece_of(s)
        pj = np.empty((n, _jets.ORDER + 1, 3))
        rj = np.empty((n, _jets.ORDER + 1, 3, 3))
        pos_done = np.zeros(n, dtype=bool)
        rot_done = np.zeros(n, dtype=bool)
        which = np.unique(k)
        for i in which:
            sel = slice(None) if which.size == 1 else np.flatnonzero(k == i)
            loc = s[sel] - self.offsets[i]
            got = self.pieces[i].derivatives(loc)
            if got is not None:
                pj[sel] = np.stack([got[0], got[1], 0.5 * got[2], got[3] / 6.0], axis=1)
                pos_done[sel] = True
            rot = self.pieces[i].rotation_taylor(loc)
            if rot is not None:
                rj[sel] = rot
                rot_done[sel] = True
        rest = np.flatnonzero(~(pos_done & rot_done))
        if rest.size:
            m = rest.size
            pts, kk, hk, fwd, bwd, centre = self._stencil(s[rest], self.h, tight=False)
            pos, rot = self.poses(pts.ravel(), np.repeat(kk, 7))
            pos = pos.reshape(m, 7, 3)
            rot = rot.reshape(m, 7, 3, 3)
            rows = np.arange(m)
            fd_p = np.empty((m, _jets.ORDER + 1, 3))
            fd_r = np.empty((m, _jets.ORDER + 1, 3, 3))
            fd_p[:, 0] = pos[rows, centre]
            fd_r[:, 0] = rot[rows, centre]
            fact = 1.0
            for order, (dp, dr) in enumerate(zip(self._differences(pos, hk, fwd, bwd),
                                                 self._differences(rot, hk, fwd, bwd)), start=1):
                fact *= order
                fd_p[:, order] = dp / fact
                fd_r[:, order] = dr / fact
            keep_p = ~pos_done[rest]
            keep_r = ~rot_done[rest]
            pj[rest[keep_p]] = fd_p[keep_p]
            rj[rest[keep_r]] = fd_r[keep_r]
        return k, pj, rj

    def _taylor_differences(self, s: np.ndarray):
        """``q`` and its first three derivatives at ``s`` (n,) by differences of the
        inverse kinematics along the tool pose's cubic Taylor polynomial at each
        point (central 7-point stencils; the rotations made orthonormal, which
        changes them at fourth order only). The polynomial has the path's first three
        derivatives, so the joints along it have the path's too, while its own
        higher derivatives vanish: the stencil's truncation error comes from the
        kinematics alone, not from a tight blend's rapidly changing curvature."""
        n = s.size
        k, pj, rj = self._pose_taylor(s)
        # (the polynomial is not bound to the piece: the full step everywhere)
        hk = np.full(n, self.h)
        e = hk[:, None] * np.arange(-3.0, 4.0)[None, :]  # (n, 7)
        powers = np.stack([np.ones_like(e), e, e * e, e * e * e], axis=-1)  # (n, 7, 4)
        pos = np.einsum("nso,nod->nsd", powers, pj)
        rot = np.einsum("nso,nodc->nsdc", powers, rj)
        # one Newton-Schulz step to the nearest rotation (the polynomial leaves SO(3) at
        # fourth order in the step only; the step squares that)
        rot = 0.5 * rot @ (3.0 * np.eye(3) - np.swapaxes(rot, -1, -2) @ rot)
        # (the seeds' spline continued past the path's ends: a redundant arm's
        # null-space motion comes from them, and a clipped seed would kink it)
        at = (s[:, None] + e).ravel()
        seeds = self.seeds(at) if self._seed is None else self._seed(at)
        kk = np.repeat(k, 7)
        q_all = self._ik_at(pos.reshape(-1, 3), rot.reshape(-1, 3, 3), kk, seeds).reshape(n, 7, -1)
        none = np.zeros(n, dtype=bool)
        d = self._differences(q_all, hk, none, none)
        return q_all[:, 3], d[0], d[1], d[2]

    def _jet_derivatives(self, s: np.ndarray):
        k, pj, rj = self._pose_taylor(s)
        q = self._ik_at(pj[:, 0], rj[:, 0], k, self.seeds(s), s)
        null = None if self._null is None else self._resolution(s)
        compiled = getattr(self.robot, "joint_taylor_many", None)
        got = None if compiled is None else (compiled(q, pj, rj) if null is None
                                              else compiled(q, pj, rj, null))
        if got is None:
            many = getattr(self.robot, "jacobian_many", None)
            got = _jets.joint_taylor(self._fk_jet, q, pj, rj, None if many is None else many(q), null)
        qj, singular = got
        d1, d2, d3 = qj[:, 1], 2.0 * qj[:, 2], 6.0 * qj[:, 3]
        if singular.any():  # on a singularity: differences of the inverse kinematics there
            self._check_followable(np.flatnonzero(singular), q, pj, rj, k)
            pts, kk, hk, fwd, bwd, _ = self._stencil(s[singular], self.h)
            d = self._differences(self._stencil_ik(pts, kk), hk, fwd, bwd)
            d1[singular], d2[singular], d3[singular] = d
        return q, d1, d2, d3
