"""Figures for palletizing plans (Cao et al., 2012, figures 6, 8, 12, and a 3-D path view).

Every function takes planned objects, returns a matplotlib Figure, and writes
it (atomically) when given ``path``. Units on the axes: mm, mm/s, s.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from . import require_matplotlib, save_figure

__all__ = [
    "plot_b_velocity",
    "plot_zmax_curve",
    "plot_gripper_path_3d",
    "write_pallet_plots",
    "PLOT_FILES",
]

#: File names written by :func:`write_pallet_plots`.
PLOT_FILES = {
    "b_velocity": "pallet_b_velocity.png",
    "zmax": "pallet_cycle_vs_zmax.png",
    "path3d": "pallet_gripper_path_3d.png",
}

#: Samples per second for the time plots and for the 3-D path.
_PLOT_RATE = 1000.0
_PATH_RATE = 100.0
_DPI = 110


def _save(fig, path):
    save_figure(fig, path, dpi=_DPI)


def _cycle_window(plan, box: int):
    """Start and end time [s] of box ``box``'s load + return trips."""
    idx = [i for i, tp in enumerate(plan.trips) if tp.spec.box == box]
    t0 = plan.trip_starts[idx[0]]
    t1 = plan.trip_starts[idx[-1]] + plan.trips[idx[-1]].duration
    return idx, t0, t1


def plot_b_velocity(plans: Mapping[str, object], box: int = 0, path=None):
    """B-axis velocity and height over one cycle (load + return) of ``box``, per plan.

    One column per plan (Cao et al., 2012, figure 6 for ``ptp``, figure 8 for
    ``merged``); the shaded spans are the windows where A, C, D move.
    """
    plt = require_matplotlib()
    names = list(plans)
    fig, axes = plt.subplots(2, len(names), figsize=(5.5 * len(names), 6.0), sharex="col",
                             squeeze=False)
    for c, name in enumerate(names):
        plan = plans[name]
        idx, t0, t1 = _cycle_window(plan, box)
        t = np.linspace(t0, t1, int((t1 - t0) * _PLOT_RATE) + 2)
        s = plan.timeline.sample(t)
        ax_v, ax_z = axes[0, c], axes[1, c]
        ax_v.plot(t - t0, s.velocity[:, 1] * 1000, color="C0", lw=1.6, label="B velocity")
        ax_z.plot(t - t0, s.position[:, 1] * 1000, color="C1", lw=1.6, label="B height")
        for i in idx:
            tp = plan.trips[i]
            ws = plan.trip_starts[i] + tp.window[0] - t0
            we = plan.trip_starts[i] + tp.window[1] - t0
            for ax in (ax_v, ax_z):
                ax.axvspan(ws, we, color="0.85", zorder=0)
            z0, z1, z2, z3 = tp.spec.z_levels
            ts = plan.trip_starts[i] - t0
            ax_z.hlines([z1 * 1000, z2 * 1000], ts, ts + tp.duration, colors=["C2", "C3"],
                        linestyles=":", lw=1)
        ax_v.axhline(0, color="k", lw=0.6)
        ax_v.set_title(f"{name}: box {box}, cycle {t1 - t0:.3f} s")
        ax_v.set_ylabel("B velocity [mm/s]")
        ax_z.set_ylabel("B height Z [mm]")
        ax_z.set_xlabel("time in cycle [s]  (grey: A, C, D moving; dotted: Z1, Z2)")
        ax_v.grid(alpha=0.3)
        ax_z.grid(alpha=0.3)
    fig.tight_layout()
    _save(fig, path)
    return fig


