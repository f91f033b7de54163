"""Compiled kinematics of a serial chain: joint jets (:func:`chain_joint_taylor`)
and the batch inverse kinematics' Newton steps (:func:`chain_ik_near`).

The same mathematics as :func:`trajkit.kinematics._jets.joint_taylor` with the
forward kinematics of a chain of revolute and prismatic joints (each with a
fixed placement in its parent and a unit axis, as
:meth:`trajkit.kinematics.urdf.UrdfRobot` reads them), point by point in one
compiled loop instead of numpy passes over all the points: the jets of every
joint frame (Taylor coefficients ``0 .. 3`` of rotation and position along the
motion), the world-frame Jacobian, the singularity test on its singular
values, and the joint coefficients order by order (the coefficient ``k`` of
the tool pose is linear in ``q_k`` through the Jacobian, plus the lower
coefficients' terms, which a jet pass with ``q_k = 0`` gives).

Used only when numba is available (:data:`AVAILABLE`); otherwise the numpy
version runs. Both give the same coefficients to round-off.

Pure math: arrays in, arrays out.
"""

from __future__ import annotations

import numpy as np

from ..profiles._compile import ENABLED
from ..profiles._compile import jit as _jit
from ._jets import COND_MAX, ORDER

__all__ = ["AVAILABLE", "chain_joint_taylor", "chain_ik_near", "chain_ik_project"]

#: True when the compiled loop is used (numba installed and not disabled).
AVAILABLE = ENABLED

_N = ORDER + 1


@_jit
def _frames(qj, parent, iq, r_pl, t_pl, axis, kx, k2, rev, R, P, W, O, rj, pj, mot, kmax):
    """Jets of every joint frame for the joint jet ``qj`` (N, m), the coefficients
    ``0 .. kmax`` (the higher ones are left as they were).

    ``R`` (J + 1, N, 3, 3), ``P`` (J + 1, N, 3): rotation and position jets of
    frame 0 (the base) and of each joint's moving frame; ``W`` (J, 3), ``O``
    (J, 3): each joint's world axis and the origin of its moving frame (the
    constant coefficients), for the Jacobian. ``kx``, ``k2`` (J, 3, 3): the
    skew matrix of each axis and its square; ``rj``, ``pj``, ``mot``: scratch.
    """
    nj = parent.shape[0]
    R[0] = 0.0
    P[0] = 0.0
    for a in range(3):
        R[0, 0, a, a] = 1.0
    for i in range(nj):
        pa = parent[i]
        # the joint's fixed frame: parent frame times the placement
        for k in range(kmax + 1):
            for r in range(3):
                s = 0.0
                for c in range(3):
                    s += R[pa, k, r, c] * t_pl[i, c]
                pj[k, r] = P[pa, k, r] + s
                for c in range(3):
                    s = 0.0
                    for b in range(3):
                        s += R[pa, k, r, b] * r_pl[i, b, c]
                    rj[k, r, c] = s
        ax0, ax1, ax2 = axis[i, 0], axis[i, 1], axis[i, 2]
        for r in range(3):
            W[i, r] = rj[0, r, 0] * ax0 + rj[0, r, 1] * ax1 + rj[0, r, 2] * ax2
        x0 = qj[0, iq[i]]
        x1 = qj[1, iq[i]]
        x2 = qj[2, iq[i]]
        x3 = qj[3, iq[i]]
        if rev[i]:
            # cos and sin jets of the angle (angle-sum formula on its non-constant part)
            c0, s0 = np.cos(x0), np.sin(x0)
            sd1, sd2, sd3 = x1, x2, x3 - x1 * x1 * x1 / 6.0
            cd2, cd3 = -0.5 * x1 * x1, -x1 * x2
            cj = (c0, -s0 * sd1, c0 * cd2 - s0 * sd2, c0 * cd3 - s0 * sd3)
            sj = (s0, c0 * sd1, s0 * cd2 + c0 * sd2, s0 * cd3 + c0 * sd3)
            # Rodrigues: I + sin K + (1 - cos) K^2
            for k in range(kmax + 1):
                for r in range(3):
                    for c in range(3):
                        mot[k, r, c] = sj[k] * kx[i, r, c] + (-cj[k]) * k2[i, r, c]
            for r in range(3):
                for c in range(3):
                    mot[0, r, c] += k2[i, r, c] + (1.0 if r == c else 0.0)
            for k in range(kmax + 1):
                for r in range(3):
                    for c in range(3):
                        R[i + 1, k, r, c] = 0.0
            for a in range(kmax + 1):
                for b in range(kmax + 1 - a):
                    for r in range(3):
                        for c in range(3):
                            s = 0.0
                            for e in range(3):
                                s += rj[a, r, e] * mot[b, e, c]
                            R[i + 1, a + b, r, c] += s
            for k in range(kmax + 1):
                for r in range(3):
                    P[i + 1, k, r] = pj[k, r]
        else:
            xs = (x0, x1, x2, x3)
            for k in range(kmax + 1):
                for r in range(3):
                    for c in range(3):
                        R[i + 1, k, r, c] = rj[k, r, c]
                    P[i + 1, k, r] = pj[k, r]
            for a in range(kmax + 1):
                for b in range(kmax + 1 - a):
                    for r in range(3):
                        w = rj[b, r, 0] * ax0 + rj[b, r, 1] * ax1 + rj[b, r, 2] * ax2
                        P[i + 1, a + b, r] += xs[a] * w
        for r in range(3):
            O[i, r] = P[i + 1, 0, r]


