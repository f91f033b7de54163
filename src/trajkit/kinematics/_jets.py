"""Truncated Taylor series ("jets") through the forward kinematics.

A jet of order 3 holds the Taylor coefficients ``f_0 .. f_3`` of a function of
one parameter ``e`` at ``e = 0`` (``f_k = f^(k) / k!``) in axis ``-3`` of an
array (``(..., 4)`` for scalars, ``(..., 4, 3)`` for vectors, ``(..., 4, 3,
3)`` for matrices). Sums are coefficient-wise, products are Cauchy products;
cosine and sine come from the angle-sum formula on the jet's non-constant
part. Pushing a joint jet ``q(e)`` through a robot's forward kinematics gives
the exact Taylor coefficients of the tool pose along the joint motion (to
round-off), which is how :func:`joint_taylor` finds the derivatives of the
inverse kinematics of a tool path order by order: the coefficient of
``e^k`` of the pose is linear in ``q_k`` (through the Jacobian) plus terms of
the lower coefficients only.

Pure math: arrays in, arrays out.
"""

from __future__ import annotations

import numpy as np

__all__ = ["ORDER", "cos_sin", "mat_mul", "mat_vec", "scale", "axis_motion", "constant", "jacobian",
           "joint_taylor", "project", "vee", "COND_MAX", "PROJECT_ITER", "PROJECT_TOL"]

#: Highest Taylor coefficient carried.
ORDER = 3

#: A Jacobian whose condition number (largest over smallest singular value) is
#: above this is singular for :func:`joint_taylor`.
COND_MAX = 1e12

_N = ORDER + 1


