"""Runtime speed and timing jitter.

1. Setpoint generation with monitors for 6 axes (``Streamer.step`` at full
   override: sampling, position/velocity/acceleration monitors with braking
   look-ahead, pulse output), then the same with the servo simulation and the
   following-error monitor, in cycles per second and microseconds per cycle.
   Peer measured in the same run: ruckig's online generator
   (``Ruckig(6, dt).update``, C++), one call per cycle on the same moves.
2. Jitter of a 1 kHz paced loop (``--jitter-s``, default 60 s): every cycle
   runs ``Streamer.step`` and then waits for its deadline ``t0 + k * dt``
   (``time.sleep`` to 0.5 ms before it, then a busy wait); lateness = wake-up
   time - deadline. Reports p50 / p99 / max lateness and the overruns.

Run::

    python benchmarks/bench_runtime.py                 # both, 60 s jitter run
    python benchmarks/bench_runtime.py --jitter-s 5    # shorter
    python benchmarks/bench_runtime.py --json

Also prints the palletizing scenario's planned vs simulated times with
``--pallet`` (servo parameters of docs/runtime.md; ~10 s per plan).
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time

import numpy as np

from trajkit import AxisLimits, plan_ptp
from trajkit.runtime import ServoParams, Streamer

#: Busy-wait the last part of each period [s] (``time.sleep`` is coarse).
SPIN_S = 0.0005


def _moves(seed: int, n: int):
    rng = np.random.default_rng(seed)
    lims = [AxisLimits(2.0, 8.0, 80.0, position_min=-4.0, position_max=4.0, name=f"J{i + 1}")
            for i in range(6)]
    pts = rng.uniform(-3.0, 3.0, (n + 1, 6))
    return lims, [plan_ptp(pts[i], pts[i + 1], lims) for i in range(n)]


def bench_streamer(cycles: int, servo: bool, seed: int) -> dict:
    _, trajs = _moves(seed, 40)
    done = 0
    elapsed = 0.0
    i = 0
    while done < cycles:
        st = Streamer(trajs[i % len(trajs)], 0.001, pulse_equivalents=1e-6,
                      servo=ServoParams() if servo else None)
        st.start()
        t0 = time.perf_counter()
        while not st.finished and done < cycles:
            st.step()
            done += 1
        elapsed += time.perf_counter() - t0
        i += 1
    return {"cycles": done, "cycles_per_s": done / elapsed, "us_per_cycle": 1e6 * elapsed / done}


def bench_ruckig(cycles: int, seed: int) -> dict | None:
    try:
        import ruckig
    except ImportError:
        return None
    lims, trajs = _moves(seed, 40)
    otg = ruckig.Ruckig(6, 0.001)
    inp = ruckig.InputParameter(6)
    out = ruckig.OutputParameter(6)
    inp.max_velocity = [lm.v_max for lm in lims]
    inp.max_acceleration = [lm.a_max for lm in lims]
    inp.max_jerk = [lm.j_max for lm in lims]
    done = 0
    elapsed = 0.0
    i = 0
    while done < cycles:
        tr = trajs[i % len(trajs)]
        inp.current_position = list(tr.start)
        inp.current_velocity = [0.0] * 6
        inp.current_acceleration = [0.0] * 6
        inp.target_position = list(tr.goal)
        t0 = time.perf_counter()
        while done < cycles:
            res = otg.update(inp, out)
            out.pass_to_input(inp)
            done += 1
            if res != ruckig.Result.Working:
                break
        elapsed += time.perf_counter() - t0
        i += 1
    return {"cycles": done, "cycles_per_s": done / elapsed, "us_per_cycle": 1e6 * elapsed / done}


def bench_jitter(seconds: float, seed: int) -> dict:
    _, trajs = _moves(seed, 40)
    dt = 0.001
    n = int(round(seconds / dt))
    late = np.empty(n)
    work = np.empty(n)
    st = None
    i = 0
    t0 = time.perf_counter() + 0.01
    for k in range(n):
        deadline = t0 + k * dt
        rem = deadline - time.perf_counter()
        if rem > SPIN_S:
            time.sleep(rem - SPIN_S)
        while True:
            now = time.perf_counter()
            if now >= deadline:
                break
        late[k] = now - deadline
        if st is None or st.finished:
            st = Streamer(trajs[i % len(trajs)], dt, pulse_equivalents=1e-6)
            st.start()
            i += 1
        st.step()
        work[k] = time.perf_counter() - now
    us = 1e6
    return {
        "seconds": seconds, "cycles": n,
        "lateness_p50_us": float(np.percentile(late, 50) * us),
        "lateness_p99_us": float(np.percentile(late, 99) * us),
        "lateness_max_us": float(late.max() * us),
        "late_over_1_period": int(np.sum(late > dt)),
        "step_p50_us": float(np.percentile(work, 50) * us),
        "step_p99_us": float(np.percentile(work, 99) * us),
        "step_max_us": float(work.max() * us),
    }


def bench_pallet() -> dict:
    from trajkit.palletizing import PAPER_TABLE1, plan_cycle, seed_scenario
    from trajkit.runtime import simulate
    from trajkit.runtime.servo import cao2012_servo

    sc = seed_scenario()
    out = {}
    for name in ("ptp", "merged"):
        plan = plan_cycle(sc, name)
        rep = simulate(plan, 0.001, cao2012_servo(sc.robot), record=False)
        out[name] = {"planned_s": rep.planned_s, "simulated_s": rep.simulated_s,
                     "paper_planned_s": PAPER_TABLE1[name]["planned_s"],
                     "paper_measured_s": PAPER_TABLE1[name].get("measured_s")}
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cycles", type=int, default=50_000, help="cycles per speed row")
    ap.add_argument("--jitter-s", type=float, default=60.0, help="length of the paced run [s]")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--pallet", action="store_true", help="also simulate the palletizing job of Cao et al. (2012)")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    res = {
        "python": sys.version.split()[0], "machine": platform.machine(),
        "streamer_6axes": bench_streamer(a.cycles, False, a.seed),
        "streamer_6axes_servo": bench_streamer(a.cycles, True, a.seed),
        "ruckig_otg_6axes": bench_ruckig(a.cycles, a.seed),
    }
    if a.jitter_s > 0:
        res["jitter_1khz"] = bench_jitter(a.jitter_s, a.seed)
    if a.pallet:
        res["pallet"] = bench_pallet()
    if a.json:
        print(json.dumps(res, indent=2))
        return 0
    for key in ("streamer_6axes", "streamer_6axes_servo", "ruckig_otg_6axes"):
        r = res[key]
        if r:
            print(f"{key:22s} {r['cycles_per_s']:10.0f} cycles/s  {r['us_per_cycle']:7.1f} us/cycle")
    if res["ruckig_otg_6axes"]:
        print(f"ratio trajkit/ruckig time per cycle: "
              f"{res['streamer_6axes']['us_per_cycle'] / res['ruckig_otg_6axes']['us_per_cycle']:.1f}")
    if "jitter_1khz" in res:
        j = res["jitter_1khz"]
        print(f"1 kHz paced loop, {j['seconds']:g} s: lateness p50 {j['lateness_p50_us']:.1f} us, "
              f"p99 {j['lateness_p99_us']:.1f} us, max {j['lateness_max_us']:.1f} us, "
              f"{j['late_over_1_period']} cycles later than one period; step p99 "
              f"{j['step_p99_us']:.1f} us")
    if "pallet" in res:
        for name, r in res["pallet"].items():
            print(f"pallet {name:7s} planned {r['planned_s']:.3f} s simulated {r['simulated_s']:.3f} s "
                  f"(paper {r['paper_planned_s']} -> {r['paper_measured_s']})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
