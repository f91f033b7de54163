"""Independent verification of planned profiles and trajectories.

One verifier for every motion: :func:`verify_motion` re-integrates any
piecewise-constant-jerk motion (:class:`~trajkit.profiles.Profile`,
:class:`~trajkit.profiles.StateProfile`, brakes, ...) phase by phase from its
phase table (it does not trust the planner's boundary table) and checks,
**exactly** at every phase boundary and at every in-phase extremum (found
analytically), and again on dense samples (:func:`verify_profile` adds the
declared legs of a rest-to-rest profile, :func:`verify_trajectory` the
synchronisation of several axes):

* the goal is reached (error relative to the travelled distance);
* the velocity limit, the acceleration limit of the accel leg, the
  acceleration limit of the decel leg, the jerk limit of each leg and the
  position range;
* continuity of position, velocity and acceleration across phase boundaries
  (an acceleration jump is allowed only on a leg whose jerk limit is
  infinite, i.e. a trapezoidal leg);
* the phase durations are finite, non-negative and add up to the duration.

The accel/decel semantics are those of :class:`~trajkit.limits.AxisLimits`:
the *accel* limits apply while |v| grows (``v * a > 0``), the *decel* limits
while |v| shrinks (``v * a < 0``), whatever the direction of motion. Inside a
constant-jerk phase the acceleration is linear and the velocity quadratic in
time, so each phase is cut at the roots of ``a`` and ``v``; on each piece the
sign of ``v * a`` is constant and every extremum lies at a piece end or at
``a = 0`` (velocity) / ``v = 0`` (position). The checks are therefore exact up
to float round-off, not limited by a sampling grid.

The module only computes; it never prints, plots or reads files.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ._constants import GOAL_RTOL, LIMIT_RTOL
from .errors import InvalidInputError, TrajkitError
from .profiles._phase import phase_eval

__all__ = [
    "QUANTITIES",
    "Violation",
    "VerificationError",
    "VerificationReport",
    "TrajectoryReport",
    "verify_motion",
    "verify_profile",
    "verify_state_profile",
    "verify_trajectory",
]

#: Quantities whose worst ratio (value / limit) a report gives, in order.
QUANTITIES = (
    "velocity",          # |v| / v_max
    "acceleration",      # |a| / a_max while |v| grows
    "deceleration",      # |a| / a_max_decel while |v| shrinks
    "jerk",              # |j| / j_max while |v| grows
    "jerk_decel",        # |j| / j_max_decel while |v| shrinks
    "position",          # excursion outside [position_min, position_max] / scale
)

#: Default number of dense samples taken in addition to the exact checks.
DEFAULT_SAMPLES = 1001

#: Relative tolerance on "the phase durations add up to the duration" and on
#: the agreement of the axis durations of a synchronised trajectory.
DURATION_SUM_RTOL = 1e-9

#: Roots of ``a`` or ``v`` closer than this fraction of the phase duration to
#: a phase end are taken to lie on that end.
CUT_RTOL = 1e-9

#: A piece of a phase on which |v| (or |a|) stays below this fraction of the
#: move's velocity (acceleration) scale is "at rest" for the accel/decel
#: classification and takes the leg of its neighbour in the phase.
SLIVER_RTOL = 1e-9

#: Positions are absolute floats: besides ``goal_rtol * distance`` they may
#: carry this many ulp of ``max(|start|, |goal|)`` of round-off.
POSITION_ULPS = 4.0

#: Sample times are placed among boundaries that are sums of 7 rounded phase
#: durations; two placements may differ by this many ulp of the duration.
TIME_ULPS = 8.0

#: Relative tolerance of the joint-space straight-line check of ``sync="phase"``.
LINE_RTOL = 1e-9


class VerificationError(TrajkitError):
    """A planned profile or trajectory breaks a limit or an invariant.

    Attributes
    ----------
    violations : tuple of Violation
        Everything found (the message names the first).
    """

    def __init__(self, message: str, violations: tuple[Violation, ...] = ()):
        super().__init__(message)
        self.violations = violations


@dataclass(frozen=True)
class Violation:
    """One failed check.

    Attributes
    ----------
    axis : str or int or None
        Axis name (from the limits) or index.
    quantity : str
        ``"velocity"``, ``"acceleration"``, ..., ``"goal"``,
        ``"continuity_position"``, ``"duration"``, ...
    value : float
        The offending value (signed where it has a sign).
    limit : float
        The bound it was compared with.
    time : float
        Time [s] where it was found (``nan`` if not applicable).
    """

    axis: str | int | None
    quantity: str
    value: float
    limit: float
    time: float = math.nan

    def message(self) -> str:
        ax = "" if self.axis is None else f" of axis {self.axis}"
        at = "" if math.isnan(self.time) else f" at t = {self.time!r} s"
        return f"{self.quantity} {self.value!r}{ax} exceeds the limit {self.limit!r}{at}"


@dataclass(frozen=True)
class VerificationReport:
    """Result of :func:`verify_profile` (one axis).

    Attributes
    ----------
    axis : str or int or None
        Axis name.
    ok : bool
        True when no check failed.
    ratios : dict of str to float
        Worst ``value / limit`` per quantity of :data:`QUANTITIES` (0 for an
        infinite limit; for ``"position"`` the excursion outside the range
        divided by ``max(|distance|, |bound|)``). A ratio above ``1 + rtol``
        fails.
    goal_error : float
        ``|end position - goal| / |distance|`` (absolute when the distance
        is zero), from independent integration of the phases.
    end_velocity_error, end_acceleration_error : float
        Residual velocity / acceleration after the last phase, relative to
        the velocity / acceleration scale of the move.
    continuity_error : float
        Largest relative jump of p, v or a across a phase boundary (jumps of
        a that an infinite jerk limit allows are not counted).
    duration_error : float
        ``|sum(phase_durations) - duration| / duration``.
    n_samples : int
        Dense samples checked in addition to the exact checks.
    violations : tuple of Violation
        Every failed check.
    """

    axis: str | int | None
    ok: bool
    ratios: dict = field(default_factory=dict)
    goal_error: float = 0.0
    end_velocity_error: float = 0.0
    end_acceleration_error: float = 0.0
    continuity_error: float = 0.0
    duration_error: float = 0.0
    n_samples: int = 0
    violations: tuple = ()

    @property
    def worst_ratio(self) -> float:
        """Largest ratio over all quantities."""
        return max(self.ratios.values(), default=0.0)

    def to_dict(self) -> dict:
        """JSON-ready summary (ratios, errors, violations)."""
        return {
            "axis": self.axis,
            "ok": self.ok,
            "ratios": dict(self.ratios),
            "goal_error": self.goal_error,
            "end_velocity_error": self.end_velocity_error,
            "end_acceleration_error": self.end_acceleration_error,
            "continuity_error": self.continuity_error,
            "duration_error": self.duration_error,
            "n_samples": self.n_samples,
            "violations": [dataclasses.asdict(v) for v in self.violations],
        }

    def raise_if_failed(self) -> VerificationReport:
        """Raise :class:`VerificationError` naming axis, quantity, value, limit.

        Returns
        -------
        VerificationReport
            ``self`` when every check passed.
        """
        if not self.ok:
            v = self.violations[0]
            more = f" (and {len(self.violations) - 1} more)" if len(self.violations) > 1 else ""
            raise VerificationError(v.message() + more, self.violations)
        return self


@dataclass(frozen=True)
class TrajectoryReport:
    """Result of :func:`verify_trajectory`.

    Attributes
    ----------
    ok : bool
        True when every axis and every synchronisation check passed.
    axes : tuple of VerificationReport
        One report per axis.
    ratios : dict of str to float
        Worst ratio per quantity over all axes.
    sync_error : float
        Largest relative difference of an axis duration from the trajectory
        duration (``sync="time"``/``"phase"``), else 0.
    line_error : float
        For ``sync="phase"``: largest deviation of the sampled motion from the
        joint-space straight line, relative to each axis' distance.
    violations : tuple of Violation
        Every failed check (axis checks first).
    """

    ok: bool
    axes: tuple
    ratios: dict
    sync_error: float = 0.0
    line_error: float = 0.0
    violations: tuple = ()

    def to_dict(self) -> dict:
        """JSON-ready summary (per-axis reports included)."""
        return {
            "ok": self.ok,
            "ratios": dict(self.ratios),
            "sync_error": self.sync_error,
            "line_error": self.line_error,
            "axes": [r.to_dict() for r in self.axes],
            "violations": [dataclasses.asdict(v) for v in self.violations],
        }

    def raise_if_failed(self) -> TrajectoryReport:
        """Raise :class:`VerificationError` for the first failed check."""
        if not self.ok:
            v = self.violations[0]
            more = f" (and {len(self.violations) - 1} more)" if len(self.violations) > 1 else ""
            raise VerificationError(v.message() + more, self.violations)
        return self


# --------------------------------------------------------------------- helpers
def _poly_state(p0, v0, a0, j, t):
    """State after time ``t`` of a constant-jerk phase (the one formula,
    :func:`trajkit.profiles._phase.phase_eval`)."""
    return phase_eval(p0, v0, a0, j, t)


def _roots_in(dt: float, v0: float, a0: float, j: float) -> list[float]:
    """Cut points in (0, dt) where ``a`` or ``v`` of the phase change sign."""
    cuts = []
    if j != 0.0:
        ta = -a0 / j
        if 0.0 < ta < dt:
            cuts.append(ta)
    # v(t) = v0 + a0 t + j t^2 / 2
    if j != 0.0:
        disc = a0 * a0 - 2.0 * j * v0
        if disc >= 0.0:
            sq = math.sqrt(disc)
            # numerically stable pair of roots
            qq = -(a0 + math.copysign(sq, a0)) if a0 != 0.0 else sq
            cand = []
            if qq != 0.0:
                cand.append(qq / j)        # = (-a0 -/+ sq) / j
                cand.append(2.0 * v0 / qq)  # the other root
            else:
                cand.append(0.0)
            cuts.extend(cand)
    elif a0 != 0.0:
        cuts.append(-v0 / a0)
    # a root within round-off of a phase end is that end (v or a reaches
    # zero exactly at the boundary); cutting there would classify a sliver
    # of the phase by the sign of round-off noise
    edge = CUT_RTOL * dt
    return sorted(r for r in cuts if edge < r < dt - edge)


class _Worst:
    """Tracks the worst ratio per quantity and the violations."""

    def __init__(self, axis: str | int | None, rtol: float) -> None:
        self.axis = axis
        self.rtol = rtol
        self.ratios = {q: 0.0 for q in QUANTITIES}
        self.violations: list[Violation] = []
        self._seen: set[str] = set()

    def ratio(self, quantity: str, value: float, limit: float, t: float) -> None:
        if not math.isfinite(limit):
            if not math.isfinite(value):
                self._fail(quantity, value, limit, t)
            return
        r = abs(value) / limit
        if not (r <= self.ratios[quantity]):  # also catches NaN
            self.ratios[quantity] = r if not math.isnan(r) else math.inf
        if not (r <= 1.0 + self.rtol):
            self._fail(quantity, value, limit, t)

    def position(self, value: float, pmin: float, pmax: float, scale: float, t: float) -> None:
        if value < pmin:
            ex, lim = pmin - value, pmin
        elif value > pmax:
            ex, lim = value - pmax, pmax
        elif math.isnan(value):
            ex, lim = math.inf, pmax
        else:
            return
        sc = max(scale, abs(lim) if math.isfinite(lim) else 0.0)
        r = ex / sc if sc > 0.0 else math.inf
        if r > self.ratios["position"]:
            self.ratios["position"] = r
        if not (r <= self.rtol):
            self._fail("position", value, lim, t)

    def check(self, quantity: str, error: float, tol: float, value: float, limit: float,
              t: float = math.nan) -> None:
        """Fail ``quantity`` when the relative ``error`` exceeds ``tol``."""
        if not (error <= tol):
            self._fail(quantity, value, limit, t)

    def report(self, goal_err, end_v, end_a, cont, dur_err, n_samples) -> VerificationReport:
        """The :class:`VerificationReport` of everything checked so far."""
        return VerificationReport(
            axis=self.axis, ok=not self.violations, ratios=dict(self.ratios),
            goal_error=goal_err, end_velocity_error=end_v, end_acceleration_error=end_a,
            continuity_error=cont, duration_error=dur_err, n_samples=n_samples,
            violations=tuple(self.violations),
        )

    def _fail(self, quantity: str, value: float, limit: float, t: float) -> None:
        # keep the first violation of each quantity (the report stays small)
        if quantity in self._seen:
            return
        self._seen.add(quantity)
        self.violations.append(Violation(self.axis, quantity, float(value), float(limit), float(t)))


def _leg_limits(lim, v, a, side_before=None):
    """Limits (a, j) of the leg in force for velocity ``v`` and acceleration ``a``.

    |v| grows when ``v * a > 0`` (accel leg) and shrinks when ``v * a < 0``
    (decel leg). At ``v == 0`` the leg is decided by ``side_before``: the
    state just before a boundary where v = 0 is slowing down (decel leg), just
    after it is speeding up (accel leg).
    """
    va = v * a
    if va > 0.0 or (va == 0.0 and side_before is False):
        return "acceleration", lim.a_max, "jerk", lim.j_max
    if va < 0.0 or (va == 0.0 and side_before is True):
        return "deceleration", lim.a_max_decel, "jerk_decel", lim.j_max_decel
    return None


def _either_leg(lim):
    """The larger of the two legs' bounds (leg undecidable at round-off level)."""
    aq = "acceleration" if lim.a_max >= lim.a_max_decel else "deceleration"
    jq = "jerk" if lim.j_max >= lim.j_max_decel else "jerk_decel"
    return aq, max(lim.a_max, lim.a_max_decel), jq, max(lim.j_max, lim.j_max_decel)


