"""Geometric paths in joint space, ``q(s)`` with ``s`` in ``[0, length]``, and their derivatives.

The timing engine needs, at any ``s``, the joint positions and their first
three derivatives in ``s``. Every path here gives them exactly (analytic);
robot paths (Cartesian lines and arcs through inverse kinematics) live in
:mod:`trajkit.robot` and implement the same protocol.
"""

from __future__ import annotations

import math
from typing import Any, Protocol, runtime_checkable

import numpy as np

from .._validate import check_array
from ..errors import InvalidInputError

__all__ = ["JointPath", "LinearJointPath", "PathRest", "derivatives_on", "check_s"]


@runtime_checkable
class JointPath(Protocol):
    """A path in joint space parameterised by ``s`` in ``[0, length]``.

    Attributes
    ----------
    length : float
        Length of the parameter range [path unit, e.g. m of tool path or rad].
    n_joints : int
    breakpoints : ndarray
        Parameter values where the path's pieces meet (grid nodes are put
        there); may be empty.
    cheap_derivatives : bool, optional
        True when :meth:`derivatives` is cheap (analytic): the engine then
        checks its limits with the exact derivatives at every check point
        instead of their interpolation on the grid.
    """

    length: float
    n_joints: int
    breakpoints: np.ndarray

    def derivatives(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``q``, ``dq/ds``, ``d2q/ds2``, ``d3q/ds3`` at ``s`` (n,), each of shape (n, n_joints)."""
        ...  # pragma: no cover


def check_s(path: Any, s: Any) -> np.ndarray:
    """``s`` as a float array inside ``[0, length]`` (round-off clipped)."""
    arr = np.atleast_1d(np.asarray(s, dtype=np.float64))
    L = float(path.length)
    tol = 1e-12 * max(L, 1.0)
    if arr.size and (arr.min() < -tol or arr.max() > L + tol or not np.isfinite(arr).all()):
        raise InvalidInputError(f"path parameter s must lie in [0, {L!r}], got values in "
                                f"[{arr.min()!r}, {arr.max()!r}]")
    return np.clip(arr, 0.0, L)


def derivatives_on(path: JointPath, s: Any):
    """:meth:`JointPath.derivatives` with ``s`` checked."""
    return path.derivatives(check_s(path, s))


class LinearJointPath:
    """The straight line in joint space from ``start`` to ``goal``, parameterised by the
    joint-space distance (``s`` in ``[0, |goal - start|]``) or by a given length.

    Parameters
    ----------
    start, goal : array_like, shape (m,)
        Joint positions [rad or m].
    length : float, optional
        Length of the parameter range; default the Euclidean joint distance.
    """

    #: Exact derivatives are cheap: the timing engine checks its limits with them.
    cheap_derivatives = True

    def __init__(self, start: Any, goal: Any, length: float | None = None) -> None:
        a = check_array(start, "start", ndim=1)
        b = check_array(goal, "goal", ndim=1, size=a.size)
        dist = float(np.linalg.norm(b - a))
        if dist == 0.0:
            raise InvalidInputError("start and goal are the same joint position: the path has no length")
        self.length = float(dist if length is None else length)
        if not self.length > 0.0:
            raise InvalidInputError(f"length must be > 0, got {length!r}")
        self.start = a
        self.goal = b
        self.n_joints = a.size
        self._dir = (b - a) / self.length
        self.breakpoints = np.zeros(0)

    def derivatives(self, s: np.ndarray):
        s = np.asarray(s, dtype=float)
        q = self.start[None, :] + s[:, None] * self._dir[None, :]
        d1 = np.broadcast_to(self._dir, q.shape).copy()
        z = np.zeros_like(q)
        return q, d1, z, z.copy()


class PathRest:
    """The part of a joint path from ``start`` on (to ``end``), parameterised from 0:
    what an online re-plan times from the state of a running timing.

    ``s`` of this path is ``s - start`` of ``path``; its length is ``end -
    start``, its breakpoints those of ``path`` between ``start`` and ``end``. A
    path callable of the original's ``s`` (a speed cap, the tool path's
    curvature) needs the same shift.

    The shift keeps every point on its own piece of ``path``: ``s + start`` can
    round onto a breakpoint from below (``s`` just before a shifted breakpoint,
    where the engine takes the derivatives of the piece that ends there), so a
    point before (at or after) a shifted breakpoint is evaluated before (at or
    after) the original one.

    Parameters
    ----------
    path : JointPath
    start : float
        Where this part begins, in ``[0, end)`` [path unit].
    end : float, optional
        Where it ends, in ``(start, path.length]`` [path unit]; the path's end
        by default.

    Examples
    --------
    Re-plan the rest of a timing ``tm`` from its state at ``t``:

    >>> s0, v0, a0, _ = tm.sample(t)[:, 0]                         # doctest: +SKIP
    >>> rest = plan_path_timing(PathRest(tm.path, s0), tm.limits,  # doctest: +SKIP
    ...                         start_speed=v0, start_accel=a0)
    """

    def __init__(self, path: JointPath, start: float, end: float | None = None) -> None:
        L = float(path.length)
        s1 = L if end is None else float(end)
        if not (math.isfinite(s1) and 0.0 < s1 <= L):
            raise InvalidInputError(f"end must lie in (0, {L!r}], got {end!r}")
        s0 = float(start)
        if not (math.isfinite(s0) and 0.0 <= s0 < s1):
            raise InvalidInputError(f"start must lie in [0, {s1!r}), got {start!r}")
        self.path = path
        self.start = s0
        self.end = s1
        self.length = s1 - s0
        self.n_joints = int(path.n_joints)
        b = np.asarray(getattr(path, "breakpoints", np.zeros(0)), dtype=float)
        b = b[(b > s0) & (b < s1)]
        self.breakpoints = b - s0
        # the range of the original s on every piece: [a breakpoint, just before the next]
        self._lo = np.concatenate([[s0], b])
        self._hi = np.concatenate([np.nextafter(b, -np.inf), [s1]])
        self.cheap_derivatives = bool(getattr(path, "cheap_derivatives", False))

    def derivatives(self, s: np.ndarray):
        """``q``, ``dq/ds``, ``d2q/ds2``, ``d3q/ds3`` at ``s`` (n,) of this path, each (n, m)."""
        s = np.asarray(s, dtype=float)
        k = np.searchsorted(self.breakpoints, s, side="right")
        return self.path.derivatives(np.clip(s + self.start, self._lo[k], self._hi[k]))
