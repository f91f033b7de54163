"""N one-axis moves between states in one call: :func:`plan_state_moves`.

The same kernel as :func:`~trajkit.profiles.state.plan_state_to_state`, run
over every move in one compiled loop (:mod:`._batch_states`, in parallel over
the cores when numba is installed; plain Python otherwise), with the inputs
validated as arrays. The results are arrays (durations, phase tables); a
:class:`~trajkit.profiles.StateProfile` of any one move is built on request.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._validate import check_array
from ..errors import InfeasibleError, InvalidInputError
from ..limits import AxisLimits
from . import _batch_states as B
from . import _kernel as K
from . import _range as R
from .batch import _float_array, _limit_array
from .state import StateProfile, _family, _from_table, _split_fixed

__all__ = ["StateMoveBatch", "plan_state_moves", "PHASES_MIN"]

#: Width of the phase table the batch is planned into: a minimum-time profile
#: between states inside the limits has at most 7 phases, a brake adds up to 3.
#: A move of more phases (a requested duration with a cruise fallback) is planned
#: again into a wider table.
PHASES_MIN = 10


@dataclass(frozen=True)
class StateMoveBatch:
    """N moves between states planned at once by :func:`plan_state_moves`.

    Attributes
    ----------
    start, goal : ndarray, shape (N, 3)
        ``(position, velocity, acceleration)`` per move.
    duration, min_duration : ndarray, shape (N,)
        Duration [s] of each move (the requested one, or the minimum) and its
        minimum.
    n_phases, n_brake_phases : ndarray of int, shape (N,)
        Phases of each move and how many of them are its brake pre-phase.
    phases : ndarray, shape (N, P, 3)
        ``(duration [s], jerk, start acceleration)`` of each phase, ``P`` the
        largest phase count of the batch (at least :data:`PHASES_MIN`); rows
        past ``n_phases[i]`` are zero.
    shape_codes : ndarray, shape (N,)
        The kernel's shape code of each move (see ``StateProfile.family``).
    v_max, a_max, j_max, a_max_decel, j_max_decel : ndarray, shape (N,)
        The (broadcast) limits.
    """

    start: np.ndarray
    goal: np.ndarray
    duration: np.ndarray
    min_duration: np.ndarray
    n_phases: np.ndarray
    n_brake_phases: np.ndarray
    phases: np.ndarray
    shape_codes: np.ndarray
    v_max: np.ndarray
    a_max: np.ndarray
    j_max: np.ndarray
    a_max_decel: np.ndarray
    j_max_decel: np.ndarray

    def __len__(self) -> int:
        return int(self.duration.shape[0])

    def profile(self, i: int) -> StateProfile:
        """Move ``i`` as a :class:`~trajkit.profiles.StateProfile`."""
        lim = AxisLimits(float(self.v_max[i]), float(self.a_max[i]), float(self.j_max[i]),
                         float(self.a_max_decel[i]), float(self.j_max_decel[i]))
        n = int(self.n_phases[i])
        s = tuple(float(x) for x in self.start[i])
        g = tuple(float(x) for x in self.goal[i])
        if n == 0:
            return StateProfile(s, g, [], 0.0, 0, "none", lim)
        return _from_table(s, g, self.phases[i, :n].ravel().tolist(), n,
                           int(self.n_brake_phases[i]), float(self.min_duration[i]),
                           _family(self.shape_codes[i]), lim)


def _states(x: Any, field: str) -> np.ndarray:
    arr = check_array(x, field, ndim=2)
    if arr.shape[1] != 3:
        raise InvalidInputError(
            f"{field} must have shape (N, 3) (position, velocity, acceleration), got {arr.shape}")
    return np.ascontiguousarray(arr, dtype=float)


def _check(s, g, vm, a1, j1, a2, j2, T) -> None:
    """The supported range of the state planners (:mod:`._range`), vectorised: raises
    for the first bad move (the compiled loop checks the same per move, see
    ``_batch_states._in_range``, and this names the field)."""
    def first(mask, field, vals, why):
        if mask.any():
            i = int(np.flatnonzero(mask)[0])
            raise InvalidInputError(
                f"{field}[{i}] {float(vals[i])!r} is outside the supported range: {why}")

    for name, x in (("v_max", vm), ("a_max", a1), ("j_max", j1), ("a_max_decel", a2),
                    ("j_max_decel", j2)):
        first(np.isfinite(x) & ((x < R.MAGNITUDE_MIN) | (x > R.MAGNITUDE_MAX)), name, x,
              f"finite limits must lie in {(R.MAGNITUDE_MIN, R.MAGNITUDE_MAX)!r}")
    first(np.isinf(vm) & np.isinf(a1) & np.isinf(a2), "v_max", vm,
          "v_max and a_max cannot both be infinite between moving states")
    with np.errstate(all="ignore"):
        for name, x, y in (("a_max_decel", a2, a1), ("j_max_decel", j2, j1)):
            r = x / y
            first(np.isfinite(r) & ((r < 1.0 / R.LEG_RATIO_MAX) | (r > R.LEG_RATIO_MAX)), name, x,
                  f"the decel leg must be within a factor {R.LEG_RATIO_MAX!r} of the accel leg")
        for A, J in ((a1, j1), (a2, j2)):
            r = vm * J / (A * A)
            first(np.isfinite(r) & ((r < 1.0 / R.SHAPE_RATIO_MAX) | (r > R.SHAPE_RATIO_MAX)),
                  "v_max j_max / a_max^2", r,
                  f"must lie in {(1.0 / R.SHAPE_RATIO_MAX, R.SHAPE_RATIO_MAX)!r}")
        for name, st in (("starts", s), ("goals", g)):
            first(np.abs(st[:, 0]) > R.POSITION_MAX, f"{name} position", st[:, 0],
                  f"|position| must be at most {R.POSITION_MAX!r}")
            first(np.abs(st[:, 1]) > R.STATE_RATIO_MAX * vm, f"{name} velocity", st[:, 1],
                  f"|velocity| must be at most {R.STATE_RATIO_MAX!r} v_max")
            am = np.maximum(a1, a2)
            first(np.abs(st[:, 2]) > R.STATE_RATIO_MAX * am, f"{name} acceleration", st[:, 2],
                  f"|acceleration| must be at most {R.STATE_RATIO_MAX!r} a_max")
            jm = np.minimum(j1, j2)
            vn = np.abs(st[:, 1]) + 0.5 * st[:, 2] ** 2 / jm
            first(np.isfinite(vm) & (vn > R.STATE_RATIO_MAX * vm), f"{name} forced speed", vn,
                  f"|v| + a^2 / (2 j) must be at most {R.STATE_RATIO_MAX!r} v_max")
        d = np.abs(g[:, 0] - s[:, 0])
        first((d != 0.0) & (d < R.DISTANCE_ABS_MIN), "distance", g[:, 0] - s[:, 0],
              f"a non-zero |distance| must be at least {R.DISTANCE_ABS_MIN!r}")
    if T is not None:
        first(T > R.DURATION_MAX, "durations", T, f"must be at most {R.DURATION_MAX!r} s")


def plan_state_moves(
    starts: Any,
    goals: Any,
    v_max: Any,
    a_max: Any,
    j_max: Any,
    a_max_decel: Any = None,
    j_max_decel: Any = None,
    durations: Any = None,
) -> StateMoveBatch:
    """Plan N one-axis moves between states at once.

    Each move is what :func:`~trajkit.profiles.state.plan_state_to_state`
    plans for it (same kernel, same results); the loop is compiled and runs
    on every core when numba is installed.

    Parameters
    ----------
    starts, goals : array_like, shape (N, 3)
        ``(position, velocity, acceleration)`` per move.
    v_max, a_max, j_max : float or array_like, shape (N,)
        Limits of the accel leg (broadcast); ``inf`` as in :class:`AxisLimits`.
    a_max_decel, j_max_decel : float or array_like, shape (N,), optional
        Limits of the decel leg; ``None`` means the same as the accel leg.
    durations : float or array_like, shape (N,), optional
        Requested durations [s] (NaN entries: the minimum).

    Returns
    -------
    StateMoveBatch

    Raises
    ------
    InvalidInputError
        Bad shapes, NaN/inf states, bad limits, values outside the supported
        range, an unreachable goal state (the first such move is named).
    InfeasibleError
        A requested duration below its minimum or inside a blocked interval,
        or a start state that cannot be braked (the first such move is named).
    """
    s = _states(starts, "starts")
    g = _states(goals, "goals")
    if s.shape != g.shape:
        raise InvalidInputError(f"starts and goals must have the same shape, got {s.shape} and {g.shape}")
    n = s.shape[0]
    vm = _limit_array(v_max, "v_max", n)
    a1 = _limit_array(a_max, "a_max", n)
    j1 = _limit_array(j_max, "j_max", n)
    a2 = a1 if a_max_decel is None else _limit_array(a_max_decel, "a_max_decel", n)
    j2 = j1 if j_max_decel is None else _limit_array(j_max_decel, "j_max_decel", n)
    for aa, jj, an, jn in ((a1, j1, "a_max", "j_max"), (a2, j2, "a_max_decel", "j_max_decel")):
        both = np.isinf(aa) & np.isinf(jj)
        if both.any():
            i = int(np.flatnonzero(both)[0])
            raise InvalidInputError(f"{an}[{i}] and {jn}[{i}] cannot both be infinite")
    T = None
    if durations is not None:
        T = np.ascontiguousarray(np.broadcast_to(_float_array(durations, "durations"), (n,)))
        bad = np.isinf(T) | (T < 0.0)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise InvalidInputError(f"durations[{i}] must be finite and >= 0 s (or NaN), got {float(T[i])!r}")
    # one writable C-contiguous array per input (one compiled signature for any input)
    lim5 = np.empty((5, n))
    for k, x in enumerate((vm, a1, j1, a2, j2)):
        lim5[k] = x
    lims = tuple(lim5)
    s_in = np.require(s, requirements=("C", "W"))
    g_in = np.require(g, requirements=("C", "W"))
    Tin = np.full(n, math.nan) if T is None else T.astype(float)
    status = np.zeros(n, dtype=np.int64)
    dur = np.zeros(n)
    tmin = np.zeros(n)
    nph = np.zeros(n, dtype=np.int64)
    nbr = np.zeros(n, dtype=np.int64)
    shape = np.zeros(n)
    ph = np.zeros((n, PHASES_MIN, 3))
    with np.errstate(all="ignore"):
        B.solve_many(s_in, g_in, *lims, Tin, status, dur, tmin, nph, nbr, shape, ph)
        wide = np.flatnonzero(status == B.ST_WIDE)
        if wide.size:
            # the moves of more phases, planned again into a table wide enough for any
            wph = np.zeros((wide.size, B.NPH, 3))
            outs = (status[wide], dur[wide], tmin[wide], nph[wide], nbr[wide], shape[wide])
            B.solve_many(s_in[wide], g_in[wide], *(x[wide] for x in lims), Tin[wide], *outs, wph)
            for arr, sub in zip((status, dur, tmin, nph, nbr, shape), outs):
                arr[wide] = sub
            ph2 = np.zeros((n, int(nph[wide].max()), 3))
            ph2[:, :PHASES_MIN] = ph
            ph2[wide] = wph[:, :ph2.shape[1]]
            ph = ph2
    if T is not None:
        # durations every shape family misses: two halves, as plan_state_to_state
        # finds them
        for i in np.flatnonzero(status == K.ST_NONE).tolist():
            lim = AxisLimits(float(vm[i]), float(a1[i]), float(j1[i]), float(a2[i]), float(j2[i]))
            split = _split_fixed(tuple(float(x) for x in s[i]), tuple(float(x) for x in g[i]),
                                 lim, float(T[i]))
            if split is None:
                continue
            table, nb, code = split
            if table.shape[0] > ph.shape[1]:
                ph = np.concatenate([ph, np.zeros((n, table.shape[0] - ph.shape[1], 3))], axis=1)
            ph[i] = 0.0
            ph[i, :table.shape[0]] = table
            status[i], dur[i], nph[i], nbr[i], shape[i] = (K.ST_OK, math.fsum(table[:, 0]),
                                                           table.shape[0], nb, code)
    bad = np.flatnonzero(status != K.ST_OK)
    if bad.size:
        out = np.flatnonzero(status == B.ST_RANGE)
        if out.size:
            # (the compiled loop found it; the vectorised check names the field)
            _check(s, g, vm, a1, j1, a2, j2, T)
            raise InvalidInputError(f"move {int(out[0])} is outside the supported range of the "
                                    "state planners")
        i = int(bad[0])
        st = int(status[i])
        if st == B.ST_GOAL:
            raise InvalidInputError(f"goals[{i}] {tuple(g[i])!r} cannot be reached within the limits")
        if st == K.ST_SHORT:
            assert T is not None  # a move is too short only for a requested duration
            raise InfeasibleError(f"durations[{i}] = {float(T[i])!r} s is below the minimum "
                                  f"duration {float(tmin[i])!r} s", minimum=float(tmin[i]))
        if st == K.ST_BLOCKED:
            assert T is not None  # a duration is blocked only when one is requested
            raise InfeasibleError(f"durations[{i}] = {float(T[i])!r} s lies in a blocked interval "
                                  f"of move {i}", minimum=float(tmin[i]))
        if st == K.ST_BRAKE:
            raise InfeasibleError(f"starts[{i}] {tuple(s[i])!r} cannot be brought back within the limits")
        raise InfeasibleError(f"no profile found for move {i} from {tuple(s[i])!r} to {tuple(g[i])!r} "
                              "(please report this input)")
    return StateMoveBatch(start=s, goal=g, duration=dur, min_duration=tmin, n_phases=nph,
                          n_brake_phases=nbr, phases=ph, shape_codes=shape, v_max=vm, a_max=a1,
                          j_max=j1, a_max_decel=a2, j_max_decel=j2)