# ---------------------------------------------------------------- one profile
def verify_profile(
    profile: Any,
    rtol: float = LIMIT_RTOL,
    n_samples: int = DEFAULT_SAMPLES,
    goal_rtol: float = GOAL_RTOL,
    expected_duration: float | None = None,
) -> VerificationReport:
    """Check a one-axis profile against its limits, exactly and on samples.

    Parameters
    ----------
    profile : Profile
        A profile from :func:`~trajkit.profiles.plan_move` (or any object
        with ``start``, ``goal``, ``duration``, ``phase_durations`` (7),
        ``jerks`` (7), ``peak_acceleration``, ``peak_deceleration``,
        ``limits`` and ``sample(t)``).
    rtol : float
        Relative tolerance on every limit (a ratio value/limit above
        ``1 + rtol`` fails) and on continuity.
    n_samples : int
        Number of uniformly spaced dense samples over ``[0, duration]``
        checked in addition to the exact checks (0 to skip; >= 2 otherwise).
    goal_rtol : float
        Tolerance on the end position, relative to the distance.
    expected_duration : float, optional
        When given, the profile's duration must equal it (relative
        ``DURATION_SUM_RTOL``).

    Returns
    -------
    VerificationReport
        Worst ratios per quantity, errors, and ``ok``; call
        :meth:`VerificationReport.raise_if_failed` to turn a failure into a
        :class:`VerificationError`.

    Raises
    ------
    InvalidInputError
        For a bad ``rtol`` or ``n_samples``.
    """
    if not (rtol >= 0.0 and math.isfinite(rtol)):
        raise InvalidInputError(f"rtol must be finite and >= 0, got {rtol!r}")
    n_samples = int(n_samples)
    if n_samples < 0 or n_samples == 1:
        raise InvalidInputError(f"n_samples must be 0 or >= 2, got {n_samples!r}")
    lim = profile.limits
    axis = lim.name
    w = _Worst(axis, rtol)
    T = float(profile.duration)
    durs = [float(x) for x in profile.phase_durations]
    jerks = [float(x) for x in profile.jerks]

    # duration
    if T < 0.0 or not math.isfinite(T):
        w._fail("duration", T, 0.0, math.nan)
    bad_phase = [k for k, d in enumerate(durs) if not (d >= 0.0 and math.isfinite(d))]
    for k in bad_phase:
        w._fail(f"phase_duration[{k}]", durs[k], 0.0, math.nan)
    total = math.fsum(durs)
    dur_err = abs(total - T) / T if T > 0 else abs(total)
    w.check("duration", dur_err, DURATION_SUM_RTOL, total, T)
    if expected_duration is not None:
        e = abs(T - expected_duration) / max(expected_duration, math.ulp(1.0))
        w.check("expected_duration", e, DURATION_SUM_RTOL, T, expected_duration)

    # declared legs: phases 0-2 speed up, 4-6 slow down (a rest-to-rest
    # profile); each must use at most its own leg's jerk and acceleration
    w.ratio("acceleration", float(profile.peak_acceleration), lim.a_max, math.nan)
    w.ratio("deceleration", float(profile.peak_deceleration), lim.a_max_decel, math.nan)
    for k in range(7):
        if durs[k] > 0.0 and k != 3:
            q, jl = ("jerk", lim.j_max) if k < 3 else ("jerk_decel", lim.j_max_decel)
            w.ratio(q, jerks[k], jl, math.fsum(durs[:k]))
    if durs[3] > 0.0 and jerks[3] != 0.0:
        w._fail("cruise_jerk", jerks[3], 0.0, math.fsum(durs[:3]))

    # the rest is the check of every motion (exact pass, goal, table, samples)
    return _core(w, profile, lim, rtol, n_samples, goal_rtol, bad_phase_checked=True)


