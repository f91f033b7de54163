"""Many axes between moving states: :func:`plan_ptp_states`.

Step 1 (ruckig's scheme): every axis' feasible durations -- its minimum and
its blocked intervals (:func:`trajkit.profiles.state.feasible_durations`).
Synchronisation: the common duration is the smallest duration every axis
can meet (the largest minimum, moved past the blocked intervals). Step 2:
every other axis planned for exactly that duration.
"""

from __future__ import annotations

import logging
import math
import struct
import threading
from collections.abc import Sequence
from functools import partial
from typing import Any

import numpy as np

from .._constants import DURATION_RTOL
from ..errors import InfeasibleError, InvalidInputError
from ..limits import AxisLimits
from ..profiles import _batch_states as B
from ..profiles.state import (
    _TABLES,
    BlockedDurationError,
    StateProfile,
    _check_limits,
    _check_range,
    _profile,
    feasible_durations,
    plan_state_to_state,
)
from ..trajectory import SYNC_MODES, Trajectory
from ._inputs import check_duration, coerce_limits, coerce_states, state_tuples

__all__ = ["plan_ptp_states", "STATE_SYNC_MODES", "COLLINEAR_RTOL"]

_log = logging.getLogger("trajkit.sync")

#: Accepted values of ``plan_ptp_states(..., sync=...)``.
STATE_SYNC_MODES = SYNC_MODES

#: Relative tolerance for "the boundary states are collinear with the
#: displacement" (phase synchronisation needs a straight line).
COLLINEAR_RTOL = 1e-9

#: Maximum re-synchronisation rounds when axes have blocked intervals.
SYNC_MAX_ROUNDS = 64

#: When step 2 of an axis finds no profile of the common duration (rare, see
#: docs/state-profiles.md "Known limits"), the duration grows by this factor.
STEP2_RETRY_FACTOR = 1.01


