"""Figures for paths and seams: the 3-D curve with its coarse chords, and the
axis positions and speeds against time (Chen et al., 2013, figures 6 and 7)."""

from __future__ import annotations

import math
import os
from typing import Any

import numpy as np

from . import require_matplotlib, save_figure, set_equal_3d

__all__ = ["plot_chords_3d", "plot_saddle_plan", "plot_path_plan"]

MM = 1e-3
#: Samples of the exact curve drawn in 3-D.
CURVE_SAMPLES = 2000
#: Samples per curve drawn against time.
TIME_SAMPLES = 4000


def plot_chords_3d(ax, path, chords, title: str = "") -> None:
    """Draw the exact curve [mm] and its coarse chords on a 3-D axes."""
    s = np.linspace(0.0, path.length, CURVE_SAMPLES)
    p = path.point(s) / MM
    ax.plot(p[:, 0], p[:, 1], p[:, 2], color="0.3", lw=1.2, label="exact curve")
    q = chords.points / MM
    ax.plot(q[:, 0], q[:, 1], q[:, 2], color="tab:red", lw=0.8, marker=".", ms=3,
            label=f"{chords.count} chords, max error {chords.max_error / MM * 1000:.3g} um")
    ax.scatter(*p[0], color="tab:green", s=30, label="start")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_zlabel("z [mm]", labelpad=4)
    set_equal_3d(ax, np.vstack([p, q]))
    if title:
        ax.set_title(title)
    ax.legend(loc="upper left", fontsize=8)


def _shade(ax, plan_sample_t, s, slowdowns):
    for z in slowdowns:
        inside = (s >= z.s_start) & (s <= z.s_end)
        if np.any(inside):
            ax.axvspan(plan_sample_t[inside][0], plan_sample_t[inside][-1], color="tab:orange",
                       alpha=0.15, lw=0)


def plot_saddle_plan(plan, chords, path: str | os.PathLike | None = None) -> Any:
    """Seam with chords, axis positions, axis speeds and tool speed against time.

    Parameters
    ----------
    plan : trajkit.interpolation.SaddlePlan
    chords : trajkit.paths.ChordSet
    path : path-like, optional
        PNG file to write.

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = require_matplotlib()
    curve = plan.curve
    fig = plt.figure(figsize=(13, 8), layout="constrained")
    gs = fig.add_gridspec(3, 2, width_ratios=(1.1, 1), wspace=0.15)
    ax3 = fig.add_subplot(gs[:, 0], projection="3d")
    plot_chords_3d(ax3, curve, chords,
                   f"saddle seam R={curve.main_radius / MM:g} mm, r={curve.branch_radius / MM:g} mm, "
                   f"angle {math.degrees(curve.angle):g} deg, offset {curve.offset / MM:g} mm")
    t = np.linspace(0.0, plan.duration, TIME_SAMPLES)
    fs = plan.feed_plan.sample(t, points=False)
    st = plan.axes(t)
    lim = plan.machine.limits_array()
    theta_deg = np.degrees(st[0, 0])

    a1 = fig.add_subplot(gs[0, 1])
    a1.plot(t, theta_deg, color="tab:blue")
    a1.set_ylabel("theta [deg]", color="tab:blue")
    a1b = a1.twinx()
    a1b.plot(t, st[1, 0] / MM, color="tab:purple")
    a1b.set_ylabel("Z [mm]", color="tab:purple")
    a1.set_title("axis positions")

    a2 = fig.add_subplot(gs[1, 1], sharex=a1)
    a2.plot(t, np.degrees(st[0, 1]), color="tab:blue", label="theta speed")
    for sgn in (1, -1):
        a2.axhline(sgn * math.degrees(lim[0, 0]), color="tab:blue", ls=":", lw=0.8)
    a2.set_ylabel("theta speed [deg/s]", color="tab:blue")
    a2b = a2.twinx()
    a2b.plot(t, st[1, 1] / MM, color="tab:purple", label="Z speed")
    for sgn in (1, -1):
        a2b.axhline(sgn * lim[1, 0] / MM, color="tab:purple", ls=":", lw=0.8)
    a2b.set_ylabel("Z speed [mm/s]", color="tab:purple")
    a2.set_title("axis speeds (dotted: limits)")
    _shade(a2, t, fs.s, plan.slowdowns)

    a3 = fig.add_subplot(gs[2, 1], sharex=a1)
    a3.plot(t, fs.v / MM, color="k", label="tool speed")
    a3.axhline(plan.feed_plan.feed / MM, color="tab:green", ls="--", lw=0.8, label="commanded feed")
    _shade(a3, t, fs.s, plan.slowdowns)
    a3.set_ylabel("tool speed [mm/s]")
    a3.set_xlabel("t [s]")
    reasons = sorted({z.reason for z in plan.slowdowns})
    a3.set_title("tool speed along the seam" + (f" (shaded: slowed by {', '.join(reasons)})" if reasons else ""),
                 fontsize=9)
    a3.legend(loc="lower center", fontsize=8)
    save_figure(fig, path)
    return fig


def plot_path_plan(plan, chords, path: str | os.PathLike | None = None) -> Any:
    """Path with chords, x/y/z positions and speeds, tool speed against time.

    Parameters
    ----------
    plan : trajkit.interpolation.FeedPlan
    chords : trajkit.paths.ChordSet
    path : path-like, optional
        PNG file to write.

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = require_matplotlib()
    fig = plt.figure(figsize=(13, 8), layout="constrained")
    gs = fig.add_gridspec(3, 2, width_ratios=(1.1, 1), wspace=0.15)
    ax3 = fig.add_subplot(gs[:, 0], projection="3d")
    plot_chords_3d(ax3, plan.path, chords, f"path, length {plan.path.length / MM:.6g} mm")
    t = np.linspace(0.0, plan.duration, TIME_SAMPLES)
    fs = plan.sample(t)
    tang = plan.path.tangent(fs.s)
    vel = tang * fs.v[:, None]
    a1 = fig.add_subplot(gs[0, 1])
    a2 = fig.add_subplot(gs[1, 1], sharex=a1)
    for k, (nm, c) in enumerate(zip("xyz", ("tab:blue", "tab:orange", "tab:green"))):
        a1.plot(t, fs.points[:, k] / MM, color=c, label=nm)
        a2.plot(t, vel[:, k] / MM, color=c, label=f"v{nm}")
    a1.set_ylabel("position [mm]")
    a1.set_title("axis positions")
    a1.legend(fontsize=8)
    a2.set_ylabel("speed [mm/s]")
    a2.set_title("axis speeds")
    a2.legend(fontsize=8)
    a3 = fig.add_subplot(gs[2, 1], sharex=a1)
    a3.plot(t, fs.v / MM, color="k", label="tool speed")
    a3.axhline(plan.feed / MM, color="tab:green", ls="--", lw=0.8, label="commanded feed")
    _shade(a3, t, fs.s, plan.slowdowns)
    a3.set_xlabel("t [s]")
    a3.set_ylabel("tool speed [mm/s]")
    a3.legend(fontsize=8, loc="lower center")
    save_figure(fig, path)
    return fig
