"""Independent checks of a :class:`CyclePlan`: limits, ranges, places, clearance, cell.

The checks do not trust the planner's bookkeeping: they read the plan's
timeline (exact phase-boundary states and dense samples) and recompute the
clearance crossing times by inverting B's profiles. When the scenario has a
cell, :func:`~trajkit.palletizing.cellcheck.check_cell` checks the swept
volume against the obstacles and the growing stack as well.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._constants import GOAL_RTOL, LIMIT_RTOL
from ..errors import TrajkitError
from ..profiles import Profile
from ..verify import verify_state_profile
from ._crossing import clearance_crossings
from .cellcheck import CellReport, check_cell
from .planners import HORIZONTAL_JOINTS, CyclePlan

__all__ = ["VerificationReport", "verify_plan", "PlanVerificationError"]

#: Absolute position tolerance [m or rad] for "place reached" and "joint at rest".
POSITION_ATOL = 1e-9

#: Velocity [m/s or rad/s] and acceleration below which a joint counts as at
#: rest (absorbs the round-off of absolute piece start times, ~1e-16 s).
REST_ATOL = 1e-9

#: Tolerance [s] on "a horizontal piece lies inside the clearance window".
#: Where B reaches a clearance height at rest (the ``ptp`` plan) the time of
#: that position is ill-conditioned (p - z ~ t^3, so a 1e-18 m change moves
#: it by microseconds): a piece end outside the window by more than this
#: fails only where B is also below its clearance height there
#: (``POSITION_ATOL``).
WINDOW_ATOL = 1e-9

#: Default number of dense samples per second of plan.
SAMPLES_PER_S = 500

_B = 1


class PlanVerificationError(TrajkitError):
    """A plan broke a limit, a range, a place or the clearance rule."""


@dataclass
class VerificationReport:
    """Result of :func:`verify_plan`.

    Attributes
    ----------
    ok : bool
    violations : list of str
        One line per problem found (empty when ``ok``).
    checks : dict
        Counts of what was checked (samples, boundaries, places, crossings)
        and the worst ratios |value| / limit per joint.
    cell : CellReport or None
        The check against the scenario's cell (``None`` without a cell).
    """

    violations: list = field(default_factory=list)
    checks: dict = field(default_factory=dict)
    cell: CellReport | None = None

    @property
    def ok(self) -> bool:
        """No violation, the cell's rules included."""
        return not self.violations and (self.cell is None or self.cell.ok)

    @property
    def ok_without_cell(self) -> bool:
        """No violation of the limits, places, order and clearance rule (cell aside)."""
        return not self.violations

    def all_violations(self) -> list[str]:
        """The violations, then the cell findings (one line each)."""
        cell = [f"cell: {f.message()}" for f in self.cell.findings] if self.cell else []
        return list(self.violations) + cell

    def raise_if_failed(self, cell: bool = True) -> None:
        """Raise :class:`PlanVerificationError` with the first violations.

        Parameters
        ----------
        cell : bool
            Count the cell's findings too (default).
        """
        vs = self.all_violations() if cell else list(self.violations)
        if vs:
            more = f" (and {len(vs) - 3} more)" if len(vs) > 3 else ""
            raise PlanVerificationError("; ".join(vs[:3]) + more)


