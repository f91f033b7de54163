"""Figures of a robot program run: joint positions/velocities and the tool path."""

from __future__ import annotations

import math
import os
from typing import Any

from . import require_matplotlib, save_figure

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
    fig = plt.figure(figsize=(13, 8))
    ax_q = fig.add_subplot(2, 2, 1)
    ax_v = fig.add_subplot(2, 2, 3, sharex=ax_q)
    ax_p = fig.add_subplot(2, 2, 2, projection="3d")
    ax_s = fig.add_subplot(2, 2, 4, sharex=ax_q)
    t = samples.t
    for j, (nm, kind, lim) in enumerate(zip(robot.joint_names, robot.joint_kinds, robot.limits)):
        sc, unit = (180.0 / math.pi, "deg") if kind == "revolute" else (1e3, "mm")
        ax_q.plot(t, samples.q[:, j] * sc, label=f"{nm} [{unit}]")
        ax_v.plot(t, samples.qd[:, j] / lim.v_max, label=nm)
    ax_q.set_ylabel("joint position")
    ax_q.legend(fontsize=7, ncol=2)
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
    ax_p.set_xlabel("x [mm]")
    ax_p.set_ylabel("y [mm]")
    ax_p.set_zlabel("z [mm]")
    ax_p.set_title("tool path")
    fig.suptitle(f"{robot.name}: program of {run.duration:.3f} s")
    fig.tight_layout()
    save_figure(fig, path)
    return fig
