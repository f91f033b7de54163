"""Figures of one-axis profiles and multi-axis trajectories.

The classic stacked position / velocity / acceleration / jerk figure with a
shared time axis, phase boundaries marked and the limits drawn as dashed
lines. Matplotlib is imported lazily (through
:func:`trajkit.plot.require_matplotlib`); the figures are built with
:class:`matplotlib.figure.Figure` directly, so they hold no pyplot state and
need no ``plt.close``.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..errors import InvalidInputError
from ..profiles.profile import Profile
from ..trajectory import Trajectory
from . import line_colors, require_matplotlib, save_figure

__all__ = ["plot_profile", "plot_trajectory", "QUANTITIES"]

#: The four stacked rows: (attribute of the sample, label, time exponent of the unit).
QUANTITIES = (
    ("position", "position", 0),
    ("velocity", "velocity", 1),
    ("acceleration", "acceleration", 2),
    ("jerk", "jerk", 3),
)

#: Points drawn per phase of a profile (the phase end points are drawn exactly).
_POINTS_PER_PHASE = 64

#: Figure size [inch] and resolution [dpi] of the saved PNG.
_FIGSIZE = (9.0, 8.5)
_DPI = 120

#: Alternating shades of the phases (accel leg, cruise, decel leg).
_PHASE_COLORS = ("#dbe9f6", "#dbe9f6", "#dbe9f6", "#eeeeee", "#f8e0d8", "#f8e0d8", "#f8e0d8")

#: Short labels written above the phases (full names are in PHASE_NAMES).
_PHASE_LABELS = ("j+", "a", "j-", "v", "j-", "d", "j+")


def _unit_label(unit: str, power: int) -> str:
    if power == 0:
        return f"[{unit}]"
    if power == 1:
        return f"[{unit}/s]"
    return f"[{unit}/s$^{power}$]"


def _profile_curve(profile: Profile) -> tuple[np.ndarray, Any]:
    """Times and samples that draw every phase exactly, jumps included.

    Each phase is sampled on ``_POINTS_PER_PHASE`` points from its start to
    just before its end (``nextafter``), so a step in acceleration (an
    infinite-jerk trapezoid) or in jerk is drawn as a vertical edge.
    """
    tb = profile.phase_times
    pieces = []
    for k in range(7):
        t0, t1 = tb[k], tb[k + 1]
        if t1 <= t0:
            continue
        seg = np.linspace(t0, t1, _POINTS_PER_PHASE)
        seg[-1] = np.nextafter(t1, -np.inf)
        pieces.append(seg)
    pieces.append(np.array([profile.duration]))
    t = np.concatenate(pieces)
    return t, profile.sample(t)


def _check_path(path: str | os.PathLike | None) -> str | None:
    if path is None:
        return None
    p = os.fspath(path)
    ext = os.path.splitext(p)[1].lower().lstrip(".")
    if ext not in ("png", "pdf", "svg"):
        raise InvalidInputError(
            f"plot path must end in .png, .pdf or .svg, got {p!r}"
        )
    return p


def _save(fig: Any, path: str | None) -> None:
    """Write the figure atomically (see :func:`trajkit.plot.save_figure`)."""
    save_figure(fig, path, dpi=_DPI)


def _new_figure(title: str, ncols: int = 1) -> tuple[Any, Any]:
    """Figure with 4 stacked rows (position .. jerk) in ``ncols`` columns; axes (4,) or (4, ncols)."""
    require_matplotlib()  # Agg backend, clear ImportError otherwise
    from matplotlib.figure import Figure

    fig = Figure(figsize=(_FIGSIZE[0] * (1 + 0.6 * (ncols - 1)), _FIGSIZE[1]), layout="constrained")
    axs = fig.subplots(4, ncols, sharex=True, squeeze=False)
    fig.suptitle(title)
    for ax in axs.ravel():
        ax.grid(True, color="#cccccc", linewidth=0.5)
        ax.axhline(0.0, color="#888888", linewidth=0.6)
    for ax in axs[-1]:
        ax.set_xlabel("time [s]")
    return fig, (axs[:, 0] if ncols == 1 else axs)


def _limit_lines(ax: Any, values: Sequence[float], color: str, label: str | None) -> None:
    first = True
    for v in values:
        if math.isfinite(v):
            ax.axhline(v, color=color, linestyle="--", linewidth=0.9,
                       label=label if first else None)
            first = False


def _limit_values(profile: Profile) -> tuple[list[float], list[float], list[float]]:
    """Velocity, acceleration and jerk limit lines on the side of the motion."""
    lim = profile.limits
    s = profile.direction if profile.direction != 0.0 else 1.0
    vel = [s * lim.v_max]
    acc = [s * lim.a_max, -s * lim.a_max_decel]
    jerk = [lim.j_max, -lim.j_max]
    if lim.j_max_decel != lim.j_max:
        jerk += [lim.j_max_decel, -lim.j_max_decel]
    return vel, acc, jerk


def plot_profile(
    profile: Profile,
    path: str | os.PathLike | None = None,
    *,
    unit: str = "m",
    title: str | None = None,
) -> Any:
    """Plot one axis' position, velocity, acceleration and jerk over time.

    Four stacked panels with a shared time axis; the seven phases are shaded
    (accel leg blue, cruise grey, decel leg red), their boundaries drawn as
    vertical lines and labelled (``j+ a j- v j- d j+``, see
    :data:`trajkit.profiles.PHASE_NAMES`); the velocity, acceleration and
    jerk limits are dashed lines.

    Parameters
    ----------
    profile : Profile
        A planned one-axis profile (:func:`trajkit.plan_move`).
    path : str or os.PathLike, optional
        Where to write the figure (``.png``, ``.pdf`` or ``.svg``); written
        atomically.
    unit : str
        Position unit for the axis labels (``"m"``, ``"rad"``, ``"mm"``).
    title : str, optional
        Figure title; by default the move, duration and shape.

    Returns
    -------
    matplotlib.figure.Figure
        Four axes (position, velocity, acceleration, jerk), shared x [s].

    Raises
    ------
    InvalidInputError
        ``profile`` is not a Profile, or ``path`` has an unsupported suffix.
    ImportError
        matplotlib is not installed.
    """
    if not isinstance(profile, Profile):
        raise InvalidInputError(f"profile must be a Profile, got {type(profile).__name__}")
    out = _check_path(path)
    if title is None:
        title = (f"{profile.start:g} → {profile.goal:g} {unit}: "
                 f"T = {profile.duration:.6g} s, {profile.shape}")
    fig, axs = _new_figure(title)
    t, smp = _profile_curve(profile)
    tb = profile.phase_times
    for ax in axs:
        for k in range(7):
            if tb[k + 1] > tb[k]:
                ax.axvspan(tb[k], tb[k + 1], color=_PHASE_COLORS[k], alpha=0.6, linewidth=0)
        for x in np.unique(tb):
            ax.axvline(x, color="#777777", linewidth=0.6, linestyle=":")
    top = axs[0]
    for k in range(7):
        if tb[k + 1] > tb[k]:
            top.text(0.5 * (tb[k] + tb[k + 1]), 1.02, _PHASE_LABELS[k],
                     transform=top.get_xaxis_transform(), ha="center", va="bottom",
                     fontsize=8, color="#444444")
    vel_l, acc_l, jerk_l = _limit_values(profile)
    limits = (None, vel_l, acc_l, jerk_l)
    for ax, (attr, name, power), lim in zip(axs, QUANTITIES, limits):
        ax.plot(t, getattr(smp, attr), color="#1f4e99", linewidth=1.6, label=name)
        if lim is not None:
            _limit_lines(ax, lim, "#c0392b", "limit")
        ax.set_ylabel(f"{name}\n{_unit_label(unit, power)}")
    axs[0].axhline(profile.goal, color="#2e7d32", linestyle="--", linewidth=0.9, label="goal")
    if math.isinf(profile.limits.j_max) or math.isinf(profile.limits.j_max_decel):
        axs[3].text(0.01, 0.95, "infinite jerk limit: acceleration steps (trapezoid)",
                    transform=axs[3].transAxes, ha="left", va="top", fontsize=8)
    axs[0].legend(loc="best", fontsize=8)
    axs[1].legend(loc="best", fontsize=8)
    axs[0].set_xlim(0.0, profile.duration if profile.duration > 0 else 1.0)
    _save(fig, out)
    return fig


def plot_trajectory(
    traj: Trajectory,
    path: str | os.PathLike | None = None,
    *,
    units: str | Sequence[str] = "m",
    title: str | None = None,
) -> Any:
    """Plot every axis of a trajectory: position, velocity, acceleration, jerk.

    One line per axis (named in the legend), four stacked panels with a
    shared time axis. Each axis' phase boundaries are ticked as thin vertical
    lines in its colour; with ``sync="phase"`` they coincide and the phases
    are shaded as in :func:`plot_profile`. Each axis' velocity and
    acceleration limits are dashed lines in its colour.

    Parameters
    ----------
    traj : Trajectory
        A planned multi-axis trajectory (:func:`trajkit.plan_ptp`).
    path : str or os.PathLike, optional
        Where to write the figure (``.png``, ``.pdf`` or ``.svg``), atomically.
    units : str or sequence of str
        Position unit of every axis, or one per axis; axes with different
        units are drawn in separate columns of panels, so that every y axis
        has one unit.
    title : str, optional
        Figure title; by default the axis count, duration and sync mode.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    InvalidInputError
        ``traj`` is not a Trajectory, a wrong number of units, or a bad path.
    """
    if not isinstance(traj, Trajectory):
        raise InvalidInputError(f"traj must be a Trajectory, got {type(traj).__name__}")
    out = _check_path(path)
    n = traj.n_axes
    ulist = [units] * n if isinstance(units, str) else list(units)
    if len(ulist) != n:
        raise InvalidInputError(
            f"units has {len(ulist)} entries but the trajectory has {n} axes"
        )
    groups = list(dict.fromkeys(ulist))  # one column of panels per position unit
    if title is None:
        title = f"{n}-axis PTP, sync={traj.sync}: T = {traj.duration:.6g} s"
    fig, axs = _new_figure(title, max(len(groups), 1))
    axs = axs.reshape(4, -1)
    colors = line_colors(n)
    if traj.sync == "phase" and n > 0:
        tb = traj.axes[0].phase_times
        for ax in axs.ravel():
            for k in range(7):
                if tb[k + 1] > tb[k]:
                    ax.axvspan(tb[k], tb[k + 1], color=_PHASE_COLORS[k], alpha=0.6, linewidth=0)
        for col in range(axs.shape[1]):
            for k in range(7):
                if tb[k + 1] > tb[k]:
                    axs[0, col].text(0.5 * (tb[k] + tb[k + 1]), 1.02, _PHASE_LABELS[k],
                                     transform=axs[0, col].get_xaxis_transform(), ha="center",
                                     va="bottom", fontsize=8, color="#444444")
    for i, (prof, name) in enumerate(zip(traj.axes, traj.names)):
        col = axs[:, groups.index(ulist[i])]
        t, smp = _profile_curve(prof)
        for ax, (attr, _, _) in zip(col, QUANTITIES):
            ax.plot(t, getattr(smp, attr), color=colors[i], linewidth=1.4,
                    label=str(name) if ax is col[0] else None)
            if traj.sync != "phase":
                for x in np.unique(prof.phase_times)[1:-1]:
                    ax.axvline(x, color=colors[i], linewidth=0.5, linestyle=":", alpha=0.7)
        vel_l, acc_l, _ = _limit_values(prof)
        _limit_lines(col[1], vel_l, colors[i], None)
        _limit_lines(col[2], acc_l, colors[i], None)
    for g, unit in enumerate(groups):
        for ax, (_, name, power) in zip(axs[:, g], QUANTITIES):
            ax.set_ylabel(f"{name}\n{_unit_label(unit, power)}")
        members = sum(1 for u in ulist if u == unit)
        axs[0, g].legend(loc="best", fontsize=8, ncol=min(members, 6))
    axs[0, 0].set_xlim(0.0, traj.duration if traj.duration > 0 else 1.0)
    _save(fig, out)
    return fig

