"""Speed of trajkit's profile planner and sampler, side by side with ruckig.

One run measures, on the same random rest-to-rest moves (symmetric limits,
so ruckig plans the same problem):

1. scalar ``plan_move`` vs ``ruckig.Ruckig(1).calculate`` (one call per move);
2. batch ``plan_moves`` (per move) vs the same ruckig loop;
3. 6-axis ``plan_ptp`` (sync="time") vs ``Ruckig(6).calculate``;
4. vectorised ``Profile.sample`` / ``Trajectory.sample`` vs ruckig's
   ``Trajectory.at_time`` loop (axis-samples per second).

Every timing is the best of ``--repeat`` runs of a whole loop (wall clock,
``time.perf_counter``), divided by the number of moves or samples. The
ruckig loops include setting the input parameters from Python, as a Python
caller must. The durations of both planners are compared as a sanity check.

Run::

    python benchmarks/bench_profiles.py            # table
    python benchmarks/bench_profiles.py --json     # machine-readable

Needs ``pip install ruckig`` (``trajkit[bench]``). These are single calls
on small arrays, so BLAS is not involved; see benchmarks/README.md about
OPENBLAS_CORETYPE anyway.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from collections.abc import Callable

import numpy as np

import trajkit
from trajkit import AxisLimits, plan_move, plan_moves, plan_ptp

#: Performance targets (what the table compares against).
TARGET_BATCH_SPEEDUP = 10.0  # plan_moves per move vs ruckig 1-DoF per move
TARGET_SCALAR_US = 15.0  # plan_move [us]
TARGET_PTP6_US = 60.0  # 6-axis plan_ptp [us]
TARGET_SAMPLES_PER_S = 20e6  # axis-samples per second

#: Relative agreement expected between trajkit's and ruckig's durations
#: (ruckig's own root finding is accurate to about 1e-12).
DURATION_AGREE_RTOL = 1e-8


def random_moves(n: int, rng: np.random.Generator, n_axes: int = 1) -> dict[str, np.ndarray]:
    """Random rest-to-rest moves spanning every profile shape.

    Distances 1e-3..10, limits v 0.1..10, a 0.1..10, j 1..100 (log-uniform),
    so short moves (no cruise, no constant acceleration) and long ones
    (7 phases) both appear. Arrays of shape (n, n_axes).
    """
    shape = (n, n_axes)
    start = rng.uniform(-1.0, 1.0, shape)
    dist = 10.0 ** rng.uniform(-3.0, 1.0, shape) * rng.choice([-1.0, 1.0], shape)
    return {
        "start": start,
        "goal": start + dist,
        "v": 10.0 ** rng.uniform(-1.0, 1.0, shape),
        "a": 10.0 ** rng.uniform(-1.0, 1.0, shape),
        "j": 10.0 ** rng.uniform(0.0, 2.0, shape),
    }


def best_of(fn: Callable[[], object], repeat: int) -> float:
    """Smallest wall-clock time [s] of ``repeat`` calls of ``fn``."""
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def _ruckig_setup(ndof: int):
    import ruckig

    otg = ruckig.Ruckig(ndof)
    inp = ruckig.InputParameter(ndof)
    out = ruckig.Trajectory(ndof)
    zeros = [0.0] * ndof
    inp.current_velocity = zeros
    inp.current_acceleration = zeros
    inp.target_velocity = zeros
    inp.target_acceleration = zeros
    return ruckig, otg, inp, out


def bench(n_scalar: int, n_batch: int, n_ptp: int, n_samples: int, repeat: int,
          seed: int) -> dict:
    """Run every measurement; return a JSON-ready dict of results."""
    ruckig, otg1, inp1, tr1 = _ruckig_setup(1)
    rng = np.random.default_rng(seed)
    res: dict = {}

    # ---- 1. scalar plan_move vs Ruckig(1).calculate ----------------------
    m = random_moves(n_scalar, rng)
    s, g = m["start"][:, 0].tolist(), m["goal"][:, 0].tolist()
    v, a, j = m["v"][:, 0].tolist(), m["a"][:, 0].tolist(), m["j"][:, 0].tolist()
    lims = [AxisLimits(v[i], a[i], j[i]) for i in range(n_scalar)]
    ours = np.empty(n_scalar)
    theirs = np.empty(n_scalar)

    def run_tk():
        for i in range(n_scalar):
            ours[i] = plan_move(s[i], g[i], lims[i]).duration

    def run_rk():
        for i in range(n_scalar):
            inp1.current_position = [s[i]]
            inp1.target_position = [g[i]]
            inp1.max_velocity = [v[i]]
            inp1.max_acceleration = [a[i]]
            inp1.max_jerk = [j[i]]
            otg1.calculate(inp1, tr1)
            theirs[i] = tr1.duration

    # ruckig's calculate alone, on prepared inputs (what its C++ costs from Python)
    inputs = []
    for i in range(n_scalar):
        ip = ruckig.InputParameter(1)
        ip.current_position, ip.target_position = [s[i]], [g[i]]
        ip.max_velocity, ip.max_acceleration, ip.max_jerk = [v[i]], [a[i]], [j[i]]
        inputs.append(ip)

    def run_rk_calc():
        for ip in inputs:
            otg1.calculate(ip, tr1)

    t_tk = best_of(run_tk, repeat) / n_scalar
    t_rk = best_of(run_rk, repeat) / n_scalar
    t_rk_calc = best_of(run_rk_calc, repeat) / n_scalar
    t_lim = best_of(lambda: [AxisLimits(v[i], a[i], j[i]) for i in range(n_scalar)],
                    repeat) / n_scalar
    rel = np.abs(ours - theirs) / theirs
    res["scalar"] = {
        "moves": n_scalar, "trajkit_us": t_tk * 1e6, "ruckig_us": t_rk * 1e6,
        "ratio_ruckig_over_trajkit": t_rk / t_tk, "axislimits_us": t_lim * 1e6,
        "ruckig_calculate_only_us": t_rk_calc * 1e6,
        "max_rel_duration_diff": float(rel.max()),
        "target_us": TARGET_SCALAR_US,
    }
    ruckig_1dof_us = t_rk_calc * 1e6

    # ---- 2. batch plan_moves per move vs the ruckig loop ------------------
    mb = random_moves(n_batch, rng)
    sb, gb = mb["start"][:, 0], mb["goal"][:, 0]
    vb, ab, jb = mb["v"][:, 0], mb["a"][:, 0], mb["j"][:, 0]
    t_b = best_of(lambda: plan_moves(sb, gb, vb, ab, jb), repeat) / n_batch
    batch = plan_moves(sb, gb, vb, ab, jb)
    # ruckig on a subset of the same moves (a loop is linear in N)
    k = min(n_batch, n_scalar)
    rk_dur = np.empty(k)
    for i in range(k):
        inp1.current_position = [float(sb[i])]
        inp1.target_position = [float(gb[i])]
        inp1.max_velocity = [float(vb[i])]
        inp1.max_acceleration = [float(ab[i])]
        inp1.max_jerk = [float(jb[i])]
        otg1.calculate(inp1, tr1)
        rk_dur[i] = tr1.duration
    rel_b = np.abs(batch.duration[:k] - rk_dur) / rk_dur
    res["batch"] = {
        "moves": n_batch, "trajkit_us_per_move": t_b * 1e6,
        "ruckig_us_per_move": ruckig_1dof_us,
        "speedup_vs_ruckig": ruckig_1dof_us / (t_b * 1e6),
        "ruckig_with_input_setting_us_per_move": t_rk * 1e6,
        "speedup_vs_ruckig_with_input_setting": t_rk / t_b,
        "max_rel_duration_diff": float(rel_b.max()),
        "target_speedup": TARGET_BATCH_SPEEDUP,
    }

    # ---- 3. 6-axis plan_ptp vs Ruckig(6) ----------------------------------
    _, otg6, inp6, tr6 = _ruckig_setup(6)
    m6 = random_moves(n_ptp, rng, 6)
    s6, g6 = m6["start"].tolist(), m6["goal"].tolist()
    v6, a6, j6 = m6["v"].tolist(), m6["a"].tolist(), m6["j"].tolist()
    lims6 = [[AxisLimits(v6[i][k], a6[i][k], j6[i][k], name=k) for k in range(6)]
             for i in range(n_ptp)]
    d6_tk = np.empty(n_ptp)
    d6_rk = np.empty(n_ptp)

    def run_tk6():
        for i in range(n_ptp):
            d6_tk[i] = plan_ptp(s6[i], g6[i], lims6[i], sync="time").duration

    def run_rk6():
        for i in range(n_ptp):
            inp6.current_position = s6[i]
            inp6.target_position = g6[i]
            inp6.max_velocity = v6[i]
            inp6.max_acceleration = a6[i]
            inp6.max_jerk = j6[i]
            otg6.calculate(inp6, tr6)
            d6_rk[i] = tr6.duration

    t6_tk = best_of(run_tk6, repeat) / n_ptp
    t6_rk = best_of(run_rk6, repeat) / n_ptp
    rel6 = np.abs(d6_tk - d6_rk) / d6_rk
    res["ptp6"] = {
        "moves": n_ptp, "trajkit_us": t6_tk * 1e6, "ruckig_us": t6_rk * 1e6,
        "ratio_ruckig_over_trajkit": t6_rk / t6_tk,
        "max_rel_duration_diff": float(rel6.max()),
        "target_us": TARGET_PTP6_US,
    }

    # ---- 4. sampling -------------------------------------------------------
    lim = AxisLimits(1.0, 2.0, 10.0, 1.5, 5.0)
    prof = plan_move(0.0, 1.0, lim)
    t = np.linspace(0.0, prof.duration, n_samples)
    ts_prof = best_of(lambda: prof.sample(t), repeat)
    traj = plan_ptp([0.0] * 6, [1.0, -2.0, 0.5, 3.0, -0.2, 1.5], lim, sync="time")
    n6 = max(n_samples // 6, 1)
    t6 = np.linspace(0.0, traj.duration, n6)
    ts_traj = best_of(lambda: traj.sample(t6), repeat)
    # ruckig: at_time loop on the same 1-DoF and 6-DoF motions
    inp1.current_position, inp1.target_position = [0.0], [1.0]
    inp1.max_velocity, inp1.max_acceleration, inp1.max_jerk = [1.0], [2.0], [10.0]
    otg1.calculate(inp1, tr1)
    n_rk = max(n_samples // 20, 1)
    tr_list = np.linspace(0.0, tr1.duration, n_rk).tolist()
    ts_rk1 = best_of(lambda: [tr1.at_time(x) for x in tr_list], repeat)
    inp6.current_position = [0.0] * 6
    inp6.target_position = [1.0, -2.0, 0.5, 3.0, -0.2, 1.5]
    inp6.max_velocity, inp6.max_acceleration, inp6.max_jerk = [1.0] * 6, [2.0] * 6, [10.0] * 6
    otg6.calculate(inp6, tr6)
    tr6_list = np.linspace(0.0, tr6.duration, n_rk).tolist()
    ts_rk6 = best_of(lambda: [tr6.at_time(x) for x in tr6_list], repeat)
    rate_prof = n_samples / ts_prof
    rate_traj = 6 * n6 / ts_traj
    rate_rk1 = n_rk / ts_rk1
    rate_rk6 = 6 * n_rk / ts_rk6
    res["sampling"] = {
        "profile_samples": n_samples, "trajectory_times": n6,
        "profile_axis_samples_per_s": rate_prof,
        "trajectory_axis_samples_per_s": rate_traj,
        "ruckig_1dof_axis_samples_per_s": rate_rk1,
        "ruckig_6dof_axis_samples_per_s": rate_rk6,
        "ratio_profile_over_ruckig": rate_prof / rate_rk1,
        "ratio_trajectory_over_ruckig": rate_traj / rate_rk6,
        "target_axis_samples_per_s": TARGET_SAMPLES_PER_S,
    }
    res["environment"] = environment()
    res["settings"] = {"seed": seed, "repeat": repeat}
    return res


def environment() -> dict:
    """Versions, CPU count and the BLAS-related environment of this run."""
    try:
        import ruckig

        rk_version = getattr(ruckig, "__version__", None)
        if rk_version is None:
            from importlib.metadata import version

            rk_version = version("ruckig")
    except Exception:  # pragma: no cover
        rk_version = None
    env = {
        "python": platform.python_version(),
        "numpy": np.__version__,
        "trajkit": trajkit.__version__,
        "ruckig": rk_version,
        "cpus": os.cpu_count(),
        "machine": platform.machine(),
        "cpu": _cpu_model(),
        "OPENBLAS_CORETYPE": os.environ.get("OPENBLAS_CORETYPE"),
        "OPENBLAS_L2_SIZE": os.environ.get("OPENBLAS_L2_SIZE"),
    }
    try:
        from threadpoolctl import threadpool_info

        env["blas"] = [
            {k: d.get(k) for k in ("internal_api", "version", "architecture", "num_threads")}
            for d in threadpool_info() if d.get("user_api") == "blas"
        ]
    except ImportError:
        env["blas"] = None
    return env


def _cpu_model() -> str | None:
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or None


def _verdict(ok: bool) -> str:
    return "meets" if ok else "MISSES"


def print_report(r: dict) -> None:
    """Print the results as a plain-text table."""
    sc, b, p6, sm = r["scalar"], r["batch"], r["ptp6"], r["sampling"]
    rows = [
        ("scalar plan_move vs Ruckig(1).calculate", f"{sc['trajkit_us']:.2f} us",
         f"{sc['ruckig_us']:.2f} us", f"{sc['ratio_ruckig_over_trajkit']:.3f}",
         f"< {TARGET_SCALAR_US:g} us: {_verdict(sc['trajkit_us'] < TARGET_SCALAR_US)}"),
        ("batch plan_moves per move vs calculate only",
         f"{b['trajkit_us_per_move']:.3f} us",
         f"{b['ruckig_us_per_move']:.2f} us", f"{b['speedup_vs_ruckig']:.2f}",
         f">= {TARGET_BATCH_SPEEDUP:g}x: "
         f"{_verdict(b['speedup_vs_ruckig'] >= TARGET_BATCH_SPEEDUP)}"),
        ("6-axis plan_ptp vs Ruckig(6).calculate", f"{p6['trajkit_us']:.2f} us",
         f"{p6['ruckig_us']:.2f} us", f"{p6['ratio_ruckig_over_trajkit']:.3f}",
         f"< {TARGET_PTP6_US:g} us: {_verdict(p6['trajkit_us'] < TARGET_PTP6_US)}"),
        ("Profile.sample vs at_time (1 axis)",
         f"{sm['profile_axis_samples_per_s'] / 1e6:.1f} M/s",
         f"{sm['ruckig_1dof_axis_samples_per_s'] / 1e6:.2f} M/s",
         f"{sm['ratio_profile_over_ruckig']:.1f}",
         f"> {TARGET_SAMPLES_PER_S / 1e6:g} M/s: "
         f"{_verdict(sm['profile_axis_samples_per_s'] > TARGET_SAMPLES_PER_S)}"),
        ("Trajectory.sample vs at_time (6 axes)",
         f"{sm['trajectory_axis_samples_per_s'] / 1e6:.1f} M/s",
         f"{sm['ruckig_6dof_axis_samples_per_s'] / 1e6:.2f} M/s",
         f"{sm['ratio_trajectory_over_ruckig']:.1f}",
         f"> {TARGET_SAMPLES_PER_S / 1e6:g} M/s: "
         f"{_verdict(sm['trajectory_axis_samples_per_s'] > TARGET_SAMPLES_PER_S)}"),
    ]
    head = ("measurement", "trajkit", "ruckig", "ratio (trajkit faster by)", "target")
    widths = [max(len(str(x[i])) for x in rows + [head]) for i in range(5)]
    line = "  ".join(f"{{:<{w}}}" for w in widths)
    print(line.format(*head))
    print("  ".join("-" * w for w in widths))
    for row in rows:
        print(line.format(*row))
    print()
    print(f"durations trajkit vs ruckig, max relative difference: scalar "
          f"{sc['max_rel_duration_diff']:.2e}, batch {b['max_rel_duration_diff']:.2e}, "
          f"6-axis {p6['max_rel_duration_diff']:.2e}")
    print(f"batch vs the ruckig loop including Python input setting: "
          f"{b['speedup_vs_ruckig_with_input_setting']:.2f}x; ruckig calculate alone "
          f"{sc['ruckig_calculate_only_us']:.2f} us/move ({b['moves']} moves in one "
          f"plan_moves call)")
    print(f"AxisLimits construction (not in the times above): {sc['axislimits_us']:.2f} us")
    e = r["environment"]
    print(f"python {e['python']}, numpy {e['numpy']}, ruckig {e['ruckig']}, "
          f"{e['cpus']} cpus ({e['cpu']}), OPENBLAS_CORETYPE={e['OPENBLAS_CORETYPE']}, "
          f"blas={e['blas']}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--moves", type=int, default=5000, help="scalar loop moves (default 5000)")
    ap.add_argument("--batch", type=int, default=100_000,
                    help="moves in one plan_moves call (default 100000)")
    ap.add_argument("--ptp", type=int, default=2000, help="6-axis moves (default 2000)")
    ap.add_argument("--samples", type=int, default=1_000_000,
                    help="sample times for Profile.sample (default 1e6)")
    ap.add_argument("--repeat", type=int, default=5, help="best of this many runs (default 5)")
    ap.add_argument("--seed", type=int, default=2)
    ap.add_argument("--json", action="store_true", help="print JSON instead of a table")
    args = ap.parse_args(argv)
    for name in ("moves", "batch", "ptp", "samples", "repeat"):
        if getattr(args, name) < 1:
            ap.error(f"--{name} must be >= 1, got {getattr(args, name)}")
    try:
        import ruckig  # noqa: F401
    except ImportError:
        print("bench_profiles needs ruckig: pip install ruckig", file=sys.stderr)
        return 2
    r = bench(args.moves, args.batch, args.ptp, args.samples, args.repeat, args.seed)
    if args.json:
        json.dump(r, sys.stdout, indent=2)
        print()
    else:
        print_report(r)
    bad = max(r["scalar"]["max_rel_duration_diff"], r["batch"]["max_rel_duration_diff"],
              r["ptp6"]["max_rel_duration_diff"])
    if bad > DURATION_AGREE_RTOL:
        print(f"WARNING: trajkit and ruckig durations differ by {bad:.3e} relative",
              file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