@_jit
def _skews(axis):
    """The skew matrix of every unit axis (J, 3) and its square, each (J, 3, 3)."""
    nj = axis.shape[0]
    k1 = np.zeros((nj, 3, 3))
    for i in range(nj):
        a0, a1, a2 = axis[i, 0], axis[i, 1], axis[i, 2]
        k1[i, 0, 1], k1[i, 0, 2], k1[i, 1, 2] = -a2, a1, -a0
        k1[i, 1, 0], k1[i, 2, 0], k1[i, 2, 1] = a2, -a1, a0
    k2 = np.empty((nj, 3, 3))
    for i in range(nj):
        k2[i] = k1[i] @ k1[i]
    return k1, k2


@_jit
def _world_jacobian(W, O, p0, p1, p2, iq, rev, jac):
    """The world-frame Jacobian (6, m) into ``jac``: the tool point ``(p0, p1, p2)``'s
    velocity, then the angular velocity, per joint velocity, from each joint's
    world axis ``W`` and moving-frame origin ``O`` (J, 3)."""
    jac[:] = 0.0
    for i in range(iq.shape[0]):
        c = iq[i]
        w0, w1, w2 = W[i, 0], W[i, 1], W[i, 2]
        if rev[i]:
            d0, d1, d2 = p0 - O[i, 0], p1 - O[i, 1], p2 - O[i, 2]
            jac[0, c] = w1 * d2 - w2 * d1
            jac[1, c] = w2 * d0 - w0 * d2
            jac[2, c] = w0 * d1 - w1 * d0
            jac[3, c] = w0
            jac[4, c] = w1
            jac[5, c] = w2
        else:
            jac[0, c] = w0
            jac[1, c] = w1
            jac[2, c] = w2


@_jit
def _tool(R, P, tpar, r_tool, t_tool, pt, rt, kmax):
    """Tool position ``pt`` (N, 3) and rotation ``rt`` (N, 3, 3) jets (coefficients
    ``0 .. kmax``) from the frame ``tpar`` and the tool's placement in it."""
    for k in range(kmax + 1):
        for r in range(3):
            s = 0.0
            for c in range(3):
                s += R[tpar, k, r, c] * t_tool[c]
            pt[k, r] = P[tpar, k, r] + s
            for c in range(3):
                s = 0.0
                for b in range(3):
                    s += R[tpar, k, r, b] * r_tool[b, c]
                rt[k, r, c] = s


