"""Fixed durations between moving states with separate accel/decel legs: how
often step 2 finds no profile, how much is reported blocked, and (optionally)
whether a blocked interval really is one.

    python benchmarks/state_step2_study.py --cases 3000 --seed 2
    python benchmarks/state_step2_study.py --cases 3000 --seed 2 --oracle 6
    python benchmarks/state_step2_study.py --cases 3000 --seed 20 --seeds 40 --no-verify

For ``--cases`` random asymmetric moves (``tests/state_reference.random_case``)
it plans four durations ``T = T_min f``, ``f`` uniform in [1, 3], and counts
the outcomes (a profile, verified by ``trajkit.verify.verify_motion``; a
blocked duration; "no profile found"), the blocked intervals of
``feasible_durations`` and their summed length in minimum durations.
``--seeds N`` runs the seeds ``seed .. seed + N - 1`` one after the other and
adds them up; ``--no-verify`` counts every returned profile as a profile
(much faster; the tests verify them); ``--brake`` draws every other move
from ``tests/state_reference.random_brake_case`` (a start outside the
limits: a brake comes first).

``--oracle N`` checks the midpoints of N blocked intervals (those that start
at the minimum duration first) with an independent mixed-integer program
(``scipy.optimize.milp``, HiGHS): piecewise-constant jerk on a grid of 200
steps of the duration, integrated exactly, with binaries for the signs of
velocity and acceleration at every node that select the leg's acceleration
bound there and the tighter of the two nodes' jerk bounds on each step
(conservative: a grid motion is a motion within the limits up to the grid's
sign changes inside a step). "feasible" means the interval is not blocked
throughout. Each solve takes up to a few minutes.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy.optimize import Bounds, LinearConstraint, milp
from scipy.sparse import lil_matrix

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from state_reference import random_brake_case, random_case  # noqa: E402

from trajkit import AxisLimits  # noqa: E402
from trajkit.errors import InfeasibleError  # noqa: E402
from trajkit.profiles.state import (  # noqa: E402
    BlockedDurationError,
    feasible_durations,
    plan_state_to_state,
)
from trajkit.verify import verify_motion  # noqa: E402


def grid_feasible(s, g, L, T, n=200, time_limit=300.0):
    """True / False / None (undecided in ``time_limit``): a grid motion of ``T``."""
    V, A, J, Ad, Jd = L
    dt = T / n
    m = n + 1
    off = {"j": 0, "p": n, "v": n + m, "a": n + 2 * m, "sv": n + 3 * m, "sa": n + 4 * m,
           "x": n + 5 * m}
    nv = n + 6 * m
    rows, lo, hi = [], [], []

    def row(d, lo_, hi_):
        rows.append(d)
        lo.append(lo_)
        hi.append(hi_)

    def at(k, i):
        return off[k] + i

    am = max(A, Ad) * 1.01
    for i in range(n):
        row({at("a", i + 1): 1, at("a", i): -1, at("j", i): -dt}, 0, 0)
        row({at("v", i + 1): 1, at("v", i): -1, at("a", i): -dt, at("j", i): -dt ** 2 / 2}, 0, 0)
        row({at("p", i + 1): 1, at("p", i): -1, at("v", i): -dt, at("a", i): -dt ** 2 / 2,
             at("j", i): -dt ** 3 / 6}, 0, 0)
        for e in (i, i + 1):  # x = 1: slowing (decel leg) at node e
            row({at("j", i): 1, at("x", e): -(Jd - J)}, -np.inf, J)
            row({at("j", i): -1, at("x", e): -(Jd - J)}, -np.inf, J)
    for i in range(m):
        row({at("v", i): 1, at("sv", i): -V}, -np.inf, 0)
        row({at("v", i): 1, at("sv", i): -V}, -V, np.inf)
        row({at("a", i): 1, at("sa", i): -am}, -np.inf, 0)
        row({at("a", i): 1, at("sa", i): -am}, -am, np.inf)
        # x = sv xor sa
        row({at("x", i): 1, at("sv", i): -1, at("sa", i): 1}, 0, np.inf)
        row({at("x", i): 1, at("sv", i): 1, at("sa", i): -1}, 0, np.inf)
        row({at("x", i): 1, at("sv", i): -1, at("sa", i): -1}, -np.inf, 0)
        row({at("x", i): 1, at("sv", i): 1, at("sa", i): 1}, -np.inf, 2)
        row({at("a", i): 1, at("x", i): -(Ad - A)}, -np.inf, A)
        row({at("a", i): -1, at("x", i): -(Ad - A)}, -np.inf, A)
    M = lil_matrix((len(rows), nv))
    for r, d in enumerate(rows):
        for c, val in d.items():
            M[r, c] = val
    lb = np.full(nv, -np.inf)
    ub = np.full(nv, np.inf)
    lb[off["v"]:off["v"] + m] = -V
    ub[off["v"]:off["v"] + m] = V
    for k in ("sv", "sa", "x"):
        lb[off[k]:off[k] + m] = 0
        ub[off[k]:off[k] + m] = 1
    for k, val in zip("pva", s):
        lb[off[k]] = ub[off[k]] = val
    for k, val in zip("pva", g):
        lb[off[k] + n] = ub[off[k] + n] = val
    integ = np.zeros(nv)
    integ[off["sv"]:] = 1
    r = milp(np.zeros(nv), constraints=LinearConstraint(M.tocsr(), lo, hi),
             bounds=Bounds(lb, ub), integrality=integ, options={"time_limit": time_limit})
    if r.status == 0:
        return True
    if r.status == 2:
        return False
    return None


def _moves(seed, n_seeds, cases, brake):
    """The random asymmetric moves of ``cases`` per seed, seeds ``seed ..``, each
    with its seed's generator (which then draws the move's durations); with
    ``brake`` every other one starts outside the limits."""
    for sd in range(seed, seed + n_seeds):
        rng = np.random.default_rng(sd)
        for i in range(cases):
            if brake and i % 2 == 1:
                yield rng, random_brake_case(rng, symmetric=False)
            else:
                yield rng, random_case(rng, symmetric=False)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", type=int, default=3000)
    ap.add_argument("--seed", type=int, default=2)
    ap.add_argument("--oracle", type=int, default=0)
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--no-verify", action="store_true")
    ap.add_argument("--brake", action="store_true")
    args = ap.parse_args()
    count = {"profile": 0, "blocked": 0, "no profile": 0, "limit broken": 0}
    blocked = []
    t_fd, t_fixed = [], []
    for rng, (s, g, L) in _moves(args.seed, args.seeds, args.cases, args.brake):
        if s == g:
            continue
        lim = AxisLimits(*L)
        try:
            t_min = plan_state_to_state(s, g, lim).duration
        except InfeasibleError:
            continue
        t0 = time.perf_counter()
        fd = feasible_durations(s, g, lim)
        t_fd.append(time.perf_counter() - t0)
        blocked += [(s, g, L, t_min, lo, hi) for lo, hi in fd.blocked]
        for f in rng.uniform(1.0, 3.0, 4):
            t0 = time.perf_counter()
            q = None
            try:
                q = plan_state_to_state(s, g, lim, duration=t_min * f)
            except BlockedDurationError:
                key = "blocked"
            except InfeasibleError:
                key = "no profile"
            t_fixed.append(time.perf_counter() - t0)  # (the planner alone)
            if q is not None:
                key = "profile" if args.no_verify or verify_motion(q).ok else "limit broken"
            count[key] += 1
    seeds = f"seed {args.seed}" if args.seeds == 1 else f"seeds {args.seed}-{args.seed + args.seeds - 1}"
    kind = ", every other with a brake" if args.brake else ""
    print(f"{args.cases * args.seeds} moves ({seeds}{kind}), {sum(count.values())} fixed durations: "
          + ", ".join(f"{k} {v}" for k, v in count.items()))
    at_min = [b for b in blocked if b[4] == b[3]]
    print(f"blocked intervals: {len(blocked)} ({len(at_min)} starting at the minimum), summed "
          f"length {sum((b[5] - b[4]) / b[3] for b in blocked):.3f} minimum durations")
    print(f"time per call: feasible_durations median {np.median(t_fd) * 1e6:.0f} us, p99 "
          f"{np.percentile(t_fd, 99) * 1e6:.0f} us; fixed duration median "
          f"{np.median(t_fixed) * 1e6:.0f} us, p99 {np.percentile(t_fixed, 99) * 1e6:.0f} us")
    # the intervals that start at the minimum first (the suspects), then the others
    for s, g, L, t_min, lo, hi in (at_min + [b for b in blocked if b[4] != b[3]])[:args.oracle]:
        T = 0.5 * (lo + hi)
        ok = grid_feasible(s, g, L, T)
        verdict = {True: "feasible (not blocked)", False: "infeasible", None: "undecided"}[ok]
        where = "from the minimum" if lo == t_min else "after the minimum"
        print(f"  interval ({lo:.6g}, {hi:.6g}) s {where}: at {T:.6g} s the grid oracle says "
              f"{verdict}", flush=True)


if __name__ == "__main__":
    main()
