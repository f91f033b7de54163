"""Speed of the state-to-state planner: time per call, typical and worst.

Seeded random non-zero states over the hard corners (the generator of
``tests/state_reference.py``), symmetric and asymmetric limits. For each case:
``min_state_duration``, ``plan_state_to_state(duration=T)`` with
``T = T_min (1 + f)``, ``f`` in {1e-6, 0.05, 0.7}, and the blocked-interval
reports among those. Every time is the best of ``--repeat`` calls
(``time.perf_counter`` around one call; the best of a few filters out the
noise of a shared machine); median, mean, 99th percentile and worst over the
cases are printed.

The compiled kernel (numba, ``pip install trajkit[fast]``) is loaded or
compiled before the timed loop; its one-off cost is printed on its own line.
``--no-jit`` times the pure-Python path (``TRAJKIT_NO_JIT=1``).

Run::

    python benchmarks/bench_states.py [--n 300] [--seed 1] [--repeat 3] [--no-jit]
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

from trajkit import AxisLimits
from trajkit.profiles.state import (
    BlockedDurationError,
    min_state_duration,
    plan_state_to_state,
)


def _stats(name, xs):
    if not xs:
        print(f"{name:34s} (none)")
        return
    a = np.array(xs) * 1e3
    print(f"{name:34s} n={a.size:5d}  median {np.median(a):8.3f} ms  mean {a.mean():8.3f} ms  "
          f"p99 {np.percentile(a, 99):8.3f} ms  worst {a.max():8.3f} ms")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=300, help="random cases per symmetry")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--repeat", type=int, default=3, help="calls per case (best is kept)")
    ap.add_argument("--no-jit", action="store_true", help="pure Python (TRAJKIT_NO_JIT=1)")
    args = ap.parse_args(argv)
    if args.no_jit:
        os.environ["TRAJKIT_NO_JIT"] = "1"
    t0 = time.perf_counter()
    min_state_duration((0.0, 0.1, 0.0), (1.0, 0.0, 0.0), AxisLimits(1.0, 1.0, 1.0))
    print(f"first call (imports, numba compile or cache load): {time.perf_counter() - t0:.3f} s")
    for symmetric in (True, False):
        rng = np.random.default_rng(args.seed)
        tmin, tfix, tblk = [], [], []
        for _ in range(args.n):
            s, g, L = random_case(rng, symmetric=symmetric)
            if s == g:
                continue
            lim = AxisLimits(*L)
            best = float("inf")
            for _ in range(args.repeat):
                t0 = time.perf_counter()
                d = min_state_duration(s, g, lim)
                best = min(best, time.perf_counter() - t0)
            tmin.append(best)
            for f in (1e-6, 0.05, 0.7):
                best, blocked = float("inf"), False
                for _ in range(args.repeat):
                    t0 = time.perf_counter()
                    try:
                        plan_state_to_state(s, g, lim, duration=d * (1 + f))
                    except BlockedDurationError:
                        blocked = True
                    best = min(best, time.perf_counter() - t0)
                (tblk if blocked else tfix).append(best)
        tag = "symmetric" if symmetric else "asymmetric"
        _stats(f"min_state_duration ({tag})", tmin)
        _stats(f"fixed duration ({tag})", tfix)
        _stats(f"blocked report ({tag})", tblk)


if __name__ == "__main__":
    main()