def _exact_phases(w, lim, start, v_start, a_start, durs, jerks, a_enter,
                  v_scale, a_scale, p_scale, rtol):
    """Exact limit pass over constant-jerk phases (cut at the roots of a and v).

    Integrates the displacement from ``(0, v_start, a_start)`` phase by phase;
    every limit is checked at piece ends (the extrema of v lie at a = 0 and of
    p at v = 0, both cut points) with the leg of each piece. An acceleration
    jump between phases is allowed only on a leg whose jerk limit is infinite.

    Returns
    -------
    (p, v, a_end, t_end, continuity_error)
        Displacement, velocity and acceleration after the last phase, its
        time, and the largest relative acceleration jump found.
    """
    p, v, a_prev_end = 0.0, float(v_start), float(a_start)
    t0 = 0.0
    cont = 0.0
    for k in range(len(durs)):
        dt, j, a0 = durs[k], jerks[k], a_enter[k]
        if dt <= 0.0 or not math.isfinite(dt):
            continue
        # continuity of a into this phase (position and velocity are
        # continuous by construction of the integration; their check is the
        # end state against the planner's boundary table below)
        jump = a0 - a_prev_end
        if jump != 0.0:
            legs_ok = True
            for side_before, x in ((True, a_prev_end), (False, a0)):
                if x == 0.0:
                    continue
                leg = _leg_limits(lim, v, x, side_before)
                if leg is not None and math.isfinite(leg[3]):
                    legs_ok = False
            rel = abs(jump) / a_scale if a_scale > 0.0 else math.inf
            if not legs_ok:
                cont = max(cont, rel)
                w.check("continuity_acceleration", rel, rtol, a0, a_prev_end, t0)
        # jerk-free entering state for this phase
        cuts = [0.0] + _roots_in(dt, v, a0, j) + [dt]
        pieces = []
        for i in range(len(cuts) - 1):
            ta, tb = cuts[i], cuts[i + 1]
            if tb <= ta:
                continue
            sa = _poly_state(p, v, a0, j, ta)
            sb = _poly_state(p, v, a0, j, tb)
            _, vm, am = _poly_state(p, v, a0, j, 0.5 * (ta + tb))
            # a piece on which v or a stays within round-off of zero (a
            # sliver next to a double root of v at the end of a move, say)
            # has no meaningful sign of v * a: it takes its neighbour's leg
            flat_v = max(abs(sa[1]), abs(sb[1])) <= SLIVER_RTOL * v_scale
            flat_a = max(abs(sa[2]), abs(sb[2])) <= SLIVER_RTOL * a_scale
            leg = None if (flat_v or flat_a) else _leg_limits(lim, vm, am)
            pieces.append([ta, tb, sa, sb, leg, flat_v or flat_a])
        for i, pc in enumerate(pieces):
            if pc[5]:
                nb = [q[4] for q in pieces[:i][::-1] + pieces[i + 1:] if not q[5]]
                if nb:
                    pc[4] = nb[0]
                else:
                    # the whole phase lies within round-off of v = 0 or
                    # a = 0 (a jerk phase of nanoseconds at the end of a long
                    # move): the sign of v * a is noise, so only the larger
                    # of the two legs' bounds can be checked on the state;
                    # the per-phase check below still holds each declared
                    # leg to its own limits
                    pc[4] = _either_leg(lim)
        for ta, tb, (pa, va, aa), (pb, vb, ab), leg, _ in pieces:
            tm = 0.5 * (ta + tb)
            # velocity: ends of the piece (an extremum inside a piece can only
            # be at a = 0, which is a cut point); position likewise at v = 0
            w.ratio("velocity", va, lim.v_max, t0 + ta)
            w.ratio("velocity", vb, lim.v_max, t0 + tb)
            w.position(start + pa, lim.position_min, lim.position_max, p_scale, t0 + ta)
            w.position(start + pb, lim.position_min, lim.position_max, p_scale, t0 + tb)
            if leg is not None:
                aq, amax, jq, jmax = leg
                w.ratio(aq, aa, amax, t0 + ta)
                w.ratio(aq, ab, amax, t0 + tb)
                if j != 0.0:
                    w.ratio(jq, j, jmax, t0 + tm)
            elif j != 0.0:
                # v * a == 0 on the whole piece only if a == 0 and j == 0
                w.ratio("jerk", j, max(lim.j_max, lim.j_max_decel), t0 + tm)
        p, v, a_prev_end = _poly_state(p, v, a0, j, dt)
        t0 += dt
    return p, v, a_prev_end, t0, cont