#: Below this bound on the condition number (``|A|_F |A^-1|_F``, computed with
#: the inverse) the Jacobian is certainly regular; at or above it the singular
#: values decide (a factor of 100 below :data:`COND_MAX` for the inverse's
#: round-off; for fewer than 6 joints the bound is on the normal matrix, whose
#: condition number is the Jacobian's squared, kept where that is accurate).
_FAST_COND = COND_MAX / 100.0
_FAST_COND_NORMAL = 1e8


@_jit
def _lu(a, piv):
    """LU factors of the square ``a`` in place, with partial pivoting (rows
    swapped as recorded in ``piv``); False at a zero or non-finite pivot."""
    n = a.shape[0]
    for k in range(n):
        p = k
        big = abs(a[k, k])
        for i in range(k + 1, n):
            if abs(a[i, k]) > big:
                big = abs(a[i, k])
                p = i
        piv[k] = p
        if not (big > 0.0 and big < np.inf):
            return False
        if p != k:
            for c in range(n):
                t = a[k, c]
                a[k, c] = a[p, c]
                a[p, c] = t
        inv = 1.0 / a[k, k]
        for i in range(k + 1, n):
            f = a[i, k] * inv
            a[i, k] = f
            if f != 0.0:
                for c in range(k + 1, n):
                    a[i, c] -= f * a[k, c]
    return True


@_jit
def _lu_solve(lu, piv, b, x):
    """``x`` solving ``a x = b`` from the factors of :func:`_lu`."""
    n = lu.shape[0]
    for i in range(n):
        x[i] = b[i]
    for k in range(n):
        p = piv[k]
        if p != k:
            t = x[k]
            x[k] = x[p]
            x[p] = t
    for i in range(n):
        acc = x[i]
        for c in range(i):
            acc -= lu[i, c] * x[c]
        x[i] = acc
    for i in range(n - 1, -1, -1):
        acc = x[i]
        for c in range(i + 1, n):
            acc -= lu[i, c] * x[c]
        x[i] = acc / lu[i, i]


@_jit
def _singular(jac, lhs, square, lu, piv, col, work):
    """The test of :func:`._jets.joint_taylor`: the Jacobian's condition number
    (largest over smallest singular value) is not below :data:`COND_MAX`.
    Decided by a cheap upper bound where that suffices (with ``lhs``'s LU
    factors, left in ``lu``, ``piv`` for the solves), else by the SVD (a
    matrix with a zero pivot counts as singular).
    ``col``, ``work``: scratch vectors."""
    m = lhs.shape[0]
    lu[:] = lhs
    factored = np.all(np.isfinite(lhs)) and _lu(lu, piv)
    if factored:
        # |lhs|_F |lhs^-1|_F, the inverse column by column
        inv2 = 0.0
        for c in range(m):
            col[:] = 0.0
            col[c] = 1.0
            _lu_solve(lu, piv, col, work)
            for r in range(m):
                inv2 += work[r] * work[r]
        bound = np.sqrt(np.sum(lhs * lhs) * inv2)
        if bound < (_FAST_COND if square else _FAST_COND_NORMAL):
            return False
    sv = np.linalg.svd(jac)[1]
    # (a matrix without LU factors has a zero pivot: singular whatever the SVD says)
    return not (sv[sv.size - 1] * COND_MAX > sv[0]) or not factored