def verify_plan(plan: CyclePlan, samples_per_s: float = SAMPLES_PER_S,
                cell: bool = True) -> VerificationReport:
    """Check a plan against the robot, the places, the clearance rule and the cell.

    Checks

    * every piece's limits exactly at its phase boundaries (velocity,
      acceleration per leg, jerk per phase, position range) and on dense
      samples of the whole timeline;
    * each place is reached exactly (joints and forward-kinematics pose) and
      the robot rests there; the job ends back at the pick;
    * the boxes are placed in a valid order: each box of the pattern once,
      a layer complete before the next starts, every load trip followed by
      the return trip of the same box;
    * the clearance rule: A, C, D rest at their start values while B is below
      ``Z1`` on the way up and at their goal values while B is below ``Z2``
      on the way down, on dense samples and exactly at the crossing times
      (recomputed by inverting B's profiles). For a plan under the cell's
      rule (``plan.rule == "cell"``) ``Z1`` and ``Z2`` are the settle
      heights: the trip's start and goal heights (read from the timeline)
      plus the cell's ``settle``;
    * with a cell: :func:`~trajkit.palletizing.cellcheck.check_cell` (the
      swept volume against the obstacles and the stack, certified between
      samples), reported in ``report.cell``.

    Parameters
    ----------
    plan : CyclePlan
    samples_per_s : float
        Density of the dense samples [1/s].
    cell : bool
        Run the cell check when the scenario has a cell (default).

    Returns
    -------
    VerificationReport
    """
    rep = VerificationReport()
    rob = plan.scenario.robot
    tl = plan.timeline
    v = rep.violations
    worst = {n: {"velocity": 0.0, "acceleration": 0.0, "jerk": 0.0} for n in rob.joint_names}

    # --- limits at the exact phase boundaries of every piece
    n_bound = 0
    for k, lim in enumerate(rob.limits):
        jn = rob.joint_names[k]
        for i, pc in enumerate(tl.pieces[k]):
            p = pc.profile
            if not isinstance(p, Profile):
                # a state profile (B turning at the top without stopping):
                # the exact phase-by-phase check of trajkit.verify
                n_bound += len(p.phase_durations) + 1
                rp = verify_state_profile(p, n_samples=0)
                for vio in rp.violations:
                    v.append(f"joint {jn} piece {i} at t={pc.t0:.4f} s: {vio.message()}")
                for q, key in (("velocity", "velocity"), ("acceleration", "acceleration"),
                               ("deceleration", "acceleration"), ("jerk", "jerk"),
                               ("jerk_decel", "jerk")):
                    worst[jn][key] = max(worst[jn][key], rp.ratios.get(q, 0.0))
                continue
            bs = p.boundary_states()
            n_bound += bs.shape[0]
            tol = 1.0 + LIMIT_RTOL
            if np.any(np.abs(bs[:, 1]) > lim.v_max * tol):
                v.append(f"joint {jn} piece {i} at t={pc.t0:.4f} s: velocity "
                         f"{np.abs(bs[:, 1]).max():.6g} above v_max {lim.v_max:.6g}")
            acc_legs = np.abs(bs[1:3, 2]).max(), np.abs(bs[4:7, 2]).max()
            if acc_legs[0] > lim.a_max * tol or acc_legs[1] > lim.a_max_decel * tol:
                v.append(f"joint {jn} piece {i} at t={pc.t0:.4f} s: acceleration "
                         f"{acc_legs} above ({lim.a_max:.6g}, {lim.a_max_decel:.6g})")
            jr = np.abs(np.array(p.jerks))
            if jr[:3].max() > lim.j_max * tol or jr[4:].max() > lim.j_max_decel * tol:
                v.append(f"joint {jn} piece {i}: jerk {jr.max():.6g} above the limit")
            lo, hi = lim.position_min, lim.position_max
            if bs[:, 0].min() < lo - POSITION_ATOL or bs[:, 0].max() > hi + POSITION_ATOL:
                v.append(f"joint {jn} piece {i}: position outside its range [{lo}, {hi}]")
            worst[jn]["velocity"] = max(worst[jn]["velocity"], float(np.abs(bs[:, 1]).max()) / lim.v_max)
            worst[jn]["acceleration"] = max(worst[jn]["acceleration"],
                                            acc_legs[0] / lim.a_max, acc_legs[1] / lim.a_max_decel)
            worst[jn]["jerk"] = max(worst[jn]["jerk"], jr[:3].max() / lim.j_max,
                                    jr[4:].max() / lim.j_max_decel)

    # --- dense samples of the whole job
    n = max(2, int(np.ceil(tl.duration * samples_per_s)) + 1)
    t = np.linspace(0.0, tl.duration, n)
    t = np.unique(np.concatenate([t, tl.segment_boundaries()]))
    s = tl.sample(t)
    for k, lim in enumerate(rob.limits):
        jn = rob.joint_names[k]
        tol = 1.0 + LIMIT_RTOL
        if np.abs(s.velocity[:, k]).max() > lim.v_max * tol:
            v.append(f"joint {jn}: sampled velocity above v_max")
        if np.abs(s.acceleration[:, k]).max() > max(lim.a_max, lim.a_max_decel) * tol:
            v.append(f"joint {jn}: sampled acceleration above the limit")
        if (s.position[:, k].min() < lim.position_min - POSITION_ATOL
                or s.position[:, k].max() > lim.position_max + POSITION_ATOL):
            v.append(f"joint {jn}: sampled position outside its range")

    # --- places reached exactly, at rest
    places = plan.scenario.place_poses()
    q_places = plan.scenario.place_joints()
    ends = plan.trip_starts + plan.trip_times()
    n_places = 0
    for tp, te in zip(plan.trips, ends):
        st = tl.sample(np.array([te]))
        q = st.position[0]
        target = tp.spec.q_goal
        scale = np.maximum(1.0, np.abs(target))
        if np.any(np.abs(q - target) > np.maximum(POSITION_ATOL, GOAL_RTOL * scale)):
            v.append(f"{tp.spec.kind} trip of box {tp.spec.box}: ends at {q.tolist()}, "
                     f"not at {target.tolist()}")
        if np.any(np.abs(st.velocity[0]) > REST_ATOL) or np.any(np.abs(st.acceleration[0]) > REST_ATOL):
            v.append(f"{tp.spec.kind} trip of box {tp.spec.box}: not at rest at its end")
        if tp.spec.kind == "load":
            n_places += 1
            # the box looks the same turned by 180 degrees: the wrist may take
            # either turn, the joints must agree with the place but for D
            qp = q_places[tp.spec.box]
            if np.any(np.abs(q[:3] - qp[:3]) > POSITION_ATOL):
                v.append(f"box {tp.spec.box}: placed at joints {q.tolist()}, planned "
                         f"{qp.tolist()}")
            pose = rob.pose_from_joints(q)
            dyaw = (pose[3] - places[tp.spec.box, 3]) % np.pi
            dyaw = min(dyaw, np.pi - dyaw)
            if np.any(np.abs(pose[:3] - places[tp.spec.box, :3]) > POSITION_ATOL) or dyaw > POSITION_ATOL:
                v.append(f"box {tp.spec.box}: gripper pose {pose.tolist()} is not the place "
                         f"{places[tp.spec.box].tolist()}")
    if np.any(np.abs(tl.goal - plan.scenario.pick_joints()) > POSITION_ATOL):
        v.append(f"the job ends at {tl.goal.tolist()}, not back at the pick")

    # --- placing order: every box once, layer by layer, load then return
    v.extend(_order_violations(plan))

    # --- clearance rule, dense samples and exact crossing times
    n_cross = 0
    h = list(HORIZONTAL_JOINTS)
    settle = plan.scenario.cell.settle if plan.scenario.cell is not None else 0.0
    for tp, ts, te in zip(plan.trips, plan.trip_starts, ends):
        z0, z1, z2, z3 = tp.spec.z_levels
        if plan.rule == "cell":
            # settle heights above where B really starts and ends the trip
            zb = tl.sample(np.array([ts, te])).position[:, _B]
            z1, z2 = float(zb[0]) + settle, float(zb[1]) + settle
        qa, qb = tp.spec.q_start[h], tp.spec.q_goal[h]
        m = (s.t >= ts) & (s.t <= te)
        tt, zb, qh = s.t[m], s.position[m, _B], s.position[m][:, h]
        vh = s.velocity[m][:, h]
        zpk = zb.max()
        at_pk = np.flatnonzero(zb >= zpk - POSITION_ATOL)
        t_pk0, t_pk1 = tt[at_pk[0]], tt[at_pk[-1]]
        going_up = (tt <= t_pk0) & (zb < z1 - POSITION_ATOL)
        coming_down = (tt >= t_pk1) & (zb < z2 - POSITION_ATOL)
        for mask, ref, label in ((going_up, qa, f"below Z1={z1 * 1000:.1f} mm going up"),
                                 (coming_down, qb, f"below Z2={z2 * 1000:.1f} mm coming down")):
            if mask.any() and (np.abs(qh[mask] - ref).max() > POSITION_ATOL
                               or np.abs(vh[mask]).max() > REST_ATOL):
                i = int(np.flatnonzero(mask & (np.abs(qh - ref).max(axis=1) > POSITION_ATOL))[0]) \
                    if np.any(mask & (np.abs(qh - ref).max(axis=1) > POSITION_ATOL)) \
                    else int(np.flatnonzero(mask)[0])
                v.append(f"{tp.spec.kind} trip of box {tp.spec.box}: a horizontal joint moves "
                         f"at t={tt[i]:.4f} s while B is {label}")
        # exact crossings: invert B's pieces inside this trip
        t_up, t_dn = _crossings(tl, ts, te, z1, z2)
        for tc, ref, zc, label in ((t_up, qa, z1, "Z1 going up"), (t_dn, qb, z2, "Z2 coming down")):
            if tc is None:
                v.append(f"{tp.spec.kind} trip of box {tp.spec.box}: B never passes {label}")
                continue
            n_cross += 1
            sc = tl.sample(np.array([tc]))
            if abs(sc.position[0, _B] - zc) > POSITION_ATOL:
                v.append(f"{tp.spec.kind} trip of box {tp.spec.box}: B at {label} crossing is "
                         f"{sc.position[0, _B]!r}, not {zc!r}")
            qhc = sc.position[0, h]
            if np.abs(qhc - ref).max() > POSITION_ATOL or np.abs(sc.velocity[0, h]).max() > REST_ATOL:
                v.append(f"{tp.spec.kind} trip of box {tp.spec.box}: horizontal joints not at "
                         f"rest at their {'start' if ref is qa else 'goal'} when B passes {label} "
                         f"(t={tc:.6f} s)")
        # exact: every horizontal piece of this trip lies inside [t_up, t_dn]
        if t_up is not None and t_dn is not None:
            for k in h:
                for pc in tl.pieces[k]:
                    if pc.t1 <= ts + WINDOW_ATOL or pc.t0 >= te - WINDOW_ATOL:
                        continue
                    zb0, zb1 = tl.sample(np.array([pc.t0, pc.t1])).position[:, _B]
                    # a piece ending outside [t_up, t_dn] by more than the
                    # time resolution of the crossings (and with B below its
                    # clearance height there) breaks the rule
                    early = pc.t0 < t_up - WINDOW_ATOL and zb0 < z1 - POSITION_ATOL
                    late = pc.t1 > t_dn + WINDOW_ATOL and zb1 < z2 - POSITION_ATOL
                    if early or late:
                        v.append(f"{tp.spec.kind} trip of box {tp.spec.box}: joint "
                                 f"{rob.joint_names[k]} moves over [{pc.t0:.6f}, {pc.t1:.6f}] s, "
                                 f"outside the clearance window [{t_up:.6f}, {t_dn:.6f}] s")
    rep.checks = {"samples": int(t.size), "phase_boundaries": n_bound, "places": n_places,
                  "crossings": n_cross, "worst_ratio": worst}
    if cell and plan.scenario.cell is not None:
        rep.cell = check_cell(plan, samples_per_s)
        rep.checks["cell_samples"] = rep.cell.samples
        rep.checks["cell_intervals"] = rep.cell.certified_intervals
    return rep


