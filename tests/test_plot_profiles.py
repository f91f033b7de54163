"""Tests of trajkit.plot.profiles: the stacked p/v/a/j figures."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from trajkit import AxisLimits, InvalidInputError, plan_move, plan_ptp  # noqa: E402
from trajkit.plot.profiles import _profile_curve, plot_profile, plot_trajectory  # noqa: E402

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
ASYM = AxisLimits(1.0, 2.0, 10.0, a_max_decel=1.5, j_max_decel=5.0)


def _data_lines(ax):
    """Curves drawn with plot() (not the axhline/axvline helpers)."""
    return [ln for ln in ax.get_lines() if len(ln.get_xdata()) > 2]


def _hlines(ax, style="--"):
    return [float(ln.get_ydata()[0]) for ln in ax.get_lines()
            if ln.get_linestyle() == style and len(ln.get_xdata()) == 2
            and ln.get_ydata()[0] == ln.get_ydata()[1]]


def test_plot_profile_structure_and_data():
    prof = plan_move(0.2, 1.2, ASYM)
    fig = plot_profile(prof)
    axs = fig.axes
    assert len(axs) == 4
    # shared time axis
    for ax in axs[1:]:
        assert ax.get_shared_x_axes().joined(axs[0], ax)
    labels = [ax.get_ylabel() for ax in axs]
    assert "position" in labels[0] and "[m]" in labels[0]
    assert "[m/s]" in labels[1]
    assert "s$^2$" in labels[2] and "s$^3$" in labels[3]
    assert axs[3].get_xlabel() == "time [s]"
    # the drawn curves are the profile: ends at start/goal, extremes at the limits
    pos = _data_lines(axs[0])[0]
    x, y = np.asarray(pos.get_xdata()), np.asarray(pos.get_ydata())
    assert x[0] == 0.0 and x[-1] == prof.duration
    assert y[0] == prof.start and y[-1] == prof.goal
    vel = np.asarray(_data_lines(axs[1])[0].get_ydata())
    assert vel.max() == pytest.approx(1.0, rel=1e-12)
    acc = np.asarray(_data_lines(axs[2])[0].get_ydata())
    assert acc.max() == pytest.approx(2.0, rel=1e-12)
    assert acc.min() == pytest.approx(-1.5, rel=1e-12)
    jerk = np.asarray(_data_lines(axs[3])[0].get_ydata())
    assert set(np.unique(jerk)) == {-10.0, -5.0, 0.0, 5.0, 10.0}
    # limits as dashed lines: v_max, a_max and -a_max_decel, +-j_max and +-j_max_decel
    assert _hlines(axs[1]) == [1.0]
    assert sorted(_hlines(axs[2])) == [-1.5, 2.0]
    assert sorted(_hlines(axs[3])) == [-10.0, -5.0, 5.0, 10.0]
    # phase boundaries: one dotted vertical line per distinct boundary time
    vlines = [ln for ln in axs[1].get_lines() if ln.get_linestyle() == ":"]
    assert len(vlines) == len(np.unique(prof.phase_times)) == 8
    # phase shading: one span per phase that lasts > 0, and a label above each
    assert len(axs[0].patches) == 7
    assert [t.get_text() for t in axs[0].texts] == ["j+", "a", "j-", "v", "j-", "d", "j+"]


def test_profile_curve_is_exact_at_phase_ends():
    prof = plan_move(-0.3, -2.0, ASYM)  # negative direction
    t, s = _profile_curve(prof)
    assert np.all(np.diff(t) >= 0.0)
    bs = prof.boundary_states()
    tb = prof.phase_times
    for k in range(7):
        # the last point drawn in phase k is just before its end: left limits
        i = np.flatnonzero(t < tb[k + 1])[-1]
        a_end = bs[k, 2] + prof.jerks[k] * prof.phase_durations[k]
        assert s.acceleration[i] == pytest.approx(a_end, abs=1e-9)
        assert s.jerk[i] == prof.jerks[k]
        assert s.position[i] == pytest.approx(bs[k + 1, 0], abs=1e-12)
    lim = prof.limits
    assert np.all(np.abs(s.velocity) <= lim.v_max * (1 + 1e-12))
    assert np.all(s.acceleration <= lim.a_max_decel * (1 + 1e-12))
    assert np.all(s.acceleration >= -lim.a_max * (1 + 1e-12))


def test_trapezoid_draws_acceleration_steps():
    prof = plan_move(0.0, 1.0, AxisLimits(1.0, 2.0, math.inf))
    fig = plot_profile(prof)
    acc = np.asarray(_data_lines(fig.axes[2])[0].get_ydata())
    x = np.asarray(_data_lines(fig.axes[2])[0].get_xdata())
    t_end_accel = 0.5  # v_max / a_max
    left = acc[x < t_end_accel][-1]
    right = acc[x >= t_end_accel][0]
    assert left == 2.0 and right == 0.0  # a vertical edge, not a ramp
    assert "infinite jerk" in fig.axes[3].texts[0].get_text()
    # no jerk limit lines for an infinite jerk
    assert _hlines(fig.axes[3]) == []


def test_zero_move_plots():
    prof = plan_move(0.5, 0.5, ASYM)
    fig = plot_profile(prof)
    assert fig.axes[0].get_xlim() == (0.0, 1.0)
    (pos,) = [ln for ln in fig.axes[0].get_lines() if ln.get_label() == "position"]
    assert np.all(np.asarray(pos.get_ydata()) == 0.5)
    (vel,) = [ln for ln in fig.axes[1].get_lines() if ln.get_label() == "velocity"]
    assert np.all(np.asarray(vel.get_ydata()) == 0.0)


def test_plot_profile_writes_png_atomically(tmp_path):
    prof = plan_move(0.0, 1.0, ASYM)
    path = tmp_path / "p.png"
    fig = plot_profile(prof, path)
    data = path.read_bytes()
    assert data[:8] == PNG_MAGIC and len(data) > 10_000
    assert os.listdir(tmp_path) == ["p.png"]  # no temporary file left behind
    assert fig.get_suptitle().startswith("0 → 1 m")
    plot_profile(prof, tmp_path / "p.svg", unit="rad")
    assert (tmp_path / "p.svg").read_text().lstrip().startswith("<?xml")


@pytest.mark.parametrize("bad, match", [
    ("p.jpg", r"plot path must end in \.png, \.pdf or \.svg, got 'p\.jpg'"),
    ("noext", r"got 'noext'"),
])
def test_plot_profile_bad_path(tmp_path, bad, match):
    with pytest.raises(InvalidInputError, match=match):
        plot_profile(plan_move(0.0, 1.0, ASYM), tmp_path / bad if "/" in bad else bad)
    assert not os.path.exists(bad)


def test_plot_profile_rejects_non_profile():
    with pytest.raises(InvalidInputError, match=r"profile must be a Profile, got list"):
        plot_profile([1, 2, 3])
    with pytest.raises(InvalidInputError, match=r"traj must be a Trajectory, got Profile"):
        plot_trajectory(plan_move(0.0, 1.0, ASYM))


@pytest.mark.parametrize("sync", ["time", "phase", "none"])
def test_plot_trajectory(sync, tmp_path):
    lims = [AxisLimits(1.0, 2.0, 10.0, name="A"), AxisLimits(1.5, 3.0, 20.0, name="B"),
            AxisLimits(0.5, 1.0, 5.0, 0.8, 2.0, name="C")]
    traj = plan_ptp([0.0, 1.0, 0.0], [1.0, -1.0, 0.3], lims, sync=sync)
    path = tmp_path / f"t_{sync}.png"
    fig = plot_trajectory(traj, path)
    assert path.read_bytes()[:8] == PNG_MAGIC
    axs = fig.axes
    assert len(axs) == 4
    for ax in axs:
        assert len(_data_lines(ax)) == 3  # one curve per axis
    assert [t.get_text() for t in axs[0].get_legend().get_texts()] == ["A", "B", "C"]
    for k, ln in enumerate(_data_lines(axs[0])):
        y = np.asarray(ln.get_ydata())
        assert y[0] == traj.axes[k].start and y[-1] == traj.axes[k].goal
    # each axis' velocity limit on the side of its motion, dashed
    assert sorted(_hlines(axs[1])) == [-1.5, 0.5, 1.0]
    assert axs[0].get_xlim()[1] == traj.duration
    assert (len(axs[0].patches) > 0) == (sync == "phase")


def test_plot_trajectory_units():
    traj = plan_ptp([0.0, 0.0], [1.0, 2.0], AxisLimits(1.0, 2.0, 10.0))
    fig = plot_trajectory(traj, units=["rad", "m"])
    # one column of panels per unit: every y axis has one unit
    axs = np.array(fig.axes).reshape(4, 2)
    assert [ax.get_ylabel() for ax in axs[:, 0]] == [
        "position\n[rad]", "velocity\n[rad/s]", "acceleration\n[rad/s$^2$]", "jerk\n[rad/s$^3$]"]
    assert axs[0, 1].get_ylabel() == "position\n[m]"
    assert [t.get_text() for t in axs[0, 0].get_legend().get_texts()] == ["q0"]
    assert [t.get_text() for t in axs[0, 1].get_legend().get_texts()] == ["q1"]
    fig = plot_trajectory(traj, units="mm")
    assert "[mm/s]" in fig.axes[1].get_ylabel()
    with pytest.raises(InvalidInputError,
                       match=r"units has 3 entries but the trajectory has 2 axes"):
        plot_trajectory(traj, units=["m", "m", "m"])


def test_many_axes_get_distinct_colours():
    from matplotlib.colors import to_rgba

    n = 14
    traj = plan_ptp(np.zeros(n), np.linspace(0.5, 2.0, n), AxisLimits(1.0, 2.0, 10.0))
    fig = plot_trajectory(traj)
    lines = _data_lines(fig.axes[0])
    colours = {to_rgba(ln.get_color()) for ln in lines}
    assert len(lines) == n and len(colours) == n