@_jit
def chain_joint_taylor(parent, iq, r_pl, t_pl, axis, rev, tpar, r_tool, t_tool, q0, pos, rot, cj, sj):
    """Joint Taylor coefficients that follow a tool-pose jet, point by point.

    Parameters
    ----------
    parent : ndarray of int64, shape (J,)
        Frame each joint hangs from (0: the base, ``i + 1``: joint ``i``).
    iq : ndarray of int64, shape (J,)
        Configuration index of each joint.
    r_pl, t_pl : ndarray, shapes (J, 3, 3), (J, 3)
        Each joint's placement in its parent frame [-, m].
    axis : ndarray, shape (J, 3)
        Unit joint axes in the joint frames.
    rev : ndarray of bool, shape (J,)
        Revolute (else prismatic).
    tpar : int
        Frame the tool hangs from; ``r_tool``, ``t_tool`` (3, 3), (3,) its
        placement there.
    q0 : ndarray, shape (n, m)
        Joints at the expansion points [rad or m].
    pos, rot : ndarray, shapes (n, 4, 3), (n, 4, 3, 3)
        Taylor coefficients of the tool position [m] and rotation.
    cj, sj : ndarray, shapes (n, 4, m) or (0, 4, m)
        For one redundant joint (``m = 7``): the Taylor coefficients of the
        direction ``c`` and of the seeds ``sigma`` of ``c . (q - sigma) = 0``,
        the seventh equation (as ``null`` of :func:`._jets.joint_taylor`);
        empty otherwise.

    Returns
    -------
    qj : ndarray, shape (n, 4, m)
        ``q_0 .. q_3`` (``q_k = q^(k) / k!``); NaN beyond ``q_0`` where singular.
    singular : ndarray of bool, shape (n,)
        The Jacobian's condition number is above :data:`COND_MAX`.
    """
    n, m = q0.shape
    nj = parent.shape[0]
    aug = cj.shape[0] > 0  # the seventh row of a redundant arm
    nr = 7 if aug else 6
    qj = np.zeros((n, _N, m))
    singular = np.zeros(n, dtype=np.bool_)
    R = np.empty((nj + 1, _N, 3, 3))
    P = np.empty((nj + 1, _N, 3))
    W = np.empty((nj, 3))
    O = np.empty((nj, 3))
    rj = np.empty((_N, 3, 3))
    pj = np.empty((_N, 3))
    mot = np.empty((_N, 3, 3))
    kx, k2 = _skews(axis)
    pt = np.empty((_N, 3))
    rt = np.empty((_N, 3, 3))
    jw = np.zeros((6, m))
    jac = np.zeros((nr, m))
    jt = np.empty((m, nr))
    lhs = np.empty((m, m))
    rhs = np.empty(nr)
    dr = np.empty((3, 3))
    x = np.empty((3, 3))
    cur = np.zeros((_N, m))
    lu = np.empty((m, m))
    piv = np.zeros(m, dtype=np.int64)
    col = np.empty(m)
    sol = np.empty(m)
    rhs_m = np.empty(m)
    for p in range(n):
        cur[:] = 0.0
        for j in range(m):
            cur[0, j] = q0[p, j]
            qj[p, 0, j] = q0[p, j]
        # (the first coefficient needs the frames alone: the Jacobian)
        _frames(cur, parent, iq, r_pl, t_pl, axis, kx, k2, rev, R, P, W, O, rj, pj, mot, 0)
        _tool(R, P, tpar, r_tool, t_tool, pt, rt, 0)
        _world_jacobian(W, O, pt[0, 0], pt[0, 1], pt[0, 2], iq, rev, jw)
        for r in range(6):
            for c in range(m):
                jac[r, c] = jw[r, c]
        if aug:
            for c in range(m):
                jac[6, c] = cj[p, 0, c]
        for r in range(nr):
            for c in range(m):
                jt[c, r] = jac[r, c]
        if m == nr:
            lhs[:] = jac
        else:  # fewer joints: the normal equations
            lhs[:] = jt @ jac
        if _singular(jac, lhs, m == nr, lu, piv, col, sol):
            singular[p] = True
            for k in range(1, _N):
                for j in range(m):
                    qj[p, k, j] = np.nan
            continue
        for k in range(1, _N):
            if k > 1:  # the coefficient k of the motion so far (q_k still 0)
                _frames(cur, parent, iq, r_pl, t_pl, axis, kx, k2, rev, R, P, W, O, rj, pj, mot, k)
                _tool(R, P, tpar, r_tool, t_tool, pt, rt, k)
            for r in range(3):
                rhs[r] = pos[p, k, r] - (pt[k, r] if k > 1 else 0.0)
                for c in range(3):
                    dr[r, c] = rot[p, k, r, c] - (rt[k, r, c] if k > 1 else 0.0)
            # the angular part: vee(dR R0^T)
            for r in range(3):
                for c in range(3):
                    acc = 0.0
                    for b in range(3):
                        acc += dr[r, b] * rot[p, 0, c, b]
                    x[r, c] = acc
            rhs[3] = 0.5 * (x[2, 1] - x[1, 2])
            rhs[4] = 0.5 * (x[0, 2] - x[2, 0])
            rhs[5] = 0.5 * (x[1, 0] - x[0, 1])
            if aug:  # sum_i c_i . (q_{k-i} - sigma_{k-i}) = 0, the term of q_k on the left
                acc = 0.0
                for j in range(m):
                    acc += cj[p, 0, j] * sj[p, k, j]
                    for i in range(1, k + 1):
                        acc -= cj[p, i, j] * (qj[p, k - i, j] - sj[p, k - i, j])
                rhs[6] = acc
            if m == nr:
                _lu_solve(lu, piv, rhs, sol)
            else:
                for j in range(m):
                    acc = 0.0
                    for r in range(nr):
                        acc += jt[j, r] * rhs[r]
                    rhs_m[j] = acc
                _lu_solve(lu, piv, rhs_m, sol)
            for j in range(m):
                qj[p, k, j] = sol[j]
                cur[k, j] = sol[j]
    return qj, singular