def plan_ptp_states(
    start: Any,
    goal: Any,
    limits: AxisLimits | Sequence[AxisLimits],
    sync: str = "time",
    duration: float | None = None,
) -> Trajectory:
    """Plan a synchronised move of several axes between moving states.

    Parameters
    ----------
    start, goal : array_like, shape (n_axes, 3) or (n_axes,)
        Per axis ``(position, velocity, acceleration)`` [unit, unit/s,
        unit/s^2]; a 1-D array gives positions at rest.
    limits : AxisLimits or sequence of n_axes AxisLimits
    sync : {"time", "phase", "none"}
        ``"time"``: every axis arrives at the same time, the smallest
        duration every axis can meet (the largest minimum, moved past any
        blocked interval). ``"phase"``: a straight line in joint space --
        possible only when every boundary velocity and acceleration is
        collinear with the displacement (``v_k = c * D_k`` for one ``c``
        over all axes, same for the goal and the accelerations); otherwise
        it falls back to ``"time"`` and the trajectory's ``sync`` says
        ``"time"``. ``"none"``: each axis at its own minimum time.
    duration : float, optional
        With ``"time"``/``"phase"``: exactly this duration [s].

    Returns
    -------
    Trajectory
        Its ``axes`` are :class:`~trajkit.profiles.StateProfile` objects
        (with ``sync="time"``, made on their first access when no axis has a
        position range: the plan itself, every axis' phase table, is complete
        when this returns).

    Raises
    ------
    InvalidInputError
        Bad shapes, NaN/inf, values outside the supported range, positions
        outside a range, unreachable goal states, unknown ``sync``.
    InfeasibleError
        ``duration`` below the synchronised minimum, or inside a blocked
        interval of some axis (the message names the axis).
    """
    if sync not in STATE_SYNC_MODES:
        raise InvalidInputError(f"sync must be one of {STATE_SYNC_MODES}, got {sync!r}")
    S = state_tuples(start)
    G = state_tuples(goal)
    if S is None or G is None or len(S) != len(G) or not S:
        s = coerce_states(start, "start")
        g = coerce_states(goal, "goal")
        if s.shape != g.shape:
            raise InvalidInputError(f"start has {s.shape[0]} axes but goal has {g.shape[0]}")
        if s.shape[0] == 0:
            raise InvalidInputError("start and goal must have at least one axis")
        S = [tuple(x) for x in s.tolist()]
        G = [tuple(x) for x in g.tolist()]
    n = len(S)
    lims = coerce_limits(limits, n, named=True)
    duration = check_duration(duration, sync, states=True)

    if sync == "none":
        return Trajectory([plan_state_to_state(S[k], G[k], lims[k]) for k in range(n)], "none")
    if sync == "phase":
        traj = _phase_sync(np.array(S, dtype=float), np.array(G, dtype=float), lims, duration)
        if traj is not None:
            return traj

    fast = _sync_time_compiled(S, G, lims, duration)
    if fast is not None:
        return fast
    sets = [feasible_durations(S[k], G[k], lims[k]) for k in range(n)]
    tmin = max(d.minimum for d in sets)
    if duration is not None:
        if duration < tmin * (1.0 - DURATION_RTOL):
            k = max(range(n), key=lambda i: sets[i].minimum)
            raise InfeasibleError(
                f"duration {duration!r} s is below the minimum synchronised duration "
                f"{tmin!r} s (axis {lims[k].name})", minimum=tmin)
        for k in range(n):
            for lo, hi in sets[k].blocked:
                if lo < duration < hi:
                    raise InfeasibleError(
                        f"duration {duration!r} s lies in a blocked interval ({lo!r}, {hi!r}) s "
                        f"of axis {lims[k].name}", minimum=tmin)
        T = duration
    else:
        T = tmin
        for _ in range(SYNC_MAX_ROUNDS):
            T2 = T
            for d in sets:
                T2 = d.next_feasible(T2)
            if T2 == T:
                break
            T = T2
    slower = False
    for _ in range(SYNC_MAX_ROUNDS):
        axes: list[StateProfile] = []
        moved = False
        for k in range(n):
            if sets[k].minimum == T or (S[k] == G[k] and T == 0.0):
                axes.append(plan_state_to_state(S[k], G[k], lims[k]))
                continue
            try:
                axes.append(plan_state_to_state(S[k], G[k], lims[k], duration=T))
            except BlockedDurationError as err:
                if duration is not None:
                    raise InfeasibleError(
                        f"duration {duration!r} s lies in a blocked interval "
                        f"{err.interval!r} s of axis {lims[k].name}", minimum=tmin) from err
                T = err.interval[1]
                moved = True
                break
            except InfeasibleError:
                # step 2 found no profile of this duration on this axis (a gap of
                # the step-2 shape families, asymmetric limits with a reversal):
                # the common duration moves up to one every axis can fill
                if duration is not None:
                    raise
                T2 = T * STEP2_RETRY_FACTOR
                for d in sets:
                    T2 = d.next_feasible(T2)
                T = T2
                moved = True
                slower = True
                break
        if not moved:
            traj = Trajectory(axes, "time")
            if slower:
                _log.warning("plan_ptp_states: step 2 found no profile of the minimum common "
                             "duration %r s on an axis; planned with %r s", tmin, T)
            return traj
    raise InfeasibleError(  # pragma: no cover - would need > 64 nested blocked intervals
        "could not find a common duration outside every axis' blocked intervals")


def _sync_time_compiled(S, G, lims, duration):
    """Time synchronisation in one compiled call (:func:`._batch_states.sync_time`,
    which also checks every state against the bounds the limits were validated
    for), or None: then the Python path plans again and gives the precise error."""
    n = len(S)
    row = []
    for k in range(n):
        lim = lims[k]
        tail = lim.__dict__.get("_srow") if type(lim) is AxisLimits else None
        if tail is None:
            tail = _check_limits(lim).__dict__["_srow"]
        row += S[k]
        row += G[k]
        row += tail
    inp, pack, out = _sync_buffers(n)
    pack.pack_into(inp, 0, *row)
    status, dur, tmin, nph, nbr, shape, ph, blk, nblk = out
    code, T = B.sync_time(inp, math.nan if duration is None else float(duration), *out)
    if code != 0:
        return None
    tmins = tmin.tolist()
    nphs = nph.tolist()
    nbrs = nbr.tolist()
    shapes = shape.tolist()
    table = ph.tobytes()  # (the buffers are reused by the next call)
    if not all(lim.__dict__["_sfast"][6] for lim in lims):
        # an axis with a position range: its profile is checked now (it may raise)
        return Trajectory(_state_axes(S, G, lims, table, tmins, nphs, nbrs, shapes), "time")
    # the profile objects are made when the axes are first used; the duration now
    # (as Trajectory computes it: the longest of the axes' durations, each the
    # correctly rounded sum of its phases, which the kernel computed)
    longest = max(dur.tolist())
    return Trajectory._deferred(
        partial(_state_axes, S, G, lims, table, tmins, nphs, nbrs, shapes), longest, "time")


