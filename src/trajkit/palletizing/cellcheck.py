"""Independent check of a plan against its scenario's cell (obstacles, stack, gripper).

Whatever planned it, a :class:`~trajkit.palletizing.planners.CyclePlan`
is read from its timeline only: the joints at any time give the moving
volume (:func:`~trajkit.palletizing.cell.moving_prisms`), the trips give
which box is carried and which boxes stand on the pallet (every placed box
is an obstacle from the end of its load trip on), and the distances are the
exact prism distances of :mod:`trajkit.palletizing.cell`.

Rules (the cell's):

* while any horizontal joint (A, C, D) moves, every obstacle is at least
  ``clearance`` away;
* while only B moves (at a trip's start or goal pose), the obstacles the
  volume touches resting at that pose (its support, the neighbours it
  slides past) may be touched but not pierced, every other obstacle keeps
  the clearance.

How it is exact:

* horizontal motion: the distances are sampled densely (``samples_per_s``
  plus every phase boundary of every joint) and each interval between two
  samples is *certified*: no distance can fall more than ``L dt / 2`` below
  the mean of its ends, ``L`` a bound on the speed of any point of the
  moving volume over the interval (from the joints' exact states and jerk
  limits). Intervals that cannot be certified are halved until they are
  (down to :data:`MIN_STEP`), so the minimum clearance reported holds for
  the continuous motion to :data:`CLEARANCE_ATOL`;
* B-only motion: the footprint is fixed, the distance depends on B alone,
  and its minimum over B's exact range in that stretch is computed in
  closed form.

Tolerance: distances within :data:`CLEARANCE_ATOL` (0.1 micrometre) of a
bound count as keeping it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import InvalidInputError
from .cell import PRISM_FIELDS, Prisms, moving_prisms, prism_signed_distance, stack_prisms
from .planners import HORIZONTAL_JOINTS, CyclePlan

__all__ = ["CellFinding", "CellReport", "check_cell", "CLEARANCE_ATOL", "MIN_STEP"]

#: Distances within this of a bound count as keeping it [m].
CLEARANCE_ATOL = 1e-7

#: Smallest interval [s] the certification halves down to.
MIN_STEP = 1e-8

#: Default dense samples per second of plan.
SAMPLES_PER_S = 500.0

#: At most this many halving rounds per trip.
MAX_ROUNDS = 40

_B = 1
_H = list(HORIZONTAL_JOINTS)


@dataclass(frozen=True)
class CellFinding:
    """One place where a trip breaks the cell's rules (its worst point).

    Attributes
    ----------
    trip : int
        Index of the trip in the plan.
    kind : str
        ``"load"`` or ``"return"``.
    box : int
        Box of the trip (index in the pattern).
    t : float
        Absolute time [s] of the worst point.
    obstacle : str
        What the volume comes too close to.
    distance : float
        Signed distance there [m] (negative: penetration depth).
    required : float
        What the rule asks for there [m] (the clearance, or 0 for contact).
    moving : bool
        Whether a horizontal joint moves there.
    """

    trip: int
    kind: str
    box: int
    t: float
    obstacle: str
    distance: float
    required: float
    moving: bool

    @property
    def penetrates(self) -> bool:
        """The volume pierces the obstacle (signed distance below zero)."""
        return self.distance < -CLEARANCE_ATOL

    def message(self) -> str:
        what = (f"pierces {self.obstacle} by {-self.distance * 1000:.1f} mm" if self.penetrates
                else f"comes within {self.distance * 1000:.2f} mm of {self.obstacle}")
        need = (f"clearance {self.required * 1000:g} mm" if self.required > 0.0
                else "no piercing")
        return (f"{self.kind} trip of box {self.box} at t={self.t:.3f} s: the "
                f"{'moving' if self.moving else 'rising/lowering'} volume {what} ({need})")


@dataclass
class CellReport:
    """Result of :func:`check_cell`.

    Attributes
    ----------
    findings : list of CellFinding
        The worst point of every trip that breaks the rules.
    min_clearance : float
        Smallest distance [m] wherever the full clearance applies (while a
        horizontal joint moves, and to non-contact obstacles while only B
        moves).
    min_clearance_at : tuple
        ``(t, trip, obstacle, joints)`` of that point (joints shape (4,)).
    min_clearance_bound : float
        Certified lower bound [m] on the distance over the whole continuous
        motion wherever the full clearance applies (from the certified
        intervals and the closed-form B-only stretches).
    samples : int
        Distance evaluations (poses x obstacles are counted once per pose).
    certified_intervals : int
        Intervals certified between samples.
    """

    findings: list = field(default_factory=list)
    min_clearance: float = math.inf
    min_clearance_at: tuple = ()
    min_clearance_bound: float = math.inf
    samples: int = 0
    certified_intervals: int = 0

    @property
    def ok(self) -> bool:
        return not self.findings

    @property
    def colliding_boxes(self) -> list[int]:
        """Boxes with a trip that pierces an obstacle."""
        return sorted({f.box for f in self.findings if f.penetrates})

    @property
    def violating_boxes(self) -> list[int]:
        """Boxes with a trip that breaks any rule (piercing or too close)."""
        return sorted({f.box for f in self.findings})


def _obstacles_per_trip(plan: CyclePlan) -> list[Prisms]:
    """Obstacles present during each trip (static, placed boxes, box at the pick)."""
    sc = plan.scenario
    cell = sc.cell
    assert cell is not None  # a plan of a scenario with a cell (check_cell refuses others)
    dims = (sc.box.length, sc.box.width, sc.box.height)
    poses = sc.place_poses()
    static = cell.static_prisms()
    pick_box = (stack_prisms(sc.pick[None, :], *dims, names=("box at the pick",))
                if cell.box_at_pick else Prisms.empty())
    placed: list[int] = []
    out = []
    for tp in plan.trips:
        obst = static
        if placed:
            obst = obst.concat(stack_prisms(poses[placed], *dims,
                                            names=tuple(f"placed box {b}" for b in placed)))
        if tp.spec.kind == "return":
            obst = obst.concat(pick_box)
        out.append(obst)
        if tp.spec.kind == "load":
            placed.append(tp.spec.box)
    return out


def _distances(q, dims, grip, carrying, obst: Prisms, directions: bool = False):
    """Signed distance of the moving volume to each obstacle, shape (n, m).

    With ``directions``: per moving part, its distances (n, m) and the unit
    vectors from each obstacle towards the part along their closest points
    (n, m, 3; zero where they touch or overlap), as a list of pairs.
    """
    keys = PRISM_FIELDS
    ob = Prisms.from_fields(np.asarray(getattr(obst, k))[None, :] for k in keys)
    d, parts = None, []
    for part, _, _ in moving_prisms(q, dims, grip, carrying):
        p = Prisms.from_fields(np.asarray(getattr(part, k))[:, None] for k in keys)
        dd = prism_signed_distance(p, ob)
        if directions:
            parts.append((dd, _closest_direction(p, ob)))
        d = dd if d is None else np.minimum(d, dd)
    return (d, parts) if directions else d


def _closest_direction(a: Prisms, b: Prisms) -> np.ndarray:
    """Unit vector from prism ``b`` towards prism ``a`` along their closest points."""
    shape = np.broadcast(a.cx, b.cx).shape
    best = np.full(shape, np.inf)
    ux = np.zeros(shape)
    uy = np.zeros(shape)
    for (p, q, sign) in ((a, b, 1.0), (b, a, -1.0)):
        cp_, sp_ = np.cos(p.yaw), np.sin(p.yaw)
        cq, sq = np.cos(q.yaw), np.sin(q.yaw)
        for sx, sy in ((1, 1), (-1, 1), (-1, -1), (1, -1)):
            ex, ey = sx * p.hx, sy * p.hy
            px, py = p.cx + cp_ * ex - sp_ * ey, p.cy + sp_ * ex + cp_ * ey
            dx, dy = px - q.cx, py - q.cy
            u = cq * dx + sq * dy
            v = -sq * dx + cq * dy
            eu = np.sign(u) * np.maximum(np.abs(u) - q.hx, 0.0)
            ev = np.sign(v) * np.maximum(np.abs(v) - q.hy, 0.0)
            dist = np.hypot(eu, ev)
            wx, wy = cq * eu - sq * ev, sq * eu + cq * ev
            take = dist < best
            best = np.where(take, dist, best)
            ux = np.where(take, sign * wx, ux)
            uy = np.where(take, sign * wy, uy)
    dxy = best
    up = a.z0 - b.z1
    down = b.z0 - a.z1
    dz = np.maximum(up, down)
    sz = np.where(up >= down, 1.0, -1.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        nxy = np.where(dxy > 0.0, 1.0 / np.where(dxy > 0.0, dxy, 1.0), 0.0)
        ux, uy = ux * nxy, uy * nxy
    gz = np.maximum(dz, 0.0)
    gx = np.where(dxy > 0.0, dxy, 0.0)
    nrm = np.hypot(gx, gz)
    with np.errstate(invalid="ignore", divide="ignore"):
        fx = np.where(nrm > 0.0, gx / np.where(nrm > 0.0, nrm, 1.0), 0.0)
        fz = np.where(nrm > 0.0, gz / np.where(nrm > 0.0, nrm, 1.0), 0.0)
    return np.stack([ux * fx, uy * fx, sz * fz], axis=-1)


def _directional_speed(st, n, dt, lims, rho) -> np.ndarray:
    """Bound on ``|n . v|`` over the next ``dt`` for every point of the volume.

    ``st``: timeline samples (n_s,), ``n``: directions (n_s, m, 3), ``dt``
    (n_s,). ``v = dR e_r + R dtheta e_theta + dpsi (z x r) + dZ z``, so
    ``|n . v| <= |dR| |n . e_r| + R |dtheta| |n . e_theta| + rho |dpsi| |n_xy|
    + |dZ| |n_z|``, with each joint's speed grown by its acceleration and
    jerk over ``dt`` and ``e_r``, ``e_theta`` turned by at most the waist's
    travel.
    """
    sp = []
    for k, lim in enumerate(lims):
        jm = max(lim.j_max, lim.j_max_decel)
        sp.append(np.abs(st.velocity[:, k]) + np.abs(st.acceleration[:, k]) * dt + jm * dt * dt / 2.0)
    wt, vz, vr, wd = sp
    th = st.position[:, 0]
    r = np.abs(st.position[:, 2]) + vr * dt
    dth = (wt * dt)[:, None]
    nx, ny, nz = n[..., 0], n[..., 1], n[..., 2]
    nxy = np.hypot(nx, ny)
    er = np.minimum(np.abs(nx * np.cos(th)[:, None] + ny * np.sin(th)[:, None]) + nxy * dth, nxy)
    et = np.minimum(np.abs(-nx * np.sin(th)[:, None] + ny * np.cos(th)[:, None]) + nxy * dth, nxy)
    return (vr[:, None] * er + (r * wt)[:, None] * et + rho * (wt + wd)[:, None] * nxy
            + vz[:, None] * np.abs(nz))


def _speed_bound(st_lo, st_hi, dt, lims, rho) -> np.ndarray:
    """Bound on the speed [m/s] of any point of the moving volume over intervals.

    ``st_lo`` / ``st_hi``: timeline samples at the interval ends. Each
    joint's speed within half an interval of an end is at most
    ``|v| + |a| dt/2 + j dt^2/8`` there.
    """
    half = 0.5 * dt
    sp = []
    for k, lim in enumerate(lims):
        jm = max(lim.j_max, lim.j_max_decel)
        if not math.isfinite(jm):  # pragma: no cover - palletizer joints are jerk-limited
            am = max(lim.a_max, lim.a_max_decel)
            e = [np.abs(s.velocity[:, k]) + am * half for s in (st_lo, st_hi)]
        else:
            e = [np.abs(s.velocity[:, k]) + np.abs(s.acceleration[:, k]) * half
                 + jm * half * half / 2.0 for s in (st_lo, st_hi)]
        sp.append(np.maximum(e[0], e[1]))
    wt, vz, vr, wd = sp
    r = np.maximum(np.abs(st_lo.position[:, 2]), np.abs(st_hi.position[:, 2])) + vr * half
    return vr + r * wt + rho * (wt + wd) + vz


def _b_range(tl, t0: float, t1: float) -> tuple[float, float]:
    """Exact smallest and largest B position over ``[t0, t1]``."""
    ts = [t0, t1]
    for pc in tl.pieces[_B]:
        if pc.t1 < t0 or pc.t0 > t1:
            continue
        prof = pc.profile
        tb = np.asarray(prof.phase_times, dtype=float)
        bs = prof.boundary_states()
        for k, j in enumerate(prof.jerks):
            a_, b_ = pc.t0 + tb[k], pc.t0 + tb[k + 1]
            if b_ < t0 or a_ > t1:
                continue
            ts += [min(max(a_, t0), t1), min(max(b_, t0), t1)]
            v, a = bs[k, 1], bs[k, 2]
            # zeros of v + a s + j s^2 / 2 inside the phase
            if j != 0.0:
                disc = a * a - 2.0 * j * v
                roots = [] if disc < 0.0 else [(-a + sg * math.sqrt(disc)) / j for sg in (1, -1)]
            else:
                roots = [-v / a] if a != 0.0 else []
            ts += [a_ + s for s in roots if 0.0 < s < b_ - a_ and t0 <= a_ + s <= t1]
    z = tl.sample(np.array(ts)).position[:, _B]
    return float(z.min()), float(z.max())


def _rest_distance(q, dims, grip, carrying, obst: Prisms, zlo: float, zhi: float) -> np.ndarray:
    """Smallest signed distance to each obstacle over B in ``[zlo, zhi]`` (footprint fixed)."""
    keys = PRISM_FIELDS
    out = np.full(len(obst), np.inf)
    qq = np.array(q, dtype=float)[None, :]
    for part, lo, hi in moving_prisms(qq, dims, grip, carrying):
        # height gap as a function of B: max(z0 - (B + hi), (B + lo) - z1), smallest at
        # B* = (z0 + z1 - lo - hi) / 2; the distance grows with the gap on each side
        bstar = 0.5 * (np.asarray(obst.z0) + np.asarray(obst.z1) - lo - hi)
        for zb in (np.full(len(obst), zlo), np.full(len(obst), zhi), np.clip(bstar, zlo, zhi)):
            p = Prisms(np.full(len(obst), part.cx[0]), np.full(len(obst), part.cy[0]),
                       np.full(len(obst), part.hx[0]), np.full(len(obst), part.hy[0]),
                       np.full(len(obst), part.yaw[0]), zb + lo, zb + hi)
            ob = Prisms.from_fields(np.asarray(getattr(obst, k)) for k in keys)
            out = np.minimum(out, prism_signed_distance(p, ob))
    return out


def check_cell(plan: CyclePlan, samples_per_s: float = SAMPLES_PER_S) -> CellReport:
    """Check every trip of ``plan`` against its scenario's cell (module docstring).

    Parameters
    ----------
    plan : CyclePlan
        Any plan of a scenario with a cell.
    samples_per_s : float
        Dense samples per second [1/s] (plus every phase boundary).

    Returns
    -------
    CellReport

    Raises
    ------
    InvalidInputError
        The scenario has no cell.
    """
    sc = plan.scenario
    cell = sc.cell
    if cell is None:
        raise InvalidInputError(f"scenario {sc.name!r} has no cell to check against")
    tl = plan.timeline
    rob = sc.robot
    dims = (sc.box.length, sc.box.width, sc.box.height)
    grip = cell.gripper_size(dims[0], dims[1])
    rho = 0.5 * max(math.hypot(dims[0], dims[1]), math.hypot(grip[0], grip[1]))
    c = cell.clearance
    rep = CellReport()
    ends = plan.trip_starts + plan.trip_times()
    bounds = np.concatenate([tl.phase_boundary_states(k)[:, 0] for k in range(4)])
    for it, (tp, obst, ts, te) in enumerate(zip(plan.trips, _obstacles_per_trip(plan),
                                                plan.trip_starts, ends)):
        kind, box = tp.spec.kind, tp.spec.box
        carrying = kind == "load"
        names = obst.names
        worst: tuple[float, float, int, float, float, bool] | None = None  # (margin, t, k, d, req, moving)
        # when the horizontal joints move: from their pieces inside the trip
        hp = [pc for k in _H for pc in tl.pieces[k]
              if pc.t1 > ts + 1e-12 and pc.t0 < te - 1e-12 and pc.profile.duration > 0.0]
        t_a = min((pc.t0 for pc in hp), default=te)
        t_b = max((pc.t1 for pc in hp), default=te)
        t_a, t_b = max(t_a, ts), min(t_b, te)
        q_s = tl.sample(np.array([ts])).position[0]
        q_g = tl.sample(np.array([te])).position[0]

        # --- only B moves: before t_a at the start pose, after t_b at the goal pose
        for (u0, u1, q_rest) in ((ts, t_a, q_s), (t_b, te, q_g)):
            if u1 <= u0:
                continue
            contact = _distances(q_rest[None, :], dims, grip, carrying, obst)[0] < c - CLEARANCE_ATOL
            zlo, zhi = _b_range(tl, u0, u1)
            d = _rest_distance(q_rest, dims, grip, carrying, obst, zlo, zhi)
            req = np.where(contact, 0.0, c)
            rep.samples += 1
            for kc in np.flatnonzero(~contact):
                rep.min_clearance_bound = min(rep.min_clearance_bound, float(d[kc]))
                if d[kc] < rep.min_clearance:
                    rep.min_clearance = float(d[kc])
                    qq = q_rest.copy()
                    qq[_B] = zlo
                    rep.min_clearance_at = (float(u0), it, names[kc] if names else str(kc), qq)
            m = d - req
            k = int(np.argmin(m))
            if m[k] < -CLEARANCE_ATOL and (worst is None or m[k] < worst[0]):
                worst = (float(m[k]), float(u0), k, float(d[k]), float(req[k]), False)

        # --- horizontal motion: dense samples, then certified intervals
        if t_b > t_a:
            n = max(2, int(math.ceil((t_b - t_a) * samples_per_s)) + 1)
            t = np.linspace(t_a, t_b, n)
            extra = bounds[(bounds > t_a) & (bounds < t_b)]
            t = np.unique(np.concatenate([t, extra]))
            st = tl.sample(t)
            d, parts = _distances(st.position, dims, grip, carrying, obst, directions=True)
            rep.samples += t.size
            lo_t, hi_t = t[:-1], t[1:]
            d_lo, d_hi = d[:-1], d[1:]
            p_lo = [(dp[:-1], npart[:-1]) for dp, npart in parts]
            p_hi = [(dp[1:], npart[1:]) for dp, npart in parts]
            s_lo = _slice(st, slice(None, -1))
            s_hi = _slice(st, slice(1, None))
            all_t, all_d = [t], [d]
            for _ in range(MAX_ROUNDS):
                dt = hi_t - lo_t
                lb = _interval_bound(p_lo, p_hi, s_lo, s_hi, dt, rob.limits, rho)
                need = np.any(lb < c - CLEARANCE_ATOL, axis=1) & (dt > MIN_STEP)
                # an interval with a sample already below the clearance needs no more
                bad_ends = np.any((d_lo < c - CLEARANCE_ATOL) | (d_hi < c - CLEARANCE_ATOL), axis=1)
                need &= ~bad_ends
                rep.certified_intervals += int(np.count_nonzero(~need))
                if (~need).any():
                    rep.min_clearance_bound = min(rep.min_clearance_bound,
                                                  float(np.min(lb[~need])))
                if not need.any():
                    break
                tm = 0.5 * (lo_t[need] + hi_t[need])
                sm = tl.sample(tm)
                dm, pm = _distances(sm.position, dims, grip, carrying, obst, directions=True)
                rep.samples += tm.size
                all_t.append(tm)
                all_d.append(dm)
                sl, sh = _slice(s_lo, need), _slice(s_hi, need)
                lo_t = np.concatenate([lo_t[need], tm])
                hi_t = np.concatenate([tm, hi_t[need]])
                d_lo = np.concatenate([d_lo[need], dm])
                d_hi = np.concatenate([dm, d_hi[need]])
                p_lo = [(np.concatenate([a[0][need], m_[0]]), np.concatenate([a[1][need], m_[1]]))
                        for a, m_ in zip(p_lo, pm)]
                p_hi = [(np.concatenate([m_[0], a[0][need]]), np.concatenate([m_[1], a[1][need]]))
                        for a, m_ in zip(p_hi, pm)]
                s_lo = _cat(sl, sm)
                s_hi = _cat(sm, sh)
            tt = np.concatenate(all_t)
            dd = np.concatenate(all_d)
            i, k = map(int, np.unravel_index(int(np.argmin(dd)), dd.shape))
            if dd[i, k] < rep.min_clearance:
                rep.min_clearance = float(dd[i, k])
                rep.min_clearance_at = (float(tt[i]), it, names[k] if names else str(k),
                                        tl.sample(np.array([tt[i]])).position[0])
            if dd[i, k] - c < -CLEARANCE_ATOL and (worst is None or dd[i, k] - c < worst[0]):
                worst = (float(dd[i, k] - c), float(tt[i]), int(k), float(dd[i, k]), c, True)
        if worst is not None:
            _, tw, kw, dw, req_w, moving = worst
            rep.findings.append(CellFinding(it, kind, box, tw, names[kw] if names else str(kw),
                                            dw, req_w, moving))
    return rep


def _full_speed(st, dt, lims, rho) -> np.ndarray:
    """Bound on the speed of any point of the volume over the next ``dt`` (n_s,)."""
    sp = []
    for k, lim in enumerate(lims):
        jm = max(lim.j_max, lim.j_max_decel)
        sp.append(np.abs(st.velocity[:, k]) + np.abs(st.acceleration[:, k]) * dt + jm * dt * dt / 2.0)
    wt, vz, vr, wd = sp
    r = np.abs(st.position[:, 2]) + vr * dt
    return vr + r * wt + rho * (wt + wd) + vz


def _interval_bound(p_lo, p_hi, s_lo, s_hi, dt, lims, rho) -> np.ndarray:
    """Certified smallest distance over each interval, shape (n_i, m).

    Per moving part: from each end the distance can fall at most as fast as
    the part moves along that end's closest direction (the gap along a fixed
    direction bounds the distance from below and equals it at the end); the
    two cones meet at the bound. Where the part touches or overlaps an
    obstacle the speed of its fastest point bounds the change instead. The
    volume's bound is the smallest over its parts.
    """
    T = dt[:, None]
    iso_lo = _full_speed(s_lo, dt, lims, rho)[:, None]
    iso_hi = _full_speed(s_hi, dt, lims, rho)[:, None]
    out: np.ndarray | None = None
    for (d_lo, n_lo), (d_hi, n_hi) in zip(p_lo, p_hi):
        a = np.where(d_lo > 0.0, _directional_speed(s_lo, n_lo, dt, lims, rho), iso_lo)
        b = np.where(d_hi > 0.0, _directional_speed(s_hi, n_hi, dt, lims, rho), iso_hi)
        s = a + b
        with np.errstate(invalid="ignore", divide="ignore"):
            tm = np.where(s > 0.0, (d_lo - d_hi + b * T) / np.where(s > 0.0, s, 1.0), 0.0)
        tm = np.clip(tm, 0.0, T)
        lb = np.where(s > 0.0, d_lo - a * tm, np.minimum(d_lo, d_hi))
        out = lb if out is None else np.minimum(out, lb)
    assert out is not None  # the volume has at least one part (the gripper)
    return out


def _slice(st, idx):
    from .timeline import TimelineSample

    return TimelineSample(st.t[idx], st.position[idx], st.velocity[idx], st.acceleration[idx],
                          st.jerk[idx])


def _cat(a, b):
    from .timeline import TimelineSample

    return TimelineSample(*(np.concatenate([getattr(a, f), getattr(b, f)])
                            for f in ("t", "position", "velocity", "acceleration", "jerk")))