@_jit
def _mat3(a, b, out):
    """``out = a @ b`` for 3 x 3 arrays (explicit loops: no BLAS call)."""
    for r in range(3):
        for c in range(3):
            out[r, c] = a[r, 0] * b[0, c] + a[r, 1] * b[1, c] + a[r, 2] * b[2, c]


@_jit
def _pose_work(nj):
    """Scratch arrays of :func:`_pose` for a chain of ``nj`` joints: ``R``, ``P``,
    ``W``, ``O``, ``pt``, ``rt``, ``rj``, ``mot``."""
    return (np.empty((nj + 1, 3, 3)), np.empty((nj + 1, 3)), np.empty((nj, 3)), np.empty((nj, 3)),
            np.empty(3), np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3)))


@_jit
def _pose(q, parent, iq, r_pl, t_pl, axis, k1, k2, rev, tpar, r_tool, t_tool, R, P, W, O, pt, rt,
          rj, mot):
    """Forward kinematics at ``q`` (m,): every joint frame (``R``, ``P`` of
    shapes (J + 1, 3, 3), (J + 1, 3)), each joint's world axis ``W`` and moving
    frame origin ``O`` (J, 3), the tool's position ``pt`` (3,) and rotation
    ``rt`` (3, 3); ``rj``, ``mot`` (3, 3): scratch."""
    nj = parent.shape[0]
    R[0] = 0.0
    P[0] = 0.0
    for a in range(3):
        R[0, a, a] = 1.0
    for i in range(nj):
        pa = parent[i]
        _mat3(R[pa], r_pl[i], rj)
        x = q[iq[i]]
        for r in range(3):
            P[i + 1, r] = P[pa, r] + (R[pa, r, 0] * t_pl[i, 0] + R[pa, r, 1] * t_pl[i, 1]
                                      + R[pa, r, 2] * t_pl[i, 2])
            W[i, r] = rj[r, 0] * axis[i, 0] + rj[r, 1] * axis[i, 1] + rj[r, 2] * axis[i, 2]
        if rev[i]:
            c, s = np.cos(x), np.sin(x)
            for r in range(3):  # Rodrigues
                for cc in range(3):
                    mot[r, cc] = (1.0 if r == cc else 0.0) + s * k1[i, r, cc] + (1.0 - c) * k2[i, r, cc]
            _mat3(rj, mot, R[i + 1])
        else:
            R[i + 1] = rj
            for r in range(3):
                P[i + 1, r] += W[i, r] * x
        for r in range(3):
            O[i, r] = P[i + 1, r]
    for r in range(3):
        pt[r] = P[tpar, r] + (R[tpar, r, 0] * t_tool[0] + R[tpar, r, 1] * t_tool[1]
                              + R[tpar, r, 2] * t_tool[2])
    _mat3(R[tpar], r_tool, rt)


