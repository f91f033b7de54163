"""Summaries of planned jobs beside table 1 of Cao et al. (2012)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from .planners import CyclePlan
from .verify import VerificationReport

__all__ = ["PAPER_TABLE1", "PAPER_BOXES", "summarize", "table_rows", "bound_lines", "TABLE_COLUMNS",
           "CELL_COLUMNS", "cell_rows", "cell_lines", "cycle_rows"]

#: Cao et al. (2012), table 1 (25 boxes): planned and measured times [s]; per box is
#: the measured time / 25 as printed in the paper.
PAPER_TABLE1 = {
    "ptp": {"planned_s": 107.854, "measured_s": 112.997, "per_box_measured_s": 4.520},
    "merged": {"planned_s": 91.850, "measured_s": 96.973, "per_box_measured_s": 3.879},
}

#: Number of boxes of the paper's experiment.
PAPER_BOXES = 25

TABLE_COLUMNS = ("plan", "total (s)", "per box (s)", "reduction", "paper planned (s)",
                 "paper per box (s)", "paper reduction", "vs paper")

#: Columns of the second table of a job with a cell (:func:`cell_rows`).
CELL_COLUMNS = ("plan", "total (s)", "lower bound (s)", "min clearance (mm)",
                "boxes piercing", "boxes too close")


def summarize(plans: Mapping[str, CyclePlan], baseline: str = "ptp",
              reports: Mapping[str, VerificationReport] | None = None) -> dict:
    """JSON-ready summary of several plans of the same scenario.

    Parameters
    ----------
    plans : mapping name -> CyclePlan
    baseline : str
        Plan the reductions are relative to.
    reports : mapping name -> VerificationReport, optional
        Adds ``"verified"`` and, for a job with a cell, the cell check:
        ``"min_clearance_mm"``, ``"colliding_boxes"`` (boxes with a trip
        that pierces an obstacle), ``"violating_boxes"`` (any rule broken)
        and ``"cell_findings"`` (one line per trip that breaks a rule).

    Returns
    -------
    dict
        ``{"boxes": N, "plans": {name: {"total_s", "per_box_s",
        "reduction_pct", "paper_planned_s", "paper_per_box_s", ...}}}``;
        ``reduction_pct`` is relative to ``baseline`` (when present); the
        paper's figures are included only for plans the paper has. With a
        cell, ``"cell": true`` at the top.
    """
    names = list(plans)
    n = next(iter(plans.values())).n_boxes if plans else 0
    base = plans[baseline].total_s if baseline in plans else None
    paper_base = PAPER_TABLE1[baseline]["planned_s"] if baseline in PAPER_TABLE1 else None
    out: dict = {"boxes": n, "plans": {}}
    has_cell = any(p.scenario.cell is not None for p in plans.values())
    if has_cell:
        out["cell"] = True
    for name in names:
        p = plans[name]
        d: dict[str, Any] = {"total_s": p.total_s, "per_box_s": p.per_box_s}
        if base is not None:
            d["reduction_pct"] = 100.0 * (1.0 - p.total_s / base)
        if name in PAPER_TABLE1:
            paper = PAPER_TABLE1[name]
            d["paper_planned_s"] = paper["planned_s"]
            d["paper_planned_per_box_s"] = paper["planned_s"] / PAPER_BOXES
            d["paper_measured_s"] = paper["measured_s"]
            if paper_base is not None:
                d["paper_reduction_pct"] = 100.0 * (1.0 - paper["planned_s"] / paper_base)
            if n == PAPER_BOXES:
                d["vs_paper_pct"] = 100.0 * (p.total_s / paper["planned_s"] - 1.0)
        if "lower_bound_s" in p.info:
            d["lower_bound_s"] = float(p.info["lower_bound_s"])
            d["vs_lower_bound_pct"] = 100.0 * (p.total_s / d["lower_bound_s"] - 1.0)
            for key in ("window_floor_s", "order_bound_s", "cell_floor_s"):
                if key in p.info:
                    d[key] = float(p.info[key])
                    d["vs_" + key[:-2] + "_pct"] = 100.0 * (p.total_s / d[key] - 1.0)
            cands: dict[str, int] = {}
            for t in p.info.get("trips", ()):
                cands[t.candidate] = cands.get(t.candidate, 0) + 1
            d["trip_candidates"] = cands
        if "order" in p.info:
            d["order"] = [int(b) for b in p.info["order"]]
        rep = reports.get(name) if reports else None
        if rep is not None:
            d["verified"] = bool(rep.ok_without_cell if p.rule != "cell" else rep.ok)
            cell = rep.cell
            if cell is not None:
                d["cell_ok"] = bool(cell.ok)
                d["min_clearance_mm"] = 1000.0 * cell.min_clearance
                d["colliding_boxes"] = cell.colliding_boxes
                d["violating_boxes"] = cell.violating_boxes
                d["cell_findings"] = [f.message() for f in cell.findings]
        out["plans"][name] = d
    return out


def bound_lines(summary: dict) -> list[str]:
    """One line per plan that knows its lower bound (``optimal``, ``cell``).

    ``optimal``: the lower bound is the sum over trips of ``max(t_up + tH +
    t_down, t_B)`` (B alone), the window floor the sum of ``t_up + tH +
    t_down`` (see :mod:`trajkit.palletizing.optimal`). ``cell``: the bound
    over every in-layer order, wrist and synchronisation, the bound of the
    chosen order, and the floor of any motion in that order (see
    :mod:`trajkit.palletizing.cellplan`). Dwells included.
    """
    out = []
    for name, d in summary["plans"].items():
        if "order_bound_s" in d:
            out.append(
                f"{name}: {d['vs_lower_bound_pct']:.2f} % above its lower bound "
                f"{d['lower_bound_s']:.3f} s (every in-layer order, wrist and synchronisation; "
                f"this order {d['order_bound_s']:.3f} s; any motion in this order "
                f"{d['cell_floor_s']:.3f} s)"
            )
        elif "lower_bound_s" in d:
            out.append(
                f"{name}: {d['vs_lower_bound_pct']:.2f} % above its lower bound "
                f"{d['lower_bound_s']:.3f} s ({d['vs_window_floor_pct']:.2f} % above the "
                f"window floor {d['window_floor_s']:.3f} s)"
            )
    return out


def cell_rows(summary: dict) -> list[list]:
    """Rows for :data:`CELL_COLUMNS` (a job with a cell; empty otherwise).

    ``boxes piercing``: boxes with a trip that drives the box or the gripper
    into an obstacle; ``boxes too close``: boxes with a trip that breaks any
    of the cell's rules (closer than the clearance while a horizontal joint
    moves, included).
    """
    if not summary.get("cell"):
        return []
    rows = []
    for name, d in summary["plans"].items():
        rows.append([
            name,
            f"{d['total_s']:.3f}",
            f"{d['lower_bound_s']:.3f}" if "lower_bound_s" in d else "-",
            f"{d['min_clearance_mm']:.2f}" if "min_clearance_mm" in d else "-",
            f"{len(d['colliding_boxes'])}" if "colliding_boxes" in d else "-",
            f"{len(d['violating_boxes'])}" if "violating_boxes" in d else "-",
        ])
    return rows


def cell_lines(summary: dict, limit: int = 1) -> list[str]:
    """What the cell check found, per plan (a job with a cell)."""
    out: list[str] = []
    if not summary.get("cell"):
        return out
    for name, d in summary["plans"].items():
        if "min_clearance_mm" not in d:
            continue
        f = d["cell_findings"]
        if not f:
            out.append(f"{name}: collision-free in the cell (min clearance "
                       f"{d['min_clearance_mm']:.3f} mm)")
            continue
        pierce = [x for x in f if "pierces" in x]
        out.append(f"{name}: breaks the cell's rules on {len(d['violating_boxes'])} of "
                   f"{summary['boxes']} boxes' trips, pierces an obstacle on "
                   f"{len(d['colliding_boxes'])}; e.g. " + "; ".join((pierce or f)[:limit]))
    return out


def table_rows(summary: dict) -> list[list]:
    """Rows for :func:`table_columns` from a :func:`summarize` result (strings/floats)."""
    rows = []
    for name, d in summary["plans"].items():
        def pct(key, d=d):
            return f"{d[key]:.1f} %" if key in d else "-"
        rows.append([
            name,
            f"{d['total_s']:.3f}",
            f"{d['per_box_s']:.3f}",
            pct("reduction_pct"),
            f"{d['paper_planned_s']:.3f}" if "paper_planned_s" in d else "-",
            f"{d['paper_planned_per_box_s']:.3f}" if "paper_planned_per_box_s" in d else "-",
            pct("paper_reduction_pct"),
            f"{d['vs_paper_pct']:+.2f} %" if "vs_paper_pct" in d else "-",
        ])
    return rows


def cycle_rows(plan: CyclePlan, period: float) -> dict:
    """The whole cycle sampled every ``period`` (the ``--csv`` export).

    Parameters
    ----------
    plan : CyclePlan
    period : float
        Sample period [s] (> 0).

    Returns
    -------
    dict of ndarray, shape (n,)
        ``"t_s"`` (0, period, ..., total), ``"box"`` (index in the pattern's
        layer order), ``"trip"`` ("load" or "return"), ``"carrying"`` (1 on
        load trips), ``"A_deg"``, ``"B_mm"``, ``"C_mm"``, ``"D_deg"``. A
        sample belongs to the trip that started last at or before it.
    """
    t = plan.timeline.times(period)
    q = plan.timeline.sample(t).position
    idx = np.clip(np.searchsorted(plan.trip_starts, t, side="right") - 1, 0, len(plan.trips) - 1)
    kinds = np.array([tp.spec.kind for tp in plan.trips])
    boxes = np.array([tp.spec.box for tp in plan.trips])
    return {
        "t_s": t,
        "box": boxes[idx],
        "trip": kinds[idx],
        "carrying": (kinds[idx] == "load").astype(int),
        "A_deg": np.degrees(q[:, 0]),
        "B_mm": q[:, 1] * 1000.0,
        "C_mm": q[:, 2] * 1000.0,
        "D_deg": np.degrees(q[:, 3]),
    }
