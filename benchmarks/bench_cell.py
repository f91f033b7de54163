"""Prism distances of the palletizing cell: trajkit's closed form against coal (hpp-fcl).

Run::

    pip install -e ".[bench]"            # coal
    python benchmarks/bench_cell.py       # table
    python benchmarks/bench_cell.py --json

Both compute the exact signed distance between two boxes turned about z (the
moving gripper and box against the conveyor, guides, end stop, pallet and the
placed boxes). trajkit's :func:`~trajkit.palletizing.cell.prism_signed_distance`
works on whole numpy batches; coal answers one pair per call (GJK/EPA, its
tolerance set to 1e-12). Reported: time per pair of each, their ratio, and the
largest difference between the two on separated pairs and on overlapping pairs.
"""

from __future__ import annotations

import argparse
import json
import math
import time

import numpy as np

from trajkit.palletizing.cell import Prisms, prism_signed_distance


def random_prisms(rng, n):
    z0 = rng.uniform(-0.5, 0.5, n)
    return Prisms(cx=rng.uniform(-1, 1, n), cy=rng.uniform(-1, 1, n), hx=rng.uniform(0.01, 0.6, n),
                  hy=rng.uniform(0.01, 0.6, n), yaw=rng.uniform(-math.pi, math.pi, n), z0=z0,
                  z1=z0 + rng.uniform(0.01, 0.6, n))


def coal_objects(coal, p, i):
    box = coal.Box(2 * p.hx[i], 2 * p.hy[i], p.z1[i] - p.z0[i])
    tf = coal.Transform3s()
    c, s = math.cos(p.yaw[i]), math.sin(p.yaw[i])
    tf.setRotation(np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]))
    tf.setTranslation(np.array([p.cx[i], p.cy[i], 0.5 * (p.z0[i] + p.z1[i])]))
    return box, tf


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=20000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    import coal

    rng = np.random.default_rng(args.seed)
    a, b = random_prisms(rng, args.pairs), random_prisms(rng, args.pairs)
    best = math.inf
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        ours = prism_signed_distance(a, b)
        best = min(best, time.perf_counter() - t0)
    t_ours = best / args.pairs
    objs = [(coal_objects(coal, a, i), coal_objects(coal, b, i)) for i in range(args.pairs)]
    req = coal.DistanceRequest()
    req.gjk_tolerance = 1e-12
    ref = np.empty(args.pairs)
    best = math.inf
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        for i, ((ga, ta), (gb, tb)) in enumerate(objs):
            ref[i] = coal.distance(ga, ta, gb, tb, req, coal.DistanceResult())
        best = min(best, time.perf_counter() - t0)
    t_coal = best / args.pairs
    sep = ref >= 0.0
    out = {
        "pairs": args.pairs,
        "trajkit_us_per_pair": t_ours * 1e6,
        "coal_us_per_pair": t_coal * 1e6,
        "speedup": t_coal / t_ours,
        "max_abs_diff_separated_m": float(np.max(np.abs(ours[sep] - ref[sep]))),
        "max_abs_diff_overlapping_m": float(np.max(np.abs(ours[~sep] - ref[~sep]))) if (~sep).any() else 0.0,
        "overlapping_pairs": int((~sep).sum()),
    }
    if args.json:
        print(json.dumps(out, indent=2))
    else:
        for k, v in out.items():
            print(f"{k:28s} {v:.4g}" if isinstance(v, float) else f"{k:28s} {v}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
