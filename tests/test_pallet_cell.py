"""The palletizing cell: exact prism distances (against coal), the cell planner on the
seed cell (targets, bound, order, settle), the independent cell check (sabotaged
plans, ptp/merged/optimal collide), random cells that never produce a colliding plan."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from conftest import sweep_size

from trajkit.errors import InvalidInputError
from trajkit.io import load_job, seed_cell_job_path
from trajkit.io.pallet_job import scenario_from_job
from trajkit.palletizing import (
    Cell,
    GripperVolume,
    Obstacle,
    check_cell,
    plan_cycle,
    seed_scenario,
    verify_plan,
)
from trajkit.palletizing.cell import (
    Prisms,
    footprint_signed_distance,
    moving_prisms,
    prism_signed_distance,
    required_height,
    stack_prisms,
    volume_floors,
)
from trajkit.palletizing.cellcheck import CLEARANCE_ATOL
from trajkit.palletizing.cellplan import FLOOR_MARGIN, TOUCH_TOL
from trajkit.palletizing.planners import CyclePlan
from trajkit.palletizing.report import cycle_rows
from trajkit.palletizing.timeline import Piece, Timeline

KEYS = ("cx", "cy", "hx", "hy", "yaw", "z0", "z1")


def _random_prisms(rng, n):
    return Prisms(
        cx=rng.uniform(-1, 1, n), cy=rng.uniform(-1, 1, n),
        hx=rng.uniform(0.01, 0.6, n), hy=rng.uniform(0.01, 0.6, n),
        yaw=rng.uniform(-math.pi, math.pi, n), z0=(z0 := rng.uniform(-0.5, 0.5, n)),
        z1=z0 + rng.uniform(0.01, 0.6, n),
    )


def _take(p, i):
    return Prisms(*(np.asarray(getattr(p, k))[i:i + 1] for k in KEYS))


# ------------------------------------------------------------------ geometry
def test_prism_distance_matches_coal(rng):
    coal = pytest.importorskip("coal")
    a, b = _random_prisms(rng, 400), _random_prisms(rng, 400)
    # a quarter of the pairs turned by multiples of 90 degrees (the stack's case)
    a.yaw[:100] = rng.integers(0, 4, 100) * math.pi / 2
    ours = prism_signed_distance(a, b)
    req = coal.DistanceRequest()
    req.gjk_tolerance = 1e-12
    n_pen = 0
    for i in range(400):
        g = []
        for p in (a, b):
            box = coal.Box(2 * p.hx[i], 2 * p.hy[i], p.z1[i] - p.z0[i])
            tf = coal.Transform3s()
            c, s = math.cos(p.yaw[i]), math.sin(p.yaw[i])
            tf.setRotation(np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]))
            tf.setTranslation(np.array([p.cx[i], p.cy[i], 0.5 * (p.z0[i] + p.z1[i])]))
            g += [box, tf]
        res = coal.DistanceResult()
        ref = coal.distance(g[0], g[1], g[2], g[3], req, res)
        if ref >= 0.0:
            assert ours[i] == pytest.approx(ref, abs=1e-9), i
        else:
            n_pen += 1
            # penetration depth: coal's EPA to its tolerance
            assert ours[i] == pytest.approx(ref, abs=1e-6), i
    assert 20 < n_pen < 380  # both cases are covered


def test_footprint_distance_is_symmetric_and_zero_on_contact(rng):
    a, b = _random_prisms(rng, 300), _random_prisms(rng, 300)
    np.testing.assert_allclose(footprint_signed_distance(a, b), footprint_signed_distance(b, a),
                               atol=1e-12)
    # two boxes side by side touch exactly
    one = Prisms(*(np.array([v]) for v in (0.0, 0.0, 0.3, 0.2, 0.0, 0.0, 0.2)))
    two = Prisms(*(np.array([v]) for v in (0.6, 0.0, 0.3, 0.2, 0.0, 0.0, 0.2)))
    assert footprint_signed_distance(one, two)[0] == pytest.approx(0.0, abs=1e-15)


def test_required_height_keeps_exactly_the_clearance(rng):
    c = 0.01
    d = rng.uniform(-0.05, 0.012, 500)
    top = rng.uniform(0.0, 1.0, 500)
    h = required_height(d, top, c)
    apart = d >= c
    assert np.all(np.isinf(h[apart]))
    near = ~apart
    # the 3-D distance at that height is the clearance (footprints apart) or the
    # vertical gap is the clearance (footprints overlapping)
    dz = h[near] - top[near]
    dist = np.where(d[near] > 0, np.hypot(d[near], dz), dz)
    np.testing.assert_allclose(dist, c, atol=1e-12)


def test_volume_floor_is_the_lowest_clear_height(rng):
    sc = load_job(seed_cell_job_path())
    obst = sc.cell.static_prisms().concat(stack_prisms(sc.place_poses()[:7], 0.6, 0.4, 0.2))
    q = np.column_stack([rng.uniform(-0.3, 2.0, 200), np.zeros(200), rng.uniform(0.3, 2.0, 200),
                         rng.uniform(-3, 3, 200)])
    F = volume_floors(q, (0.6, 0.4, 0.2), (0.6, 0.4, 0.1), True, obst, 0.01).max(axis=1)
    has = np.isfinite(F)
    assert has.sum() > 50
    for dz, ok in ((1e-9, True), (-1e-6, False)):
        qq = q[has].copy()
        qq[:, 1] = F[has] + dz
        d = np.full(qq.shape[0], np.inf)
        for part, _, _ in moving_prisms(qq, (0.6, 0.4, 0.2), (0.6, 0.4, 0.1), True):
            p = Prisms(*(np.asarray(getattr(part, k))[:, None] for k in KEYS))
            o = Prisms(*(np.asarray(getattr(obst, k))[None, :] for k in KEYS))
            d = np.minimum(d, prism_signed_distance(p, o).min(axis=1))
        if ok:
            assert np.all(d >= 0.01 - 1e-9)
        else:
            assert np.all(d < 0.01)


def test_volume_floors_without_obstacles_constrain_nothing():
    q = np.array([[0.0, 1.0, 1.5, 0.0], [1.0, 0.5, 1.0, 0.3]])
    F = volume_floors(q, (0.6, 0.4, 0.2), (0.6, 0.4, 0.1), True, Prisms.empty(), 0.01)
    assert F.shape == (2, 0) and F.dtype == np.float64
    empty = Cell().static_prisms()
    assert volume_floors(q, (0.6, 0.4, 0.2), (0.6, 0.4, 0.1), False, empty, 0.01).shape == (2, 0)


# ------------------------------------------------------------------ job file
def test_cell_section_is_validated_with_field_names():
    job = yaml.safe_load(seed_cell_job_path().read_text())
    sc = scenario_from_job(job)
    assert sc.cell.clearance == pytest.approx(0.01) and len(sc.cell.obstacles) == 5
    bad = yaml.safe_load(seed_cell_job_path().read_text())
    bad["cell"]["obstacles"][3]["z_mm"] = [450, 200]
    with pytest.raises(InvalidInputError, match=r"j\.yaml: field cell\.obstacles\.3\.z_mm: .*max > min"):
        scenario_from_job(bad, "j.yaml")
    bad = yaml.safe_load(seed_cell_job_path().read_text())
    bad["cell"]["clearance_mm"] = -1
    with pytest.raises(InvalidInputError, match=r"field cell\.clearance_mm: Input should be greater"):
        scenario_from_job(bad, "j.yaml")
    bad = yaml.safe_load(seed_cell_job_path().read_text())
    bad["cell"]["gripper"]["colour"] = "red"
    with pytest.raises(InvalidInputError, match=r"field cell\.gripper\.colour: Extra inputs"):
        scenario_from_job(bad, "j.yaml")
    bad = yaml.safe_load(seed_cell_job_path().read_text())
    bad["cell"]["obstacles"].append({"name": "post", "x_mm": [-100, 100], "y_mm": [1500, 1600],
                                     "z_mm": [0, 700]})
    with pytest.raises(InvalidInputError, match=r"obstacle 'post' overlaps box 3 at its place"):
        scenario_from_job(bad, "j.yaml")


def test_cell_objects_reject_bad_numbers():
    with pytest.raises(InvalidInputError, match="obstacle 'w': z max"):
        Obstacle((0, 1), (0, 1), (1, 0), "w")
    with pytest.raises(InvalidInputError, match="cell clearance must be >= 0"):
        Cell(clearance=-0.001)
    with pytest.raises(InvalidInputError, match="gripper height"):
        GripperVolume(height=0.0)
    with pytest.raises(InvalidInputError, match="needs a cell"):
        plan_cycle(seed_scenario(layers=1), "cell")


# --------------------------------------------------------------- seed cell
@pytest.fixture(scope="module")
def seed_cell():
    sc = load_job(seed_cell_job_path())
    plan = plan_cycle(sc, "cell")
    return sc, plan, verify_plan(plan)


def test_seed_cell_targets(seed_cell):
    sc, plan, rep = seed_cell
    assert rep.ok, rep.all_violations()[:3]
    assert rep.cell.min_clearance >= sc.cell.clearance - CLEARANCE_ATOL
    assert plan.total_s <= 82.0
    lb = plan.info["lower_bound_s"]
    assert plan.info["cell_floor_s"] <= lb <= plan.info["order_bound_s"] <= plan.total_s
    assert plan.total_s <= 1.03 * lb
    for tp, info in zip(plan.trips, plan.info["trips"]):
        assert info.duration == pytest.approx(tp.duration, rel=1e-12)
        assert info.lower_bound <= tp.duration * (1 + 1e-9)
        # over the floor, which keeps FLOOR_MARGIN (1 um) above the obstacles: a B motion
        # placed on its binding floor point touches it up to round-off
        assert info.margin >= -TOUCH_TOL and TOUCH_TOL < 1e-3 * FLOOR_MARGIN


def test_seed_cell_order_and_wrists(seed_cell):
    sc, plan, _ = seed_cell
    order = plan.info["order"]
    assert sorted(order) == list(range(25))
    assert [b // 5 for b in order] == sorted(b // 5 for b in order)  # layer by layer
    # the wrist may turn either way: the place is reached up to the box's symmetry
    poses = sc.place_poses()
    for tp in plan.trips[::2]:
        pose = sc.robot.pose_from_joints(tp.spec.q_goal)
        np.testing.assert_allclose(pose[:3], poses[tp.spec.box, :3], atol=1e-12)
        dy = (pose[3] - poses[tp.spec.box, 3]) % math.pi
        assert min(dy, math.pi - dy) < 1e-12


def test_seed_cell_settle_zones_are_vertical(seed_cell):
    sc, plan, _ = seed_cell
    tl = plan.timeline
    ends = plan.trip_starts + plan.trip_times()
    for _tp, ts, te in zip(plan.trips, plan.trip_starts, ends):
        t = np.linspace(ts, te, 2001)
        s = tl.sample(t)
        z0, z3 = s.position[0, 1], s.position[-1, 1]
        moving = np.any(np.abs(s.velocity[:, [0, 2, 3]]) > 1e-12, axis=1)
        assert np.all(s.position[moving, 1] >= min(z0, z3) + sc.cell.settle - 1e-9)
        # the horizontal joints start above the start's settle height, stop above the goal's
        i0, i1 = np.flatnonzero(moving)[[0, -1]]
        assert s.position[i0, 1] >= z0 + sc.cell.settle - 1e-9
        assert s.position[i1, 1] >= z3 + sc.cell.settle - 1e-9


def test_seed_rule_plans_collide_in_the_cell(seed_cell):
    sc = seed_cell[0]
    n_pierce = {}
    for name in ("ptp", "merged", "optimal"):
        rep = check_cell(plan_cycle(sc, name))
        assert not rep.ok
        assert rep.min_clearance < 0.0
        n_pierce[name] = len(rep.colliding_boxes)
        assert any("placed box" in f.obstacle for f in rep.findings if f.penetrates)
    assert n_pierce["ptp"] > n_pierce["merged"] >= n_pierce["optimal"] > 0


def test_cycle_rows_cover_the_whole_job(seed_cell):
    _, plan, _ = seed_cell
    r = cycle_rows(plan, 0.05)
    assert r["t_s"][0] == 0.0 and r["t_s"][-1] == pytest.approx(plan.total_s, abs=0)
    assert set(r["trip"]) == {"load", "return"}
    assert np.all(r["carrying"] == (r["trip"] == "load"))
    assert list(dict.fromkeys(r["box"].tolist())) == plan.info["order"]
    assert r["B_mm"].min() >= 400.0 - 1e-9 and r["C_mm"].min() >= 300.0


# ------------------------------------------------------------ sabotage
def _small_cell_job(**cell_overrides):
    job = yaml.safe_load(seed_cell_job_path().read_text())
    job["layers"] = 2
    job["cell"].update(cell_overrides)
    return scenario_from_job(job)


def test_a_horizontal_move_5_mm_too_low_is_caught():
    honest = _small_cell_job()
    low = _small_cell_job(clearance_mm=5)       # planned as if 5 mm were enough
    plan = plan_cycle(low, "cell")
    assert verify_plan(plan).ok                  # fine in the cell it was planned for
    judged = CyclePlan(plan.planner, honest, plan.trips, plan.trip_starts, plan.timeline,
                       plan.info, plan.rule)
    rep = verify_plan(judged)
    assert rep.ok_without_cell and not rep.ok
    worst = min(f.distance for f in rep.cell.findings)
    assert worst == pytest.approx(0.005, abs=2e-4)
    assert all(f.moving and not f.penetrates for f in rep.cell.findings)


def _swap_boxes(plan: CyclePlan, i: int, j: int) -> CyclePlan:
    """The same motions, but boxes ``i`` and ``j`` (trip pairs) swapped in time."""
    order = list(range(len(plan.trips) // 2))
    order[i], order[j] = order[j], order[i]
    trips, pieces, starts, t = [], [[] for _ in range(4)], [], 0.0
    for k in order:
        for tp in plan.trips[2 * k:2 * k + 2]:
            starts.append(t)
            trips.append(tp)
            for jn in range(4):
                pieces[jn] += [Piece(t + pc.t0, pc.profile) for pc in tp.pieces[jn]]
            t += tp.duration
    tl = Timeline(pieces, plan.timeline.start, t, names=plan.timeline.names)
    return CyclePlan(plan.planner, plan.scenario, trips, np.array(starts), tl, plan.info, plan.rule)


@pytest.fixture(scope="module")
def small_cell_plan():
    sc = _small_cell_job()
    return plan_cycle(sc, "cell")


def test_a_box_placed_out_of_order_is_caught(small_cell_plan):
    plan = small_cell_plan
    assert verify_plan(plan).ok
    # across layers: a layer-2 box before layer 1 is complete
    rep = verify_plan(_swap_boxes(plan, 2, 6))
    assert any("before layer 1 is complete" in v for v in rep.violations)
    # within a layer: the motions planned for the other order drive a box into
    # one that is now already placed (or place it through one)
    a, b = 1, 3
    rep = verify_plan(_swap_boxes(plan, a, b))
    assert not rep.violations  # the order itself is a valid one
    assert not rep.cell.ok and rep.cell.colliding_boxes


def test_certified_minimum_is_not_above_a_dense_sweep(small_cell_plan):
    plan = small_cell_plan
    rep = check_cell(plan)
    t_c, trip, obst, _ = rep.min_clearance_at
    ts = plan.trip_starts[trip]
    te = ts + plan.trips[trip].duration
    from trajkit.palletizing.cellcheck import _distances, _obstacles_per_trip
    sc = plan.scenario
    ob = _obstacles_per_trip(plan)[trip]
    t = np.linspace(ts, te, 20001)
    q = plan.timeline.sample(t).position
    s = plan.timeline.sample(t)
    moving = np.any(np.abs(s.velocity[:, [0, 2, 3]]) > 0.0, axis=1)
    d = _distances(q[moving], (0.6, 0.4, 0.2), sc.cell.gripper_size(0.6, 0.4),
                   plan.trips[trip].spec.kind == "load", ob)
    # the certified bound is below every distance of a 20x denser sweep, and
    # both keep the clearance (to the tolerance)
    assert rep.min_clearance_bound <= d.min() + 1e-12
    assert rep.min_clearance_bound <= rep.min_clearance
    assert d.min() >= sc.cell.clearance - CLEARANCE_ATOL
    assert rep.min_clearance_bound >= sc.cell.clearance - 2 * CLEARANCE_ATOL


# ------------------------------------------------------------ random cells
def _random_cell_job(rng):
    L = float(rng.uniform(400, 650))
    W = float(rng.uniform(250, min(450, 0.8 * L)))
    H = float(rng.uniform(150, 300))
    pattern = str(rng.choice(["column", "interlock", "pinwheel"]))
    pal = (float(rng.uniform(1000, 1300)), float(rng.uniform(900, 1200)))
    if pattern == "pinwheel":
        pal = (max(pal), max(pal))
    px, pz = float(rng.uniform(1000, 1400)), float(rng.uniform(300, 600))
    guide_gap = float(rng.uniform(4, 40))       # box to guide, may be below the clearance
    guide_top = pz - H + float(rng.uniform(60, 220))
    stop_gap = float(rng.uniform(10, 40))
    belt = [pz - H - 200, pz - H]
    half_w = W / 2 + guide_gap
    pal_top = float(rng.uniform(250, 500))
    pc = [float(rng.uniform(-300, 300)), float(rng.uniform(1300, 1600))]
    return {
        "name": "random cell",
        "pick": {"x_mm": px, "y_mm": 0, "z_mm": pz, "yaw_deg": 0},
        "pallet": {"centre_mm": [pc[0], pc[1], pal_top], "length_mm": pal[0], "width_mm": pal[1]},
        "box": {"length_mm": L, "width_mm": W, "height_mm": H},
        "pattern": {"name": pattern, "alternate": str(rng.choice(["none", "rotate180", "mirror"]))},
        "layers": int(rng.integers(1, 3)),
        "cell": {
            "clearance_mm": float(rng.uniform(5, 15)),
            "settle_mm": float(rng.uniform(10, 30)),
            "gripper": {"height_mm": float(rng.uniform(60, 150))},
            "obstacles": [
                {"name": "belt", "x_mm": [px - L / 2 - 300, px + L / 2], "y_mm": [-half_w - 80, half_w + 80],
                 "z_mm": belt},
                {"name": "guide +y", "x_mm": [px - L / 2 - 300, px + L / 2], "y_mm": [half_w, half_w + 20],
                 "z_mm": [belt[1], guide_top]},
                {"name": "guide -y", "x_mm": [px - L / 2 - 300, px + L / 2], "y_mm": [-half_w - 20, -half_w],
                 "z_mm": [belt[1], guide_top]},
                {"name": "end stop", "x_mm": [px + L / 2 + stop_gap, px + L / 2 + stop_gap + 20],
                 "y_mm": [-half_w - 60, half_w + 60], "z_mm": [belt[1], pz + float(rng.uniform(0, 60))]},
                {"name": "pallet", "x_mm": [pc[0] - pal[0] / 2, pc[0] + pal[0] / 2],
                 "y_mm": [pc[1] - pal[1] / 2, pc[1] + pal[1] / 2], "z_mm": [pal_top - 150, pal_top]},
            ],
        },
    }


@pytest.mark.parametrize("seed", range(sweep_size(3)))
def test_random_cells_never_produce_a_colliding_plan(seed):
    rng = np.random.default_rng(1500 + seed)
    for _ in range(20):  # draw until the job is valid (reach, fit)
        job = _random_cell_job(rng)
        try:
            sc = scenario_from_job(job)
        except Exception:
            continue
        break
    else:  # pragma: no cover - the generator is tuned to give valid jobs
        pytest.skip("no valid random job")
    plan = plan_cycle(sc, "cell")
    rep = verify_plan(plan)
    assert rep.ok, rep.all_violations()[:3]
    assert rep.cell.min_clearance >= sc.cell.clearance - CLEARANCE_ATOL
    assert plan.info["lower_bound_s"] <= plan.total_s * (1 + 1e-12)


def test_cell_check_of_a_job_without_a_cell_is_a_typed_error():
    from trajkit.io import seed_job_path

    plan = plan_cycle(load_job(seed_job_path()), "ptp")
    with pytest.raises(InvalidInputError, match="has no cell to check against"):
        check_cell(plan)