def cos_sin(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cosine and sine jets of the scalar jet ``x`` (..., N), N <= 4 coefficients."""
    nc = x.shape[-1]
    if nc < _N:
        x = np.concatenate([x, np.zeros(x.shape[:-1] + (_N - nc,))], axis=-1)
    x0, x1, x2, x3 = x[..., 0], x[..., 1], x[..., 2], x[..., 3]
    c0, s0 = np.cos(x0), np.sin(x0)
    # d = x - x0: sin d = x1 e + x2 e^2 + (x3 - x1^3/6) e^3, cos d = 1 - x1^2/2 e^2 - x1 x2 e^3
    sd1, sd2, sd3 = x1, x2, x3 - x1 * x1 * x1 / 6.0
    cd2, cd3 = -0.5 * x1 * x1, -x1 * x2
    c = np.stack([c0, -s0 * sd1, c0 * cd2 - s0 * sd2, c0 * cd3 - s0 * sd3][:nc], axis=-1)
    s = np.stack([s0, c0 * sd1, s0 * cd2 + c0 * sd2, s0 * cd3 + c0 * sd3][:nc], axis=-1)
    return c, s


def mat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Product of matrix jets ``a`` (..., N, p, q) and ``b`` (..., N, q, r)."""
    nc = a.shape[-3]
    out = np.zeros(np.broadcast_shapes(a.shape[:-3], b.shape[:-3]) + (nc, a.shape[-2], b.shape[-1]))
    for i in range(nc):
        for j in range(nc - i):
            out[..., i + j, :, :] += a[..., i, :, :] @ b[..., j, :, :]
    return out


def mat_vec(a: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Matrix jet ``a`` (..., N, 3, 3) times vector jet ``v`` (..., N, 3)."""
    return mat_mul(a, v[..., None])[..., 0]


def scale(x: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Scalar jet ``x`` (..., N) times vector jet ``v`` (..., N, 3)."""
    nc = x.shape[-1]
    out = np.zeros(np.broadcast_shapes(x.shape[:-1], v.shape[:-2]) + (nc, v.shape[-1]))
    for i in range(nc):
        for j in range(nc - i):
            out[..., i + j, :] += x[..., i, None] * v[..., j, :]
    return out


def axis_motion(x: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Rotation jet (..., N, 3, 3) about the fixed unit ``axis`` by the angle jet ``x`` (..., N)
    (Rodrigues: ``I + sin K + (1 - cos) K^2``)."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    k2 = k @ k
    c, s = cos_sin(x)
    out = s[..., None, None] * k + (-c)[..., None, None] * k2
    out[..., 0, :, :] += np.eye(3) + k2
    return out


def constant(m: np.ndarray, lead: tuple, nc: int = _N) -> np.ndarray:
    """The constant jet (lead + (nc,) + m.shape) of the array ``m``."""
    out = np.zeros(lead + (nc,) + m.shape)
    out[(..., 0) + (slice(None),) * m.ndim] = m
    return out


def vee(x: np.ndarray) -> np.ndarray:
    """Vector of the skew-symmetric part of ``x`` (..., 3, 3)."""
    return 0.5 * np.stack([x[..., 2, 1] - x[..., 1, 2], x[..., 0, 2] - x[..., 2, 0],
                           x[..., 1, 0] - x[..., 0, 1]], axis=-1)


def jacobian(fk_jet, q0: np.ndarray) -> np.ndarray:
    """World-frame Jacobian (n, 6, m) (linear velocity of the tool point, then angular
    velocity) at joints ``q0`` (n, m): the order-1 coefficients of the forward
    kinematics along every joint direction."""
    n, m = q0.shape
    unit = np.zeros((n, m, 2, m))
    unit[:, :, 0] = q0[:, None, :]
    unit[:, :, 1] = np.eye(m)
    pj, rj = fk_jet(unit.reshape(n * m, 2, m))
    r0t = np.swapaxes(rj[::m, 0], -1, -2)
    jv = pj[:, 1].reshape(n, m, 3)
    jw = vee(rj[:, 1].reshape(n, m, 3, 3) @ r0t[:, None])
    return np.swapaxes(np.concatenate([jv, jw], axis=2), 1, 2)


def joint_taylor(fk_jet, q0: np.ndarray, pos: np.ndarray, rot: np.ndarray,
                 jac: np.ndarray | None = None,
                 null: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Taylor coefficients of the joints that follow a tool-pose jet.

    Parameters
    ----------
    fk_jet : callable
        ``fk_jet(q (n, N, m)) -> (position (n, N, 3), rotation (n, N, 3, 3))``:
        the robot's forward kinematics on joint jets of ``N <= 4`` coefficients.
    q0 : ndarray, shape (n, m)
        Joints at the expansion points (the inverse kinematics of ``pos[:, 0]``,
        ``rot[:, 0]``).
    pos, rot : ndarray, shapes (n, 4, 3), (n, 4, 3, 3)
        Taylor coefficients of the tool position [m] and rotation along the path.
    jac : ndarray, shape (n, 6, m), optional
        The world-frame Jacobian at ``q0`` (:func:`jacobian` when not given).
    null : tuple of 2 ndarray, shapes (n, 4, m), optional
        For an arm with one redundant joint (``m = 7``): the Taylor coefficients
        of a direction ``c`` and of the seed joints ``sigma`` along the path;
        the joints keep ``c . (q - sigma) = 0`` (the seed's part along ``c``, a
        direction close to the Jacobian's null space), the seventh equation of
        every order.

    Returns
    -------
    qj : ndarray, shape (n, 4, m)
        Joint Taylor coefficients ``q_0 .. q_3``: ``q_k = q^(k) / k!`` [rad or m per
        path unit^k]. Least squares where the robot has fewer than 6 joints (a
        reachable pose path is matched exactly); a redundant robot needs ``null``.
    singular : ndarray of bool, shape (n,)
        Points where the Jacobian is singular (condition number above
        :data:`COND_MAX`): their higher coefficients are not computed (NaN).
    """
    n, m = q0.shape
    if null is None and m > 6:
        raise ValueError("joint_taylor needs a non-redundant robot (at most 6 joints) or, "
                         "for 7 joints, the redundancy's direction and seeds (null)")
    if null is not None and m != 7:
        raise ValueError(f"joint_taylor resolves one redundant joint (7 joints), got {m}")
    if jac is None:
        jac = jacobian(fk_jet, q0)
    if null is not None:  # the seventh row: the direction c
        cj, sj = null
        jac = np.concatenate([jac, cj[:, 0][:, None, :]], axis=1)
    if jac.shape[1] == m:
        lhs, jt = jac, None
    else:  # fewer joints: the normal equations (the pose path lies in the reachable set)
        jt = np.swapaxes(jac, 1, 2)
        lhs = jt @ jac
    qj = np.zeros((n, _N, m))
    qj[:, 0] = q0
    sv = np.linalg.svd(jac, compute_uv=False)
    singular = ~(sv[:, -1] * COND_MAX > sv[:, 0])
    ok = ~singular
    qj[singular, 1:] = np.nan
    if not ok.any():
        return qj, singular
    lhs = lhs[ok]
    jt = None if jt is None else jt[ok]
    r0t = np.swapaxes(rot[ok, 0], -1, -2)
    for k in range(1, _N):
        if k == 1:  # nothing of lower order contributes to the first coefficient
            dp, dr = pos[ok, 1], rot[ok, 1]
        else:  # the coefficient k of the motion so far (q_k still 0): jets of k + 1 terms
            p_now, r_now = fk_jet(qj[ok, :k + 1])
            dp, dr = pos[ok, k] - p_now[:, k], rot[ok, k] - r_now[:, k]
        rows = [dp, vee(dr @ r0t)]
        if null is not None:
            # sum_i c_i . (q_{k-i} - sigma_{k-i}) = 0, the term of q_k on the left
            c, sg = cj[ok], sj[ok]
            extra = np.einsum("nj,nj->n", c[:, 0], sg[:, k])
            for i in range(1, k + 1):
                extra -= np.einsum("nj,nj->n", c[:, i], qj[ok, k - i] - sg[:, k - i])
            rows.append(extra[:, None])
        rhs = np.concatenate(rows, axis=1)[..., None]
        qj[ok, k] = np.linalg.solve(lhs, rhs if jt is None else jt @ rhs)[..., 0]
    return qj, singular


#: Newton steps of :func:`project` at most, and the residual [m, rad] below which
#: the next step is the last (the polishing one).
PROJECT_ITER = 6
PROJECT_TOL = 1e-12


def project(fk_jet, pos: np.ndarray, rot: np.ndarray, q: np.ndarray, c: np.ndarray,
            sig: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joints of a 7-joint arm with the tool poses and ``c . (q - sig) = 0``.

    Newton steps on the seven equations (the pose error in the world frame: the
    position's difference and the vector part of the relative rotation; the
    seeds' part along the direction ``c``) from ``q``, close to the solutions.

    Parameters
    ----------
    fk_jet : callable
        As for :func:`joint_taylor`.
    pos, rot : ndarray, shapes (n, 3), (n, 3, 3)
        Tool poses [m].
    q, c, sig : ndarray, shape (n, 7)
        Starting joints, the directions ``c`` and the seeds [rad or m].

    Returns
    -------
    q : ndarray, shape (n, 7)
        The joints (the starting ones where the steps did not converge).
    ok : ndarray of bool, shape (n,)
        Converged.
    """
    q0 = np.array(q, dtype=float)
    x = q0.copy()
    n = x.shape[0]
    ok = np.zeros(n, dtype=bool)
    active = np.arange(n)
    for _ in range(PROJECT_ITER):
        if not active.size:
            break
        xa = x[active]
        p_now, r_now = fk_jet(xa[:, None, :])
        rel = rot[active] @ np.swapaxes(r_now[:, 0], -1, -2)
        res = np.concatenate([pos[active] - p_now[:, 0], vee(rel),
                              np.einsum("nj,nj->n", c[active], sig[active] - xa)[:, None]], axis=1)
        good = np.trace(rel, axis1=1, axis2=2) > 1.0
        lhs = np.concatenate([jacobian(fk_jet, xa), c[active][:, None, :]], axis=1)
        good &= np.isfinite(lhs).all(axis=(1, 2)) & (np.abs(np.linalg.det(lhs)) > 0.0)
        step = np.zeros_like(xa)
        step[good] = np.linalg.solve(lhs[good], res[good][..., None])[..., 0]
        x[active] = xa + step
        done = good & (np.abs(res).max(axis=1) < PROJECT_TOL)
        ok[active[done]] = True
        active = active[good & ~done]
    x[~ok] = q0[~ok]
    return x, ok
