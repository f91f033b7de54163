"""The streaming fixed-period interpolator: one setpoint per control period.

How it works
------------
The program is a function of *program time* ``tau``: ``Q(tau)`` with
derivatives ``Q'`` and ``Q''`` (:class:`~trajkit.runtime.source.ProgramSource`).
The streamer advances ``tau`` at a *rate* ``s = dtau/dt`` in ``[0, 1]``
(the feed override; ``s = 0`` is a stop on the path) and outputs::

    q = Q(tau),   q' = Q'(tau) s,   q'' = Q''(tau) s^2 + Q'(tau) s'

The rate follows a jerk-limited law towards its target (``max_rate`` times
the override, or 0 when paused / stopping on the path) with ``|s'| <= sigma1``
and ``|s'(k+1) - s'(k)| <= sigma2 * period`` (:attr:`Streamer.rate_limits`).

Proof that no limit is exceeded (velocity, acceleration *and jerk*): with the
program's envelope per axis (:attr:`ProgramSource.envelope`: ``V >= |Q'|``,
``A_acc``/``A_dec`` bounds of ``sign(Q') Q''``, ``J >= |Q'''|``) and the
machine's limits, ``q''' = Q''' s^3 + 3 Q'' s s' + Q' s''`` gives::

    A_acc s^2 + V sigma1 <= a_max,   A_dec s^2 + V sigma1 <= a_max_decel
    J s^3 + 3 max(A_acc, A_dec) s sigma1 + V sigma2 <= min(j_max, j_max_decel)
    sigma2 <= j_max (1 - J s^3 / j_max) / V            (velocity look-ahead)

at the top rate ``s``; :func:`override_rate_limits` picks the pair with the
shortest stop. The stream is discrete (``s'`` constant in a cycle, ``tau``
advances by ``period (s_k + s_k+1) / 2``); its jerk ``(a_k+1 - a_k) / period``
splits exactly into ``Delta Q'' s_k+1^2 + Q'' (s_k+1^2 - s_k^2) +
Delta Q' s'_k+1 + Q' Delta s'``, each bounded by the same terms
(``|Delta Q''| <= J period s_mean``, ``|Delta Q'| <= A period s_mean``), so
the bound holds per cycle with no O(period) remainder (:attr:`jerk_bound`).
The leg of the stream can differ from the program's (the program speeds
up while the falling rate makes the axis slow down), hence the ``min`` of
the two jerk limits; :func:`override_limits` plans with that.

Programs streamed with override are planned with :func:`override_limits`
(:data:`OVERRIDE_RESERVE` of the acceleration and jerk limits) and streamed
under the machine's full limits (``limits=``). A program without slack at
``max_rate`` (planned at full limits) gets the proven *ceiling*
:func:`reserve_rate` (the rate at which it has the reserve's slack): rate
changes below it follow the law; above it the rate holds (``s' = 0``, so
``q''' = Q''' s^3``) and switches to its target at the next stop point (all
axes at rest), where nothing jumps; a controlled stop there is the
per-axis brake. Callers that want immediate override on such a program
(the HMI) pass ``max_rate=reserve_rate(...)``. Each cycle ``s'`` is still
clipped to the admissible interval of the accelerations and the velocity
look-ahead (``-a_max_decel <= sign(Q') q'' <= min(a_max,
sqrt(2 j_max (v_max - |q'|)))``) as a safety net: with rate limits from the
proof it never acts (:attr:`Streamer.clip_count`, tested), and it is what
keeps velocity and acceleration for a program whose envelope exceeds the
limits (no jerk proof then).

Controlled stop: on a continuous-path (LIN/CIRC) segment, and for every
pause, the target rate becomes 0 and the machine stops on the path; on
joint (PTP) segments and for position/velocity/acceleration faults each
axis brakes in minimum time from its commanded velocity and acceleration
(:func:`~trajkit.runtime.brake_profile`). Emergency stop: the output buffer
is cleared (the last output position is held), the drives are disabled and
the brakes engaged.

State machine::

    idle --start--> running --stop--> stopping --(at rest)--> idle
    running/stopping --fault--> stopping --(at rest)--> fault
    any --estop--> fault;   fault --reset--> reset --(1 cycle)--> idle

``start()`` after a stop resumes the program where it stopped; when the
machine left the path (per-axis brake, emergency stop) it first moves back
to the path point on a rest-to-rest PTP move.
"""

from __future__ import annotations

import asyncio
import logging
import math
import threading
from collections import deque
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._validate import check_finite, check_positive
from ..errors import InvalidInputError, TrajkitError
from ..limits import AxisLimits
from ..sync import plan_ptp, plan_ptp_states
from ..trajectory import Trajectory
from ._brake import BrakeProfile, brake_profile
from ._warmup import warm_up
from .pulses import PulseAxis, check_pulse_equivalents, pulse_count
from .safety import Monitors, RuntimeFault, SafetyConfig
from .servo import ServoBank, ServoParams
from .source import ProgramSource, as_source

__all__ = [
    "BLOCK_CYCLES",
    "OVERRIDE_RESERVE",
    "RATE_SNAP",
    "REENTRY_ATOL",
    "STATES",
    "RuntimeEvent",
    "Setpoint",
    "Streamer",
    "override_limits",
    "override_rate_limits",
    "slowdown_rate_table",
    "reserve_rate",
]

_log = logging.getLogger("trajkit.runtime")

#: Runtime states.
STATES = ("idle", "running", "stopping", "fault", "reset")

#: Setpoints sampled ahead in one vectorised call while the rate is steady.
BLOCK_CYCLES = 256

#: The rate snaps to its target when within this distance (and ``s'`` tiny).
RATE_SNAP = 1e-9

#: A held position within this distance [unit] of the path point needs no re-entry move.
REENTRY_ATOL = 1e-9

#: Default rate limits as a fraction of ``min_i a_i / v_i`` and ``min_i j_i / v_i``.
RATE_LIMIT_FRACTION = 0.5

#: Default following-error limit as a multiple of the servo in-position window.
FE_WINDOW_FACTOR = 50.0

#: Planning reserve for programs streamed with feed override: they are planned
#: with ``reserve`` times the machine's acceleration and jerk limits
#: (:func:`override_limits`); the rest is what a change of the rate may use.
OVERRIDE_RESERVE = 0.8

#: Safety factor on the rate limits derived from the slack (float round-off).
RATE_BOUND_SAFETY = 1.0 - 1e-6

#: Candidate values of ``sigma1`` tried between 0 and its largest admissible value.
RATE_GRID = 200

#: Levels of the rate at which the slowing-down rate limits are tabulated
#: (:func:`slowdown_rate_table`).
SLOWDOWN_LEVELS = 16


