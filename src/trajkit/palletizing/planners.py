"""Cycle planners for palletizing: classic ``ptp`` and Cao et al.'s (2012) ``merged`` plan.

A planner takes a :class:`~trajkit.palletizing.scenario.PalletScenario` and
returns a :class:`CyclePlan`: the whole job as a :class:`Timeline` of
per-joint rest-to-rest profiles (which can be sampled and verified), plus a
:class:`TripPlan` per trip. Planners live in the registry :data:`PLANNERS`
(``register_planner`` adds one, e.g. a later "optimal" planner).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

from ..errors import InvalidInputError
from ..profiles import min_duration, plan_move
from ..sync import plan_ptp
from ._crossing import time_at_position
from .scenario import PalletScenario, TripSpec
from .timeline import Piece, Timeline

__all__ = [
    "TripPlan",
    "CyclePlan",
    "PLANNERS",
    "register_planner",
    "plan_cycle",
    "plan_trip_ptp",
    "plan_trip_merged",
    "merged_trip_times",
    "optimal_zmax",
    "HORIZONTAL_JOINTS",
    "transfer_trajectory",
]

#: Indices of the horizontal joints A (theta), C (R), D (wrist).
HORIZONTAL_JOINTS = (0, 2, 3)
_B = 1

#: Absolute tolerance [m] on Zmax for the merged plan's optimisation (a
#: nanometre: the trip time then agrees with the optimum to ~1e-9 s).
ZMAX_XTOL = 1e-9


@dataclass(frozen=True)
class TripPlan:
    """The plan of one trip, times relative to the trip start.

    Attributes
    ----------
    spec : TripSpec
    duration : float
        Trip duration [s] (rest to rest).
    pieces : tuple of 4 tuples of Piece
        Per-joint pieces (times relative to the trip start).
    window : (float, float)
        When A, C, D move [s]: from B passing ``Z1`` going up to B passing
        ``Z2`` coming down (``ptp``: the transfer move).
    zmax : float
        Highest B position [m] in the trip.
    """

    spec: TripSpec
    duration: float
    pieces: tuple
    window: tuple[float, float]
    zmax: float


@dataclass
class CyclePlan:
    """A planned palletizing job.

    Attributes
    ----------
    planner : str
        Planner name (key in :data:`PLANNERS`).
    scenario : PalletScenario
    trips : list of TripPlan
        Load and return trips in order.
    trip_starts : ndarray, shape (n_trips,)
        Absolute start time of each trip [s].
    timeline : Timeline
        The whole job's joint trajectory (joints A, B, C, D; rad, m, m, rad).
    info : dict
        Planner-specific details (bounds, per-trip choices).
    rule : {"seed", "cell"}
        The clearance rule the plan keeps: ``"seed"`` (A, C, D move only
        while B is above the trips' clearance heights ``Z1``, ``Z2``) or
        ``"cell"`` (the cell's geometry; the trips' clearance heights are
        then the settle heights).
    """

    planner: str
    scenario: PalletScenario
    trips: list
    trip_starts: np.ndarray
    timeline: Timeline
    info: dict = field(default_factory=dict)
    rule: str = "seed"

    @property
    def total_s(self) -> float:
        """Total planned time of the job [s]."""
        return self.timeline.duration

    @property
    def n_boxes(self) -> int:
        return self.scenario.n_boxes

    @property
    def per_box_s(self) -> float:
        """Planned time per box [s]."""
        return self.total_s / self.n_boxes

    def trip_times(self) -> np.ndarray:
        """Duration of each trip [s], shape (n_trips,)."""
        return np.array([tp.duration for tp in self.trips])

    def summary(self) -> dict:
        """JSON-ready summary: total and per-box times, trips, Zmax values."""
        return {
            "total_s": self.total_s,
            "per_box_s": self.per_box_s,
            "trips": len(self.trips),
            "mean_load_trip_s": float(np.mean([t.duration for t in self.trips if t.spec.kind == "load"])),
            "mean_return_trip_s": float(np.mean([t.duration for t in self.trips if t.spec.kind == "return"])),
        }


PlannerFunc = Callable[[PalletScenario], CyclePlan]

#: Planners by name; each maps a scenario to a :class:`CyclePlan`.
PLANNERS: dict[str, PlannerFunc] = {}


def register_planner(name: str, func: PlannerFunc) -> None:
    """Add (or replace) a planner in :data:`PLANNERS`."""
    if not isinstance(name, str) or not name:
        raise InvalidInputError(f"planner name must be a non-empty string, got {name!r}")
    PLANNERS[name] = func


def plan_cycle(scenario: PalletScenario, planner: str = "merged") -> CyclePlan:
    """Plan the whole job of ``scenario`` with the planner named ``planner``.

    Raises
    ------
    InvalidInputError
        Unknown planner name (the message lists the known ones).
    """
    if planner not in PLANNERS:
        raise InvalidInputError(f"planner must be one of {sorted(PLANNERS)}, got {planner!r}")
    return PLANNERS[planner](scenario)


# ------------------------------------------------------------------- ptp
def plan_trip_ptp(scenario: PalletScenario, spec: TripSpec) -> TripPlan:
    """Classic plan of one trip: rise (B), transfer (all joints, time-synchronised), lower (B).

    Every move is rest to rest and time-optimal; the transfer is
    synchronised over the four joints (all start and arrive together).
    """
    lims = scenario.robot.limits
    z0, z1, z2, z3 = spec.z_levels
    rise = plan_move(z0, z1, lims[_B])
    tr = transfer_trajectory(scenario, spec)
    lower = plan_move(z2, z3, lims[_B])
    t_a = rise.duration
    t_b = t_a + tr.duration
    pieces: list[list[Piece]] = [[] for _ in range(4)]
    pieces[_B].append(Piece(0.0, rise))
    for k in range(4):
        pieces[k].append(Piece(t_a, tr.axes[k]))
    pieces[_B].append(Piece(t_b, lower))
    return TripPlan(spec, t_b + lower.duration, tuple(tuple(p) for p in pieces), (t_a, t_b),
                    max(z1, z2))


# ---------------------------------------------------------------- merged
def _horizontal_time(scenario: PalletScenario, spec: TripSpec) -> float:
    lims = scenario.robot.limits
    return max(min_duration(spec.q_goal[k] - spec.q_start[k], lims[k]) for k in HORIZONTAL_JOINTS)


def _merged_parts(scenario: PalletScenario, spec: TripSpec, zmax: float, t_h: float):
    lb = scenario.robot.limits[_B]
    z0, z1, z2, z3 = spec.z_levels
    up = plan_move(z0, zmax, lb)
    down = plan_move(zmax, z3, lb)
    t1 = time_at_position(up, z1)
    t3 = down.duration - time_at_position(down, z2)
    return up, down, t1, t3


def merged_trip_times(scenario: PalletScenario, spec: TripSpec, zmax) -> dict:
    """Cao et al.'s (2012) trip-time terms as functions of ``Zmax`` (figures 9 to 12).

    Parameters
    ----------
    scenario : PalletScenario
    spec : TripSpec
    zmax : float or array_like, shape (n,)
        Highest B position(s) [m], each in ``[max(Z0..Z3), Z_top]``.

    Returns
    -------
    dict of ndarray, shape (n,)
        ``"zmax"``, ``"t_b"`` = f'(Z0, Zmax) + g'(Zmax, Z3) [s] (B alone),
        ``"t1"`` (B passes Z1 going up), ``"t3"`` (from passing Z2 to Z3),
        ``"t_h"`` = max(tA, tC, tD), ``"t_window"`` = t1 + tH + t3 and
        ``"trip"`` = max(t_b, t_window) [s].
    """
    zs = np.atleast_1d(np.asarray(zmax, dtype=float))
    lo, hi = _zmax_bounds(scenario, spec)
    if np.any(zs < lo) or np.any(zs > hi):
        bad = zs[(zs < lo) | (zs > hi)][0]
        raise InvalidInputError(
            f"zmax {bad * 1000:.6g} mm is outside [{lo * 1000:.6g}, {hi * 1000:.6g}] mm "
            "(max(Z0..Z3) .. Z_top)"
        )
    t_h = _horizontal_time(scenario, spec)
    tb, t1, t3 = np.empty_like(zs), np.empty_like(zs), np.empty_like(zs)
    for i, z in enumerate(zs):
        up, down, a, c = _merged_parts(scenario, spec, float(z), t_h)
        tb[i], t1[i], t3[i] = up.duration + down.duration, a, c
    tw = t1 + t_h + t3
    return {"zmax": zs, "t_b": tb, "t1": t1, "t3": t3, "t_h": np.full_like(zs, t_h),
            "t_window": tw, "trip": np.maximum(tb, tw)}


def _zmax_bounds(scenario: PalletScenario, spec: TripSpec) -> tuple[float, float]:
    return max(spec.z_levels), scenario.robot.z_top


def optimal_zmax(scenario: PalletScenario, spec: TripSpec) -> float:
    """The ``Zmax`` [m] that minimises the merged trip time.

    ``f' + g'`` grows with ``Zmax`` and ``t1 + t3`` never grows with it (a
    higher goal only delays B's braking), so the minimum of their maximum is
    at the lower bound, at the upper bound, or where the two terms are equal
    (found by Brent's method to :data:`ZMAX_XTOL`).
    """
    lo, hi = _zmax_bounds(scenario, spec)
    t_h = _horizontal_time(scenario, spec)

    def gap(z: float) -> float:
        up, down, t1, t3 = _merged_parts(scenario, spec, z, t_h)
        return (up.duration + down.duration) - (t1 + t_h + t3)

    g_lo = gap(lo)
    if g_lo >= 0.0 or hi <= lo:
        return lo
    if gap(hi) <= 0.0:
        return hi
    z = brentq(gap, lo, hi, xtol=ZMAX_XTOL)
    # the root may sit a hair on the "window" side; take the better neighbour
    return z if gap(z) >= 0.0 else min(z + ZMAX_XTOL, hi)


def plan_trip_merged(scenario: PalletScenario, spec: TripSpec, zmax: float | None = None) -> TripPlan:
    """Cao et al.'s (2012) merged plan of one trip: B moves Z0 -> Zmax -> Z3 in two moves.

    A, C and D start together (time-synchronised, shortest common duration
    ``tH``) when B passes ``Z1`` going up; B starts down as early as
    possible but late enough that it passes ``Z2`` only after A, C, D have
    arrived. Trip time ``max(f'(Z0, Zmax) + g'(Zmax, Z3), t1 + tH + t3)``.

    Parameters
    ----------
    zmax : float, optional
        B's highest position [m]; default :func:`optimal_zmax`.
    """
    lims = scenario.robot.limits
    if zmax is None:
        zmax = optimal_zmax(scenario, spec)
    else:
        lo, hi = _zmax_bounds(scenario, spec)
        if not (lo <= zmax <= hi):
            raise InvalidInputError(
                f"zmax {zmax * 1000:.6g} mm is outside [{lo * 1000:.6g}, {hi * 1000:.6g}] mm"
            )
    t_h = _horizontal_time(scenario, spec)
    up, down, t1, t3 = _merged_parts(scenario, spec, zmax, t_h)
    qa = spec.q_start[list(HORIZONTAL_JOINTS)]
    qb = spec.q_goal[list(HORIZONTAL_JOINTS)]
    hz = plan_ptp(qa, qb, [lims[k] for k in HORIZONTAL_JOINTS], sync="time")
    t_down = max(up.duration, t1 + hz.duration + t3 - down.duration)
    pieces: list[list[Piece]] = [[] for _ in range(4)]
    pieces[_B] = [Piece(0.0, up), Piece(t_down, down)]
    for i, k in enumerate(HORIZONTAL_JOINTS):
        pieces[k] = [Piece(t1, hz.axes[i])]
    duration = t_down + down.duration
    window = (t1, t_down + down.duration - t3)
    return TripPlan(spec, duration, tuple(tuple(p) for p in pieces), window, zmax)


# ----------------------------------------------------------------- cycle
def _assemble(name: str, scenario: PalletScenario, trips: list[TripPlan]) -> CyclePlan:
    starts = []
    pieces: list[list[Piece]] = [[] for _ in range(4)]
    t = 0.0
    for tp in trips:
        if tp.spec.kind == "load":
            t += scenario.grip_s
        starts.append(t)
        for k in range(4):
            for pc in tp.pieces[k]:
                pieces[k].append(Piece(t + pc.t0, pc.profile))
        t += tp.duration
        if tp.spec.kind == "load":
            t += scenario.release_s
    tl = Timeline(pieces, scenario.pick_joints(), t, names=scenario.robot.joint_names)
    return CyclePlan(name, scenario, trips, np.array(starts), tl)


def plan_cycle_ptp(scenario: PalletScenario) -> CyclePlan:
    """Classic plan of the whole job (see :func:`plan_trip_ptp`)."""
    return _assemble("ptp", scenario, [plan_trip_ptp(scenario, s) for s in scenario.trips()])


def plan_cycle_merged(scenario: PalletScenario) -> CyclePlan:
    """Cao et al.'s (2012) merged plan of the whole job (see :func:`plan_trip_merged`)."""
    return _assemble("merged", scenario, [plan_trip_merged(scenario, s) for s in scenario.trips()])


register_planner("ptp", plan_cycle_ptp)
register_planner("merged", plan_cycle_merged)


def transfer_trajectory(scenario: PalletScenario, spec: TripSpec):
    """The classic plan's transfer move P1 -> P2 of one trip as a 4-axis Trajectory.

    Returns
    -------
    trajkit.Trajectory
        Joints A, B, C, D (rad, m, m, rad), time-synchronised.
    """
    z0, z1, z2, z3 = spec.z_levels
    q1 = spec.q_start.copy()
    q1[_B] = z1
    q2 = spec.q_goal.copy()
    q2[_B] = z2
    return plan_ptp(q1, q2, list(scenario.robot.limits), sync="time")
