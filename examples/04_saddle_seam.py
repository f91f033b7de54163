"""Example 04: welding the seam of a pipe branch on a theta/Z machine (Chen et al., 2013).

1. The paper's worked chord-error example (r = 100, 100 vs 200 points per
   turn), recomputed: the paper's printed numbers are 200 times too small.
2. An orthogonal tee, R = 150 mm, r = 100 mm: coarse chords within 10 um,
   adaptive vs equal theta steps.
3. An oblique (60 deg) and offset (20 mm) branch on the same main pipe.
4. The saddle machine (rotary theta, linear Z) at a 60 mm/s feed: where an
   axis limit would break, the feed slows down; the report says where/why,
   and the axis limits are checked on the setpoints.

Run::

    python examples/04_saddle_seam.py --out /tmp/trajkit-examples
"""

from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path

import numpy as np

from trajkit import AxisLimits
from trajkit.interpolation import SaddleMachine, plan_saddle
from trajkit.paths import SaddleCurve, chord_error, discretize, uniform_chord_count

MM = 1e-3


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", help="directory for the outputs (default: a new temp dir)")
    args = ap.parse_args(argv)
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="trajkit-ex04-"))
    out.mkdir(parents=True, exist_ok=True)

    # 1. the example of Chen et al. (2013): chord of a 3.6 / 1.8 deg step on a circle of radius 100
    for pts, step in ((100, 3.6), (200, 1.8)):
        L = 2 * 100 * math.sin(math.radians(step / 2))
        printed = 100 - math.sqrt(100**2 - 200 * math.sin(math.radians(step / 2)) ** 2 / 4)
        print(f"r = 100, {pts} points per turn ({step} deg): chord {L:.6f}, "
              f"E = {chord_error(L, 100.0):.6e} (paper prints {printed:.3e})")

    # 2. orthogonal tee
    tol = 10e-6
    machine = SaddleMachine(
        AxisLimits(120.0, 600.0, 6000.0, name="theta").scaled(math.pi / 180),  # deg -> rad
        AxisLimits(40.0, 400.0, 4000.0, name="z_axis").scaled(MM),  # mm -> m
    )
    cases = {
        "orthogonal": SaddleCurve(0.150, 0.100),
        "oblique 60 deg, offset 20 mm": SaddleCurve(0.150, 0.100, math.radians(60), 0.020),
    }
    for name, curve in cases.items():
        chords = discretize(curve, tol)
        n_u = uniform_chord_count(curve, tol, start=chords.count)
        p = curve.point(np.linspace(0, curve.length, 10001))
        res = max(np.abs(curve.branch_residual(p)).max(), np.abs(curve.main_residual(p)).max())
        print(f"{name}: seam length {curve.length / MM:.6f} mm, on both pipes to {res:.1e} m; "
              f"{chords.count} adaptive chords vs {n_u} equal theta steps for {tol / MM * 1000:g} um")

    # 4. the machine
    period = 0.004
    for name, curve in cases.items():
        plan = plan_saddle(curve, 0.060, 0.5, 5.0, machine, tol, period)
        fs, ax = plan.setpoints(period)
        peaks_fd = np.max(np.abs(np.diff(ax[:, 0], axis=1)), axis=1) / period
        print(f"{name} at 60 mm/s: duration {plan.duration:.4f} s, {fs.t.size} setpoints; "
              f"theta speed max {math.degrees(plan.check.peaks[0, 0]):.3f} deg/s (limit 120), "
              f"Z speed max {plan.check.peaks[1, 0] / MM:.3f} mm/s (limit 40); "
              f"from setpoint differences {math.degrees(peaks_fd[0]):.3f} deg/s, {peaks_fd[1] / MM:.3f} mm/s")
        for z in plan.report():
            print(f"  slowed to {z['speed'] / MM:.3f} mm/s for theta {z['theta_start_deg']:.2f}"
                  f"..{z['theta_end_deg']:.2f} deg (s {z['s_start'] / MM:.2f}..{z['s_end'] / MM:.2f} mm): "
                  f"{z['reason']}")
        tag = "orthogonal" if name == "orthogonal" else "oblique_offset"
        csv_path = out / f"saddle_{tag}.csv"
        rows = np.column_stack([fs.t, fs.points / MM, np.degrees(ax[0, 0]), ax[1, 0] / MM])
        np.savetxt(csv_path, rows, delimiter=",", header="t,x,y,z,theta,z_axis", comments="", fmt="%.12g")
        print(f"wrote {csv_path}")
        try:
            from trajkit.plot.paths import plot_saddle_plan
        except ImportError:  # pragma: no cover
            continue
        png = out / f"saddle_{tag}.png"
        plot_saddle_plan(plan, discretize(curve, tol), path=png)
        print(f"wrote {png}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
