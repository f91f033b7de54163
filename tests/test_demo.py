"""``trajkit demo``: runs the seed scenario, prints the table, writes the figures."""

from __future__ import annotations

import os

from trajkit.cli import main


def test_demo_writes_figures(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["demo"]) == 0
    out = capsys.readouterr().out
    folder = tmp_path / "trajkit-demo"
    assert f"figures in {folder.resolve()}" in out
    assert "107.854" in out and "verified: ptp ok, merged ok, optimal ok" in out
    assert "optimal: " in out and "above its lower bound" in out
    # the cell planner's row, and what every plan does in the cell
    assert "cell ok" in out and "cell: collision-free in the cell" in out
    assert "in the cell: ptp collides, merged collides, optimal collides, cell clear" in out
    names = sorted(os.listdir(folder))
    for n in ("pallet_b_velocity.png", "pallet_cycle_vs_zmax.png", "pallet_gripper_path_3d.png"):
        assert n in names and (folder / n).stat().st_size > 10_000
    try:
        import trajkit.plot.profiles as prof
        has_traj = hasattr(prof, "plot_trajectory")
    except ImportError:
        has_traj = False
    assert ("ptp_transfer_4axis.png" in names) == has_traj
    if not has_traj:
        assert "skipped the 4-axis transfer figure" in out


def test_transfer_plot_skipped_without_plot_trajectory(tmp_path, monkeypatch):
    import sys

    from trajkit.cli._demo import write_transfer_plot
    from trajkit.palletizing import seed_scenario

    monkeypatch.setitem(sys.modules, "trajkit.plot.profiles", None)  # import fails
    assert write_transfer_plot(seed_scenario(), tmp_path) is None
    assert os.listdir(tmp_path) == []


def test_demo_bad_out_dir_is_one_line(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["demo", "--out", str(blocker / "sub")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("trajkit demo: error:") and len(err.strip().splitlines()) == 1
