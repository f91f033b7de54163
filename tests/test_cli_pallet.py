"""``trajkit pallet``: table, exact JSON shape, plots, errors as one line + exit 2."""

from __future__ import annotations

import json

import pytest
import yaml

from trajkit._atomicio import TEMP_GLOB
from trajkit.cli import main
from trajkit.io import seed_job_path
from trajkit.palletizing import plan_cycle, seed_scenario


@pytest.fixture(scope="module")
def seed_totals():
    sc = seed_scenario()
    return {n: plan_cycle(sc, n).total_s for n in ("ptp", "merged", "optimal")}


def test_json_shape_and_values(capsys, seed_totals):
    assert main(["pallet", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) == {"boxes", "plans"}
    assert out["boxes"] == 25
    assert list(out["plans"]) == ["ptp", "merged", "optimal"]
    for n, d in out["plans"].items():
        assert d["total_s"] == pytest.approx(seed_totals[n], rel=1e-15)
        assert d["per_box_s"] == pytest.approx(seed_totals[n] / 25, rel=1e-15)
        assert d["verified"] is True
    assert out["plans"]["merged"]["reduction_pct"] == pytest.approx(
        100 * (1 - seed_totals["merged"] / seed_totals["ptp"]), rel=1e-12)
    opt = out["plans"]["optimal"]
    assert opt["total_s"] < out["plans"]["merged"]["total_s"]
    assert opt["window_floor_s"] <= opt["lower_bound_s"] <= opt["total_s"]
    assert opt["vs_lower_bound_pct"] == pytest.approx(
        100 * (opt["total_s"] / opt["lower_bound_s"] - 1), rel=1e-12)
    assert "paper_planned_s" not in opt  # the paper has no such plan


def test_table_beside_paper(capsys, seed_totals):
    assert main(["pallet", str(seed_job_path())]) == 0
    out = capsys.readouterr().out
    assert "107.854" in out and "91.850" in out
    assert "107.753" in out and "89.422" in out
    assert f"{seed_totals['optimal']:.3f}" in out and "above its lower bound" in out
    assert "verified: ptp ok" in out and "optimal ok" in out


def test_plots_written(tmp_path, capsys):
    job = yaml.safe_load(seed_job_path().read_text())
    job["layers"] = 2
    job["pattern"] = {"name": "column", "alternate": "none"}
    p = tmp_path / "small.yaml"
    p.write_text(yaml.safe_dump(job))
    d = tmp_path / "figs"
    assert main(["pallet", str(p), "--plot", str(d), "--planner", "merged", "--box", "3"]) == 0
    out = capsys.readouterr().out
    for name in ("pallet_b_velocity.png", "pallet_cycle_vs_zmax.png", "pallet_gripper_path_3d.png"):
        f = d / name
        assert f.stat().st_size > 10_000
        assert f.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert f"wrote {f}" in out
    assert not list(d.glob(TEMP_GLOB))


@pytest.mark.parametrize("args,match", [
    (["pallet", "/nonexistent/job.yaml"], "No such file"),
    (["pallet", "--planner", "fastest"], r"--planner must be one of \['cell', 'merged', 'optimal', 'ptp'\], got 'fastest'"),
    (["pallet", "--box", "25"], r"--box must be in \[0, 24\] for this job, got 25"),
])
def test_errors_one_line_exit_2(capsys, args, match):
    assert main(args) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1
    assert err.startswith("trajkit pallet: error:")
    import re
    assert re.search(match, err)


def test_invalid_job_field_is_named(tmp_path, capsys):
    job = yaml.safe_load(seed_job_path().read_text())
    job["box"]["height_mm"] = 0
    p = tmp_path / "bad.yaml"
    p.write_text(yaml.safe_dump(job))
    assert main(["pallet", str(p), "--json"]) == 2
    cap = capsys.readouterr()
    assert cap.out == ""
    assert "field box.height_mm: Input should be greater than 0 (got 0)" in cap.err


# ------------------------------------------------------------------ a cell job
@pytest.fixture(scope="module")
def cell_job(tmp_path_factory):
    from trajkit.io import seed_cell_job_path

    job = yaml.safe_load(seed_cell_job_path().read_text())
    job["layers"] = 1
    p = tmp_path_factory.mktemp("cell") / "cell.yaml"
    p.write_text(yaml.safe_dump(job))
    return p


def test_cell_job_json_and_csv(cell_job, tmp_path, capsys):
    csv = tmp_path / "cycle.csv"
    assert main(["pallet", str(cell_job), "--json", "--csv", str(csv), "--period", "0.01"]) == 0
    cap = capsys.readouterr()
    out = json.loads(cap.out)
    assert out["cell"] is True
    assert list(out["plans"]) == ["ptp", "merged", "optimal", "cell"]
    cell = out["plans"]["cell"]
    assert cell["verified"] is True and cell["cell_ok"] is True
    assert cell["min_clearance_mm"] >= 10.0 - 1e-4 and cell["colliding_boxes"] == []
    assert cell["lower_bound_s"] <= cell["total_s"] <= 1.03 * cell["lower_bound_s"]
    assert cell["total_s"] < out["plans"]["optimal"]["total_s"]
    assert sorted(cell["order"]) == [0, 1, 2, 3, 4]
    assert out["plans"]["ptp"]["verified"] is True      # its own rule holds ...
    assert out["plans"]["ptp"]["cell_ok"] is False      # ... the cell's does not
    assert f"wrote {csv} (cell plan" in cap.err
    lines = csv.read_text().splitlines()
    assert lines[0] == "t_s,box,trip,carrying,A_deg,B_mm,C_mm,D_deg"
    first, last = lines[1].split(","), lines[-1].split(",")
    assert float(first[0]) == 0.0 and first[2] == "load" and first[3] == "1"
    assert float(last[0]) == pytest.approx(cell["total_s"], abs=1e-6) and last[2] == "return"
    assert float(last[5]) == pytest.approx(400.0) and float(last[6]) == pytest.approx(1200.0)
    assert len(lines) == int(cell["total_s"] / 0.01) + 3 or len(lines) == int(cell["total_s"] / 0.01) + 2


def test_cell_job_table(cell_job, capsys):
    assert main(["pallet", str(cell_job), "--planner", "optimal", "--planner", "cell"]) == 0
    out = capsys.readouterr().out
    assert "in the cell" in out and "min clearance" in out
    assert "cell: collision-free in the cell" in out
    assert "optimal: breaks the cell's rules" in out
    assert "above its lower bound" in out and "any motion in this order" in out


@pytest.mark.parametrize("args,match", [
    (["--period", "0.01"], "--period needs --csv FILE"),
    (["--csv", "x.csv"], "--csv needs --period DT"),
    (["--csv", "x.csv", "--period", "0"], "--period must be a finite time > 0 s, got 0.0"),
    (["--csv", "x.csv", "--period", "abc"], "--period must be a number, got 'abc'"),
    (["--csv", "/nonexistent/dir/x.csv", "--period", "0.1"], "folder /nonexistent/dir does not exist"),
    (["--csv", "x.csv", "--period", "1e-9"], "more than the 10000000 allowed"),
    (["--planner", "cell"], "the 'cell' planner needs a cell"),
])
def test_csv_and_cell_errors_one_line(args, match, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["pallet", "--planner", "ptp", *args] if "--planner" not in args else ["pallet", *args]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and match in err
    assert not list(tmp_path.iterdir())