def _state_axes(S, G, lims, table, tmins, nphs, nbrs, shapes):
    """The axes' profiles from the compiled synchronisation's outputs (their
    positions checked against the axes' ranges)."""
    axes = []
    stride = 24 * B.NPH  # bytes per axis of the phase table
    for k in range(len(S)):
        lim = lims[k]
        prof = _profile(S[k], G[k], _TABLES[nphs[k]].unpack_from(table, k * stride), tmins[k],
                        nbrs[k], int(shapes[k]), lim)
        axes.append(prof if lim.__dict__["_sfast"][6] else _check_range(prof, lim))
    return axes


_tls = threading.local()


def _sync_buffers(n):
    """The input array of :func:`._batch_states.sync_time` for ``n`` axes, the
    struct that fills it from one flat sequence, and its output arrays (one set
    per thread and axis count, reused: every input entry is written and the
    kernel writes every output entry read back)."""
    cache = getattr(_tls, "buf", None)
    if cache is None:
        cache = _tls.buf = {}
    bufs = cache.get(n)
    if bufs is None:
        out = (np.zeros(n, dtype=np.int64), np.zeros(n), np.zeros(n), np.zeros(n, dtype=np.int64),
               np.zeros(n, dtype=np.int64), np.zeros(n), np.zeros((n, B.NPH, 3)),
               np.zeros((n, B.NBLK, 2)), np.zeros(n, dtype=np.int64))
        bufs = (np.zeros((n, B.NSYNC)), struct.Struct(f"={n * B.NSYNC}d"), out)
        if n <= 64:
            cache[n] = bufs
    return bufs


def _phase_sync(s, g, lims, duration):
    """Straight-line synchronisation, or None when the states are not collinear."""
    D = g[:, 0] - s[:, 0]
    scale = float(np.abs(D).max())
    if scale == 0.0:
        return None
    u = D / scale
    coef = []
    for col, arr in ((1, s), (2, s), (1, g), (2, g)):
        x = arr[:, col]
        c = float(np.dot(x, u) / np.dot(u, u))
        if np.abs(x - c * u).max() > COLLINEAR_RTOL * max(np.abs(x).max(), np.finfo(float).tiny):
            return None
        coef.append(c)
    moving = [k for k in range(len(D)) if D[k] != 0.0]
    # path parameter z in [0, scale]: axis k = s_k + u_k z (|u_k| <= 1)
    vmax = min(lims[k].v_max / abs(u[k]) for k in moving)
    amax = min(lims[k].a_max / abs(u[k]) for k in moving)
    jmax = min(lims[k].j_max / abs(u[k]) for k in moving)
    admax = min(lims[k].a_max_decel / abs(u[k]) for k in moving)
    jdmax = min(lims[k].j_max_decel / abs(u[k]) for k in moving)
    unit = AxisLimits(vmax, amax, jmax, admax, jdmax, name="path")
    try:
        z = plan_state_to_state((0.0, coef[0], coef[1]), (scale, coef[2], coef[3]), unit,
                                duration=duration)
    except InvalidInputError:
        return None
    axes = []
    for k in range(len(D)):
        ph = [(dt, u[k] * j, u[k] * a) for dt, j, a in
              zip(z.phase_durations, z.jerks, z.phase_accelerations)]
        axes.append(StateProfile(tuple(s[k]), tuple(g[k]), ph, z.min_duration,
                                 z.n_brake_phases, "phase", lims[k]))
    return Trajectory(axes, "phase")