def plot_zmax_curve(scenario, box: int = 0, kind: str = "load", n: int = 201, path=None):
    """Trip time against B's highest point ``Zmax`` for one trip (Cao et al., 2012, figure 12).

    Shows ``f' + g'`` (B alone), ``t1 + tH + t3`` (horizontal window) and
    their maximum (the trip time), with the optimum found by the planner.
    """
    from ..palletizing.planners import merged_trip_times, optimal_zmax

    plt = require_matplotlib()
    spec = next(s for s in scenario.trips() if s.box == box and s.kind == kind)
    lo, hi = max(spec.z_levels), scenario.robot.z_top
    z = np.linspace(lo, hi, n)
    r = merged_trip_times(scenario, spec, z)
    zo = optimal_zmax(scenario, spec)
    ro = merged_trip_times(scenario, spec, zo)
    fig, ax = plt.subplots(figsize=(7.0, 4.5))
    ax.plot(z * 1000, r["t_b"], "--", label="f'(Z0,Zmax) + g'(Zmax,Z3)  (B alone)")
    ax.plot(z * 1000, r["t_window"], "--", label="t1 + tH + t3  (horizontal window)")
    ax.plot(z * 1000, r["trip"], "k", lw=2, label="trip time = max")
    ax.plot([zo * 1000], ro["trip"], "o", color="C3",
            label=f"optimum Zmax = {zo * 1000:.1f} mm, {ro['trip'][0]:.4f} s")
    ax.set_xlabel("Zmax [mm]")
    ax.set_ylabel("time [s]")
    ax.set_title(f"{kind} trip of box {box}: trip time against Zmax")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    _save(fig, path)
    return fig


def _box_edges(pose, size):
    """12 edges of a box whose top-face centre is ``pose`` (x, y, z, yaw), size (l, w, h) [m]."""
    x, y, z, yaw = pose
    l, w, h = size
    c, s = np.cos(yaw), np.sin(yaw)
    corners = []
    for dz in (0.0, -h):
        for dx, dy in ((l / 2, w / 2), (-l / 2, w / 2), (-l / 2, -w / 2), (l / 2, -w / 2)):
            corners.append((x + c * dx - s * dy, y + s * dx + c * dy, z + dz))
    P = np.array(corners)
    edges = [(i, (i + 1) % 4) for i in range(4)] + [(4 + i, 4 + (i + 1) % 4) for i in range(4)]
    edges += [(i, i + 4) for i in range(4)]
    return [P[[a, b]] for a, b in edges]


def _joined(edges):
    """Stack edges (2, 3) into one polyline with NaN breaks (one artist, fast)."""
    gap = np.full((1, 3), np.nan)
    return np.vstack([np.vstack([e, gap]) for e in edges])