def verify_motion(
    motion: Any,
    rtol: float = LIMIT_RTOL,
    n_samples: int = DEFAULT_SAMPLES,
    goal_rtol: float = GOAL_RTOL,
    expected_duration: float | None = None,
    limits: Any = None,
) -> VerificationReport:
    """Check any piecewise-constant-jerk motion against its limits, exactly and on samples.

    The one verifier of trajkit: a rest-to-rest :class:`~trajkit.profiles.Profile`,
    a :class:`~trajkit.profiles.StateProfile`, a runtime brake or any
    :class:`~trajkit.profiles.motion.JerkMotion`. The phases are re-integrated
    from the start state (the planner's boundary table is not trusted, it is
    compared) and cut at the roots of ``a`` and ``v``; every limit is checked
    at the piece ends with the leg in force (accel limits while |v| grows,
    decel limits while it shrinks); the end state is compared with the
    declared goal; dense samples are checked as well.

    Parameters
    ----------
    motion : JerkMotion
        Needs ``start_state``, ``phase_durations``, ``jerks``,
        ``phase_accelerations``, ``duration``, ``sample(t)`` and a goal
        (``end_state`` or ``goal_state``). A brake pre-phase
        (``n_brake_phases``) is exempt from the limits: it exists because the
        start state breaks them.
    rtol, n_samples, goal_rtol
        As in :func:`verify_profile`; ``goal_rtol`` is relative to the
        larger of the distance and the travelled path scale (``max |v| T``).
    expected_duration : float, optional
        When given, the duration must equal it (relative ``DURATION_SUM_RTOL``).
    limits : AxisLimits, optional
        The limits to check against (default: ``motion.limits``).

    Returns
    -------
    VerificationReport
    """
    if not (rtol >= 0.0 and math.isfinite(rtol)):
        raise InvalidInputError(f"rtol must be finite and >= 0, got {rtol!r}")
    n_samples = int(n_samples)
    if n_samples < 0 or n_samples == 1:
        raise InvalidInputError(f"n_samples must be 0 or >= 2, got {n_samples!r}")
    lim = limits if limits is not None else motion.limits
    w = _Worst(lim.name, rtol)
    if expected_duration is not None:
        T = float(motion.duration)
        e = abs(T - expected_duration) / max(expected_duration, math.ulp(1.0))
        w.check("expected_duration", e, DURATION_SUM_RTOL, T, expected_duration)
    return _core(w, motion, lim, rtol, n_samples, goal_rtol)


