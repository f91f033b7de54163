"""Summaries of planned jobs beside seed 000's table 1."""

from __future__ import annotations

from typing import Mapping

from .planners import CyclePlan

__all__ = ["PAPER_TABLE1", "PAPER_BOXES", "summarize", "table_rows", "bound_lines", "TABLE_COLUMNS"]

#: Seed 000, table 1 (25 boxes): planned and measured times [s]; per box is
#: the measured time / 25 as printed in the paper.
PAPER_TABLE1 = {
    "ptp": {"planned_s": 107.854, "measured_s": 112.997, "per_box_measured_s": 4.520},
    "merged": {"planned_s": 91.850, "measured_s": 96.973, "per_box_measured_s": 3.879},
}

#: Number of boxes of the paper's experiment.
PAPER_BOXES = 25

TABLE_COLUMNS = ("plan", "total (s)", "per box (s)", "reduction", "paper planned (s)",
                 "paper per box (s)", "paper reduction", "vs paper")


def summarize(plans: Mapping[str, CyclePlan], baseline: str = "ptp") -> dict:
    """JSON-ready summary of several plans of the same scenario.

    Returns
    -------
    dict
        ``{"boxes": N, "plans": {name: {"total_s", "per_box_s",
        "reduction_pct", "paper_planned_s", "paper_per_box_s", ...}}}``;
        ``reduction_pct`` is relative to ``baseline`` (when present); the
        paper's figures are included only for plans the paper has.
    """
    names = list(plans)
    n = next(iter(plans.values())).n_boxes if plans else 0
    base = plans[baseline].total_s if baseline in plans else None
    paper_base = PAPER_TABLE1[baseline]["planned_s"] if baseline in PAPER_TABLE1 else None
    out: dict = {"boxes": n, "plans": {}}
    for name in names:
        p = plans[name]
        d = {"total_s": p.total_s, "per_box_s": p.per_box_s}
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
            d["window_floor_s"] = float(p.info["window_floor_s"])
            d["vs_lower_bound_pct"] = 100.0 * (p.total_s / d["lower_bound_s"] - 1.0)
            d["vs_window_floor_pct"] = 100.0 * (p.total_s / d["window_floor_s"] - 1.0)
            cands: dict = {}
            for t in p.info.get("trips", ()):
                cands[t.candidate] = cands.get(t.candidate, 0) + 1
            d["trip_candidates"] = cands
        out["plans"][name] = d
    return out


def bound_lines(summary: dict) -> list[str]:
    """One line per plan that knows its lower bound (the ``optimal`` plan).

    The lower bound is the sum over trips of ``max(t_up + tH + t_down, t_B)``
    (B alone), the window floor the sum of ``t_up + tH + t_down`` (see
    :mod:`trajkit.palletizing.optimal`), dwells included.
    """
    out = []
    for name, d in summary["plans"].items():
        if "lower_bound_s" in d:
            out.append(
                f"{name}: {d['vs_lower_bound_pct']:.2f} % above its lower bound "
                f"{d['lower_bound_s']:.3f} s ({d['vs_window_floor_pct']:.2f} % above the "
                f"window floor {d['window_floor_s']:.3f} s)"
            )
    return out


def table_rows(summary: dict) -> list[list]:
    """Rows for :data:`TABLE_COLUMNS` from a :func:`summarize` result (strings/floats)."""
    rows = []
    for name, d in summary["plans"].items():
        def pct(key):
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
