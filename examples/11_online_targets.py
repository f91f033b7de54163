"""Online re-targeting: new goal states while the axes move (``Streamer.set_target``).

Run::

    python examples/11_online_targets.py --out /tmp/trajkit-examples

1. a 3-axis streamer at 1 kHz standing still (``Streamer.hold_at``) gets a
   new random goal state (position and velocity per axis) every 10 ms for
   two seconds, as a joystick or a vision system would send them; each
   target is re-planned from the commanded state of that cycle with the
   time-optimal planner between states, and the setpoint of the same cycle
   is already on the new motion;
2. then one last goal at rest, which it reaches exactly;
3. a jog with a reduced speed (``set_target(..., limits=...)``) while an axis
   still runs at full speed: it is braked down to the jog speed first (the
   brake ends at the first instant inside the jog limits, the least time
   above them, as ruckig does; still decelerating there, the speed dips
   below the jog speed before it settles on it);
4. prints the number of re-plans, the largest |velocity|, |acceleration| and
   |jerk| of the stream over the limits (never above 1) and the final state,
   and writes the stream to ``--out`` (``online_targets.png`` when
   matplotlib is installed, and ``online_targets.csv``).
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from trajkit import AxisLimits
from trajkit.runtime import Streamer

DT = 0.001
EVERY = 10  # cycles between targets: 100 Hz


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", help="directory for the figure and CSV (default: a new temp dir)")
    args = ap.parse_args(argv)
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="trajkit-ex11-"))
    out.mkdir(parents=True, exist_ok=True)

    lims = [AxisLimits(1.0, 4.0, 40.0, a_max_decel=6.0, j_max_decel=60.0, name="X"),
            AxisLimits(0.5, 2.0, 30.0, name="Y"),
            AxisLimits(2.0, 8.0, 100.0, a_max_decel=5.0, j_max_decel=50.0, name="Z")]
    rng = np.random.default_rng(3)
    st = Streamer.hold_at([0.0, 0.0, 0.0], DT, lims)
    sps = []
    for _ in range(200):
        goal = rng.uniform(-1.0, 1.0, 3)
        vel = rng.uniform(-0.8, 0.8, 3) * [lm.v_max for lm in lims]
        st.set_target(goal, vel)
        for _ in range(EVERY):
            sps.append(st.step())
    final = [0.25, -0.5, 0.75]
    st.set_target(final)
    while st.state != "idle":
        sps.append(st.step())
    replans = sum(1 for ev in st.events if ev.kind == "target")
    print(f"{replans - 1} targets at {1 / (EVERY * DT):.0f} Hz, then one at rest: "
          f"{len(sps) * DT:.3f} s streamed, {st.events[-1].kind} at {st.events[-1].t:.3f} s")
    print(f"final position {sps[-1].position.tolist()}, velocity {sps[-1].velocity.tolist()}")

    # a reduced-speed jog while X runs at full speed: X is braked down to it first
    st.set_target([5.0, -0.5, 0.75])
    for _ in range(800):
        sps.append(st.step())
    v_before = abs(sps[-1].velocity[0])
    jog = [AxisLimits(0.2, 4.0, 40.0, a_max_decel=6.0, j_max_decel=60.0, name="X"), lims[1], lims[2]]
    st.set_target([1.5, -0.5, 0.75], limits=jog)
    k0 = len(sps)
    while st.state != "idle":
        sps.append(st.step())
    v_jog = np.abs([sp.velocity[0] for sp in sps[k0:]])
    slow = int(np.argmax(v_jog <= 0.2 * (1 + 1e-9)))
    print(f"jog at 20 % of X's speed from {v_before:.3f} m/s: braked to 0.2 m/s in {slow * DT:.3f} s, "
          f"then at most {v_jog[slow:].max():.4f} m/s; at rest on {sps[-1].position[0]:.6f} m")

    t = np.arange(len(sps)) * DT
    Q = np.array([sp.position for sp in sps])
    V = np.array([sp.velocity for sp in sps])
    A = np.array([sp.acceleration for sp in sps])
    vmax = np.array([lm.v_max for lm in lims])
    cap = np.where(V * A > 0, [lm.a_max for lm in lims], [lm.a_max_decel for lm in lims])
    jmax = np.array([max(lm.j_max, lm.j_max_decel) for lm in lims])
    jerk = np.abs(np.diff(A, axis=0)) / DT
    print(f"largest |v|/v_max = {np.max(np.abs(V) / vmax):.4f}, |a|/a_max = {np.max(np.abs(A) / cap):.4f}, "
          f"|j|/j_max = {np.max(jerk / jmax):.4f}")

    header = "t_s," + ",".join(f"{lm.name}_m,{lm.name}_velocity_m_s" for lm in lims)
    rows = np.column_stack([t] + [c for k in range(3) for c in (Q[:, k], V[:, k])])
    np.savetxt(out / "online_targets.csv", rows, delimiter=",", header=header, comments="", fmt="%.9g")
    written = ["online_targets.csv"]
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no figure")
    else:
        fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
        for k, lm in enumerate(lims):
            ax1.plot(t, Q[:, k], label=lm.name)
            ax2.plot(t, V[:, k], label=lm.name)
        ax1.set_ylabel("position [m]")
        ax2.set_ylabel("velocity [m/s]")
        ax2.set_xlabel("t [s]")
        ax1.set_title("a new goal state every 10 ms, then a goal at rest and a slow jog")
        ax1.legend(ncol=3, fontsize=8)
        fig.tight_layout()
        fig.savefig(out / "online_targets.png", dpi=110)
        plt.close(fig)
        written.append("online_targets.png")
    for name in written:
        print(f"wrote {out / name}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
