"""``trajkit run PROGRAM.yaml --period DT``: summary, CSV, plot, JSON, one-line errors."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from trajkit._atomicio import TEMP_GLOB
from trajkit.cli import main

EXAMPLES = Path(__file__).resolve().parent.parent / "examples" / "data"
SCARA = str(EXAMPLES / "scara_pick.yaml")


def test_run_json_csv_plot(tmp_path, capsys):
    out_csv = tmp_path / "samples.csv"
    out_png = tmp_path / "run.png"
    rc = main(["run", SCARA, "--period", "0.004", "--csv", str(out_csv), "--plot", str(out_png),
               "--json"])
    assert rc == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["robot"] == "scara"
    assert summary["duration_s"] > 0
    assert [lm["joint"] for lm in summary["limits"]] == ["J1", "J2", "J3", "J4"]
    for lm in summary["limits"]:
        assert lm["velocity_ratio"] <= 1 + 1e-9 and lm["acceleration_ratio"] <= 1 + 1e-9
    rows = list(csv.reader(out_csv.open()))
    assert rows[0][:5] == ["t_s", "J1_deg", "J2_deg", "J3_mm", "J4_deg"]
    t = np.array([float(r[0]) for r in rows[1:]])
    assert len(rows) - 1 == summary["samples"]
    assert np.allclose(np.diff(t)[:-1], 0.004)
    assert t[-1] == pytest.approx(summary["duration_s"], abs=1e-12)
    assert out_png.stat().st_size > 10_000
    assert not list(tmp_path.glob(TEMP_GLOB))


def test_run_table_output(capsys):
    assert main(["run", SCARA, "--period", "0.01"]) == 0
    out = capsys.readouterr().out
    assert "joint limit usage" in out and "scara" in out


@pytest.mark.parametrize("args,pattern", [
    (["run", "missing.yaml", "--period", "0.004"], "No such file"),
    (["run", SCARA, "--period", "-1"], r"--period must be between 0\.0001 and 0\.1 s, got -1\.0"),
    (["run", SCARA, "--period", "nan"], r"--period must be between .* got nan"),
])
def test_run_errors_one_line(args, pattern, capsys):
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("trajkit run: error:")
    import re
    assert re.search(pattern, err)


def test_run_bad_program_names_line(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text("robot: arm6\npoints:\n  a: {joints_deg: [0, 20, 10, 0, 60, 0]}\n"
                   "program:\n  - PTP: a\n  - LIN: a\n    speed_mm_s: 0\n")
    assert main(["run", str(bad), "--period", "0.004"]) == 2
    err = capsys.readouterr().err
    assert "bad.yaml:7: program[1].speed_mm_s: Input should be greater than 0 (got 0)" in err


def test_run_unreachable_is_one_line(tmp_path, capsys):
    prog = tmp_path / "far.yaml"
    prog.write_text("robot: arm6\npoints:\n  a: {joints_deg: [0, 20, 10, 0, 60, 0]}\n"
                    "  far: {xyz_mm: [1500, 0, 500], abc_deg: [0, 0, 180]}\n"
                    "program:\n  - PTP: a\n  - LIN: far\n")
    assert main(["run", str(prog), "--period", "0.004"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert err.startswith("trajkit run: error: instruction 1 (LIN far, line 7): point (")
    assert "unreachable" in err
