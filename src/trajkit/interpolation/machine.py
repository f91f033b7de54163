"""The saddle machine of seed 003: rotary axis theta and linear axis Z.

The torch follows the seam of a :class:`~trajkit.paths.SaddleCurve` at a
constant tool speed (the feed). Machine axes as functions of the seam's arc
length s (exact, :meth:`SaddleCurve.machine_axes`): theta(s) around the
branch axis, Z(s) along it. With the tool speed v = ds/dt, a = d2s/dt2,
jerk = d3s/dt3, each axis q moves with

    dq/dt   = q' v
    d2q/dt2 = q'' v^2 + q' a
    d3q/dt3 = q''' v^3 + 3 q'' v a + q' jerk

(primes: derivatives in s). The planner gives every axis limit a budget
(:data:`BUDGET`): the constant-speed terms ``q' v``, ``q'' v^2``,
``q''' v^3`` set the speed-limit curve ``v_lim(s)``; the tangential
acceleration and jerk are lowered so that the terms with ``a`` and ``jerk``
fit in the rest. Then the feed is planned below ``v_lim`` (see
:func:`~trajkit.interpolation.plan_feed`) and the result is verified on a
fine grid; if the verification finds any excess (sampling of ``v_lim``
between grid points), the budgets shrink and it plans again.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._sampling import MAX_SAMPLES
from .._validate import check_positive
from ..errors import InfeasibleError, InvalidInputError
from ..limits import AxisLimits
from ..paths.saddle import SaddleCurve
from .feed import FeedPlan, FeedSample, _check_period, plan_feed, setpoint_times

__all__ = ["SaddleMachine", "SaddlePlan", "AxisCheck", "plan_saddle", "BUDGET", "AXIS_NAMES"]

#: Names of the machine axes, in order.
AXIS_NAMES = ("theta", "z_axis")
_QUANTITIES = ("velocity", "acceleration", "jerk")

#: Share of each axis limit given to the constant-speed terms (v^1, v^2, v^3)
#: and to the tangential terms (a, jerk, and the cross term 3 q'' v a).
BUDGET = {
    "accel_static": 0.7,
    "accel_tangential": 0.3,
    "jerk_static": 0.5,
    "jerk_tangential": 0.25,
    "jerk_cross": 0.25,
}

#: Verification grid: this many points per control period (plus every piece boundary).
CHECK_PER_PERIOD = 8

#: Largest number of verification points.
CHECK_MAX_POINTS = 200_000

#: Replanning rounds when the verification finds an excess.
MAX_ROUNDS = 8

#: Extra margin when shrinking budgets after an excess.
SHRINK_MARGIN = 0.999

#: Guards a division when an axis never accelerates along the seam.
_TINY = 1e-300

#: Relative slack of the final limit check (floating-point round-off).
CHECK_RTOL = 1e-9


@dataclass(frozen=True)
class SaddleMachine:
    """Limits of the two axes of the saddle welder/cutter.

    Parameters
    ----------
    theta : AxisLimits
        Rotary axis around the branch pipe [rad, rad/s, rad/s^2, rad/s^3].
    z : AxisLimits
        Linear axis along the branch pipe [m, m/s, m/s^2, m/s^3].

    Notes
    -----
    The slower of the accel and decel legs of each limit is used (the
    sign of an axis motion along the seam changes all the time).
    """

    theta: AxisLimits
    z: AxisLimits

    def __post_init__(self) -> None:
        for nm in ("theta", "z"):
            if not isinstance(getattr(self, nm), AxisLimits):
                raise InvalidInputError(f"{nm} limits must be AxisLimits, got {type(getattr(self, nm)).__name__}")

    def limits_array(self) -> np.ndarray:
        """Shape (2, 3): rows theta, Z; columns velocity, acceleration, jerk limits."""
        out = np.empty((2, 3))
        for i, lim in enumerate((self.theta, self.z)):
            out[i] = (lim.v_max, min(lim.a_max, lim.a_max_decel), min(lim.j_max, lim.j_max_decel))
        return out


@dataclass(frozen=True)
class AxisCheck:
    """Largest axis velocity, acceleration and jerk of a plan and their limits.

    Attributes
    ----------
    peaks : ndarray, shape (2, 3)
        Rows theta [rad/s...], Z [m/s...]; columns |velocity|, |acceleration|, |jerk|.
    limits : ndarray, shape (2, 3)
    ratio : ndarray, shape (2, 3)
        ``peaks / limits`` (<= 1 when the limits hold).
    n_points : int
        Number of time points checked.
    """

    peaks: np.ndarray
    limits: np.ndarray
    ratio: np.ndarray
    n_points: int

    @property
    def ok(self) -> bool:
        """True when no limit is exceeded (beyond round-off)."""
        return bool(np.all(self.ratio <= 1.0 + CHECK_RTOL))


class SaddlePlan:
    """A planned seam: feed plan plus machine-axis setpoints and checks.

    Attributes
    ----------
    curve : SaddleCurve
    machine : SaddleMachine
    feed_plan : FeedPlan
    check : AxisCheck
        Verification on the fine grid.
    budget_scale : float
        Final scale of the speed-limit budgets (1 unless replanning shrank them).
    rounds : int
        Planning rounds used.
    """

    def __init__(self, curve, machine, feed_plan, check, budget_scale, rounds):
        self.curve = curve
        self.machine = machine
        self.feed_plan = feed_plan
        self.check = check
        self.budget_scale = budget_scale
        self.rounds = rounds

    @property
    def duration(self) -> float:
        return self.feed_plan.duration

    @property
    def slowdowns(self):
        return self.feed_plan.slowdowns

    def axes(self, t: Any) -> np.ndarray:
        """Machine-axis states at times ``t`` [s], exact.

        Returns
        -------
        ndarray, shape (2, 4, n)
            ``[axis][order]``: axis 0 theta [rad...], 1 Z [m...]; order 0..3 =
            position, velocity, acceleration, jerk.
        """
        return axis_states(self.curve, self.feed_plan.sample(t, points=False))

    def setpoints(self, period: float,
                  max_samples: int | None = MAX_SAMPLES) -> tuple[FeedSample, np.ndarray]:
        """Fixed-period setpoints: the feed samples and the axis states (2, 4, n);
        at most ``max_samples`` (see :func:`~trajkit.interpolation.setpoint_times`)."""
        fs = self.feed_plan.sample(setpoint_times(self.duration, period, max_samples))
        return fs, axis_states(self.curve, fs)

    def report(self) -> list[dict]:
        """Where and why the feed is lowered: s range [m], theta range [deg], speed, reason."""
        out = []
        th0 = self.curve.theta_start
        for z in self.slowdowns:
            th = self.curve.theta_of_s(np.array([z.s_start, z.s_end]))
            d = z.to_dict()
            d["theta_start_deg"] = math.degrees(float(th[0]) - th0)
            d["theta_end_deg"] = math.degrees(float(th[1]) - th0)
            out.append(d)
        return out


def axis_states(curve: SaddleCurve, fs: FeedSample) -> np.ndarray:
    """Axis position/velocity/acceleration/jerk from feed samples (exact chain rule).

    Returns
    -------
    ndarray, shape (2, 4, n)
    """
    q = curve.machine_axes(fs.s)  # (2, 4, n): value, q', q'', q'''
    v, a, j = fs.v, fs.a, fs.j
    out = np.empty_like(q)
    out[:, 0] = q[:, 0]
    out[:, 1] = q[:, 1] * v
    out[:, 2] = q[:, 2] * v * v + q[:, 1] * a
    out[:, 3] = q[:, 3] * v ** 3 + 3.0 * q[:, 2] * v * a + q[:, 1] * j
    return out


def check_axes(plan_curve: SaddleCurve, feed_plan: FeedPlan, machine: SaddleMachine,
               period: float) -> AxisCheck:
    """Verify the axis limits on a grid of ``CHECK_PER_PERIOD`` points per period.

    Every constant-jerk piece boundary of the feed is included (where the
    tangential acceleration and jerk change), the values are exact there
    (analytic derivatives, no finite differences).
    """
    T = feed_plan.duration
    n = int(min(CHECK_MAX_POINTS, max(1000, math.ceil(T / period) * CHECK_PER_PERIOD)))
    t = np.unique(np.concatenate([np.linspace(0.0, T, n), feed_plan.motion.t,
                                  np.nextafter(feed_plan.motion.t, -np.inf).clip(0.0)]))
    st = axis_states(plan_curve, feed_plan.sample(t, points=False))
    peaks = np.max(np.abs(st[:, 1:]), axis=2)
    lim = machine.limits_array()
    return AxisCheck(peaks, lim, peaks / lim, int(t.size))


def plan_saddle(
    curve: SaddleCurve,
    feed: float,
    a_max: float,
    j_max: float,
    machine: SaddleMachine,
    tolerance: float,
    period: float,
) -> SaddlePlan:
    """Plan a constant-feed pass along a saddle seam within the machine's axis limits.

    Parameters
    ----------
    curve : SaddleCurve
    feed : float
        Commanded torch speed along the 3-D seam [m/s].
    a_max, j_max : float
        Tangential acceleration [m/s^2] and jerk [m/s^3] limits of the feed.
    machine : SaddleMachine
        Axis limits (theta in rad, Z in m).
    tolerance : float
        Chord tolerance [m]: the straight line between consecutive setpoints
        stays within it (the speed is limited accordingly).
    period : float
        Control period [s], 0.1 ms ... 100 ms.

    Returns
    -------
    SaddlePlan
        Its ``check`` holds every axis limit on the verification grid.

    Raises
    ------
    InvalidInputError
        For bad numbers.
    InfeasibleError
        When no plan within the limits is found after :data:`MAX_ROUNDS`.
    """
    if not isinstance(curve, SaddleCurve):
        raise InvalidInputError(f"curve must be a SaddleCurve, got {type(curve).__name__}")
    if not isinstance(machine, SaddleMachine):
        raise InvalidInputError(f"machine must be a SaddleMachine, got {type(machine).__name__}")
    F = check_positive(feed, "feed")
    A = check_positive(a_max, "tangential acceleration a_max")
    J = check_positive(j_max, "tangential jerk j_max")
    E = check_positive(tolerance, "tolerance")
    dt = _check_period(period)
    lim = machine.limits_array()
    # largest |q'|, |q''| over the seam (dense exact evaluation)
    sg = np.linspace(0.0, curve.length, 8193)
    qg = curve.machine_axes(sg)
    q1max = np.max(np.abs(qg[:, 1]), axis=1)
    q2max = np.max(np.abs(qg[:, 2]), axis=1)
    reasons = [f"{ax} {qty}" for ax in AXIS_NAMES for qty in _QUANTITIES]

    scale = 1.0
    tan_scale = 1.0
    last = None
    for rnd in range(1, MAX_ROUNDS + 1):
        ea, ej = BUDGET["accel_static"] * scale, BUDGET["jerk_static"] * scale

        def vlim(s, ea=ea, ej=ej, scale=scale):
            q = curve.machine_axes(s)
            cand = np.empty((6, np.size(s)))
            with np.errstate(divide="ignore"):
                for i in range(2):
                    cand[3 * i] = scale * lim[i, 0] / np.abs(q[i, 1])
                    cand[3 * i + 1] = np.sqrt(ea * lim[i, 1] / np.abs(q[i, 2]))
                    cand[3 * i + 2] = np.cbrt(ej * lim[i, 2] / np.abs(q[i, 3]))
            return np.min(cand, axis=0), np.argmin(cand, axis=0)

        a_eff = A
        j_eff = J
        for i in range(2):
            a_eff = min(a_eff, tan_scale * BUDGET["accel_tangential"] * lim[i, 1] / q1max[i])
            a_eff = min(a_eff, tan_scale * BUDGET["jerk_cross"] * lim[i, 2]
                        / (3.0 * math.sqrt(max(ea * lim[i, 1] * q2max[i], _TINY))))
            j_eff = min(j_eff, tan_scale * BUDGET["jerk_tangential"] * lim[i, 2] / q1max[i])
        fp = plan_feed(curve, F, a_eff, j_eff, speed_limit=vlim, reasons=reasons,
                       tolerance=E, period=dt)
        chk = check_axes(curve, fp, machine, dt)
        last = SaddlePlan(curve, machine, fp, chk, scale, rnd)
        if chk.ok:
            return last
        worst = float(np.max(chk.ratio))
        scale *= SHRINK_MARGIN / worst
        tan_scale *= SHRINK_MARGIN / worst
    raise InfeasibleError(  # pragma: no cover - not reached in the sweeps
        f"no saddle plan within the axis limits after {MAX_ROUNDS} rounds "
        f"(worst ratio {float(np.max(last.check.ratio))!r})"
    )