def verify_state_profile(
    profile: Any,
    rtol: float = LIMIT_RTOL,
    n_samples: int = DEFAULT_SAMPLES,
    goal_rtol: float = GOAL_RTOL,
) -> VerificationReport:
    """Check a profile between moving states: :func:`verify_motion` (same checks)."""
    return verify_motion(profile, rtol=rtol, n_samples=n_samples, goal_rtol=goal_rtol)


def _goal_of(m):
    g = getattr(m, "goal_state", None)
    if g is None:
        g = m.end_state
    return tuple(float(x) for x in g)


def _core(w, m, lim, rtol, n_samples, goal_rtol, bad_phase_checked=False):
    """The checks of every motion (see :func:`verify_motion`) into ``w``."""
    p0, v0, a0 = (float(x) for x in m.start_state)
    pg, vg, ag = _goal_of(m)
    durs = [float(x) for x in m.phase_durations]
    jerks = [float(x) for x in m.jerks]
    a_enter = [float(x) for x in m.phase_accelerations]
    nb = int(getattr(m, "n_brake_phases", 0))
    T = float(m.duration)
    # the brake pre-phase: integrated without checks
    p, v, a = 0.0, v0, a0
    for k in range(nb):
        p, v, a = _poly_state(p, v, a_enter[k], jerks[k], durs[k])
    tb = math.fsum(durs[:nb])
    # scales: the largest |v| and |a| at phase boundaries and in-phase extrema
    vs, as_ = [abs(v), abs(vg)], [abs(a), abs(ag)]
    pp, vv = p, v
    for k in range(nb, len(durs)):
        as_.append(abs(a_enter[k]))
        if jerks[k] != 0.0 and 0.0 < -a_enter[k] / jerks[k] < durs[k]:
            vs.append(abs(_poly_state(pp, vv, a_enter[k], jerks[k], -a_enter[k] / jerks[k])[1]))
        pp, vv, aa = _poly_state(pp, vv, a_enter[k], jerks[k], durs[k])
        vs.append(abs(vv))
        as_.append(abs(aa))
    v_scale, a_scale = max(vs), max(as_)
    dist = abs(pg - p0)
    p_scale = max(dist, v_scale * (T - tb))
    if not p_scale > 0.0:
        p_scale = max(abs(p0), 1.0)
    if not bad_phase_checked:
        for k, d in enumerate(durs):
            if not (d >= 0.0 and math.isfinite(d)):
                w._fail(f"phase_duration[{k}]", d, 0.0, math.nan)
    total = math.fsum(durs)
    dur_err = abs(total - T) / T if T > 0 else abs(total)
    w.check("duration", dur_err, DURATION_SUM_RTOL, total, T)
    start_main = p0 + p
    w.position(start_main, lim.position_min, lim.position_max, p_scale, tb)
    dp, v, a, _, cont = _exact_phases(w, lim, start_main, v, a, durs[nb:], jerks[nb:],
                                      a_enter[nb:], v_scale, a_scale, p_scale, rtol)
    ulp_p = math.ulp(max(abs(p0), abs(pg)))
    pos_tol = goal_rtol * p_scale + POSITION_ULPS * ulp_p
    goal_err = abs(start_main + dp - pg) / p_scale
    w.check("goal", abs(start_main + dp - pg), pos_tol, start_main + dp, pg, T)
    end_v = abs(v - vg) / v_scale if v_scale > 0.0 else abs(v - vg)
    w.check("end_velocity", end_v, rtol, v, vg, T)
    # an acceleration may end by a jump only on a leg with an infinite jerk limit
    end_a = abs(a - ag) / a_scale if a_scale > 0.0 else abs(a - ag)
    if end_a > rtol:
        legs_ok = True
        for side_before, x in ((True, a), (False, ag)):
            if x != 0.0:
                leg = _leg_limits(lim, v, x, side_before)
                if leg is not None and math.isfinite(leg[3]):
                    legs_ok = False
        if legs_ok:
            end_a = 0.0
    w.check("end_acceleration", end_a, rtol, a, ag, T)
    # agreement with the motion's own boundary table (what sample() uses)
    if hasattr(m, "boundary_states"):
        bs = np.asarray(m.boundary_states(), dtype=float)
        pp, vv = 0.0, v0
        for k in range(len(durs)):
            e_abs = abs(bs[k, 0] - (p0 + pp))
            ev = abs(bs[k, 1] - vv) / v_scale if v_scale > 0.0 else abs(bs[k, 1] - vv)
            cont = max(cont, e_abs / p_scale, ev)
            w.check("continuity_position", e_abs, pos_tol, bs[k, 0], p0 + pp)
            w.check("continuity_velocity", ev, rtol, bs[k, 1], vv)
            pp, vv, _ = _poly_state(pp, vv, a_enter[k], jerks[k], durs[k])
    if n_samples and T > tb:
        ts = np.linspace(tb, T, n_samples)
        smp = m.sample(ts)
        P = np.asarray(smp.position)
        V = np.asarray(smp.velocity)
        A = np.asarray(smp.acceleration)
        J = np.asarray(smp.jerk)
        _check_samples(w, lim, ts, P, V, A, J, p_scale, v_scale, a_scale)
        # samples against the independent integration (a wrong table would show
        # here); both place a sample time among boundaries that are sums of
        # rounded durations, so they may differ by a few ulp of T in time
        ref = _integrate_at(p0, v0, durs, jerks, a_enter, ts)
        dtq = TIME_ULPS * math.ulp(T)
        ip = int(np.argmax(np.abs(P - ref[0])))
        iv = int(np.argmax(np.abs(V - ref[1])))
        e_p = abs(float(P[ip] - ref[0][ip]))
        e_v = abs(float(V[iv] - ref[1][iv]))
        cont = max(cont, e_p / p_scale, e_v / v_scale if v_scale > 0.0 else e_v)
        w.check("sample_position", e_p, pos_tol + v_scale * dtq, float(P[ip]),
                float(ref[0][ip]), float(ts[ip]))
        w.check("sample_velocity", e_v, rtol * v_scale + a_scale * dtq, float(V[iv]),
                float(ref[1][iv]), float(ts[iv]))
    return w.report(goal_err, end_v, end_a, cont, dur_err, n_samples if T > tb else 0)


