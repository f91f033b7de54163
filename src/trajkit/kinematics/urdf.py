"""Robots from a URDF file, through pinocchio (PyPI package ``pin``).

Pinocchio parses the URDF and computes forward kinematics and frame
Jacobians; trajkit adds a damped least-squares inverse kinematics seeded
from the previous sample (so a Cartesian path stays on one branch), the
joint limits and the :class:`~trajkit.kinematics.base.RobotModel` interface.

``pin`` is an optional dependency (``pip install pin``); importing this
module without it raises an :class:`ImportError` that says so.

URDF gives joint ranges and velocity limits but no acceleration or jerk
limits: they default to ``accel_factor * v_max`` and ``jerk_factor *
a_max`` (overridable per joint with ``limits=``).
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from typing import Any, cast

import numpy as np
from scipy.linalg.lapack import dposv as _dposv

from .._validate import check_array, check_positive
from ..errors import InvalidInputError, UnreachableError
from ..limits import AxisLimits
from . import _chain_jit, _jets
from .base import PRISMATIC, REVOLUTE, Pose, RobotModel, _fmt_xyz

try:  # pragma: no cover - depends on the install
    import pinocchio as _pin
except ImportError as exc:  # pragma: no cover
    raise ImportError("URDF robots need pinocchio: pip install pin") from exc

__all__ = ["UrdfRobot", "URDF_CONFIG"]

#: The single configuration label of a numerically solved URDF robot.
URDF_CONFIG = "numeric"

#: IK converges when the pose error (position [m] / length scale, and angle
#: [rad]) is below this.
IK_TOL = 1e-12

#: Iterations of the damped least-squares IK per seed.
IK_MAX_ITER = 200

#: Damping of the least-squares step (squared, relative to 1).
IK_DAMPING = 1e-10

#: :meth:`UrdfRobot.ik_near_many` steps the poses whose seed's pose error is below
#: this together (the error to first order is then exact to its square) ...
IK_BATCH_ENTRY = 1e-6

#: ... for at most this many steps (the rest one by one).
IK_BATCH_ITER = 6

#: Largest joint step per IK iteration [rad or m] (keeps Newton local).
IK_MAX_STEP = 0.5

#: Number of deterministic extra seeds tried by :meth:`UrdfRobot.ik_all`.
IK_ALL_SEEDS = 24

#: Two numeric solutions closer than this in every joint are the same [rad or m].
IK_DISTINCT_TOL = 1e-6

#: Smallest length scale [m] assumed for a URDF robot (relative tolerances).
MIN_LENGTH_SCALE = 1e-3

#: Per joint of the chain: parent joint, configuration index, placement in the
#: parent (rotation, translation), unit axis, revolute (else prismatic).
_Chain = list[tuple[int, int, np.ndarray, np.ndarray, np.ndarray, bool]]

_KINDS = {
    "JointModelRX": REVOLUTE, "JointModelRY": REVOLUTE, "JointModelRZ": REVOLUTE,
    "JointModelRevoluteUnaligned": REVOLUTE,
    "JointModelPX": PRISMATIC, "JointModelPY": PRISMATIC, "JointModelPZ": PRISMATIC,
    "JointModelPrismaticUnaligned": PRISMATIC,
}


class UrdfRobot(RobotModel):
    """A serial robot read from a URDF file.

    Parameters
    ----------
    path : str or PathLike
        URDF file.
    tip_link : str
        Name of the tool link (or any frame) whose pose is the tool pose. Only
        the joints of the chain from the base to it are the robot's joints;
        any other joint (a gripper's fingers) is locked at its neutral position.
    accel_factor, jerk_factor : float
        Default a_max = accel_factor * v_max [1/s], j_max = jerk_factor *
        a_max [1/s] for joints whose limits are not given.
    limits : sequence of AxisLimits, optional
        Per-joint limits overriding the URDF (ranges included).
    name : str, optional
        Model name (default: the URDF robot name).

    Raises
    ------
    InvalidInputError
        A missing file or link, a joint type other than revolute/prismatic
        (continuous, floating, planar joints are not supported), a joint
        without range or velocity limit.
    """

    configs = (URDF_CONFIG,)

    def __init__(self, path: str | os.PathLike, tip_link: str, accel_factor: float = 4.0,
                 jerk_factor: float = 10.0, limits: Sequence[AxisLimits] | None = None,
                 name: str | None = None) -> None:
        path = os.fspath(path)
        if not os.path.isfile(path):
            raise InvalidInputError(f"URDF file {path!r} does not exist")
        try:
            model = _pin.buildModelFromUrdf(path)
        except Exception as exc:  # pinocchio raises plain RuntimeError/ValueError
            raise InvalidInputError(f"cannot read URDF {path!r}: {exc}") from None
        if not model.existFrame(tip_link):
            raise InvalidInputError(f"URDF {path!r} has no link named {tip_link!r}")
        # joints that do not move the tip (a gripper's fingers, other branches) are
        # locked at their neutral position: the robot is the chain to the tip
        support = set(model.supports[model.frames[model.getFrameId(tip_link)].parentJoint])
        lock = [j for j in range(1, model.njoints) if j not in support]
        if lock:
            model = _pin.buildReducedModel(model, lock, _pin.neutral(model))
        af = check_positive(accel_factor, "accel_factor")
        jf = check_positive(jerk_factor, "jerk_factor")
        self.model = model
        self.data = model.createData()
        self.frame_id = model.getFrameId(tip_link)
        self.tip_link = tip_link
        self.path = path
        self.name = name or model.name
        names, kinds = [], []
        for i in range(1, model.njoints):
            short = model.joints[i].shortname()
            if short not in _KINDS or model.joints[i].nq != 1:
                raise InvalidInputError(
                    f"joint {model.names[i]!r} of {path!r} has type {short}; only revolute and "
                    "prismatic joints with finite ranges are supported"
                )
            names.append(model.names[i])
            kinds.append(_KINDS[short])
        self.joint_names = tuple(names)
        self.joint_kinds = tuple(kinds)
        lims: list[AxisLimits]
        if limits is not None:
            lims = list(limits)
            if len(lims) != len(names):
                raise InvalidInputError(f"limits has {len(lims)} entries, the URDF has {len(names)} joints")
        else:
            lims = []
            for k, nm in enumerate(names):
                lo, hi = float(model.lowerPositionLimit[k]), float(model.upperPositionLimit[k])
                v = float(model.velocityLimit[k])
                if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
                    raise InvalidInputError(f"joint {nm!r} of {path!r} has no valid range [{lo}, {hi}]")
                if not (math.isfinite(v) and v > 0):
                    raise InvalidInputError(f"joint {nm!r} of {path!r} has no velocity limit (got {v})")
                lims.append(AxisLimits(v, af * v, jf * af * v, position_min=lo, position_max=hi))
        self.limits = tuple(lim.with_name(n) for lim, n in zip(lims, names))
        self.length_scale = self._reach_estimate()

    def _reach_estimate(self) -> float:
        mid = 0.5 * (self.joint_ranges[:, 0] + self.joint_ranges[:, 1])
        _pin.framesForwardKinematics(self.model, self.data, mid)
        total = 0.0
        for i in range(1, self.model.njoints):
            total += float(np.linalg.norm(self.model.jointPlacements[i].translation))
        total += float(np.linalg.norm(self.model.frames[self.frame_id].placement.translation))
        return max(total, MIN_LENGTH_SCALE)

    def fk(self, q: Any) -> Pose:
        """Tool pose of joints ``q`` (n_joints,) [rad or m]."""
        qq = check_array(q, "joints", ndim=1, size=self.n_joints)
        _pin.framesForwardKinematics(self.model, self.data, qq)
        m = self.data.oMf[self.frame_id]
        return Pose(np.array(m.translation), np.array(m.rotation))

    def config_of(self, q: Any) -> str:
        """Always :data:`URDF_CONFIG` (numeric IK follows its seed)."""
        return URDF_CONFIG

    def _ik_constants(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Joint ranges (lower, upper), the pose error's row scale and the damping matrix
        of the IK, computed once per set of limits and length scale."""
        key = (self.limits, float(self.length_scale))
        cached = getattr(self, "_ik_cache", None)
        if cached is None or cached[0] is not key[0] or cached[1] != key[1]:
            rng = self.joint_ranges
            scale = np.array([1.0 / key[1]] * 3 + [1.0] * 3)
            cached = (key[0], key[1], (np.ascontiguousarray(rng[:, 0]), np.ascontiguousarray(rng[:, 1]),
                                       scale, IK_DAMPING * np.eye(6)))
            self._ik_cache = cached
        return cached[2]

    def _solve_from(self, pose: Pose, seed: np.ndarray) -> np.ndarray | None:
        target = _pin.SE3(pose.rotation, pose.position)
        q = np.array(seed, dtype=np.float64)
        lo, hi, scale, damping = self._ik_constants()
        model, data, fid = self.model, self.data, self.frame_id
        local = _pin.ReferenceFrame.LOCAL
        col = scale[:, None]
        polish = False
        for _ in range(IK_MAX_ITER):
            # one pass: placements and joint Jacobians, then the tool frame's
            _pin.computeJointJacobians(model, data, q)
            cur = _pin.updateFramePlacement(model, data, fid)
            es = _pin.log6(cur.actInv(target)).vector  # in the tool frame
            es *= scale
            if float(np.abs(es).max()) < IK_TOL:
                if polish:
                    return q
                # one more Newton step: the error is squared, far below IK_TOL, so
                # neighbouring solutions along a path differ by round-off only (their
                # differences are the joint path's derivatives)
                polish = True
            js = _pin.getFrameJacobian(model, data, fid, local)
            js *= col
            # damped least squares: dq = js^T (js js^T + damping)^-1 es (Cholesky)
            _, y, info = _dposv(js @ js.T + damping, es)
            if info != 0:
                y = np.linalg.lstsq(js @ js.T + damping, es, rcond=None)[0]
            dq = js.T @ y
            step = float(np.abs(dq).max())
            if step > IK_MAX_STEP:
                dq *= IK_MAX_STEP / step
            q += dq
            np.clip(q, lo, hi, out=q)
            if polish:
                return q
        return None

    def _chain(self) -> _Chain | None:
        """The kinematic chain for the vectorised forward kinematics: per joint its
        parent, configuration index, placement (rotation, translation) in the parent
        and unit axis, and whether it is revolute; None when a joint is not one of
        the axis-aligned or unaligned revolute/prismatic kinds."""
        if "_chain_cache" in self.__dict__:
            return cast("_Chain | None", self.__dict__["_chain_cache"])
        axes = {"X": np.array([1.0, 0.0, 0.0]), "Y": np.array([0.0, 1.0, 0.0]),
                "Z": np.array([0.0, 0.0, 1.0])}
        chain: _Chain | None = []
        model = self.model
        for i in range(1, model.njoints):
            short = model.joints[i].shortname()
            if short[-2:] in ("RX", "RY", "RZ", "PX", "PY", "PZ"):
                axis = axes[short[-1]]
            else:
                axis = np.asarray(getattr(model.joints[i].extract(), "axis", np.zeros(3)), dtype=float)
                if not (axis.shape == (3,) and abs(float(np.linalg.norm(axis)) - 1.0) < 1e-12):
                    chain = None
                    break
            place = model.jointPlacements[i]
            assert chain is not None
            chain.append((int(model.parents[i]), int(model.joints[i].idx_q), np.array(place.rotation),
                          np.array(place.translation), axis, _KINDS[short] == REVOLUTE))
        self._chain_cache = chain
        return chain

    def _fk_jacobian_many(self, q: np.ndarray):
        """Tool poses and tool-frame (LOCAL) Jacobians of many joint vectors at once.

        Parameters
        ----------
        q : ndarray, shape (n, n_joints)

        Returns
        -------
        pos : ndarray, shape (n, 3)
            Tool positions [m].
        rot : ndarray, shape (n, 3, 3)
        jac : ndarray, shape (n, 6, n_joints)
            Linear (rows 0-2, [m per rad or m/m]) and angular (rows 3-5) velocity of
            the tool frame per joint velocity, in the tool frame (pinocchio's LOCAL).
        """
        chain = self._chain()
        assert chain is not None
        n = q.shape[0]
        rots = [np.broadcast_to(np.eye(3), (n, 3, 3))]
        poss = [np.zeros((n, 3))]
        world_axes = []
        for parent, iq, r_pl, t_pl, axis, revolute in chain:
            r_par, p_par = rots[parent], poss[parent]
            r_j = r_par @ r_pl  # (n, 3, 3)
            p_j = p_par + r_par @ t_pl
            qi = q[:, iq]
            if revolute:
                c, s = np.cos(qi), np.sin(qi)
                k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]],
                              [-axis[1], axis[0], 0.0]])
                motion = (np.eye(3) + s[:, None, None] * k
                          + (1.0 - c)[:, None, None] * (k @ k))  # Rodrigues
                r_i = r_j @ motion
                p_i = p_j
            else:
                r_i = r_j
                p_i = p_j + (r_j @ axis) * qi[:, None]
            world_axes.append((r_j @ axis, p_i, revolute))
            rots.append(r_i)
            poss.append(p_i)
        frame = self.model.frames[self.frame_id]
        r_par, p_par = rots[int(frame.parentJoint)], poss[int(frame.parentJoint)]
        rot = r_par @ np.array(frame.placement.rotation)
        pos = p_par + r_par @ np.array(frame.placement.translation)
        jw = np.zeros((n, 6, self.n_joints))
        for (_parent, iq, *_rest), (w, p_i, revolute) in zip(chain, world_axes):
            if revolute:
                jw[:, :3, iq] = np.cross(w, pos - p_i)
                jw[:, 3:, iq] = w
            else:
                jw[:, :3, iq] = w
        rt = np.swapaxes(rot, 1, 2)
        jac = np.concatenate([rt @ jw[:, :3], rt @ jw[:, 3:]], axis=1)
        return pos, rot, jac

    def jacobian_many(self, q: np.ndarray) -> np.ndarray:
        """World-frame Jacobians (n, 6, n_joints) of many joint vectors ``q`` (n, n_joints):
        the tool point's linear velocity (rows 0-2) and the tool's angular velocity
        (rows 3-5) per joint velocity (pinocchio's LOCAL_WORLD_ALIGNED)."""
        _pos, rot, jac = self._fk_jacobian_many(q)
        return np.concatenate([rot @ jac[:, :3], rot @ jac[:, 3:]], axis=1)

    def fk_jet(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """Forward kinematics of joint jets (see :mod:`trajkit.kinematics._jets`).

        Parameters
        ----------
        q : ndarray, shape (n, N, n_joints)
            Taylor coefficients of the joints along a motion.

        Returns
        -------
        position : ndarray, shape (n, N, 3)
            Taylor coefficients of the tool position [m] (world frame).
        rotation : ndarray, shape (n, N, 3, 3)
            Taylor coefficients of the tool rotation matrix.

        None when the chain has a joint kind the vectorised kinematics does not cover.
        """
        chain = self._chain()
        if chain is None:
            return None
        lead = (q.shape[0],)
        nc = q.shape[1]
        rots = [_jets.constant(np.eye(3), lead, nc)]
        poss = [_jets.constant(np.zeros(3), lead, nc)]
        for parent, iq, r_pl, t_pl, axis, revolute in chain:
            r_par, p_par = rots[parent], poss[parent]
            r_j = r_par @ r_pl
            p_j = p_par + r_par @ t_pl
            if revolute:
                rots.append(_jets.mat_mul(r_j, _jets.axis_motion(q[:, :, iq], axis)))
                poss.append(p_j)
            else:
                rots.append(r_j)
                poss.append(p_j + _jets.scale(q[:, :, iq], r_j @ axis))
        frame = self.model.frames[self.frame_id]
        r_par, p_par = rots[int(frame.parentJoint)], poss[int(frame.parentJoint)]
        return (p_par + r_par @ np.array(frame.placement.translation),
                r_par @ np.array(frame.placement.rotation))

    def joint_taylor_many(self, q0: np.ndarray, pos: np.ndarray, rot: np.ndarray,
                          null: tuple[np.ndarray, np.ndarray] | None = None
                          ) -> tuple[np.ndarray, np.ndarray] | None:
        """:func:`trajkit.kinematics._jets.joint_taylor` of this robot, compiled.

        Parameters
        ----------
        q0 : ndarray, shape (n, n_joints)
            Joints at the expansion points [rad or m].
        pos, rot : ndarray, shapes (n, 4, 3), (n, 4, 3, 3)
            Taylor coefficients of the tool position [m] and rotation.
        null : tuple of 2 ndarray, shapes (n, 4, n_joints), optional
            A 7-joint arm's redundancy resolution, as for ``joint_taylor``.

        Returns
        -------
        (qj, singular) as ``joint_taylor`` returns them, or None when the compiled
        loop is not available (no numba, a chain the vectorised kinematics does
        not cover, or a redundant robot without ``null``): then ``joint_taylor``
        with :meth:`fk_jet` gives the same coefficients to round-off.
        """
        arrays = self._chain_arrays()
        m = self.n_joints
        if arrays is None or m > 7 or (m == 7) != (null is not None):
            return None
        if null is None:
            cj = sj = np.zeros((0, _jets.ORDER + 1, m))
        else:
            cj, sj = (np.ascontiguousarray(a, dtype=np.float64) for a in null)
        return _chain_jit.chain_joint_taylor(
            *arrays, np.ascontiguousarray(q0, dtype=np.float64),
            np.ascontiguousarray(pos, dtype=np.float64), np.ascontiguousarray(rot, dtype=np.float64),
            cj, sj)

    def ik_project_many(self, positions: np.ndarray, rotations: np.ndarray, q_init: np.ndarray,
                        direction: np.ndarray, seeds: np.ndarray
                        ) -> tuple[np.ndarray, np.ndarray] | None:
        """Joints of a 7-joint arm with the tool poses and ``c . (q - seeds) = 0``.

        Newton steps on the seven equations from ``q_init`` (close to the
        solutions, e.g. :meth:`ik_near_many`'s), in one compiled loop.

        Parameters
        ----------
        positions : ndarray, shape (n, 3)
            Tool positions [m].
        rotations : ndarray, shape (n, 3, 3)
            Tool rotation matrices.
        q_init, direction, seeds : ndarray, shape (n, 7)
            Starting joints, the directions ``c`` and the seeds [rad or m].

        Returns
        -------
        (q, ok) : ndarray (n, 7) and ndarray of bool (n,)
            The joints (``q_init`` where not converged) and where they converged;
            None when the compiled loop is not available (no numba, a chain the
            vectorised kinematics does not cover, or not 7 joints).
        """
        arrays = self._chain_arrays()
        if arrays is None or self.n_joints != 7:
            return None
        return _chain_jit.chain_ik_project(
            *arrays, *(np.ascontiguousarray(a, dtype=np.float64)
                       for a in (positions, rotations, q_init, direction, seeds)),
            _jets.PROJECT_ITER, _jets.PROJECT_TOL)

    def _chain_arrays(self) -> tuple | None:
        """The chain as the arrays the compiled kinematics take
        (:func:`._chain_jit.chain_joint_taylor`, :func:`._chain_jit.chain_ik_near`), or
        None (no numba, or a chain the vectorised kinematics does not cover)."""
        if "_chain_arrays_cache" in self.__dict__:
            return cast("tuple | None", self.__dict__["_chain_arrays_cache"])
        chain = self._chain()
        out: tuple | None = None
        if chain is not None and _chain_jit.AVAILABLE:
            frame = self.model.frames[self.frame_id]
            out = (np.array([c[0] for c in chain], dtype=np.int64),
                   np.array([c[1] for c in chain], dtype=np.int64),
                   np.array([c[2] for c in chain], dtype=np.float64).reshape(-1, 3, 3),
                   np.array([c[3] for c in chain], dtype=np.float64).reshape(-1, 3),
                   np.array([c[4] for c in chain], dtype=np.float64).reshape(-1, 3),
                   np.array([c[5] for c in chain], dtype=np.bool_),
                   int(frame.parentJoint), np.array(frame.placement.rotation, dtype=np.float64),
                   np.array(frame.placement.translation, dtype=np.float64))
        self._chain_arrays_cache = out
        return out

    def ik_near_many(self, positions: np.ndarray, rotations: np.ndarray,
                     seeds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`ik_near` of many poses, vectorised where the seeds are close.

        The poses whose seed is within :data:`IK_BATCH_ENTRY` of its pose take
        the IK's Newton steps together (in one compiled loop over the chain where
        numba is installed, else the forward kinematics and Jacobians vectorised
        over the poses; the pose error to first order, which is exact to its
        square): steps until the error is below the tolerance,
        then the one polishing step, as :meth:`ik_near` does. The others, and any
        not converged after :data:`IK_BATCH_ITER` steps, are solved one by one by
        :meth:`ik_near`'s solver from their seeds. The solutions are those of
        :meth:`ik_near` (to round-off).

        Parameters
        ----------
        positions : ndarray, shape (n, 3)
            Tool positions [m].
        rotations : ndarray, shape (n, 3, 3)
            Tool rotation matrices (proper rotations, not checked).
        seeds : ndarray, shape (n, n_joints)
            Seeds [rad or m].

        Returns
        -------
        q : ndarray, shape (n, n_joints)
            Solutions (NaN rows where the solver did not converge).
        ok : ndarray of bool, shape (n,)
            Where it converged.
        """
        seeds = np.asarray(seeds, dtype=np.float64)
        n = seeds.shape[0]
        q = seeds.copy()
        ok = np.zeros(n, dtype=bool)
        lo, hi, scale, damping = self._ik_constants()
        arrays = self._chain_arrays()
        if arrays is not None:  # the same steps, compiled
            q, ok = _chain_jit.chain_ik_near(
                *arrays, np.ascontiguousarray(positions, dtype=np.float64),
                np.ascontiguousarray(rotations, dtype=np.float64), np.ascontiguousarray(seeds),
                lo, hi, scale, damping, IK_BATCH_ENTRY, IK_BATCH_ITER, IK_TOL, IK_MAX_STEP)
            active = np.zeros(0, dtype=int)
        else:
            active = np.arange(n) if self._chain() is not None else np.zeros(0, dtype=int)
        for it in range(IK_BATCH_ITER):
            if not active.size:
                break
            qa = q[active]
            pos, rot, jac = self._fk_jacobian_many(qa)
            rt = np.swapaxes(rot, 1, 2)
            rel = rt @ rotations[active]  # current^-1 target (rotation part)
            lin = np.einsum("nij,nj->ni", rt, positions[active] - pos)
            ang = 0.5 * np.stack([rel[:, 2, 1] - rel[:, 1, 2], rel[:, 0, 2] - rel[:, 2, 0],
                                  rel[:, 1, 0] - rel[:, 0, 1]], axis=-1)
            es = np.concatenate([lin, ang], axis=1) * scale
            err = np.abs(es).max(axis=1)
            if it == 0:  # only seeds close to their pose (principal rotation branch)
                near = (err < IK_BATCH_ENTRY) & (np.trace(rel, axis1=1, axis2=2) > 1.0)
                active, qa, jac, es, err = active[near], qa[near], jac[near], es[near], err[near]
            js = jac * scale[None, :, None]
            jt = np.swapaxes(js, 1, 2)
            y = np.linalg.solve(js @ jt + damping, es[:, :, None])
            dq = (jt @ y)[:, :, 0]
            step = np.abs(dq).max(axis=1)
            big = step > IK_MAX_STEP
            dq[big] *= (IK_MAX_STEP / step[big])[:, None]
            q[active] = np.clip(qa + dq, lo, hi)
            conv = err < IK_TOL  # this step was the polishing one
            ok[active[conv]] = True
            active = active[~conv]
        for i in np.nonzero(~ok)[0]:
            sol = self._solve_from(Pose.trusted(positions[i], rotations[i]), seeds[i])
            if sol is not None:
                q[i] = sol
                ok[i] = True
            else:
                q[i] = np.nan
        return q, ok

    def ik_near(self, pose: Pose, seed: Any) -> np.ndarray:
        """Numeric IK started at ``seed`` (n_joints,); the solution nearest the seed's branch.

        Raises
        ------
        UnreachableError
            When the solver does not converge inside the joint ranges.
        """
        s = check_array(seed, "seed", ndim=1, size=self.n_joints)
        q = self._solve_from(pose, s)
        if q is None:
            raise UnreachableError(
                f"pose at {_fmt_xyz(pose.position)} could not be reached by {self.name} "
                "from the previous joints (out of reach, outside the joint ranges, or singular)"
            )
        return q

    def ik(self, pose: Pose, config: Any = None, seed: Any = None) -> np.ndarray:
        """Numeric IK from ``seed`` (default: the middle of the ranges, then other seeds)."""
        if config is not None:
            self.parse_config(config)
        seeds = [] if seed is None else [check_array(seed, "seed", ndim=1, size=self.n_joints)]
        seeds += self._seeds()
        for s in seeds:
            q = self._solve_from(pose, s)
            if q is not None:
                return q
        raise UnreachableError(
            f"pose at {_fmt_xyz(pose.position)} is outside the workspace of {self.name} "
            f"(no IK solution from {len(seeds)} seeds)"
        )

    def _seeds(self) -> list[np.ndarray]:
        lo, hi = self.joint_ranges[:, 0], self.joint_ranges[:, 1]
        rng = np.random.default_rng(0)
        out = [0.5 * (lo + hi)]
        out += [lo + (hi - lo) * rng.uniform(0.1, 0.9, self.n_joints) for _ in range(IK_ALL_SEEDS)]
        return out

    def ik_all(self, pose: Pose) -> list[tuple[str, np.ndarray]]:
        """Distinct solutions found from deterministic seeds (not guaranteed complete)."""
        sols: list[np.ndarray] = []
        for s in self._seeds():
            q = self._solve_from(pose, s)
            if q is not None and not any(np.abs(q - p).max() < IK_DISTINCT_TOL for p in sols):
                sols.append(q)
        return [(URDF_CONFIG, q) for q in sols]

    def to_dict(self) -> dict:
        """JSON-ready description."""
        return {"model": "urdf", "path": self.path, "tip_link": self.tip_link}
