"""Example 01: one axis, time-optimal jerk-limited move (Cao et al., 2012; patent CN105892402).

Plans a 0.8 m move of a vertical axis three ways and prints real numbers:

1. symmetric limits (the classic 7-phase S-curve of Cao et al., 2012);
2. asymmetric limits (patent CN105892402): a gentle jerk while stopping, so the arm
   does not ring at the goal, at the price of a slightly longer move;
3. the asymmetric move stretched to a fixed, longer duration.

Then it samples the profile at a 1 ms control period and writes the stacked
position/velocity/acceleration/jerk figure.

Run::

    python examples/01_single_axis_move.py --out /tmp/trajkit-examples
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from trajkit import PHASE_NAMES, AxisLimits, plan_move


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", help="directory for the figure (default: a new temp dir)")
    args = ap.parse_args(argv)
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="trajkit-ex01-"))
    out.mkdir(parents=True, exist_ok=True)

    # Limits in SI units: m/s, m/s^2, m/s^3.
    symmetric = AxisLimits(v_max=1.0, a_max=4.0, j_max=40.0, name="Z")
    # Patent CN105892402: accel leg J1 = 40, A1 = 4; decel leg J2 = 10 (R1 = 0.25), A2 = 3 (R2 = 0.75).
    asymmetric = AxisLimits(v_max=1.0, a_max=4.0, j_max=40.0,
                            a_max_decel=3.0, j_max_decel=10.0, name="Z")

    start, goal = 0.0, 0.8  # [m]
    sym = plan_move(start, goal, symmetric)
    asym = plan_move(start, goal, asymmetric)
    print(f"symmetric : T = {sym.duration:.6f} s, shape {sym.shape}, "
          f"reached {sorted(sym.reached)}")
    print(f"asymmetric: T = {asym.duration:.6f} s, shape {asym.shape}, "
          f"reached {sorted(asym.reached)}")
    print(f"the gentle stop costs {1e3 * (asym.duration - sym.duration):.1f} ms")

    print("\nphases of the asymmetric move:")
    print(f"{'phase':>15} {'duration [s]':>13} {'jerk [m/s^3]':>13}")
    for name, dt, j in zip(PHASE_NAMES, asym.phase_durations, asym.jerks):
        print(f"{name:>15} {dt:13.6f} {j:13.3f}")

    # A fixed, longer duration: the cruise velocity is lowered to fit exactly.
    slow = plan_move(start, goal, asymmetric, duration=1.5)
    print(f"\nstretched to {slow.duration:.3f} s: cruise at {slow.peak_velocity:.6f} m/s "
          f"(shape {slow.shape})")

    # Sample at a 1 ms control period (exact integration of the jerk phases).
    t = np.arange(0.0, asym.duration, 1e-3)
    s = asym.sample(np.append(t, asym.duration))
    print(f"\n{s.position.size} samples at 1 ms: max |v| = {np.abs(s.velocity).max():.6f} m/s, "
          f"max a = {s.acceleration.max():.6f}, min a = {s.acceleration.min():.6f} m/s^2, "
          f"final position {float(s.position[-1])!r} m")

    from trajkit.plot.profiles import plot_profile

    png = out / "01_single_axis_move.png"
    plot_profile(asym, png, unit="m", title="Z axis 0 -> 0.8 m, asymmetric limits (CN105892402)")
    print(f"wrote {png}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