def _integrate_at(start, v0, durs, jerks, a_enter, ts):
    """Position and velocity at times ``ts`` from the phases (numpy)."""
    n = len(durs)
    tb = np.concatenate([[0.0], np.cumsum(durs)])
    P = np.empty(n)
    V = np.empty(n)
    p, v = 0.0, v0
    for k in range(n):
        P[k], V[k] = p, v
        p, v, _ = _poly_state(p, v, a_enter[k], jerks[k], durs[k])
    idx = np.clip(np.searchsorted(tb, ts, side="right") - 1, 0, n - 1)
    dt = np.minimum(ts - tb[idx], np.asarray(durs)[idx])
    a0 = np.asarray(a_enter)[idx]
    j = np.asarray(jerks)[idx]
    pos, vel, _ = _poly_state(P[idx], V[idx], a0, j, dt)
    return start + pos, vel


def _check_samples(w, lim, ts, P, V, A, J, p_scale, v_scale, a_scale):
    """Limit checks on dense samples (same leg semantics as the exact pass).

    A sample whose velocity or acceleration lies within round-off of zero
    (:data:`SLIVER_RTOL` of the motion's scales; e.g. the end of a brake at a
    velocity reversal, integrated to 1e-16 m/s) has no meaningful sign of
    ``v * a``: it gets the check of ``v * a == 0`` (the larger bound of both
    legs), as the exact pass gives such slivers."""
    noise = (np.abs(V) <= SLIVER_RTOL * v_scale) | (np.abs(A) <= SLIVER_RTOL * a_scale)
    va = np.where(noise, 0.0, V * A)
    grow = va > 0.0
    shrink = va < 0.0
    checks = (
        ("velocity", np.abs(V), np.ones_like(V, dtype=bool), lim.v_max),
        ("acceleration", np.abs(A), grow, lim.a_max),
        ("deceleration", np.abs(A), shrink, lim.a_max_decel),
        ("jerk", np.abs(J), grow, lim.j_max),
        ("jerk_decel", np.abs(J), shrink, lim.j_max_decel),
    )
    for q, vals, mask, limit in checks:
        if not mask.any():
            continue
        m = np.where(mask, vals, 0.0)
        i = int(np.argmax(m))
        w.ratio(q, float(m[i]), limit, float(ts[i]))
    # where v * a == 0 (rest, cruise), no |a| or |j| may exceed the larger bound
    flat = ~(grow | shrink)
    if flat.any():
        amax = max(lim.a_max, lim.a_max_decel)
        jmax = max(lim.j_max, lim.j_max_decel)
        ia = int(np.argmax(np.where(flat, np.abs(A), 0.0)))
        if flat[ia]:
            w.ratio("acceleration" if lim.a_max >= lim.a_max_decel else "deceleration",
                    float(A[ia]), amax, float(ts[ia]))
        ij = int(np.argmax(np.where(flat, np.abs(J), 0.0)))
        if flat[ij]:
            w.ratio("jerk" if lim.j_max >= lim.j_max_decel else "jerk_decel",
                    float(J[ij]), jmax, float(ts[ij]))
    i_lo = int(np.argmin(P))
    i_hi = int(np.argmax(P))
    w.position(float(P[i_lo]), lim.position_min, lim.position_max, p_scale, float(ts[i_lo]))
    w.position(float(P[i_hi]), lim.position_min, lim.position_max, p_scale, float(ts[i_hi]))


