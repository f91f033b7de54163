"""Figures: 3-D views with equal axis scales, one unit per y axis, distinct legend colours."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from trajkit.interpolation import plan_feed  # noqa: E402
from trajkit.paths import Arc3, discretize  # noqa: E402


def _spans(ax):
    return [np.diff(ax.get_xlim())[0], np.diff(ax.get_ylim())[0], np.diff(ax.get_zlim())[0]]


def test_path_figure_3d_has_equal_scales():
    from trajkit.plot.paths import plot_path_plan

    arc = Arc3([0.0, 0.0, 0.0], [0.05, 0.05, 0.0], [0.1, 0.0, 0.001])  # nearly flat
    plan = plan_feed(arc, 0.05, 0.5, 5.0, tolerance=1e-5, period=0.001)
    fig = plot_path_plan(plan, discretize(arc, 1e-5))
    ax3 = next(ax for ax in fig.axes if ax.name == "3d")
    spans = _spans(ax3)
    assert spans == pytest.approx([spans[0]] * 3, rel=1e-12)
    box = np.asarray(ax3.get_box_aspect())
    assert box == pytest.approx([box[0]] * 3, rel=1e-9)


def test_robot_figure_splits_units_and_scales_3d_equally():
    from trajkit.io.program import parse_program
    from trajkit.plot.robot import plot_robot_run

    prog = parse_program(
        "robot: scara\n"
        "points:\n"
        "  a: {joints: {J1_deg: 0, J2_deg: 30, J3_mm: 50, J4_deg: 0}}\n"
        "  b: {joints: {J1_deg: 40, J2_deg: -20, J3_mm: 120, J4_deg: 90}}\n"
        "program:\n  - PTP: a\n  - PTP: b\n")
    run = prog.run()
    fig = plot_robot_run(run, run.sample(run.times(0.01)))
    labels = [ax.get_ylabel() for ax in fig.axes if ax.name != "3d"]
    assert "joint position [deg]" in labels and "joint position [mm]" in labels
    ax3 = next(ax for ax in fig.axes if ax.name == "3d")
    spans = _spans(ax3)
    assert spans == pytest.approx([spans[0]] * 3, rel=1e-12)
