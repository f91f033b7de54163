"""Speed of the state-to-state planner side by side with ruckig, in one run.

Seeded random states over the hard corners (the generator of
``tests/state_reference.py``), symmetric limits (ruckig's problem), moving
start and goal states. Rows:

* **1 axis**: ``plan_state_to_state(start, goal, limits)`` per call vs
  ``Ruckig(1).calculate`` per call (the five input lists set in Python each
  call, as a controller would). Each case is timed ``--repeat`` times, the
  best is kept; median and 99th percentile over the cases.
* **6 axes**: ``plan_ptp_states(start, goal, limits)`` (time
  synchronisation) vs ``Ruckig(6).calculate``; then the control cycle: the
  same plan and the state one period (1 ms) in, ``Trajectory.state_at`` vs
  ruckig's ``at_time`` (trajkit makes the axes' profile objects on that
  first access).
* **batch**: ``plan_state_moves`` on ``--batch`` moves in one call vs a
  Python loop of ``Ruckig(1).calculate`` over the same moves (inputs set as
  in the 1-axis row), per move (throughput); the two calls alternate
  ``--batch-repeat`` times (default 20: a call of 20,000 moves lasts a few
  milliseconds, where the machine's jitter shows in a best of few) and the
  best of each is kept. A line below gives the
  parts: ``plan_state_moves`` on one thread, and ruckig's ``calculate`` alone
  (its inputs set before the timer), per move.
* **fixed duration** (trajkit only): ``plan_state_to_state(..., duration=T)``
  with ``T = 1.3 T_min`` (or the end of the blocked interval it falls in); asymmetric limits ``min_state_duration``.

Every duration is compared with ruckig's (max relative difference printed).
The compiled kernel (numba, ``pip install trajkit[fast]``) is loaded or
compiled before the timed loops; its one-off cost is printed on its own line.

Run::

    python benchmarks/bench_states.py [--n 300] [--seed 1] [--repeat 5] [--batch 20000]
                                      [--batch-repeat 20]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from state_reference import random_case

from trajkit import AxisLimits, plan_ptp_states, plan_state_moves
from trajkit.profiles.state import (
    feasible_durations,
    min_state_duration,
    plan_state_to_state,
)


def _ruckig(n_dof):
    from ruckig import InputParameter, Ruckig, Trajectory

    return Ruckig(n_dof), InputParameter(n_dof), Trajectory(n_dof)


def _set_inputs(inp, s, g, L):
    """A 1-axis ruckig input from Python lists, as a controller sets it each call."""
    inp.current_position = [s[0]]
    inp.current_velocity = [s[1]]
    inp.current_acceleration = [s[2]]
    inp.target_position = [g[0]]
    inp.target_velocity = [g[1]]
    inp.target_acceleration = [g[2]]
    inp.max_velocity = [L[0]]
    inp.max_acceleration = [L[1]]
    inp.max_jerk = [L[2]]


def _best(fn, repeat):
    b = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        b = min(b, time.perf_counter() - t0)
    return b


def _cases(rng, n, dof=1):
    out = []
    while len(out) < n:
        cs = [random_case(rng, symmetric=True) for _ in range(dof)]
        if any(c[0] == c[1] for c in cs):
            continue
        out.append(cs)
    return out


def _row(name, tk, rk, ratio_note=""):
    tk, rk = np.asarray(tk) * 1e6, np.asarray(rk) * 1e6
    m1, m2 = np.median(tk), np.median(rk)
    p1, p2 = np.percentile(tk, 99), np.percentile(rk, 99)
    print(f"| {name} | {m1:.2f} / {p1:.2f} us | {m2:.2f} / {p2:.2f} us | "
          f"median {m1 / m2:.1f}x, p99 {p1 / p2:.1f}x{ratio_note} |")
    return m1, m2, p1, p2


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=300, help="random cases (1 axis and 6 axes)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--repeat", type=int, default=5, help="calls per case (best is kept)")
    ap.add_argument("--batch-repeat", type=int, default=20,
                    help="alternated calls of the batch rows (best is kept)")
    ap.add_argument("--batch", type=int, default=20000, help="moves of the batch row")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    lim0 = AxisLimits(1.0, 1.0, 1.0)
    min_state_duration((0.0, 0.1, 0.0), (1.0, 0.0, 0.0), lim0)
    plan_ptp_states([(0.0, 0.1, 0.0)] * 2, [(1.0, 0.0, 0.0)] * 2, lim0)
    plan_state_moves([(0.0, 0.1, 0.0)] * 2, [(1.0, 0.0, 0.0)] * 2, 1.0, 1.0, 1.0)
    print(f"first calls (imports, numba compile or cache load): {time.perf_counter() - t0:.3f} s")
    print(f"cores: {os.cpu_count()}, numba threads: "
          f"{__import__('numba').get_num_threads() if _has_numba() else 'no numba'}")
    rng = np.random.default_rng(args.seed)
    worst = 0.0

    # ---- 1 axis
    r, inp, traj = _ruckig(1)
    tk, rk = [], []
    for (c,) in _cases(rng, args.n):
        s, g, L = c
        lim = AxisLimits(*L)

        def one_rk(s=s, g=g, L=L):
            _set_inputs(inp, s, g, L)
            r.calculate(inp, traj)

        tk.append(_best(lambda s=s, g=g, lim=lim: plan_state_to_state(s, g, lim), args.repeat))
        rk.append(_best(one_rk, args.repeat))
        worst = max(worst, abs(plan_state_to_state(s, g, lim).duration - traj.duration) / traj.duration)
    print()
    print("| measurement (median / p99 per call) | trajkit | ruckig 0.19 | trajkit / ruckig |")
    print("|---|---|---|---|")
    _row("1 axis: `plan_state_to_state` vs `Ruckig(1).calculate`", tk, rk)

    # ---- 6 axes
    r6, inp6, traj6 = _ruckig(6)
    tk, rk, tk_cy, rk_cy = [], [], [], []
    for cs in _cases(rng, args.n, dof=6):
        S = [c[0] for c in cs]
        G = [c[1] for c in cs]
        lims = [AxisLimits(*c[2]) for c in cs]

        def six_rk(cs=cs):
            inp6.current_position = [c[0][0] for c in cs]
            inp6.current_velocity = [c[0][1] for c in cs]
            inp6.current_acceleration = [c[0][2] for c in cs]
            inp6.target_position = [c[1][0] for c in cs]
            inp6.target_velocity = [c[1][1] for c in cs]
            inp6.target_acceleration = [c[1][2] for c in cs]
            inp6.max_velocity = [c[2][0] for c in cs]
            inp6.max_acceleration = [c[2][1] for c in cs]
            inp6.max_jerk = [c[2][2] for c in cs]
            r6.calculate(inp6, traj6)

        tk.append(_best(lambda S=S, G=G, lims=lims: plan_ptp_states(S, G, lims), args.repeat))
        rk.append(_best(six_rk, args.repeat))
        # the control cycle: plan, then read the first setpoint (one period in)
        tk_cy.append(_best(lambda S=S, G=G, lims=lims: plan_ptp_states(S, G, lims).state_at(1e-3),
                           args.repeat))
        rk_cy.append(_best(lambda: (six_rk(), traj6.at_time(1e-3)), args.repeat))
        d = plan_ptp_states(S, G, lims).duration
        worst = max(worst, abs(d - traj6.duration) / traj6.duration)
    _row("6 axes: `plan_ptp_states` vs `Ruckig(6).calculate`", tk, rk)
    _row("6 axes, plan and the first setpoint: `.state_at(1 ms)` vs `.at_time(1 ms)`", tk_cy, rk_cy)

    # ---- batch
    cs = [c for (c,) in _cases(rng, args.batch)]
    S = np.array([c[0] for c in cs])
    G = np.array([c[1] for c in cs])
    L = np.array([c[2] for c in cs])
    from ruckig import RuckigError

    durs = np.zeros(len(cs))

    def loop_rk():
        for i, (s, g, L1) in enumerate(cs):
            _set_inputs(inp, s, g, L1)
            try:
                r.calculate(inp, traj)
                durs[i] = traj.duration
            except RuckigError:  # ruckig's error corner (the sweeps in tests/ count it)
                durs[i] = np.nan

    # the same moves both ways, the calls interleaved (the same machine state for
    # both), the best of --batch-repeat kept for each
    t_tk = t_rk = float("inf")
    for _ in range(args.batch_repeat):
        t_tk = min(t_tk, _best(lambda: plan_state_moves(S, G, L[:, 0], L[:, 1], L[:, 2]), 1))
        t_rk = min(t_rk, _best(loop_rk, 1))
    per, per_rk = t_tk / len(cs), t_rk / len(cs)
    batch = plan_state_moves(S, G, L[:, 0], L[:, 1], L[:, 2])
    ok = np.isfinite(durs)
    worst = max(worst, float(np.max(np.abs(batch.duration[ok] - durs[ok]) / durs[ok])))
    print(f"| batch: `plan_state_moves` ({len(cs)} moves, one call) vs the ruckig loop over the "
          f"same moves, per move | {per * 1e6:.2f} us | {per_rk * 1e6:.2f} us | throughput "
          f"{per_rk / per:.2f}x ruckig's |")
    # the compiled loop on one core against ruckig's C++ alone (its inputs set
    # before the timer, five calls per move): what the batch ratio is made of
    k1 = _one_thread_per_move(lambda: plan_state_moves(S, G, L[:, 0], L[:, 1], L[:, 2]),
                              len(cs), args.batch_repeat)
    calc = []
    for s1, g1, L1 in cs[:2000]:
        _set_inputs(inp, s1, g1, L1)
        try:
            r.calculate(inp, traj)
        except RuckigError:
            continue
        t0 = time.perf_counter()
        for _ in range(5):
            r.calculate(inp, traj)
        calc.append((time.perf_counter() - t0) / 5)
    if k1 is not None:
        print(f"(one thread: `plan_state_moves` {k1 * 1e6:.2f} us per move; ruckig's `calculate` "
              f"alone, inputs set outside the timer: {np.mean(calc) * 1e6:.2f} us per move)")
    print()
    print(f"max relative difference of the durations from ruckig's: {worst:.1e}"
          f" (ruckig failed on {int(np.sum(~ok))} of the batch's moves, trajkit on none)")

    # ---- trajkit only: fixed durations, asymmetric limits
    rng = np.random.default_rng(args.seed + 1)
    tf, ta = [], []
    for (c,) in _cases(rng, args.n):
        s, g, L = c
        lim = AxisLimits(*L)
        T = feasible_durations(s, g, lim).next_feasible(1.3 * min_state_duration(s, g, lim))
        tf.append(_best(lambda s=s, g=g, lim=lim, T=T: plan_state_to_state(s, g, lim, duration=T), args.repeat))
    for _ in range(args.n):
        s, g, L = random_case(rng, symmetric=False)
        if s == g:
            continue
        lim = AxisLimits(*L)
        ta.append(_best(lambda s=s, g=g, lim=lim: min_state_duration(s, g, lim), args.repeat))
    for name, xs in (("fixed duration T = 1.3 T_min (symmetric)", tf),
                     ("min_state_duration (asymmetric limits)", ta)):
        a = np.asarray(xs) * 1e6
        print(f"{name}: median {np.median(a):.1f} us, p99 {np.percentile(a, 99):.1f} us")


def _one_thread_per_move(fn, n, repeat):
    """Best time per move of ``fn`` with numba on one thread (None without numba)."""
    if not _has_numba():
        return None
    import numba

    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        return _best(fn, repeat) / n
    finally:
        numba.set_num_threads(threads)


def _has_numba():
    try:
        import numba  # noqa: F401
    except ImportError:
        return False
    return not os.environ.get("TRAJKIT_NO_JIT")


if __name__ == "__main__":
    main()