# ------------------------------------------------------------ many axes
def _is_rest_profile(p) -> bool:
    """A 7-phase rest-to-rest Profile (checked with its declared legs)."""
    return hasattr(p, "peak_deceleration") and len(p.phase_durations) == 7


def verify_trajectory(
    traj: Any,
    rtol: float = LIMIT_RTOL,
    n_samples: int = DEFAULT_SAMPLES,
    goal_rtol: float = GOAL_RTOL,
) -> TrajectoryReport:
    """Check every axis of a trajectory and its synchronisation.

    Every axis is checked by :func:`verify_profile` (rest-to-rest profiles) or
    :func:`verify_motion` (profiles between states, any motion). For ``sync="time"`` and
    ``sync="phase"`` every axis must last the trajectory's duration; for
    ``sync="phase"`` the sampled motion must also lie on the joint-space
    straight line ``start + (goal - start) * u(t)`` with one common ``u``.

    Parameters
    ----------
    traj : Trajectory
        From :func:`~trajkit.trajectory.plan_ptp`.
    rtol, n_samples, goal_rtol
        As in :func:`verify_profile`.

    Returns
    -------
    TrajectoryReport
    """
    reports = tuple(
        verify_profile(p, rtol=rtol, n_samples=n_samples, goal_rtol=goal_rtol)
        if _is_rest_profile(p) else
        verify_motion(p, rtol=rtol, n_samples=n_samples, goal_rtol=goal_rtol)
        for p in traj.axes
    )
    ratios = {q: max((r.ratios[q] for r in reports), default=0.0) for q in QUANTITIES}
    violations = [v for r in reports for v in r.violations]
    T = float(traj.duration)
    sync = getattr(traj, "sync", "none")
    sync_err = 0.0
    line_err = 0.0
    if sync in ("time", "phase") and reports:
        for k, p in enumerate(traj.axes):
            e = abs(p.duration - T) / T if T > 0 else abs(p.duration)
            sync_err = max(sync_err, e)
            if e > DURATION_SUM_RTOL:
                violations.append(Violation(p.limits.name if p.limits.name is not None else k,
                                            "sync_duration", float(p.duration), T))
    if sync == "phase" and T > 0.0 and n_samples:
        # the line from start to goal, with one common path parameter u(t)
        ts = np.linspace(0.0, T, max(n_samples, 2))
        smp = traj.sample(ts)
        s0 = np.array([float(p.start_state[0]) for p in traj.axes])
        d = np.array([_goal_of(p)[0] for p in traj.axes]) - s0
        moving = np.abs(d) > 0.0
        if moving.any():
            u = (smp.position[:, moving] - s0[moving]) / d[moving]
            spread = u.max(axis=1) - u.min(axis=1)
            i = int(np.argmax(spread))
            line_err = float(spread[i])
            if line_err > LINE_RTOL:
                violations.append(Violation(None, "joint_space_line", line_err, LINE_RTOL,
                                            float(ts[i])))
    return TrajectoryReport(
        ok=not violations, axes=reports, ratios=ratios,
        sync_error=sync_err, line_error=line_err, violations=tuple(violations),
    )
