"""Runtime: stream a program at 1 kHz with override, pause, faults, pulses and servo.

Run::

    python examples/08_runtime_stream.py --out /tmp/trajkit-examples

1. streams a 3-axis PTP move with the feed override changed while moving
   (100 -> 40 -> 100 %) and a pause/resume, and prints the applied rate over
   time and the largest |velocity| / v_max and |acceleration| / limit of the
   stream (never above 1). The move is planned with ``override_limits`` (a
   reserve of acceleration and jerk for the slow-downs) and streamed against
   the machine's full limits: that is what lets override and pause act at
   once while keeping every limit. The rate itself changes within proven
   bounds (its first and second derivatives are limited so that the
   stream's acceleration and jerk stay within the machine's), so reaching a
   new override level takes a fraction of a second to a few seconds;
2. streams a move whose target lies beyond a soft limit: the look-ahead
   monitor trips on the cycle whose brake would cross it, the axes stop in
   minimum time inside the range, and the pulse count equals the position held;
3. simulates the servo (following error, in-position) and prints planned vs
   simulated time, then writes the stream and following-error figures to --out.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from trajkit import AxisLimits, plan_ptp
from trajkit.runtime import ServoParams, Streamer, pulse_counts, simulate
from trajkit.runtime.streamer import override_limits

DT = 0.001
EQ = 1e-6  # pulse equivalent [m/pulse]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", help="directory for the figures (default: a new temp dir)")
    args = ap.parse_args(argv)
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="trajkit-ex08-"))
    out.mkdir(parents=True, exist_ok=True)

    lims = [AxisLimits(0.4, 4.0, 40.0, a_max_decel=6.0, j_max_decel=60.0,
                       position_min=-1.0, position_max=1.0, name=n) for n in "XYZ"]
    # planned with the override reserve, streamed against the machine's limits
    move = plan_ptp([-0.9, 0.6, -0.3], [0.9, -0.6, 0.3], override_limits(lims))

    # 1. override and pause while moving: each command waits until the rate
    #    has settled at the previous target, then 100 cycles more
    script = [("override 40 %", lambda st: st.set_override(40), 0.4),
              ("override 100 %", lambda st: st.set_override(100), 1.0),
              ("pause", lambda st: st.pause(), 0.0),
              ("resume", lambda st: st.resume(), 1.0)]
    st = Streamer(move, DT, limits=lims, pulse_equivalents=EQ)
    st.start()
    sps = []
    issued, settled, step = [], [], 0
    next_at = 100
    while not st.finished:
        if step < len(script) and len(sps) == next_at:
            script[step][1](st)
            issued.append(len(sps))
        sps.append(st.step())
        if len(issued) > len(settled) and abs(sps[-1].override - script[step][2]) < 1e-9:
            settled.append(len(sps) - 1)
            step += 1
            next_at = len(sps) + 100
    for (what, _, target), k, done in zip(script, issued, settled):
        print(f"{what:15s} at cycle {k:4d}: rate {target:.2f} from cycle {done:4d} "
              f"({(done - k) * DT:.3f} s later, program time {sps[done].tau:.3f} s)")
    v = np.array([s.velocity for s in sps])
    a = np.array([s.acceleration for s in sps])
    vmax = np.array([lm.v_max for lm in lims])
    alim = np.where(v * a < 0, [lm.a_max_decel for lm in lims], [lm.a_max for lm in lims])
    print(f"planned {move.duration:.3f} s, streamed {len(sps) * DT:.3f} s with override and pause")
    print(f"largest |v|/v_max = {np.max(np.abs(v) / vmax):.4f}, "
          f"|a|/a_limit = {np.max(np.abs(a) / alim):.4f}")
    print("events:", ", ".join(f"{e.kind}@{e.cycle}" for e in st.events))
    print(f"pulses X/Y/Z = {sps[-1].pulse_count.tolist()} "
          f"(goal / {EQ:g} = {pulse_counts(move.goal, EQ).tolist()})")

    # 2. a target beyond the soft limit of X (the machine allows 0.6 m)
    far = plan_ptp([0.0, 0.0, 0.0], [0.9, 0.2, 0.0], lims)
    tight = [AxisLimits(0.4, 4.0, 40.0, a_max_decel=6.0, j_max_decel=60.0,
                        position_min=-1.0, position_max=0.6, name="X")] + lims[1:]
    st2 = Streamer(far, DT, limits=tight, pulse_equivalents=EQ)
    sps2 = list(st2)
    held = sps2[-1].position
    print(f"fault: {st2.fault}")
    print(f"stopped at X = {held[0]:.6f} m (limit 0.6), state {sps2[-1].state}, "
          f"pulse count {sps2[-1].pulse_count[0]} = round(X / eq) "
          f"{int(pulse_counts(held, EQ)[0])}")

    # 3. servo simulation: planned vs simulated time
    rep = simulate(move, DT, ServoParams(inertia_ratio=1.5))
    print(f"servo: planned {rep.planned_s:.3f} s, simulated {rep.simulated_s:.3f} s, "
          f"max following error {1e3 * rep.max_following_error.max():.4f} mm")

    from trajkit.plot.runtime import plot_following_error, plot_stream

    plot_stream(sps, move.names, out / "stream.png")
    plot_following_error(rep, out / "following_error.png", scale=[1e3] * 3, unit="mm")
    print(f"figures written to {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