def plot_gripper_path_3d(plans: Mapping[str, object] | object, boxes: Sequence[int] | None = None,
                         path=None, reports: Mapping[str, object] | None = None):
    """3-D view of the gripper path (forward kinematics) over the stack, in its cell.

    Equal scales on the three axes. With a cell: its obstacles, and for
    every plan with a cell check (``reports[name].cell``, run here when
    missing) the point of its tightest clearance, marked and labelled.

    Parameters
    ----------
    plans : CyclePlan or mapping name -> CyclePlan
    boxes : sequence of int, optional
        Boxes whose cycles are drawn; default: all.
    reports : mapping name -> VerificationReport, optional
    """
    plt = require_matplotlib()
    if not isinstance(plans, Mapping):
        plans = {getattr(plans, "planner", "plan"): plans}
    first = next(iter(plans.values()))
    sc = first.scenario
    fig = plt.figure(figsize=(9.0, 8.0))
    ax = fig.add_subplot(111, projection="3d")
    size = (sc.box.length, sc.box.width, sc.box.height)
    pts = [np.zeros((1, 3))]
    stack = _joined([e for pose in sc.place_poses() for e in _box_edges(pose, size)])
    ax.plot(*(stack.T * 1000), color="0.6", lw=0.5, label="boxes on the pallet")
    pick = _joined(_box_edges(sc.pick, size))
    ax.plot(*(pick.T * 1000), color="C8", lw=0.8, label="box at the pick")
    pts += [stack[np.isfinite(stack[:, 0])], pick[np.isfinite(pick[:, 0])]]
    cell = getattr(sc, "cell", None)
    if cell is not None and cell.obstacles:
        edges = []
        for o in cell.obstacles:
            pose = (0.5 * (o.x[0] + o.x[1]), 0.5 * (o.y[0] + o.y[1]), o.z[1], 0.0)
            edges += _box_edges(pose, (o.x[1] - o.x[0], o.y[1] - o.y[0], o.z[1] - o.z[0]))
        cj = _joined(edges)
        ax.plot(*(cj.T * 1000), color="0.3", lw=0.9, label="cell obstacles")
        pts.append(cj[np.isfinite(cj[:, 0])])
    for k, (name, plan) in enumerate(plans.items()):
        tl = plan.timeline
        if boxes is None:
            t = np.linspace(0.0, tl.duration, int(tl.duration * _PATH_RATE) + 2)
        else:
            t = np.concatenate([np.linspace(*_cycle_window(plan, b)[1:], 400) for b in boxes])
        q = tl.sample(t).position
        xyz = plan.scenario.robot.pose_from_joints(q)[:, :3] * 1000
        ax.plot(xyz[:, 0], xyz[:, 1], xyz[:, 2], color=f"C{k}", lw=0.9, label=f"{name} gripper path")
        pts.append(xyz / 1000)
        if cell is not None:
            rep = (reports or {}).get(name)
            cr = getattr(rep, "cell", None)
            if cr is None:
                from ..palletizing.cellcheck import check_cell

                cr = check_cell(plan)
            if cr.min_clearance_at:
                t_c, _, obst, qc = cr.min_clearance_at
                pc = plan.scenario.robot.pose_from_joints(np.asarray(qc))[:3] * 1000
                ax.scatter([pc[0]], [pc[1]], [pc[2]], color=f"C{k}", marker="X", s=70,
                           edgecolors="k", zorder=5,
                           label=f"{name}: tightest clearance {cr.min_clearance * 1000:.1f} mm "
                                 f"({obst}, t={t_c:.2f} s)")
    ax.scatter([0], [0], [0], color="k", marker="^", label="robot base")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_zlabel("z [mm]")
    ax.set_title(f"{sc.name}: gripper path over the stack ({sc.n_boxes} boxes)")
    ax.legend(fontsize=7, loc="upper left")
    # equal scales: a cube around everything drawn
    allp = np.vstack(pts) * 1000
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    mid, half = 0.5 * (lo + hi), 0.5 * float(np.max(hi - lo)) * 1.05
    ax.set_xlim(mid[0] - half, mid[0] + half)
    ax.set_ylim(mid[1] - half, mid[1] + half)
    ax.set_zlim(max(0.0, mid[2] - half), max(0.0, mid[2] - half) + 2 * half)
    try:
        ax.set_box_aspect((1.0, 1.0, 1.0))
    except Exception:  # pragma: no cover - older matplotlib
        pass
    fig.tight_layout()
    _save(fig, path)
    return fig


def write_pallet_plots(plans: Mapping[str, object], out_dir, box: int = 0,
                       reports: Mapping[str, object] | None = None) -> list[Path]:
    """Write the palletizing figures into ``out_dir`` (created if missing).

    ``reports`` (name -> VerificationReport) give the 3-D figure its
    tightest-clearance marks on a job with a cell.

    Returns
    -------
    list of Path
        The files written (see :data:`PLOT_FILES`).
    """
    plt = require_matplotlib()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    sc = next(iter(plans.values())).scenario
    written = []
    for key, fn in (("b_velocity", lambda p: plot_b_velocity(plans, box, p)),
                    ("zmax", lambda p: plot_zmax_curve(sc, box, "load", path=p)),
                    ("path3d", lambda p: plot_gripper_path_3d(plans, path=p, reports=reports))):
        p = out / PLOT_FILES[key]
        fig = fn(p)
        plt.close(fig)
        written.append(p)
    return written