@_jit
def chain_ik_near(parent, iq, r_pl, t_pl, axis, rev, tpar, r_tool, t_tool, positions, rotations,
                  seeds, lo, hi, scale, damping, entry, max_iter, tol, max_step):
    """Damped least-squares IK steps of many poses from seeds close to them.

    For each pose: the pose error in the tool frame (position times
    ``scale[:3]``, the rotation's vector part times ``scale[3:]``); a seed whose
    error is at least ``entry``, or whose rotation is not on the principal
    branch (trace of the relative rotation <= 1), is left to the caller. Then
    steps ``dq = J^T (J J^T + damping)^-1 e`` (tool-frame Jacobian with the rows
    scaled), at most ``max_step`` per joint, clipped to ``[lo, hi]``, until the
    error before a step is below ``tol`` (that step, the polishing one,
    included), at most ``max_iter`` steps.

    Returns
    -------
    q : ndarray, shape (n, m)
        The final joints (the seeds where not converged).
    ok : ndarray of bool, shape (n,)
        Converged.
    """
    n, m = seeds.shape
    k1, k2 = _skews(axis)
    R, P, W, O, pt, rt, rj, mot = _pose_work(parent.shape[0])
    jw = np.zeros((6, m))
    js = np.empty((6, m))
    es = np.empty(6)
    out = seeds.copy()
    ok = np.zeros(n, dtype=np.bool_)
    q = np.empty(m)
    rel = np.empty((3, 3))
    lin = np.empty(3)
    A = np.empty((6, 6))
    dq = np.empty(m)
    for p in range(n):
        for j in range(m):
            q[j] = seeds[p, j]
        for it in range(max_iter):
            _pose(q, parent, iq, r_pl, t_pl, axis, k1, k2, rev, tpar, r_tool, t_tool,
                  R, P, W, O, pt, rt, rj, mot)
            # the error in the tool frame: rt^T (target - current), vee(rt^T R_target)
            for r in range(3):
                lin[r] = (rt[0, r] * (positions[p, 0] - pt[0]) + rt[1, r] * (positions[p, 1] - pt[1])
                          + rt[2, r] * (positions[p, 2] - pt[2]))
                for c in range(3):
                    rel[r, c] = (rt[0, r] * rotations[p, 0, c] + rt[1, r] * rotations[p, 1, c]
                                 + rt[2, r] * rotations[p, 2, c])
            es[0] = lin[0] * scale[0]
            es[1] = lin[1] * scale[1]
            es[2] = lin[2] * scale[2]
            es[3] = 0.5 * (rel[2, 1] - rel[1, 2]) * scale[3]
            es[4] = 0.5 * (rel[0, 2] - rel[2, 0]) * scale[4]
            es[5] = 0.5 * (rel[1, 0] - rel[0, 1]) * scale[5]
            err = 0.0
            for r in range(6):
                err = max(err, abs(es[r]))
            if it == 0 and not (err < entry and rel[0, 0] + rel[1, 1] + rel[2, 2] > 1.0):
                break
            # the world-frame Jacobian, then the tool frame's, rows scaled
            _world_jacobian(W, O, pt[0], pt[1], pt[2], iq, rev, jw)
            for h in range(2):
                for r in range(3):
                    for c in range(m):
                        js[3 * h + r, c] = (rt[0, r] * jw[3 * h, c] + rt[1, r] * jw[3 * h + 1, c]
                                            + rt[2, r] * jw[3 * h + 2, c]) * scale[3 * h + r]
            for r in range(6):
                for c in range(6):
                    acc = damping[r, c]
                    for j in range(m):
                        acc += js[r, j] * js[c, j]
                    A[r, c] = acc
            y = np.linalg.solve(A, es)
            step = 0.0
            for j in range(m):
                acc = 0.0
                for r in range(6):
                    acc += js[r, j] * y[r]
                dq[j] = acc
                step = max(step, abs(acc))
            f = max_step / step if step > max_step else 1.0
            for j in range(m):
                q[j] = min(max(q[j] + (dq[j] * f if f != 1.0 else dq[j]), lo[j]), hi[j])
            if err < tol:  # this step was the polishing one
                ok[p] = True
                for j in range(m):
                    out[p, j] = q[j]
                break
    return out, ok


