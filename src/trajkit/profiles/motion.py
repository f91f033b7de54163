"""The one motion type: piecewise-constant jerk (:class:`JerkMotion`).

Every jerk-limited motion of one coordinate in trajkit is a table of phases
of constant jerk: rest-to-rest profiles (:class:`~trajkit.profiles.Profile`),
profiles between moving states (:class:`~trajkit.profiles.StateProfile`),
the runtime's brakes and the feed pieces along a path. Like scipy's
``PPoly`` under every interpolator, :class:`JerkMotion` holds the table and
evaluates it exactly (the formula of :mod:`trajkit.profiles._phase`); the
subclasses only add their own names and planning metadata.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ._phase import phase_end, phase_eval

__all__ = ["JerkMotion", "ProfileSample", "MotionExtrema"]

#: Sorted time arrays at least this long are sampled phase by phase (slices)
#: instead of with a per-sample phase lookup.
SORTED_FAST_PATH_MIN = 64


@dataclass(frozen=True)
class ProfileSample:
    """Kinematic state sampled at one or more times.

    Each attribute is a float64 array shaped like the time argument
    (a 0-d array for a scalar time).

    Attributes
    ----------
    position : ndarray [unit]
    velocity : ndarray [unit/s]
    acceleration : ndarray [unit/s^2]
    jerk : ndarray [unit/s^3]
    """

    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray


@dataclass(frozen=True)
class MotionExtrema:
    """Exact extreme values of a motion over ``[0, duration]``.

    Attributes
    ----------
    position, velocity, acceleration : tuple of 2 float
        ``(min, max)`` [unit], [unit/s], [unit/s^2].
    position_times, velocity_times, acceleration_times : tuple of 2 float
        Times [s] where the minimum and the maximum are reached (the first).
    """

    position: tuple
    velocity: tuple
    acceleration: tuple
    position_times: tuple
    velocity_times: tuple
    acceleration_times: tuple


class JerkMotion:
    """Motion of one coordinate made of phases of constant jerk.

    Parameters
    ----------
    start_state : sequence of 3 float
        ``(position [unit], velocity [unit/s], acceleration [unit/s^2])`` at
        ``t = 0``.
    phase_durations : sequence of float
        Duration of each phase [s], >= 0.
    jerks : sequence of float
        Constant jerk of each phase [unit/s^3].
    phase_accelerations : sequence of float, optional
        Acceleration at the start of each phase [unit/s^2]; by default the
        acceleration is continuous (integrated from the start state). Give
        it where an infinite jerk limit lets the acceleration jump.
    end_state : sequence of 3 float, optional
        The state at ``t = duration`` (the goal), returned exactly there and
        continued at constant acceleration after it; by default the
        integrated end state.

    Notes
    -----
    Sampling (:meth:`sample`) integrates exactly from the phase table; before
    ``t = 0`` the start state is held, after the end the end state is
    continued at constant acceleration (``p + v dt + a dt^2/2``), which is
    rest for a rest goal. Positions are integrated as displacements from the
    start, so their round-off scales with the motion, not with ``|start|``.
    """

    __slots__ = ("start_state", "phase_durations", "jerks", "phase_accelerations",
                 "duration", "_end", "_tab")

    def __init__(self, start_state: Any, phase_durations: Any, jerks: Any,
                 phase_accelerations: Any = None, end_state: Any = None) -> None:
        p0, v0, a0 = (float(x) for x in start_state)
        self.start_state = (p0, v0, a0)
        self.phase_durations = tuple(float(x) for x in phase_durations)
        self.jerks = tuple(float(x) for x in jerks)
        if len(self.jerks) != len(self.phase_durations):
            raise ValueError("phase_durations and jerks must have the same length")
        if phase_accelerations is None:
            acc = []
            a = a0
            for dt, j in zip(self.phase_durations, self.jerks):
                acc.append(a)
                a = a + dt * j
            self.phase_accelerations = tuple(acc)
        else:
            self.phase_accelerations = tuple(float(x) for x in phase_accelerations)
        self.duration = float(math.fsum(self.phase_durations))
        self._end = None if end_state is None else tuple(float(x) for x in end_state)
        self._tab = None

    # ------------------------------------------------------------------ table
    def _table(self):
        """(tb (n+1,), P (n,) displacement, V (n,), A (n,), J (n,), end (p, v, a))."""
        c = self._tab
        if c is not None:
            return c
        n = len(self.phase_durations)
        tb = np.empty(n + 1)
        P = np.empty(n)
        Vv = np.empty(n)
        p, v, _ = 0.0, self.start_state[1], self.start_state[2]
        a = self.start_state[2]
        t = 0.0
        for k in range(n):
            dt = self.phase_durations[k]
            tb[k] = t
            P[k] = p
            Vv[k] = v
            p, v, a = phase_end(p, v, self.phase_accelerations[k], self.jerks[k], dt)
            t += dt
        tb[n] = self.duration
        end = self._end
        if end is None:
            end = (self.start_state[0] + p, v, a)
        c = (tb, P, Vv, np.array(self.phase_accelerations, dtype=float),
             np.array(self.jerks, dtype=float), end)
        self._tab = c
        return c

    @property
    def end_state(self) -> tuple:
        """``(p, v, a)`` at ``t = duration`` (declared or integrated)."""
        return self._end if self._end is not None else self._table()[5]

    @property
    def n_phases(self) -> int:
        """Number of phases."""
        return len(self.phase_durations)

    @property
    def phase_times(self) -> np.ndarray:
        """Phase boundary times, shape (n_phases + 1,) [s]: 0, ..., duration."""
        return self._table()[0].copy()

    def boundary_states(self) -> np.ndarray:
        """Exact state at every phase boundary.

        Returns
        -------
        ndarray, shape (n_phases + 1, 3)
            Position, velocity, acceleration at each boundary time (the
            acceleration is the value entering the next phase); the last row
            is the end state.
        """
        tb, P, Vv, A, _, end = self._table()
        n = self.n_phases
        out = np.empty((n + 1, 3))
        out[:n, 0] = self.start_state[0] + P
        out[:n, 1] = Vv
        out[:n, 2] = A
        out[n] = end
        return out

    # -------------------------------------------------------------- sampling
    def sample(self, t: Any) -> ProfileSample:
        """Evaluate the motion at time(s) ``t`` [s] by exact integration.

        Parameters
        ----------
        t : float or array_like, shape (n,)
            Times [s]. Before 0 the start state is held (jerk 0); at and after
            ``duration`` the end state is continued at constant acceleration.

        Returns
        -------
        ProfileSample
            Arrays shaped like ``t``.
        """
        tb, P, Vv, A, J, end = self._table()
        tt = np.asarray(t, dtype=np.float64)
        n = J.size
        T = self.duration
        p0, v0, a0 = self.start_state
        if n == 0:
            dt = np.maximum(tt, 0.0)
            pe, ve, ae = end
            before = tt < 0.0
            return ProfileSample(
                np.where(before, p0, pe + dt * (ve + 0.5 * ae * dt)),
                np.where(before, v0, ve + ae * dt),
                np.where(before, a0, ae + 0.0 * dt),
                np.zeros_like(dt),
            )
        tc = np.clip(tt, 0.0, T)
        if tc.ndim == 1 and tc.size >= SORTED_FAST_PATH_MIN and bool(np.all(tc[1:] >= tc[:-1])):
            pos, vel, acc, jer = self._sample_sorted(tc, tb, P, Vv, A, J)
        else:
            idx = np.searchsorted(tb[1:n], tc, side="right")
            dt = tc - tb[idx]
            pos, vel, acc = phase_eval(P[idx], Vv[idx], A[idx], J[idx], dt)
            jer = J[idx]
        pos = p0 + pos
        after = tt >= T
        before = tt < 0.0
        if np.any(after) or np.any(before):
            pe, ve, ae = end
            da = np.where(after, tt - T, 0.0)
            pos = np.where(after, pe + da * (ve + 0.5 * ae * da), np.where(before, p0, pos))
            vel = np.where(after, ve + ae * da, np.where(before, v0, vel))
            acc = np.where(after, ae, np.where(before, a0, acc))
            jer = np.where(after | before, 0.0, jer)
        return ProfileSample(pos, vel, acc, jer)

    def state_at(self, t: float) -> tuple[float, float, float, float]:
        """The state at one time ``t`` [s] as Python floats: what :meth:`sample`
        gives there (the same arithmetic), without arrays -- for a control loop
        that reads one setpoint per period.

        Returns
        -------
        tuple of 4 float
            ``(position, velocity, acceleration, jerk)`` [unit, unit/s,
            unit/s^2, unit/s^3].
        """
        t = float(t)
        T = self.duration
        if t >= T:
            pe, ve, ae = self.end_state
            da = t - T
            return (pe + da * (ve + 0.5 * ae * da), ve + ae * da, ae, 0.0)
        p0, v0, a0 = self.start_state
        if not t >= 0.0:  # (before the start, and NaN)
            return (p0, v0, a0, 0.0) if t < 0.0 else (math.nan,) * 4
        durs = self.phase_durations
        acc = self.phase_accelerations
        jerks = self.jerks
        # the phase table as :meth:`_table` integrates it, up to the phase holding t
        # (the last phase starting at or before t)
        p, v, tk = 0.0, v0, 0.0
        k = 0
        n = len(durs)
        while k + 1 < n:
            t_next = tk + durs[k]
            if t_next > t:
                break
            p, v, _ = phase_end(p, v, acc[k], jerks[k], durs[k])
            tk = t_next
            k += 1
        dt = t - tk
        pos, vel, a = phase_end(p, v, acc[k], jerks[k], dt)
        return (p0 + pos, vel, a, jerks[k])

    def _sample_sorted(self, tc, tb, P, Vv, A, J):
        """:meth:`sample` for sorted times: each phase on its slice, scalar coefficients."""
        m = tc.shape[0]
        n = J.size
        pos = np.empty(m)
        vel = np.empty(m)
        acc = np.empty(m)
        jer = np.empty(m)
        cuts = [0, *np.searchsorted(tc, tb[1:n], side="left").tolist(), m]
        for k in range(n):
            lo, hi = cuts[k], cuts[k + 1]
            if hi <= lo:
                continue
            dt = tc[lo:hi] - tb[k]
            pos[lo:hi], vel[lo:hi], acc[lo:hi] = phase_eval(P[k], Vv[k], A[k], J[k], dt)
            jer[lo:hi] = J[k]
        return pos, vel, acc, jer

    # -------------------------------------------------------------- extrema
    def extrema(self) -> MotionExtrema:
        """Exact minimum and maximum of position, velocity and acceleration.

        Inside a phase the acceleration is linear, the velocity quadratic
        (extremum where ``a = 0``) and the position cubic (extrema where
        ``v = 0``): the candidates are the phase ends and these roots.

        Returns
        -------
        MotionExtrema
        """
        tb, P, Vv, A, J, end = self._table()
        p0 = self.start_state[0]
        ts = [0.0]
        ps = [p0]
        vs = [self.start_state[1]]
        as_ = [self.start_state[2]]
        n = self.n_phases
        for k in range(n):
            dt = self.phase_durations[k]
            a, j, v = A[k], J[k], Vv[k]
            # the end of the last phase is the declared end state (added below)
            cand = [0.0, dt] if k < n - 1 else [0.0]
            if j != 0.0 and 0.0 < -a / j < dt:
                cand.append(-a / j)
            for r in _quad_roots(0.5 * j, a, v):
                if 0.0 < r < dt:
                    cand.append(r)
            for t in cand:
                pp, vv, aa = phase_end(P[k], v, a, j, t)
                ts.append(tb[k] + t)
                ps.append(p0 + pp)
                vs.append(vv)
                as_.append(aa)
        ts.append(self.duration)
        ps.append(end[0])
        vs.append(end[1])
        as_.append(end[2])

        def mm(xs):
            i = int(np.argmin(xs))
            k = int(np.argmax(xs))
            return (float(xs[i]), float(xs[k])), (float(ts[i]), float(ts[k]))

        pmm, pt = mm(ps)
        vmm, vt = mm(vs)
        amm, at = mm(as_)
        return MotionExtrema(pmm, vmm, amm, pt, vt, at)

    # ------------------------------------------------------------------ export
    def phases(self) -> list:
        """The phase table as a list of ``(duration [s], jerk, start acceleration)``."""
        return list(zip(self.phase_durations, self.jerks, self.phase_accelerations))

    def to_dict(self) -> dict:
        """JSON-ready phase table (axis units)."""
        return {
            "start_state": list(self.start_state),
            "end_state": list(self.end_state),
            "duration_s": self.duration,
            "phases": [
                {"duration_s": d, "jerk": j, "start_acceleration": a}
                for d, j, a in zip(self.phase_durations, self.jerks, self.phase_accelerations)
            ],
        }

    def __repr__(self) -> str:
        return (f"{type(self).__name__}(start_state={self.start_state!r}, "
                f"duration={self.duration!r}, n_phases={self.n_phases})")


def _quad_roots(qa, qb, qc):
    """Real roots of ``qa t^2 + qb t + qc`` (numerically stable)."""
    if qa == 0.0:
        return [] if qb == 0.0 else [-qc / qb]
    disc = qb * qb - 4.0 * qa * qc
    if disc < 0.0:
        return []
    sq = math.sqrt(disc)
    q = -0.5 * (qb + math.copysign(sq, qb))
    if q == 0.0:
        return [0.0]
    return [q / qa, qc / q]