def override_limits(limits: Sequence[AxisLimits], reserve: float = OVERRIDE_RESERVE) -> list[AxisLimits]:
    """Planning limits for a program that is streamed with feed override.

    Accelerations of both legs times ``reserve`` (:meth:`AxisLimits.derated`),
    and the jerk of *both* legs ``reserve * min(j_max, j_max_decel)``: the leg
    of the stream can differ from the leg of the program while the rate
    changes (the program speeds up, the slowing rate makes the axis slow
    down), so the proof needs the program's jerk below the smaller machine
    jerk. The velocity limit is kept.

    Parameters
    ----------
    limits : sequence of AxisLimits
        The machine's limits (what the monitors enforce).
    reserve : float
        Factor in (0, 1) [-].

    Returns
    -------
    list of AxisLimits

    Raises
    ------
    InvalidInputError
        ``reserve`` not in (0, 1] (named ``accel``/``jerk`` factor).
    """
    out = []
    for lm in limits:
        d = lm.derated(accel=reserve, jerk=reserve)
        jm = reserve * min(lm.j_max, lm.j_max_decel)
        out.append(AxisLimits(d.v_max, d.a_max, jm, d.a_max_decel, jm,
                              d.position_min, d.position_max, lm.name))
    return out


def _machine(limits: Sequence[AxisLimits]) -> tuple[np.ndarray, ...]:
    v = np.array([lm.v_max for lm in limits], dtype=float)
    a = np.array([lm.a_max for lm in limits], dtype=float)
    ad = np.array([lm.a_max_decel for lm in limits], dtype=float)
    j = np.array([lm.j_max for lm in limits], dtype=float)
    jm = np.array([min(lm.j_max, lm.j_max_decel) for lm in limits], dtype=float)
    return v, a, ad, j, jm


def _rate_bounds(envelope: np.ndarray, limits: Sequence[AxisLimits],
                 top: float) -> tuple[np.ndarray, ...]:
    """Per-axis bounds: sigma1 <= s1max, 3 A top sigma1 + V sigma2 <= sj, sigma2 <= s2v."""
    V, Aa, Ad, J = (np.asarray(x, dtype=float) for x in envelope)
    _, a, ad, j, jm = _machine(limits)
    mv = V > 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        s1max = np.where(mv, np.minimum(a - Aa * top ** 2, ad - Ad * top ** 2) / V, np.inf)
        sj = np.where(mv, jm - J * top ** 3, np.inf)
        mu = np.where(mv, J * top ** 3 / j, 0.0)
        s2v = np.where(mv, j * (1.0 - mu) / V, np.inf)
    A = np.maximum(Aa, Ad)
    return V, A, s1max, sj, s2v, mv


def override_rate_limits(envelope: Any, limits: Sequence[AxisLimits],
                         max_rate: float = 1.0) -> tuple[float, float] | None:
    """Largest rate limits ``(sigma1, sigma2)`` that keep every limit, or None.

    With the program's envelope per axis (:attr:`ProgramSource.envelope`:
    ``V >= |Q'|``, ``A_acc``/``A_dec`` bounds of ``sign(Q') Q''``,
    ``J >= |Q'''|``) and the machine's limits ``v, a, a_dec, j, j_dec``,
    a rate ``0 <= s <= max_rate`` with ``|s'| <= sigma1``,
    ``|s''| <= sigma2`` gives

        sign(q') q''  = sign(Q') Q'' s^2 + |Q'| s'   in [-(A_dec s^2 + V sigma1), A_acc s^2 + V sigma1]
        |q'''|        <= J s^3 + 3 max(A_acc, A_dec) s sigma1 + V sigma2

    so the conditions (per axis, ``s = max_rate``)

        A_acc s^2 + V sigma1 <= a,    A_dec s^2 + V sigma1 <= a_dec
        J s^3 + 3 A s sigma1 + V sigma2 <= min(j, j_dec)
        sigma2 <= j (1 - J s^3 / j) / V          (velocity look-ahead)

    prove the limits for every override sequence. Among the admissible pairs
    the one with the shortest stop from ``max_rate`` (``s/sigma1 + sigma1/sigma2``)
    is returned, times :data:`RATE_BOUND_SAFETY`.

    Parameters
    ----------
    envelope : array_like, shape (4, n_axes)
    limits : sequence of AxisLimits (n_axes)
        Machine limits.
    max_rate : float
        Largest rate ``s`` [-] in (0, 1].

    Returns
    -------
    (float, float) or None
        ``(sigma1 [1/s], sigma2 [1/s^2])``; None when the program has no
        slack at ``max_rate`` (some axis uses its full acceleration or jerk).
    """
    V, A, s1max, sj, s2v, mv = _rate_bounds(envelope, limits, max_rate)
    if not mv.any():
        return (1.0, 1e3)
    if np.any(s1max[mv] <= 0.0) or np.any(sj[mv] <= 0.0) or np.any(s2v[mv] <= 0.0) \
            or np.any(~np.isfinite(sj[mv] * 0.0 + A[mv] + V[mv])):
        return None
    with np.errstate(divide="ignore", invalid="ignore"):
        s1hi = float(min(np.min(s1max[mv]), np.min(np.where(A[mv] > 0, sj[mv] / (3.0 * A[mv] * max_rate),
                                                               np.inf))))
    if not math.isfinite(s1hi):
        s1hi = 1e3
    # every candidate sigma1 at once: sigma2 is the largest the axes allow for it
    s1 = s1hi * np.linspace(1.0 / RATE_GRID, 1.0, RATE_GRID)
    s2 = np.min(np.minimum((sj[mv][None, :] - 3.0 * A[mv][None, :] * max_rate * s1[:, None])
                           / V[mv][None, :], s2v[mv][None, :]), axis=1)
    ok = s2 > 0.0
    if not ok.any():
        return None
    s1, s2 = s1[ok], np.minimum(s2[ok], 1e6)
    i = int(np.argmin(max_rate / s1 + s1 / s2))  # the shortest stop from max_rate
    return float(s1[i]) * RATE_BOUND_SAFETY, float(s2[i]) * RATE_BOUND_SAFETY


def reserve_rate(envelope: Any, limits: Sequence[AxisLimits], reserve: float = OVERRIDE_RESERVE,
                 max_rate: float = 1.0) -> float:
    """Rate at which a program leaves the same slack as one planned with ``reserve``.

    The largest ``s <= max_rate`` with ``J s^3 <= reserve min(j, j_dec)`` and
    ``A_acc s^2 <= reserve a``, ``A_dec s^2 <= reserve a_dec`` on every axis
    (running at rate ``s`` is the program time-scaled by ``s``).

    Returns
    -------
    float
        Rate [-] in (0, max_rate].
    """
    V, Aa, Ad, J = (np.asarray(x, dtype=float) for x in envelope)
    _, a, ad, _, jm = _machine(limits)
    r = float(max_rate)
    with np.errstate(divide="ignore", invalid="ignore"):
        for num, den, p in ((reserve * jm, J, 1.0 / 3.0), (reserve * a, Aa, 0.5), (reserve * ad, Ad, 0.5)):
            m = (V > 0.0) & (den > 0.0)
            if m.any():
                r = min(r, float(np.min((num[m] / den[m]) ** p)))
    return max(r, 1e-6)