def _order_violations(plan: CyclePlan) -> list[str]:
    """Each box of the pattern placed once, layer by layer, each load followed by its return."""
    sc = plan.scenario
    per_layer = sc.pattern.layer.n_boxes
    out = []
    seen: set = set()
    layer = 0
    trips = plan.trips
    if len(trips) != 2 * sc.n_boxes:
        out.append(f"the plan has {len(trips)} trips, the job needs {2 * sc.n_boxes} "
                   f"(a load and a return trip per box)")
    for i, tp in enumerate(trips):
        kind, box = tp.spec.kind, tp.spec.box
        want = "load" if i % 2 == 0 else "return"
        if kind != want:
            out.append(f"trip {i} is a {kind} trip, expected a {want} trip")
            continue
        if not 0 <= box < sc.n_boxes:
            out.append(f"trip {i}: box {box} is not a box of the pattern (0..{sc.n_boxes - 1})")
            continue
        if kind == "return":
            if box != trips[i - 1].spec.box:
                out.append(f"trip {i}: return trip of box {box} after the load trip of box "
                           f"{trips[i - 1].spec.box}")
            continue
        if box in seen:
            out.append(f"box {box} is placed twice (trip {i})")
        seen.add(box)
        k = box // per_layer
        if k < layer:
            out.append(f"box {box} of layer {k + 1} is placed after layer {layer + 1} started "
                       f"(trip {i})")
        elif k > layer:
            missing = [b for b in range(layer * per_layer, k * per_layer) if b not in seen]
            if missing:
                out.append(f"box {box} of layer {k + 1} is placed before layer {layer + 1} is "
                           f"complete (boxes {missing} missing, trip {i})")
            layer = k
    if not out and len(seen) != sc.n_boxes:
        out.append(f"{sc.n_boxes - len(seen)} boxes are never placed")
    return out


def _crossings(tl, ts: float, te: float, z1: float, z2: float):
    """Last time B rises through ``z1`` before its peak and first time it falls
    through ``z2`` after it, within ``[ts, te]`` (exact inversion of B's pieces)."""
    pcs = [(pc.t0, pc.profile) for pc in tl.pieces[_B]
           if pc.t0 >= ts - POSITION_ATOL and pc.t1 <= te + POSITION_ATOL]
    z_start = float(tl.sample(np.array([ts])).position[0, _B])
    r = clearance_crossings(pcs, z1, z2, ts, te, z_start)
    if r is None:
        return None, None
    return r[0], r[1]
