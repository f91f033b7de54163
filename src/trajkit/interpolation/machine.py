"""The saddle machine: rotary axis theta and linear axis Z along a pipe-intersection seam.

The torch follows the seam of a :class:`~trajkit.paths.SaddleCurve` at a
constant tool speed (the feed). Machine axes as functions of the seam's arc
length s (exact, :meth:`SaddleCurve.machine_axes`): theta(s) around the
branch axis, Z(s) along it. With the tool speed v = ds/dt, a = d2s/dt2,
jerk = d3s/dt3, each axis q moves with

    dq/dt   = q' v
    d2q/dt2 = q'' v^2 + q' a
    d3q/dt3 = q''' v^3 + 3 q'' v a + q' jerk

(primes: derivatives in s). :func:`plan_saddle` hands the two axes to the
path-timing engine (:func:`trajkit.timing.plan_path_timing`) with their
exact derivatives: the minimum-time feed under the axis limits, the
tangential limits, the feed and the chord tolerance at the period.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from .._sampling import MAX_SAMPLES
from .._validate import check_positive
from ..errors import InfeasibleError, InvalidInputError
from ..limits import AxisLimits
from ..paths import _saddle_jit
from ..paths.saddle import SaddleCurve
from .feed import FeedPlan, FeedSample, _check_period, plan_feed, setpoint_times

__all__ = ["SaddleMachine", "SaddlePlan", "SaddleAxesPath", "AxisCheck", "plan_saddle", "AXIS_NAMES"]

#: Names of the machine axes, in order.
AXIS_NAMES = ("theta", "z_axis")
_QUANTITIES = ("velocity", "acceleration", "jerk")

#: Verification grid: this many points per control period (plus every piece boundary).
CHECK_PER_PERIOD = 8

#: Largest number of verification points.
CHECK_MAX_POINTS = 200_000

#: Replanning rounds when the verification finds an excess.
MAX_ROUNDS = 8

#: Extra margin when the axis limits are lowered after an excess.
SHRINK_MARGIN = 1.0 - 1e-6

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
        Final scale of the axis limits (1 unless a replanning round lowered them).
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
        fs = self.feed_plan.sample(setpoint_times(self.duration, period, max_samples), points=False)
        theta = self.curve.theta_of_s(fs.s)  # once, for the points and the axes
        fs = replace(fs, points=self.curve.point_theta(theta))
        return fs, axis_states(self.curve, fs, theta)

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


def axis_states(curve: SaddleCurve, fs: FeedSample, theta: np.ndarray | None = None) -> np.ndarray:
    """Axis position/velocity/acceleration/jerk from feed samples (exact chain rule);
    ``theta``: the seam angles at ``fs.s`` when already known.

    Returns
    -------
    ndarray, shape (2, 4, n)
    """
    # (2, 4, n): value, q', q'', q'''
    q = curve.machine_axes(fs.s) if theta is None else curve.machine_axes_theta(theta)
    v, a, j = fs.v, fs.a, fs.j
    out = np.empty_like(q)
    out[:, 0] = q[:, 0]
    out[:, 1] = q[:, 1] * v
    out[:, 2] = q[:, 2] * v * v + q[:, 1] * a
    out[:, 3] = q[:, 3] * v ** 3 + 3.0 * q[:, 2] * v * a + q[:, 1] * j
    return out


def check_times(feed_plan: FeedPlan, period: float) -> np.ndarray:
    """The times [s] where :func:`check_axes` verifies the limits, shape (n,), increasing.

    A uniform grid of ``CHECK_PER_PERIOD`` points per period over the
    duration (at least 1000, at most :data:`CHECK_MAX_POINTS`), every
    constant-jerk piece boundary of the feed and the float just before each
    (the last state of the piece that ends there), without repeats.

    Parameters
    ----------
    feed_plan : FeedPlan
    period : float
        Control period [s].

    Returns
    -------
    ndarray, shape (n,)
        Times [s] in ``[0, duration]``.
    """
    grid, bounds = _check_lists(feed_plan, period)
    return np.unique(np.concatenate([grid, bounds]))


def _check_lists(feed_plan: FeedPlan, period: float) -> tuple[np.ndarray, np.ndarray]:
    """The uniform grid (n,) [s] and the sorted piece boundaries with the float before each (2 k + 2,) [s]."""
    T = feed_plan.duration
    n = int(min(CHECK_MAX_POINTS, max(1000, math.ceil(T / period) * CHECK_PER_PERIOD)))
    tb = feed_plan.motion.t
    return np.linspace(0.0, T, n), np.sort(np.concatenate([tb, np.nextafter(tb, -np.inf).clip(0.0)]))


def check_axes(plan_curve: SaddleCurve, feed_plan: FeedPlan, machine: SaddleMachine,
               period: float) -> AxisCheck:
    """Verify the axis limits on a grid of ``CHECK_PER_PERIOD`` points per period.

    Every constant-jerk piece boundary of the feed is included (where the
    tangential acceleration and jerk change), the values are exact there
    (analytic derivatives, no finite differences); the times are
    :func:`check_times`. With the compiled kernels the feed is sampled, the
    arc lengths inverted and the axis states reduced to their peaks in one
    pass over the sorted times (no state arrays); otherwise, and for a feed
    along another path or without pieces, the peaks of :func:`axis_states`
    there (the same values to a few ulps).

    Parameters
    ----------
    plan_curve : SaddleCurve
    feed_plan : FeedPlan
        The feed along ``plan_curve``.
    machine : SaddleMachine
    period : float
        Control period [s].

    Returns
    -------
    AxisCheck
    """
    lim = machine.limits_array()
    grid, bounds = _check_lists(feed_plan, period)
    m = feed_plan.motion
    if _saddle_jit.AVAILABLE and m.jerk.size and feed_plan.path is plan_curve:
        st = m.state
        peaks = np.empty((2, 3))
        count = _saddle_jit.axis_peaks(
            grid, bounds, m.t, np.ascontiguousarray(st[:-1, 0]), np.ascontiguousarray(st[:-1, 1]),
            np.ascontiguousarray(st[:-1, 2]), m.jerk, m.s0, m.s_end, plan_curve.length,
            *plan_curve._inversion_args(), plan_curve.branch_radius ** 2, peaks)
        if count > 0:
            return AxisCheck(peaks, lim, peaks / lim, int(count))
    t = check_times(feed_plan, period)
    st = axis_states(plan_curve, feed_plan.sample(t, points=False))
    peaks = np.max(np.abs(st[:, 1:]), axis=2)
    return AxisCheck(peaks, lim, peaks / lim, int(t.size))


class SaddleAxesPath:
    """The saddle machine's axes theta(s), Z(s) along the seam (a :class:`trajkit.timing.JointPath`)
    with exact derivatives (:meth:`SaddleCurve.machine_axes`)."""

    #: Exact derivatives are cheap: the timing engine checks its limits with them.
    cheap_derivatives = True

    def __init__(self, curve: SaddleCurve) -> None:
        self.curve = curve
        self.length = curve.length
        self.n_joints = 2
        self.breakpoints = np.zeros(0)

    def derivatives(self, s: np.ndarray):
        q = self.curve.machine_axes(np.clip(np.asarray(s, dtype=float), 0.0, self.length))
        return q[:, 0].T, q[:, 1].T, q[:, 2].T, q[:, 3].T


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

    The torch speed is the path-timing engine's minimum-time motion
    (:func:`trajkit.timing.plan_path_timing`) under the feed, the tangential
    acceleration and jerk, the chord tolerance at the period and every
    velocity, acceleration and jerk limit of the theta and Z axes, evaluated
    with the seam's exact derivatives; it runs at the feed wherever no limit
    is below it. The result is checked on a fine grid with the exact axis
    states (:func:`check_axes`); an excess there (between the engine's own
    check points) lowers the axis limits by the excess and plans again.

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
    axes_path = SaddleAxesPath(curve)
    scale = 1.0
    last = None
    for rnd in range(1, MAX_ROUNDS + 1):
        lims = [machine.theta.derated(scale, scale, scale) if scale < 1.0 else machine.theta,
                machine.z.derated(scale, scale, scale) if scale < 1.0 else machine.z]
        fp = plan_feed(curve, F, A, J, tolerance=E, period=dt,
                       axes=(axes_path, lims, AXIS_NAMES))
        chk = check_axes(curve, fp, machine, dt)
        last = SaddlePlan(curve, machine, fp, chk, scale, rnd)
        if chk.ok:
            return last
        scale *= SHRINK_MARGIN / float(np.max(chk.ratio))
    assert last is not None  # MAX_ROUNDS >= 1: at least one round ran
    raise InfeasibleError(  # pragma: no cover - not reached in the sweeps
        f"no saddle plan within the axis limits after {MAX_ROUNDS} rounds "
        f"(worst ratio {float(np.max(last.check.ratio))!r})"
    )