def slowdown_rate_table(envelope: Any, limits: Sequence[AxisLimits], top: float,
                        levels: int = SLOWDOWN_LEVELS) -> tuple[np.ndarray, np.ndarray] | None:
    """Rate limits for a rate that only decreases, by level of the rate.

    The conditions of :func:`override_rate_limits` get weaker as the rate
    ``s`` falls (``A s^2``, ``J s^3`` and ``3 A s sigma1`` shrink), so a
    stop or slow-down may use larger ``(sigma1, sigma2)`` the lower the rate
    already is. Level ``i`` holds the componentwise minimum of the pairs
    admissible at levels ``<= u_i``: admissible at ``u_i`` (every condition
    grows with sigma1 and sigma2) and non-increasing in the level, so while
    ``s`` falls the pair in use never has to shrink. The streamer uses the
    pair of the lowest level ``>=`` the cycle's rates while ``s' <= 0``.

    Parameters
    ----------
    envelope : array_like, shape (4, n_axes)
    limits : sequence of AxisLimits
        Machine limits.
    top : float
        Highest rate [-] (the streamer's ceiling).
    levels : int
        Number of levels ``u_i = top * i / levels``.

    Returns
    -------
    (ndarray, ndarray) or None
        Levels, shape (levels,), and pairs, shape (levels, 2); None when
        some level has no admissible pair.
    """
    us = top * np.arange(1, levels + 1) / levels
    pairs = []
    for u in us:
        p = override_rate_limits(envelope, limits, float(u))
        if p is None:
            return None
        pairs.append(p)
    arr = np.minimum.accumulate(np.array(pairs, dtype=float), axis=0)
    return us, arr


@dataclass
class Setpoint:
    """One control period's output.

    Attributes
    ----------
    cycle : int
        Cycle number (0-based).
    t : float
        Time of this setpoint, ``cycle * period`` [s].
    state : str
        One of :data:`STATES` after this cycle.
    paused : bool
    tau : float
        Program time [s].
    progress : float
        ``tau / duration`` in [0, 1].
    motion : int
        Index of the running motion (``source.motion_labels``).
    override : float
        Current rate ``s`` in [0, 1] (the applied override).
    position, velocity, acceleration : ndarray, shape (n_axes,)
        Commanded joint state [unit, unit/s, unit/s^2].
    actual : ndarray, shape (n_axes,) or None
        Simulated measured position (servo simulation) [unit].
    following_error : ndarray, shape (n_axes,) or None
        ``position - actual`` [unit].
    pulses : ndarray of int, shape (n_axes,) or None
        Signed pulses emitted this period.
    pulse_count : ndarray of int, shape (n_axes,) or None
        Accumulated pulse count (equals ``round(position / pulse_equivalent)``).
    fault : RuntimeFault or None
        The fault detected on this cycle.
    """

    cycle: int
    t: float
    state: str
    paused: bool
    tau: float
    progress: float
    motion: int
    override: float
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    actual: np.ndarray | None = None
    following_error: np.ndarray | None = None
    pulses: np.ndarray | None = None
    pulse_count: np.ndarray | None = None
    fault: RuntimeFault | None = None

    def to_dict(self) -> dict:
        """JSON-ready dict (lists of floats / ints)."""
        def lst(x: np.ndarray | None) -> list[float | int] | None:
            return None if x is None else [float(v) if isinstance(v, (float, np.floating))
                                           else int(v) for v in x]
        return {
            "cycle": self.cycle, "t": self.t, "state": self.state, "paused": self.paused,
            "tau": self.tau, "progress": self.progress, "motion": self.motion,
            "override": self.override, "position": lst(self.position),
            "velocity": lst(self.velocity), "acceleration": lst(self.acceleration),
            "actual": lst(self.actual), "following_error": lst(self.following_error),
            "pulses": lst(self.pulses), "pulse_count": lst(self.pulse_count),
            "fault": None if self.fault is None else str(self.fault),
        }


@dataclass(slots=True)
class _Block:
    """Setpoints sampled ahead while the rate is steady: program times
    ``taus`` (shape (m,)), the program's ``Q, Q', Q''`` there (shape
    (m, n_axes)) and the index ``i`` of the next row to output."""

    taus: np.ndarray
    Q: np.ndarray
    Qd: np.ndarray
    Qdd: np.ndarray
    i: int


#: A per-axis brake in progress: the profiles, their positions, velocities
#: and accelerations per cycle (shape (m, n_axes)) and the next row.
_BrakeRun = tuple[list[BrakeProfile], np.ndarray, np.ndarray, np.ndarray, int]


@dataclass(frozen=True)
class RuntimeEvent:
    """An entry of the event log.

    Attributes
    ----------
    cycle : int
    t : float [s]
    kind : str
        ``start``, ``override``, ``pause``, ``paused``, ``resume``, ``stop``,
        ``stopped``, ``estop``, ``fault``, ``reset``, ``reentry``,
        ``in_position``, ``finished`` or ``rejected``.
    state : str
        State after the event.
    message : str
    """

    cycle: int
    t: float
    kind: str
    state: str
    message: str


