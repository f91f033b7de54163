"""``trajkit run PROGRAM.yaml --simulate [--plot]``: planned vs simulated time, FE plot."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from trajkit._atomicio import TEMP_GLOB
from trajkit.cli import main

SCARA = str(Path(__file__).resolve().parent.parent / "examples" / "data" / "scara_pick.yaml")


def test_simulate_json_and_plots(tmp_path, capsys):
    png = tmp_path / "run.png"
    assert main(["run", SCARA, "--period", "0.004", "--simulate", "--plot", str(png),
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    sim = out["simulation"]
    assert sim["planned_s"] == pytest.approx(out["duration_s"])
    assert sim["simulated_s"] > sim["planned_s"]
    assert len(sim["motions"]) == len(out["segments"])
    assert sum(m["simulated_s"] for m in sim["motions"]) == pytest.approx(sim["simulated_s"])
    assert sum(m["planned_s"] for m in sim["motions"]) == pytest.approx(sim["planned_s"])
    # exact stop at every segment end: each waits at least settle_cycles periods
    assert all(m["settle_s"] >= 5 * 0.004 - 1e-12 for m in sim["motions"])
    fe_png = tmp_path / "run-following-error.png"
    assert out["following_error_plot"] == str(fe_png)
    assert png.stat().st_size > 10_000 and fe_png.stat().st_size > 10_000
    assert not list(tmp_path.glob(TEMP_GLOB))


def test_simulate_table_and_heavier_load(capsys):
    assert main(["run", SCARA, "--period", "0.004", "--simulate"]) == 0
    out = capsys.readouterr().out
    assert "planned vs simulated time" in out and "total" in out
    assert main(["run", SCARA, "--period", "0.004", "--simulate", "--inertia-ratio", "3",
                 "--json"]) == 0
    heavy = json.loads(capsys.readouterr().out)["simulation"]
    assert heavy["servo"][0]["inertia_ratio"] == 3.0
    assert max(heavy["max_following_error"]) > 0


def test_simulate_bad_inertia_one_line(capsys):
    assert main(["run", SCARA, "--period", "0.004", "--simulate", "--inertia-ratio", "0"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "inertia_ratio should be larger than zero, got 0.0" in err