@_jit
def chain_ik_project(parent, iq, r_pl, t_pl, axis, rev, tpar, r_tool, t_tool, positions, rotations,
                     q_init, c, sig, max_iter, tol):
    """Newton steps onto the joints of one redundant joint's resolution, point by point.

    For each pose: the joints ``q`` (m = 7) with the tool pose and
    ``c . (q - sigma) = 0`` (the seeds' part along the direction ``c``, close to
    the Jacobian's null space), from ``q_init`` close to them: steps
    ``[J; c] dq = [e; c . (sigma - q)]`` (world-frame Jacobian, the pose error
    ``e`` in the world frame: the position's difference and the vector part of
    the relative rotation) until the residual before a step is below ``tol``
    (that step, the polishing one, included), at most ``max_iter`` steps.

    Parameters
    ----------
    parent, iq, r_pl, t_pl, axis, rev, tpar, r_tool, t_tool
        The chain, as for :func:`chain_joint_taylor`.
    positions, rotations : ndarray, shapes (n, 3), (n, 3, 3)
        Tool poses [m].
    q_init, c, sig : ndarray, shape (n, m)
        Starting joints, directions and seeds [rad or m].
    max_iter : int
    tol : float
        Residual [m, rad].

    Returns
    -------
    q : ndarray, shape (n, m)
        The joints (``q_init`` where not converged).
    ok : ndarray of bool, shape (n,)
        Converged.
    """
    n, m = q_init.shape
    k1, k2 = _skews(axis)
    R, P, W, O, pt, rt, rj, mot = _pose_work(parent.shape[0])
    jw = np.zeros((6, m))
    A = np.empty((m, m))
    b = np.empty(m)
    dq = np.empty(m)
    piv = np.zeros(m, dtype=np.int64)
    rel = np.empty((3, 3))
    out = q_init.copy()
    ok = np.zeros(n, dtype=np.bool_)
    q = np.empty(m)
    for p in range(n):
        for j in range(m):
            q[j] = q_init[p, j]
        for _it in range(max_iter):
            _pose(q, parent, iq, r_pl, t_pl, axis, k1, k2, rev, tpar, r_tool, t_tool,
                  R, P, W, O, pt, rt, rj, mot)
            for r in range(3):
                b[r] = positions[p, r] - pt[r]
                for cc in range(3):  # R_target R^T
                    rel[r, cc] = (rotations[p, r, 0] * rt[cc, 0] + rotations[p, r, 1] * rt[cc, 1]
                                  + rotations[p, r, 2] * rt[cc, 2])
            b[3] = 0.5 * (rel[2, 1] - rel[1, 2])
            b[4] = 0.5 * (rel[0, 2] - rel[2, 0])
            b[5] = 0.5 * (rel[1, 0] - rel[0, 1])
            acc = 0.0
            for j in range(m):
                acc += c[p, j] * (sig[p, j] - q[j])
            b[6] = acc
            err = 0.0
            for r in range(7):
                err = max(err, abs(b[r]))
            if not (rel[0, 0] + rel[1, 1] + rel[2, 2] > 1.0):
                break  # not on the principal branch of the rotation: too far
            _world_jacobian(W, O, pt[0], pt[1], pt[2], iq, rev, jw)
            for r in range(6):
                for j in range(m):
                    A[r, j] = jw[r, j]
            for j in range(m):
                A[6, j] = c[p, j]
            if not _lu(A, piv):
                break
            _lu_solve(A, piv, b, dq)
            for j in range(m):
                q[j] += dq[j]
            if err < tol:  # this step was the polishing one
                ok[p] = True
                for j in range(m):
                    out[p, j] = q[j]
                break
    return out, ok