class Streamer:
    """Streaming interpolator with override, pause, controlled stop, safety, pulses and servo.

    Parameters
    ----------
    program : ProgramSource or anything :func:`as_source` accepts
    period : float
        Control period [s], > 0.
    limits : sequence of AxisLimits, optional
        Limits the monitors enforce (default: the program's joint limits).
    servo : ServoParams or sequence of ServoParams, optional
        Simulate the servo axes (actual position, following error).
    pulse_equivalents : float or sequence of float, optional
        Travel per pulse per axis [unit/pulse]; enables pulse output.
    max_pulse_rate : float or sequence of float
        Largest pulse rate per axis [pulses/s] (default: no check).
    safety : SafetyConfig, optional
    wait_in_position : bool
        Hold program time at ``program.stop_points`` until every axis is in
        position (needs ``servo``).
    rate_limits : (float, float), optional
        ``(sigma1 [1/s], sigma2 [1/s^2])``: largest rate of change of the
        override and of that rate. Default: :func:`override_rate_limits`
        of the program's envelope and ``limits`` (the proof); given values
        are checked against the same inequalities.
    max_rate : float
        Rate ``s`` [-] in (0, 1] that an override of 100 % gives (the
        program time-scaled by it). :func:`reserve_rate` gives the rate that
        leaves a program planned at full limits the slack of
        :data:`OVERRIDE_RESERVE`.

    Attributes
    ----------
    rate_ceiling : float
        Largest rate at which rate changes are proven (``max_rate`` when
        the program has slack there, else :func:`reserve_rate`).
    jerk_bound : ndarray, shape (n_axes,)
        Proven bound of the stream's jerk ``|q'''|`` (and of ``|Delta a| / period``)
        per axis [unit/s^3] (``J s^3 + 3 A s sigma1 + V sigma2`` at the ceiling).
    clip_count : int
        Cycles on which the admissible-interval clip changed ``s'`` (0 when
        the rate limits come from the proof).

    Raises
    ------
    InvalidInputError
        Bad period, limits, pulse or servo settings, ``max_rate`` outside
        (0, 1], or ``rate_limits`` that the program's slack does not allow
        (the message names the axis, the bound and the value).

    Notes
    -----
    Commands (:meth:`start`, :meth:`set_override`, :meth:`pause`,
    :meth:`resume`, :meth:`stop`, :meth:`estop`, :meth:`reset`,
    :meth:`inject_encoder_jump`) are thread-safe: they are queued and
    applied at the start of the next cycle.

    Making a streamer makes the compiled kernels of its cycle ready
    (:func:`~trajkit.runtime.warm_up`: the brake of every stop and of the
    safety look-ahead, the planner of online targets), so that no cycle
    waits for the compiler. With numba installed, the first streamer after
    an install therefore takes minutes to make (``trajkit warmup`` does it
    ahead); later ones, in any process, about a second at most.
    """

    def __init__(self, program: Any, period: float, *, limits: Sequence[AxisLimits] | None = None,
                 servo: ServoParams | Sequence[ServoParams] | None = None,
                 pulse_equivalents: Any = None, max_pulse_rate: Any = math.inf,
                 safety: SafetyConfig | None = None, wait_in_position: bool = False,
                 rate_limits: tuple[float, float] | None = None, max_rate: float = 1.0) -> None:
        # the kernels of its cycle (brake, online targets) compiled now, not in a cycle
        warm_up(("runtime",))
        self.source: ProgramSource = as_source(program)
        src = self.source
        self.period = check_positive(period, "period")
        n = src.n_axes
        self.n_axes = n
        lims = tuple(limits) if limits is not None else src.limits
        if len(lims) != n:
            raise InvalidInputError(f"limits must have {n} AxisLimits, got {len(lims)}")
        self.limits = tuple(lm.with_name(nm) if lm.name is None else lm
                            for lm, nm in zip(lims, src.names))
        self.safety = safety if safety is not None else SafetyConfig()
        self.servo: ServoBank | None = None
        if servo is not None:
            self.servo = ServoBank(servo, n, self.period, src.start_position)
        fe = self.safety.following_error
        if fe is None:
            fe = (FE_WINDOW_FACTOR * self.servo.window) if self.servo is not None else np.full(n, np.inf)
        fe = np.broadcast_to(np.asarray(fe, dtype=float), (n,)).copy()
        if np.any(~(fe > 0)):
            raise InvalidInputError(f"following_error limits must be > 0, got {fe.tolist()}")
        self.monitors = Monitors(self.limits, src.names, fe, self.safety.look_ahead)
        self.pulse_axes: list[PulseAxis] | None = None
        self._peq: list[float] = []
        if pulse_equivalents is not None:
            eqs = check_pulse_equivalents(pulse_equivalents, n)
            rates = np.broadcast_to(np.asarray(max_pulse_rate, dtype=float), (n,))
            self.pulse_axes = [PulseAxis(e, r, p, nm) for e, r, p, nm in
                               zip(eqs, rates, src.start_position, src.names)]
            self._peq = [pa.pulse_equivalent for pa in self.pulse_axes]
        self.wait_in_position = bool(wait_in_position) and self.servo is not None
        top = check_finite(max_rate, "max_rate")
        if not 0.0 < top <= 1.0:
            raise InvalidInputError(f"max_rate must be in (0, 1], got {max_rate!r}")
        self.max_rate = top
        env = src.envelope
        ceil = top
        auto = override_rate_limits(env, self.limits, top)
        if auto is None:
            ceil = min(top, reserve_rate(env, self.limits))
            auto = override_rate_limits(env, self.limits, ceil)
        self.rate_ceiling = ceil
        if rate_limits is None:
            if auto is None:  # the program itself exceeds a limit: legacy law, clip only
                vm = np.array([lm.v_max for lm in self.limits])
                am = np.array([min(lm.a_max, lm.a_max_decel) for lm in self.limits])
                jm = np.array([min(lm.j_max, lm.j_max_decel) for lm in self.limits])
                s1 = RATE_LIMIT_FRACTION * float(np.min(am / vm))
                s2 = RATE_LIMIT_FRACTION * float(np.min(jm / vm))
                auto = (s1 if math.isfinite(s1) and s1 > 0 else 1.0,
                        s2 if math.isfinite(s2) and s2 > 0 else 1e3)
                self.rate_ceiling = ceil = 0.0
            rate_limits = auto
        auto_pair = rate_limits is auto and ceil > 0.0
        self.rate_limits = (check_positive(rate_limits[0], "rate_limits[0]"),
                            check_positive(rate_limits[1], "rate_limits[1]"))
        V, A, s1max, sj, s2v, mv = _rate_bounds(env, self.limits, max(ceil, 1e-300))
        s1, s2 = self.rate_limits
        self.jerk_bound = np.where(mv, env[3] * ceil ** 3 + 3.0 * A * ceil * s1 + V * s2, 0.0)
        # stops and slow-downs: larger rate limits the lower the rate (proven per level)
        self._slow_table = slowdown_rate_table(env, self.limits, ceil) if auto_pair else None
        self._slow_s2max = 0.0
        if self._slow_table is not None:
            us, arr = self._slow_table
            self._slow_s2max = float(arr[:, 1].max())
            Vl, Al = V[:, None], A[:, None]
            per_level = env[3][:, None] * us ** 3 + 3.0 * Al * us * arr[:, 0] + Vl * arr[:, 1]
            self.jerk_bound = np.where(mv, np.maximum(self.jerk_bound, per_level.max(axis=1)), 0.0)
        if ceil > 0.0:
            for k in np.nonzero(mv)[0]:
                nm = self.limits[k].name
                if s1 > s1max[k] * (1.0 + 1e-9):
                    raise InvalidInputError(
                        f"rate_limits[0] {s1!r} of axis {nm} exceeds {float(s1max[k])!r} 1/s: "
                        f"the program's acceleration envelope plus V sigma1 would exceed the "
                        f"acceleration limit")
                if 3.0 * A[k] * ceil * s1 + V[k] * s2 > sj[k] * (1.0 + 1e-9) or s2 > s2v[k] * (1.0 + 1e-9):
                    raise InvalidInputError(
                        f"rate_limits {self.rate_limits!r} of axis {nm}: the stream's jerk bound "
                        f"{float(self.jerk_bound[k])!r} exceeds the jerk limit "
                        f"{float(min(self.limits[k].j_max, self.limits[k].j_max_decel))!r} "
                        f"(or sigma2 exceeds the velocity look-ahead bound {float(s2v[k])!r})")
        self.clip_count = 0
        self._am = np.array([lm.a_max for lm in self.limits])
        self._vm = np.array([lm.v_max for lm in self.limits])
        self._jm2 = 2.0 * np.array([lm.j_max for lm in self.limits])
        self._ad = np.array([lm.a_max_decel for lm in self.limits])
        # ---- run state
        self._lock = threading.Lock()
        self._cmds: deque[tuple[Any, ...]] = deque()
        self.state = "idle"
        self.paused = False
        self.finished = False
        self.fault: RuntimeFault | None = None
        self.events: list[RuntimeEvent] = []
        self.cycle = 0
        self.override = 1.0
        self.tau = 0.0
        self.s = 0.0
        self.sd = 0.0
        self._mode = "hold"  # hold | path | brake | detour | target
        self._stop_kind: str | None = None  # None | "command" | "fault"
        self._path_stop = False
        self._q = src.start_position.copy()
        self._v = np.zeros(n)
        self._a = np.zeros(n)
        self._blk: _Block | None = None
        self._brake: _BrakeRun | None = None
        self._detour: tuple[Trajectory, int] | None = None
        self._online: tuple[Trajectory, int] | None = None
        self._stops: list[float] = list(src.stop_points) if self.wait_in_position else []
        self._settle = 0
        self._waiting = False
        self.stop_log: list[tuple[float, float, float]] = []
        self._wait_since: float | None = None
        self._pause_logged = False
        self._last: Setpoint | None = None
        self._mcache: tuple[int, float, float] | None = None
        if self.rate_ceiling < self.max_rate:
            _log.info(
                f"override changes are proven up to rate {self.rate_ceiling:.4g} only (the program "
                "leaves no slack at full rate: plan it with override_limits); above it the rate "
                "changes at the program's stop points", )

    @classmethod
    def hold_at(cls, position: Any, period: float, limits: Sequence[AxisLimits],
                **kwargs: Any) -> Streamer:
        """A streamer whose program is to stand still at ``position``: for online
        targets only (:meth:`set_target`; e.g. a jog without a loaded job).

        Parameters
        ----------
        position : array_like, shape (n_axes,)
            Where the axes are [unit].
        period : float
            Control period [s].
        limits : sequence of AxisLimits
            One per axis (the targets are planned and monitored with these).
        **kwargs
            Further :class:`Streamer` options (``servo``, ``pulse_equivalents``, ...).
        """
        q = np.asarray(position, dtype=float)
        lims = list(limits)
        return cls(plan_ptp(q, q, lims), period, limits=lims, **kwargs)

    # ================================================================ commands
    def _push(self, *cmd: Any) -> None:
        with self._lock:
            self._cmds.append(cmd)

    def start(self) -> None:
        """Start (idle -> running), or resume the program after a stop/reset."""
        self._push("start")

    def set_override(self, percent: float) -> None:
        """Set the feed override [%] in 0..100 (applied smoothly).

        Raises
        ------
        InvalidInputError
            Outside 0..100 or not finite.
        """
        x = check_finite(percent, "override")
        if not 0.0 <= x <= 100.0:
            raise InvalidInputError(f"override must be in [0, 100] %, got {x!r}")
        self._push("override", x / 100.0)

    def pause(self) -> None:
        """Stop on the path (controlled); :meth:`resume` continues."""
        self._push("pause")

    def resume(self) -> None:
        """Continue after :meth:`pause`."""
        self._push("resume")

    def stop(self) -> None:
        """Controlled stop (running -> stopping -> idle)."""
        self._push("stop")

    def estop(self) -> None:
        """Emergency stop: clear the output, disable the drives, engage the brakes."""
        self._push("estop")

    def reset(self) -> None:
        """Acknowledge a fault (fault -> reset -> idle)."""
        self._push("reset")

    def set_target(self, position: Any, velocity: Any = None, acceleration: Any = None, *,
                   sync: str = "time", limits: Sequence[AxisLimits] | None = None) -> None:
        """Move to a goal state now, re-planning from the commanded state (online target).

        Applied at the start of the next cycle: the axes leave the current
        commanded state ``(position, velocity, acceleration)`` -- whatever
        they were doing (a program, a previous target, at rest) -- on a
        time-optimal, jerk-limited motion between states
        (:func:`trajkit.sync.plan_ptp_states`, under :attr:`limits`), and the
        setpoint of that same cycle is already on it. Call it again at any
        time (e.g. at every jog tick) to change the goal while moving.

        Parameters
        ----------
        position : array_like, shape (n_axes,)
            Goal positions [unit].
        velocity, acceleration : array_like, shape (n_axes,), optional
            Goal velocities [unit/s] and accelerations [unit/s^2] (default 0:
            the axes stop at the goal). With a goal velocity the axes go on at
            it after arriving (the goal acceleration continued), until the
            next target or a stop.
        sync : {"time", "none"}
            ``"time"``: all axes arrive together; ``"none"``: each as fast as
            it can.
        limits : sequence of AxisLimits, optional
            One per axis: plan this target with lower limits than
            :attr:`limits` (e.g. a jog at a reduced speed). Each value must
            be within the streamer's own limit for that axis; a current
            velocity or acceleration above them is braked time-optimally
            first.

        Raises
        ------
        InvalidInputError
            A malformed goal (shape, NaN/inf), an unknown ``sync`` or
            ``limits`` above the streamer's own; a goal
            the limits cannot reach or a position outside an axis' range is
            refused when the command is applied (event ``rejected``, the
            motion goes on unchanged).

        Notes
        -----
        In state ``running`` (a program on its path, a target) or ``idle``;
        ``stop()`` brakes every axis to rest as for a program, ``estop()``
        clears the output. After a target the program does not continue by
        itself: ``start()`` returns to its path (re-entry move) and resumes it.
        """
        n = self.n_axes
        goal = np.zeros((n, 3))
        for col, value, field in ((0, position, "position"), (1, velocity, "velocity"),
                                  (2, acceleration, "acceleration")):
            if value is None:
                continue
            arr = np.asarray(value, dtype=float) if not isinstance(value, np.ndarray) else value
            try:
                arr = np.broadcast_to(np.asarray(arr, dtype=float), (n,))
            except (TypeError, ValueError):
                raise InvalidInputError(
                    f"target {field} must have {n} entries (one per axis), got {value!r}") from None
            if not np.all(np.isfinite(arr)):
                raise InvalidInputError(f"target {field} must be finite, got {arr.tolist()}")
            goal[:, col] = arr
        if sync not in ("time", "none"):
            raise InvalidInputError(f"target sync must be 'time' or 'none', got {sync!r}")
        self._push("target", goal, sync, None if limits is None else self._target_limits(limits))

    def _target_limits(self, limits: Sequence[AxisLimits]) -> list[AxisLimits]:
        """``limits`` checked against the streamer's own, one per axis."""
        lims = list(limits) if isinstance(limits, (list, tuple)) else None
        if lims is None or len(lims) != self.n_axes or not all(isinstance(lm, AxisLimits) for lm in lims):
            raise InvalidInputError(f"target limits must be {self.n_axes} AxisLimits (one per axis), "
                                    f"got {type(limits).__name__}")
        for k, (lm, own) in enumerate(zip(lims, self.limits)):
            for field in ("v_max", "a_max", "j_max", "a_max_decel", "j_max_decel"):
                val, bound = getattr(lm, field), getattr(own, field)
                if val > bound:
                    raise InvalidInputError(f"target limits[{k}].{field} = {val!r} exceeds the axis' "
                                            f"limit {bound!r} ({own.name or f'axis {k}'})")
        return lims

    @property
    def target_motion(self) -> tuple[float, float] | None:
        """``(elapsed, duration)`` [s] of the motion to the current online target, or None."""
        if self._mode != "target" or self._online is None:
            return None
        traj, i = self._online
        return min(i * self.period, traj.duration), traj.duration

    def inject_encoder_jump(self, axis: int, delta: float) -> None:
        """Fault injection: the measured position of ``axis`` jumps by ``delta`` [unit]."""
        if self.servo is None:
            raise InvalidInputError("inject_encoder_jump needs the servo simulation (servo=...)")
        if not 0 <= int(axis) < self.n_axes:
            raise InvalidInputError(f"axis must be in [0, {self.n_axes}), got {axis!r}")
        self._push("encoder", int(axis), check_finite(delta, "delta"))

    # ================================================================ helpers
    @property
    def t(self) -> float:
        """Time of the next cycle [s]."""
        return self.cycle * self.period

    def _event(self, kind: str, message: str) -> None:
        ev = RuntimeEvent(self.cycle, self.t, kind, self.state, message)
        self.events.append(ev)
        _log.info("cycle %d: %s: %s", self.cycle, kind, message)

    def snapshot(self) -> dict:
        """JSON-ready status: state, progress, override, last setpoint, fault, last events."""
        last = self._last.to_dict() if self._last is not None else None
        return {
            "state": self.state, "paused": self.paused, "finished": self.finished,
            "cycle": self.cycle, "t": self.t, "tau": self.tau,
            "progress": self.tau / self.source.duration if self.source.duration > 0 else 1.0,
            "motion": self.source.motion_at(self.tau),
            "motion_label": self.source.motion_labels[self.source.motion_at(self.tau)],
            "override_target": self.override, "rate": self.s,
            "fault": None if self.fault is None else str(self.fault),
            "setpoint": last,
            "events": [ev.__dict__ for ev in self.events[-20:]],
        }

    def _path_rest(self) -> bool:
        return self.s == 0.0 and self.sd == 0.0

    def _apply(self, cmd: tuple[Any, ...]) -> None:
        kind = cmd[0]
        if kind in ("override", "pause", "resume"):
            self._blk = None  # the rate target changes: drop the block sampled ahead
        if kind == "override":
            self.override = cmd[1]
            self._event("override", f"override {100 * cmd[1]:g} %")
        elif kind == "encoder":
            assert self.servo is not None  # queued only with the servo (inject_encoder_jump)
            self.servo.inject_encoder_jump(cmd[1], cmd[2])
            self._event("encoder", f"encoder of axis {self.source.names[cmd[1]]} jumps by {cmd[2]!r}")
        elif kind == "start":
            if self.state != "idle" or self.finished:
                self._event("rejected", f"start rejected in state {self.state}"
                            + (" (program finished)" if self.finished else ""))
                return
            self.state = "running"
            self.paused = False
            self._begin_motion()
            self._event("start", f"start at program time {self.tau:.6g} s")
        elif kind == "pause" and self._mode == "target":
            self._event("rejected", "pause rejected while moving to a target (use stop)")
        elif kind == "pause":
            if self.state == "running" and not self.paused:
                self.paused = True
                self._event("pause", "pause: stopping on the path")
        elif kind == "resume":
            if self.state == "running" and self.paused:
                self.paused = False
                self._event("resume", "resume")
            else:
                self._event("rejected", f"resume rejected in state {self.state}")
        elif kind == "stop":
            if self.state == "running":
                self._begin_stop("command")
                self._event("stop", "controlled stop")
        elif kind == "estop":
            if self.state in ("running", "stopping", "idle"):
                f = RuntimeFault("all", "emergency stop", 0.0, 0.0, self.cycle, self.t)
                self._emergency(f)
        elif kind == "target":
            self._apply_target(cmd[1], cmd[2], cmd[3])
        elif kind == "reset":
            if self.state == "fault":
                self.state = "reset"
                self.fault = None
                if self.servo is not None:
                    self.servo.release_brake()
                    self._q = self.servo.measured.copy()  # re-sync the command to the feedback
                    self._v[:] = 0.0
                    self._a[:] = 0.0
                    if self.pulse_axes is not None:
                        for k, pa in enumerate(self.pulse_axes):
                            pa.count = pulse_count(self._q[k], pa.pulse_equivalent)
                self._event("reset", "fault reset")
            else:
                self._event("rejected", f"reset rejected in state {self.state}")

    def _apply_target(self, goal: np.ndarray, sync: str, limits: list[AxisLimits] | None) -> None:
        """Re-plan from the commanded state to ``goal`` (see :meth:`set_target`)."""
        if self.state not in ("idle", "running") or self._mode == "brake":
            self._event("rejected", f"target rejected in state {self.state}")
            return
        start = np.column_stack([self._q, self._v, self._a])
        try:
            traj = plan_ptp_states(start, goal, self.limits if limits is None else limits, sync=sync)
        except TrajkitError as err:
            self._event("rejected", f"target rejected: {err}")
            return
        self._online = (traj, 0)
        self._mode = "target"
        self._blk = None
        self._path_stop = False
        self.paused = False
        self.state = "running"
        self._event("target", f"target {goal[:, 0].tolist()} in {traj.duration:.6g} s")

    def _begin_motion(self) -> None:
        qp, qdp, _ = self.source.sample(self.tau)
        off = np.abs(qp[0] - self._q)
        if np.any(off > REENTRY_ATOL * np.maximum(1.0, np.abs(qp[0]))):
            lims = [AxisLimits(lm.v_max, lm.a_max, lm.j_max, lm.a_max_decel, lm.j_max_decel,
                               name=lm.name) for lm in self.limits]
            self._detour = (plan_ptp(self._q, qp[0], lims), 0)
            self._mode = "detour"
            self.s = self.sd = 0.0
            self._event("reentry", f"re-entry move of {self._detour[0].duration:.6g} s to the "
                        f"path at program time {self.tau:.6g} s")
            return
        self._mode = "path"
        self._blk = None
        # at rest on the path (start, stop point): full rate at once; else ramp from 0
        self.s = self._target() if not np.any(qdp[0]) else 0.0
        self.sd = 0.0

    def _begin_stop(self, why: str) -> None:
        self.state = "stopping"
        self._stop_kind = why
        if self._mode == "path" and self.source.on_path(self.tau) and self._can_change_rate():
            self._path_stop = True
            self._blk = None
            return
        self._start_brake()

    def _start_brake(self) -> _BrakeRun:
        n = self.n_axes
        profs = []
        for k in range(n):
            lm = self.limits[k]
            profs.append(brake_profile(self._q[k], self._v[k], self._a[k], lm))
        T = max(p.duration for p in profs)
        m = int(math.ceil(T / self.period - 1e-12)) + 1
        tt = np.arange(1, m + 1) * self.period
        Q = np.empty((m, n))
        V = np.empty((m, n))
        A = np.empty((m, n))
        for k, p in enumerate(profs):
            s = p.sample(tt)
            Q[:, k], V[:, k], A[:, k] = s.position, s.velocity, s.acceleration
        brake = self._brake = (profs, Q, V, A, 0)
        self._online = None
        self._mode = "brake"
        self._blk = None
        return brake

    def _emergency(self, fault: RuntimeFault) -> None:
        self.fault = fault
        self._mode = "hold"
        self._v = np.zeros(self.n_axes)
        self._a = np.zeros(self.n_axes)
        self._brake = None
        self._detour = None
        self._online = None
        self.s = self.sd = 0.0
        self._path_stop = False
        self.paused = False
        if self.servo is not None:
            self.servo.engage_brake()
        self.state = "fault"
        self._event("estop" if fault.quantity == "emergency stop" else "fault",
                    f"{fault} -> emergency stop (output cleared, brakes engaged)")

    # ================================================================ one cycle
    def _target(self) -> float:
        """Target rate: the override times ``max_rate``, 0 when paused or stopping on the path."""
        return 0.0 if (self.paused or self._path_stop) else self.override * self.max_rate

    def _can_change_rate(self) -> bool:
        """True when the rate may change now (at or below the proven ceiling, or no proof at all)."""
        return self.rate_ceiling <= 0.0 or self.s <= self.rate_ceiling

    def _rate_step(self, Qd: np.ndarray, Qdd: np.ndarray) -> float:
        """Choose ``s'`` for this cycle (jerk-limited law; ``|Delta s'| <= sigma2 dt`` always)."""
        s, sd, dt = self.s, self.sd, self.period
        ceil = self.rate_ceiling if self.rate_ceiling > 0.0 else self.max_rate
        target = min(self._target(), ceil)
        s1, s2 = self.rate_limits
        tab = self._slow_table
        if tab is not None and sd <= 0.0:
            # the rate is not rising: the pair of the lowest level >= every rate of
            # this cycle (s' <= 0 now; a new s' > 0 is at most sigma2 dt); that pair
            # grows while s falls, so a falling rate never has to shrink s'. Once
            # s' > 0 the global pair applies (s' then starts from <= sigma2 dt).
            us, arr = tab
            s_hi = s + self._slow_s2max * dt * dt
            i = min(int(np.searchsorted(us, s_hi, side="left")), us.size - 1)
            if -sd <= arr[i, 0] and us[i] >= s_hi:
                s1, s2 = float(arr[i, 0]), float(arr[i, 1])
        e = target - s
        if abs(e) <= RATE_SNAP and abs(sd) <= s2 * dt:
            self.s = target
            return 0.0
        # braking curve with half the s'' budget, so the rate-limited s' can
        # follow it without lagging (no jump in s' when the target is reached)
        des = math.copysign(min(s1, math.sqrt(s2 * abs(e))), e)
        # the same braking curve towards the bounds 0 and the ceiling of the rate
        des = min(max(des, -math.sqrt(s2 * s)), math.sqrt(s2 * max(ceil - s, 0.0)))
        new = sd + min(max(des - sd, -s2 * dt), s2 * dt)
        if abs(e) <= s2 * dt * dt and abs(e / dt - sd) <= s2 * dt and abs(e / dt) <= s1:
            new = e / dt  # last step: land on the target
        new = min(max(new, -s / dt), (ceil - s) / dt)
        # safety net (never active with rate limits from the proof, see the tests):
        # -a_dec <= sign(Q') (Q'' s^2 + Q' s') <= a_cap, a_cap = min(a_max,
        # sqrt(2 j_max (v_max - |v|))): the acceleration from which a ramp-down at
        # j_max still ends at or below v_max (the velocity look-ahead)
        g = np.abs(Qd)
        m = g > 0.0
        if m.any():
            gm = g[m]
            sg = np.sign(Qd[m])
            h = sg * Qdd[m] * s * s
            cap = np.sqrt(np.maximum(self._jm2[m] * (self._vm[m] - gm * s), 0.0))
            lo = float(np.max((-self._ad[m] - h) / gm))
            hi = float(np.min((np.minimum(self._am[m], cap) - h) / gm))
            clipped = min(max(new, min(lo, 0.0)), max(hi, 0.0))
            if clipped != new:
                self.clip_count += 1
                new = clipped
        return new

    def _path_candidate(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, float, float]:
        """This cycle's ``(q, q', q'')`` on the path, and the next ``(tau, s, s')``."""
        src = self.source
        dt = self.period
        target = self._target()
        steady = (self.sd == 0.0 and not self._waiting
                  and (self.s == target or not self._can_change_rate()))
        stops = self._stops
        if steady and self.s != target:
            # above the proven ceiling: the rate holds until the next stop point
            # (rest), where it switches to the target at once
            stops = [x for x in src.stop_points if x > self.tau][:1] or [src.duration]
            if self._stops:
                stops = [min(stops[0], self._stops[0])]
        if steady and self.s > 0.0:
            blk = self._blk
            if blk is None or blk.i >= blk.taus.size or blk.taus[blk.i] != self.tau:
                taus = self.tau + self.s * dt * np.arange(BLOCK_CYCLES + 1)
                nxt = stops[0] if stops else src.duration
                taus = np.minimum(taus, nxt)
                Q, Qd, Qdd = src.sample(taus)
                blk = _Block(taus, Q, Qd, Qdd, 0)
                self._blk = blk
            i = blk.i
            blk.i = i + 1
            q, qd, qdd = blk.Q[i], blk.Qd[i], blk.Qdd[i]
            sd = 0.0
            tau_next = blk.taus[i + 1] if i + 1 < blk.taus.size else None
            if self.s != target and not np.any(qd) and not np.any(qdd):
                self.s = target  # at rest on the path: the rate switches at once
                self._blk = None
                tau_next = None
        else:
            self._blk = None
            Q, Qd, Qdd = src.sample(self.tau)
            q, qd, qdd = Q[0], Qd[0], Qdd[0]
            if self._waiting:
                sd = 0.0
            elif self.s != target and not np.any(qd) and not np.any(qdd) and self.sd == 0.0:
                self.s = target  # at rest on the path (start, stop point): no ramp needed
                sd = 0.0
            else:
                sd = self._rate_step(qd, qdd)
            tau_next = None
        s = self.s
        v = qd * s
        a = qdd * (s * s) + qd * sd
        if tau_next is None:
            tau_next = self.tau + s * dt + 0.5 * sd * dt * dt
        return q, v, a, tau_next, s + sd * dt, sd

    def step(self) -> Setpoint:
        """Run one control period and return its setpoint."""
        with self._lock:
            cmds = list(self._cmds)
            self._cmds.clear()
        for c in cmds:
            self._apply(c)
        if self.state == "reset":
            self.state = "idle"
        n = self.n_axes
        k = self.cycle
        t = k * self.period
        measured = None
        if self.servo is not None:
            if k > 0:
                self.servo.step(self._q, self._v, self._a)
            measured = self.servo.measured
        fault_now = None
        path_next = None
        tau_out = self.tau
        mode = self._mode
        if mode == "path":
            q, v, a, tau_next, s_next, sd = self._path_candidate()
            path_next = (tau_next, s_next, sd)
        elif mode == "brake":
            assert self._brake is not None  # set with the mode (_start_brake)
            profs, Q, V, A, i = self._brake
            q, v, a = Q[i], V[i], A[i]
            self._brake = (profs, Q, V, A, i + 1)
        elif mode == "target":
            assert self._online is not None  # set with the mode (_apply_target)
            traj, i = self._online
            smp = traj.sample(np.array([(i + 1) * self.period]))
            q, v, a = smp.position[0], smp.velocity[0], smp.acceleration[0]
            self._online = (traj, i + 1)
        elif mode == "detour":
            assert self._detour is not None  # set with the mode (_begin_motion)
            traj, i = self._detour
            smp = traj.sample(np.array([(i + 1) * self.period]))
            q, v, a = smp.position[0], smp.velocity[0], smp.acceleration[0]
            self._detour = (traj, i + 1)
        else:
            q, v, a = self._q, self._v, self._a
        # ---- monitors (on the candidate, before it is output)
        counts = None
        if self.state in ("running", "stopping") and mode in ("path", "detour", "brake", "target"):
            chk = self.monitors.check(q, v, a, measured if self.state == "running" else None)
            if chk is None and self.pulse_axes is not None and self.state == "running":
                counts = [math.floor(x / e + 0.5) for x, e in zip(q.tolist(), self._peq)]
                for j, pa in enumerate(self.pulse_axes):
                    rate = abs(counts[j] - pa.count) / self.period
                    if rate > pa.max_rate:
                        chk = (j, "pulse rate", rate, pa.max_rate)
                        counts = None
                        break
            if chk is not None and (self.state == "running" or mode != "brake"):
                j, qty, val, lim = chk[:4]
                fault_now = RuntimeFault(self.source.names[j], qty, val, lim, k, t,
                                         chk[4] if len(chk) > 4 else "")
                if self.safety.reaction(qty) == "emergency":
                    self._emergency(fault_now)
                    q, v, a = self._q, self._v, self._a
                else:
                    self.fault = fault_now
                    self._event("fault", f"{fault_now} -> controlled stop")
                    self.state = "stopping"
                    self._stop_kind = "fault"
                    self._path_stop = False
                    # per-axis brake from the last good state
                    profs, Q, V, A, i = self._start_brake()
                    q, v, a = Q[0], V[0], A[0]
                    self._brake = (profs, Q, V, A, 1)
                path_next = None
                counts = None
        # ---- commit the output
        if path_next is not None and self._mode == "path":
            tau_next, s_next, sd = path_next
            self.sd = sd
            self.s = min(max(s_next, 0.0), 1.0)
            if self._stops and tau_next >= self._stops[0]:
                tau_next = self._stops[0]
            self.tau = min(tau_next, self.source.duration)
            self._path_bookkeeping(q, measured, tau_out)
        elif self._mode == "brake" and self._brake is not None and self._brake[4] >= self._brake[1].shape[0]:
            self._at_rest_after_stop()
        elif self._mode == "target" and self._online is not None:
            traj, i = self._online
            if i * self.period >= traj.duration:
                gs = traj.goal_states
                if not np.any(gs[:, 1:]):
                    # at rest on the target: hold there
                    q = gs[:, 0].copy()
                    v = np.zeros(n)
                    a = np.zeros(n)
                    self._online = None
                    self._mode = "hold"
                    self.state = "idle"
                    self._event("target_reached", f"at rest on the target {q.tolist()}")
        elif self._mode == "detour" and self._detour is not None:
            traj, i = self._detour
            if i * self.period >= traj.duration:
                self._detour = None
                self._mode = "path"
                self._blk = None
                self.s = 0.0
                self.sd = 0.0
                q = self.source.sample(self.tau)[0][0]
                v = np.zeros(n)
                a = np.zeros(n)
        # rows of the sampled blocks are never written to: no copies needed
        self._q, self._v, self._a = q, v, a
        pulses = pulse_counts = None
        if self.pulse_axes is not None:
            if counts is None:
                counts = [math.floor(x / e + 0.5) for x, e in zip(q.tolist(), self._peq)]
            d = []
            for j, pa in enumerate(self.pulse_axes):
                dj = counts[j] - pa.count
                pa.count = counts[j]
                if dj:
                    pa.direction = 1 if dj > 0 else -1
                d.append(dj)
            pulses = np.array(d, dtype=np.int64)
            pulse_counts = np.array(counts, dtype=np.int64)
        fe = None if measured is None else self._q - measured
        src = self.source
        sp = Setpoint(
            k, t, self.state, self.paused, tau_out,
            tau_out / src.duration if src.duration > 0 else 1.0,
            self._motion_index(tau_out), self.s, self._q, self._v, self._a,
            None if measured is None else measured.copy(), fe, pulses, pulse_counts, fault_now,
        )
        self._last = sp
        self.cycle = k + 1
        return sp

    def _motion_index(self, tau: float) -> int:
        c = self._mcache
        if c is None or not (c[1] <= tau < c[2]):
            i = self.source.motion_at(tau)
            ms = self.source.motion_starts
            lo = ms[i] if i > 0 else -math.inf
            hi = ms[i + 1] if i + 1 < ms.size else math.inf
            c = self._mcache = (i, lo, hi)
        return c[0]

    def _path_bookkeeping(self, q: np.ndarray, measured: np.ndarray | None, tau_out: float) -> None:
        src = self.source
        if self._path_stop and self._path_rest():
            self._at_rest_after_stop()
            return
        if self.paused and self._path_rest() and not self._pause_logged:
            self._pause_logged = True
            self._event("paused", f"paused on the path at program time {self.tau:.6g} s")
        if not self.paused:
            self._pause_logged = False
        if self._stops and tau_out >= self._stops[0]:
            if not self._waiting:
                self._waiting = True
                self._wait_since = self.t
                self._settle = 0
                self._blk = None
            # stop points are waited for only with the servo (wait_in_position)
            servo = self.servo
            since = self._wait_since
            assert servo is not None and measured is not None and since is not None
            fe = np.abs(q - measured)
            self._settle = self._settle + 1 if np.all(fe <= servo.window) else 0
            waited = self.t + self.period - since
            if self._settle < servo.settle_cycles and waited > servo.settle_timeout:
                j = int(np.argmax(fe / servo.window))
                f = RuntimeFault(self.source.names[j], "in position", float(waited),
                                 servo.settle_timeout, self.cycle, self.t,
                                 f" s (following error {float(fe[j])!r} > window {float(servo.window[j])!r})")
                self.fault = f
                self._waiting = False
                self._stop_kind = "fault"
                self._event("fault", str(f))
                self._at_rest_after_stop()
                return
            if self._settle >= servo.settle_cycles:
                sp_tau = self._stops.pop(0)
                self.stop_log.append((sp_tau, since, self.t + self.period))
                self._waiting = False
                self._event("in_position", f"in position at program time {sp_tau:.6g} s")
            else:
                return
        if tau_out >= src.duration and not self._waiting:
            self.finished = True
            self.state = "idle"
            self._mode = "hold"
            self._event("finished", f"program finished at t = {self.t + self.period:.6g} s")

    def _at_rest_after_stop(self) -> None:
        self._mode = "hold"
        self._brake = None
        self._path_stop = False
        self.s = self.sd = 0.0
        if self._stop_kind == "fault":
            self.state = "fault"
            self._event("stopped", "at rest after the fault stop")
        else:
            self.state = "idle"
            self._event("stopped", "at rest after the controlled stop")
        self._stop_kind = None

    # ================================================================ loops
    def __iter__(self) -> Iterator[Setpoint]:
        """Yield setpoints until the machine rests in ``idle`` or ``fault``.

        Starts the program first when it is idle and has not run yet.
        """
        if self.state == "idle" and self.cycle == 0 and not self._cmds:
            self.start()
        while True:
            sp = self.step()
            yield sp
            if sp.state in ("idle", "fault") and self._mode == "hold" and not self._cmds:
                return

    async def astream(self, paced: bool = True) -> Any:
        """Asynchronous iterator of setpoints (same end condition as iteration).

        Parameters
        ----------
        paced : bool
            Sleep so that cycle ``k`` is produced at ``k * period`` after the
            first one (event-loop time); otherwise only yield control.
        """
        loop = asyncio.get_running_loop()
        t0 = loop.time()
        for sp in self:
            yield sp
            if paced:
                delay = t0 + (sp.cycle + 1) * self.period - loop.time()
                await asyncio.sleep(max(delay, 0.0))
            else:
                await asyncio.sleep(0)

    def run(self, max_cycles: int | None = None) -> list[Setpoint]:
        """Iterate to the end (or ``max_cycles``) and return the setpoints."""
        out = []
        for sp in self:
            out.append(sp)
            if max_cycles is not None and len(out) >= max_cycles:
                break
        return out
