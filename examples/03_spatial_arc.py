"""Example 03: a spatial arc through three taught points, at constant feed (Jiang, 1987).

Jiang (1987) teaches three points and interpolates the circle through them:
the plane of the points, the centre and radius, then equal angle steps.
This example builds the same arc with :class:`trajkit.paths.Arc3`, joins it
to a taught line, splits the path into chords within a 10 um tolerance,
and moves along it at 40 mm/s with a jerk-limited feed, sampled every 2 ms.
It prints the circle, the chord counts and the speed checks, and writes
the setpoints (CSV) and a figure (PNG).

Run::

    python examples/03_spatial_arc.py --out /tmp/trajkit-examples
"""

from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path

import numpy as np

from trajkit.interpolation import plan_feed
from trajkit.paths import Arc3, CompositePath, Line, chord_deviations, discretize, uniform_chord_count

MM = 1e-3


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", help="directory for the outputs (default: a new temp dir)")
    args = ap.parse_args(argv)
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="trajkit-ex03-"))
    out.mkdir(parents=True, exist_ok=True)

    # Three taught points [m] on a tilted circle, then a taught line that leaves the arc.
    p1 = np.array([0.10, 0.00, 0.05])
    p2 = np.array([0.00, 0.10, 0.08])
    p3 = np.array([-0.10, 0.00, 0.05])
    arc = Arc3(p1, p2, p3)
    print(f"arc: centre {np.round(arc.centre / MM, 6).tolist()} mm, radius {arc.radius / MM:.6f} mm, "
          f"sweep {math.degrees(arc.sweep):.6f} deg, length {arc.length / MM:.6f} mm")
    print(f"plane normal {np.round(arc.normal, 9).tolist()}")
    end_gap = np.linalg.norm(arc.point(arc.length) - p3)
    print(f"distance of the arc end from the third point: {end_gap:.3e} m")

    path = CompositePath([Line([0.10, -0.05, 0.05], p1), arc, Line(p3, [-0.15, 0.0, 0.05])])
    print(f"path: {len(path.segments)} segments, length {path.length / MM:.6f} mm, "
          f"{len(path.corners())} corner(s) where the feed stops")

    tol = 10e-6
    chords = discretize(path, tol)
    arc_chords = discretize(arc, tol)
    n_uniform = uniform_chord_count(arc, tol, start=arc_chords.count)
    step = 2 * arc.radius * math.acos(1 - tol / arc.radius)  # Chen et al. (2013) eq. 11 solved for the arc
    print(f"coarse stage, tolerance {tol / MM * 1000:.0f} um: {chords.count} chords on the path "
          f"(largest error {chords.max_error / MM * 1000:.3f} um); on the arc alone "
          f"{arc_chords.count} adaptive chords, {n_uniform} equal angle steps, "
          f"closed form ceil(sweep / step) = {math.ceil(arc.length / step)}")

    period = 0.002
    plan = plan_feed(path, 0.040, 0.5, 5.0, tolerance=tol, period=period)
    fs = plan.setpoints(period)
    speed = np.linalg.norm(np.diff(fs.points, axis=0), axis=1) / period
    cruise = plan.cruise_mask(fs.t[:-1]) & plan.cruise_mask(fs.t[1:])
    dev = chord_deviations(path, np.unique(fs.s))
    print(f"feed 40 mm/s: duration {plan.duration:.6f} s, {fs.t.size} setpoints every {period * 1000:g} ms")
    print(f"cruise speed from setpoints: {speed[cruise].min() / MM:.4f} .. {speed[cruise].max() / MM:.4f} mm/s")
    print(f"largest deviation of the lines between setpoints: {dev.max() / MM * 1000:.4f} um")

    csv_path = out / "spatial_arc_setpoints.csv"
    rows = np.column_stack([fs.t, fs.points / MM])
    np.savetxt(csv_path, rows, delimiter=",", header="t,x,y,z", comments="", fmt="%.12g")
    print(f"wrote {csv_path}")
    try:
        from trajkit.plot.paths import plot_path_plan
    except ImportError:  # pragma: no cover
        return 0
    png = out / "spatial_arc.png"
    plot_path_plan(plan, chords, path=png)
    print(f"wrote {png}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
