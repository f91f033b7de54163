"""Figures of a robot program run: joint positions/velocities and the tool path."""

from __future__ import annotations

import os
from typing import Any

from . import line_colors, require_matplotlib, save_figure, set_equal_3d

__all__ = ["plot_robot_run"]


def plot_robot_run(run: Any, samples: Any, path: str | os.PathLike | None = None):
    """Joint positions, joint velocities (as a fraction of v_max), tool speed and tool path.

    Parameters
    ----------
    run : trajkit.robot.RobotRun
    samples : trajkit.robot.RobotSamples
        From ``run.sample(run.times(period))``.
    path : str or PathLike, optional
        Write the figure there (PNG, SVG, PDF by extension), atomically.

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = require_matplotlib()
    robot = run.robot
    units = [robot.joint_unit(j) for j in range(robot.n_joints)]
    groups = list(dict.fromkeys(u for u, _ in units))  # one position panel per unit
    fig = plt.figure(figsize=(13, 8))
    gs = fig.add_gridspec(len(groups) + 2, 2)
    ax_q = [fig.add_subplot(gs[0, 0])]
    ax_q += [fig.add_subplot(gs[g, 0], sharex=ax_q[0]) for g in range(1, len(groups))]
    ax_v = fig.add_subplot(gs[len(groups):, 0], sharex=ax_q[0])
    ax_p = fig.add_subplot(gs[: len(groups) + 1, 1], projection="3d")
    ax_s = fig.add_subplot(gs[len(groups) + 1, 1], sharex=ax_q[0])
    t = samples.t
    colors = line_colors(robot.n_joints)
    for j, (nm, lim) in enumerate(zip(robot.joint_names, robot.limits)):
        unit, sc = units[j]
        ax_q[groups.index(unit)].plot(t, samples.q[:, j] * sc, color=colors[j], label=nm)
        ax_v.plot(t, samples.qd[:, j] / lim.v_max, color=colors[j], label=nm)
    for ax, unit in zip(ax_q, groups):
        ax.set_ylabel(f"joint position [{unit}]")
        ax.legend(fontsize=7, ncol=2)
    ax_v.legend(fontsize=7, ncol=3)
    ax_v.axhline(1.0, color="k", lw=0.7, ls="--")
    ax_v.axhline(-1.0, color="k", lw=0.7, ls="--")
    ax_v.set_ylabel("joint velocity / v_max")
    ax_v.set_xlabel("t [s]")
    ax_s.plot(t, 1e3 * samples.tool_speed, color="C3")
    ax_s.set_ylabel("tool speed [mm/s]")
    ax_s.set_xlabel("t [s]")
    xyz = 1e3 * samples.xyz
    ax_p.plot(xyz[:, 0], xyz[:, 1], xyz[:, 2], color="C0", lw=1.2)
    ax_p.scatter(*xyz[0], color="g", s=20)
    ax_p.scatter(*xyz[-1], color="r", s=20)
    set_equal_3d(ax_p, xyz)
    ax_p.set_xlabel("x [mm]")
    ax_p.set_ylabel("y [mm]")
    ax_p.set_zlabel("z [mm]")
    ax_p.set_title("tool path")
    fig.suptitle(f"{robot.name}: program of {run.duration:.3f} s")
    fig.tight_layout()
    save_figure(fig, path)
    return fig
