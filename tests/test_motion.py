"""One motion type, one formula, one verifier, no import cycles.

* ``Profile`` (rest to rest), ``StateProfile``, the runtime's ``BrakeProfile``
  are :class:`~trajkit.profiles.motion.JerkMotion` objects; the feed's
  ``JerkPieces`` evaluates with the same phase formula.
* ``verify_trajectory`` checks trajectories of either planner; CSV columns are
  named ``q<i>_pos`` for unnamed axes.
* The planning packages import each other in one direction only.
"""

from __future__ import annotations

import ast
import json
import math
import pathlib

import numpy as np
import pytest

from trajkit import AxisLimits, plan_move
from trajkit.profiles import Profile, StateProfile
from trajkit.profiles._phase import phase_end, phase_eval
from trajkit.profiles.motion import JerkMotion
from trajkit.profiles.state import plan_state_to_state
from trajkit.runtime._brake import BrakeProfile, brake_profile
from trajkit.sync import plan_ptp, plan_ptp_states
from trajkit.verify import (
    verify_motion,
    verify_profile,
    verify_state_profile,
    verify_trajectory,
)

LIM = AxisLimits(v_max=1.0, a_max=2.0, j_max=10.0)
ASYM = AxisLimits(1.0, 2.0, 10.0, a_max_decel=1.0, j_max_decel=3.0)


def _motions():
    return [
        plan_move(0.2, 1.7, ASYM),
        plan_move(0.0, -0.4, LIM, duration=2.0),
        plan_state_to_state((0.0, 0.3, -1.0), (1.0, -0.2, 0.5), LIM),
        plan_state_to_state((0.0, 1.5, 0.0), (2.0, 0.0, 0.0), ASYM),  # with a brake
        brake_profile(0.0, 0.8, 1.5, ASYM),
    ]


def test_every_profile_is_a_jerk_motion():
    kinds = (Profile, Profile, StateProfile, StateProfile, BrakeProfile)
    for m, kind in zip(_motions(), kinds):
        assert isinstance(m, kind) and isinstance(m, JerkMotion)
        # the phase table reproduces the motion: a JerkMotion built from it samples the same
        twin = JerkMotion(m.start_state, m.phase_durations, m.jerks)
        t = np.linspace(0.0, m.duration, 257)
        a, b = m.sample(t), twin.sample(t)
        for f in ("position", "velocity", "acceleration"):
            np.testing.assert_allclose(getattr(a, f), getattr(b, f), rtol=1e-12, atol=1e-12)
        # the end state of the table is the goal (exact to round-off)
        np.testing.assert_allclose(twin.end_state, m.end_state, rtol=1e-9, atol=1e-12)
        assert verify_motion(m).ok


def test_state_at_is_what_sample_gives_there():
    """One time at once (Python floats) equals the vectorised sampler bit for bit
    (the same operations in the same order): at random times, at every phase
    boundary, before the start and after the end; on one-axis motions of every
    kind and on the axes of a trajectory between states."""
    rng = np.random.default_rng(5)
    lims = [AxisLimits(1.0, 2.0, 10.0), AxisLimits(0.5, 1.0, 5.0, 0.5, 2.0), AxisLimits(2.0, 4.0, 40.0)]
    trajs = [plan_ptp([0.0, 1.0, -2.0], [1.5, -0.5, 0.3], lims)]
    for _ in range(20):
        s = [(rng.uniform(-1, 1), 0.4 * rng.uniform(-1, 1) * lm.v_max, 0.0) for lm in lims]
        g = [(rng.uniform(-1, 1), 0.0, 0.0) for _lm in lims]
        trajs.append(plan_ptp_states(s, g, lims))
    motions = _motions() + [p for tr in trajs for p in tr.axes]
    checked = 0
    for m in motions:
        bounds = np.cumsum(m.phase_durations)
        ts = np.concatenate([[-0.5, 0.0, m.duration, m.duration + 0.7], bounds,
                             np.nextafter(bounds, -np.inf), rng.uniform(0.0, m.duration, 40)])
        smp = m.sample(ts)
        for i, t in enumerate(ts):
            assert m.state_at(t) == (smp.position[i], smp.velocity[i], smp.acceleration[i],
                                     smp.jerk[i]), (m, t)
            checked += 1
    assert checked > 3000
    for tr in trajs:
        for t in (0.0, 0.37 * tr.duration, tr.duration, tr.duration + 1.0):
            smp = tr.sample([t])
            want = np.stack([smp.position[0], smp.velocity[0], smp.acceleration[0], smp.jerk[0]])
            np.testing.assert_array_equal(tr.state_at(t), want)


def test_one_phase_formula():
    rng = np.random.default_rng(1)
    for _ in range(100):
        p, v, a, j, t = rng.normal(size=5)
        t = abs(t)
        e = phase_end(p, v, a, j, t)
        assert e == tuple(float(x) for x in phase_eval(np.float64(p), v, a, j, t))
        # its derivatives
        h = 1e-6
        assert (phase_end(p, v, a, j, t + h)[0] - phase_end(p, v, a, j, t - h)[0]) / (2 * h) == \
            pytest.approx(e[1], rel=1e-6, abs=1e-6)


def test_feed_pieces_use_the_phase_formula():
    from trajkit.interpolation._pieces import JerkPieces

    pieces = [(0.1, 10.0), (0.2, 0.0), (0.1, -10.0), (0.5, 0.0), (0.1, -10.0), (0.2, 0.0), (0.1, 10.0)]
    m = JerkMotion((0.5, 0.0, 0.0), [d for d, _ in pieces], [j for _, j in pieces])
    jp = JerkPieces(pieces, 0.5, m.end_state[0])
    t = np.linspace(0.0, m.duration * 0.999, 101)
    s = jp.sample(t)
    ref = m.sample(t)
    np.testing.assert_allclose(s[0], ref.position, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(s[1], ref.velocity, rtol=1e-13, atol=1e-13)


def test_extrema_and_to_dict():
    m = plan_state_to_state((0.0, 0.8, 0.0), (-0.3, 0.0, 0.0), LIM)  # overshoots, comes back
    ex = m.extrema()
    t = np.linspace(0.0, m.duration, 20001)
    s = m.sample(t)
    assert ex.position[0] <= s.position.min() + 1e-15 and ex.position[1] >= s.position.max() - 1e-15
    assert ex.position[1] == pytest.approx(s.position.max(), abs=1e-7)
    assert ex.velocity[0] == pytest.approx(s.velocity.min(), abs=1e-6)
    d = json.loads(json.dumps(m.to_dict()))
    assert d["duration_s"] == pytest.approx(m.duration)
    assert len(d["phases"]) == m.n_phases


def test_verify_trajectory_of_states_and_csv_names():
    # used to raise AttributeError, and the CSV said "0_pos"
    traj = plan_ptp([0, 0], [1, 2], LIM, start_velocity=[0.1, 0.2])
    rep = verify_trajectory(traj)
    assert rep.ok, rep.violations[:3]
    header = traj.to_csv(period=0.05).splitlines()[0].split(",")
    assert header[1].startswith("q0_position") and header[2].startswith("q0_velocity")
    assert [h for h in header if h.startswith("q1_position")]
    # the explicit state form gives the same plan
    traj2 = plan_ptp([(0, 0.1, 0), (0, 0.2, 0)], [(1, 0, 0), (2, 0, 0)], LIM)
    assert traj2.duration == pytest.approx(traj.duration, rel=1e-12)
    assert verify_trajectory(traj2).ok
    # rest to rest: Profiles, same verifier
    assert verify_trajectory(plan_ptp([0, 0], [1, 2], LIM)).ok


def test_the_verifier_finds_a_broken_motion():
    p = plan_state_to_state((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), LIM)
    bad = JerkMotion(p.start_state, p.phase_durations, [1.5 * j for j in p.jerks], None, p.goal_state)
    rep = verify_motion(bad, limits=LIM)
    assert not rep.ok
    assert {v.quantity for v in rep.violations} & {"jerk", "goal", "jerk_decel"}
    assert verify_profile(plan_move(0.0, 1.0, LIM)).ok
    assert verify_state_profile(p).ok


def test_the_verifier_takes_a_brake_ending_at_a_reversal():
    """A brake that ends where the velocity reverses (integrated to 1e-16 m/s,
    not to zero) leaves the acceleration of the speeding leg: -5.89 m/s^2,
    beyond the slowing leg's 2.43 but within the speeding one's 7.67. The
    samples at that instant have no meaningful sign of v * a; the verifier
    accepts the motion, and still refuses it with that acceleration held
    where the velocity is clearly positive."""
    lim = AxisLimits(2.988960718557596, 7.671486639116658, 23.462231297230435,
                     2.428105754707435, 82.84571870417285)
    p = plan_state_to_state((-1.571936214525773, 0.5137147037211093, -10.945710461386186),
                            (-3.1704661792652584, 0.0, -0.34921713928685877), lim)
    assert p.n_brake_phases == 1
    v_end, a_end = p.state_at(p.brake_duration)[1:3]
    assert abs(v_end) < 1e-12 and a_end < -lim.a_max_decel
    assert verify_motion(p).ok
    # the same acceleration entered while the axis still moves forward: slowing, too hard
    bad = JerkMotion((0.0, 0.5, a_end), (0.05,), (0.0,), None, None)
    rep = verify_motion(bad, limits=lim)
    assert not rep.ok and "deceleration" in {v.quantity for v in rep.violations}


# ------------------------------------------------------------------ imports
PKG = pathlib.Path(__file__).resolve().parents[1] / "src" / "trajkit"
#: The planning core: modules here must not import each other in a cycle
#: (module-level imports; a deferred import inside a function is not a cycle).
CORE = ("profiles", "sync", "trajectory", "verify", "runtime", "sync_states", "limits", "errors")


def _module_name(path: pathlib.Path) -> str:
    rel = path.relative_to(PKG.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _top_level_imports(path: pathlib.Path, name: str) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    pkg = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    out = set()
    for node in tree.body:  # module level only
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg.split(".")
                base = base[: len(base) - (node.level - 1)] if node.level > 1 else base
                mod = ".".join(base + ([node.module] if node.module else []))
                if node.module is None:
                    out.update(f"{mod}.{a.name}" for a in node.names)
                else:
                    out.add(mod)
                    out.update(f"{mod}.{a.name}" for a in node.names)
            elif node.module and node.module.startswith("trajkit"):
                out.add(node.module)
        elif isinstance(node, ast.Import):
            out.update(a.name for a in node.names if a.name.startswith("trajkit"))
    return out


def test_no_import_cycles_in_the_planning_core():
    mods = {}
    for path in PKG.rglob("*.py"):
        name = _module_name(path)
        top = name.split(".")[1] if "." in name else ""
        if top.split(".")[0] in CORE:
            mods[name] = path
    graph = {}
    for name, path in mods.items():
        deps = _top_level_imports(path, name)
        # a package import means its __init__; keep edges to modules of the core
        graph[name] = {d for d in deps if d in mods and d != name}
    # the old pairs are gone
    assert "trajkit.profiles._state_jit" not in mods
    assert not ("trajkit.sync_states" in graph.get("trajkit.trajectory", set())
                and "trajkit.trajectory" in graph.get("trajkit.sync_states", set()))
    # no cycle at all (depth-first search)
    state = {}

    def visit(n, stack):
        state[n] = 1
        for m in graph[n]:
            if state.get(m) == 1:
                cyc = stack[stack.index(m):] + [m] if m in stack else [n, m]
                raise AssertionError(f"import cycle: {' -> '.join(cyc)}")
            if m not in state:
                visit(m, stack + [m])
        state[n] = 2

    for n in sorted(graph):
        if n not in state:
            visit(n, [n])


def test_no_source_exec_in_the_kernels():
    for path in (PKG / "profiles").glob("*.py"):
        text = path.read_text(encoding="utf-8")
        assert "inspect.getsource" not in text and "exec(" not in text, path.name


def test_plan_ptp_takes_explicit_states():
    rest = plan_ptp([0.0, 0.0], [1.0, -1.0], LIM)
    assert all(isinstance(p, Profile) for p in rest.axes)
    states = plan_ptp([(0.0, 0.0, 0.0), (0.0, 0.0, 0.0)], [(1.0, 0.0, 0.0), (-1.0, 0.0, 0.0)], LIM)
    assert all(isinstance(p, StateProfile) for p in states.axes)
    # the same motion either way
    assert states.duration == pytest.approx(rest.duration, rel=1e-12)
    assert math.isfinite(states.duration)
