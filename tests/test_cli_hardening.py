"""The command line under hostile and careless input: one line, exit 2, nothing half-written.

Every case here once printed a traceback, ran for minutes or left files behind.
"""

from __future__ import annotations

import csv
import os
import re
import subprocess
import sys

import numpy as np
import pytest

from trajkit._atomicio import TEMP_GLOB, output_group, write_file
from trajkit._csvio import csv_text, safe_name
from trajkit.cli import main

PROGRAM = """robot: arm6
points:
  home: {joints_deg: [0, 20, 10, 0, 60, 0]}
  p1: {xyz_mm: [550, 0, 580], abc_deg: [0, 90, 0]}
  p2: {xyz_mm: [550, 200, 580], abc_deg: [0, 90, 0]}
program:
  - PTP: p1
  - LIN: p2
"""

SADDLE = ["saddle", "--main-radius", "110", "--branch-radius", "100", "--feed", "20",
          "--tolerance", "0.01", "--period", "0.001"]


def cli(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err.strip()


def one_line_error(code, err, command):
    assert code == 2, err
    assert "\n" not in err and "Traceback" not in err, err
    assert err.startswith(f"trajkit {command}: error: "), err
    assert "np.float64" not in err and not re.search(r"\d{25}", err), err
    return err


# ------------------------------------------------------------- bounded work
def test_slowed_saddle_is_refused_from_its_planned_duration(capsys):
    code, _, err = cli(capsys, *SADDLE, "--z-vmax", "0.01", "--json")
    err = one_line_error(code, err, "saddle")
    assert re.search(r"at a period of 0\.001 s is [0-9.e+]+ setpoints, more than the cap of "
                     r"5,000,000: choose a longer period, or raise the cap", err)


def test_long_wait_is_refused_before_sampling(tmp_path, capsys):
    f = tmp_path / "wait.yaml"
    f.write_text(PROGRAM + "  - WAIT: {time_s: 80000}\n")
    code, _, err = cli(capsys, "run", f, "--period", "0.001")
    assert "more than the cap of 5,000,000" in one_line_error(code, err, "run")
    f.write_text(PROGRAM + "  - WAIT: {time_s: 1e6}\n")
    code, _, err = cli(capsys, "run", f, "--period", "0.001")
    assert "time_s: Input should be less than or equal to 86400 (got 1000000.0)" in \
        one_line_error(code, err, "run")


def test_program_sizes_and_ranges_are_capped(tmp_path, capsys):
    f = tmp_path / "p.yaml"
    many = "".join("  - LIN: p2\n  - LIN: p1\n" for _ in range(1001))
    f.write_text(PROGRAM + many)
    code, _, err = cli(capsys, "run", f, "--period", "0.01")
    assert "program: List should have at most 2000 items" in one_line_error(code, err, "run")
    f.write_text(PROGRAM.replace("[550, 200, 580]", "[1e300, 0, 400]"))
    code, _, err = cli(capsys, "run", f, "--period", "0.01")
    assert "p.yaml:5: points.p2.xyz_mm[0]: Input should be less than or equal to 1000000 " \
           "(got 1e+300)" in one_line_error(code, err, "run")
    f.write_text(PROGRAM.replace("  - LIN: p2\n", "  - LIN: p2\n    speed_mm_s: 1e-300\n"))
    code, _, err = cli(capsys, "run", f, "--period", "0.01")
    assert ("instruction 1 (LIN p2, line 8): the motion along this path would take at least "
            "2e+302 s, more than the 1e+07 s the path timing supports") in one_line_error(code, err, "run")


def test_joint_errors_are_in_the_units_of_the_file(tmp_path, capsys):
    f = tmp_path / "p.yaml"
    f.write_text(PROGRAM.replace("[0, 20, 10, 0, 60, 0]", "[0, 20, 10, 0, 600, 0]"))
    code, _, err = cli(capsys, "run", f, "--period", "0.01")
    err = one_line_error(code, err, "run")
    assert re.search(r"joint A5 = 600 deg is outside its range \[-?[0-9.]+, [0-9.]+\] deg$", err)


def test_pallet_job_numbers_have_a_supported_range(tmp_path, capsys):
    import yaml

    from trajkit.io import seed_job_path

    job = yaml.safe_load(seed_job_path().read_text())
    job["gripper"] = {"grip_s": 1e300}
    f = tmp_path / "job.yaml"
    f.write_text(yaml.safe_dump(job))
    code, _, err = cli(capsys, "pallet", f)
    assert "field gripper.grip_s: Input should be less than or equal to 86400 (got 1e+300)" in \
        one_line_error(code, err, "pallet")


def test_ptp_axis_count_duplicate_names_and_units(tmp_path, capsys):
    import json

    f = tmp_path / "big.json"
    f.write_text(json.dumps({"start": [0] * 2000, "goal": [1] * 2000,
                             "limits": {"v_max": 1, "a_max": 2, "j_max": 10}}))
    code, _, err = cli(capsys, "ptp", "--file", f)
    assert "field start: List should have at most 1024 items" in one_line_error(code, err, "ptp")
    code, _, err = cli(capsys, "ptp", "--start", "0,0", "--goal", "1,1", "--names", "A,A",
                       "--v-max", "1", "--a-max", "2", "--j-max", "10")
    assert "--names: axes 0 and 1 are both called 'A'; axis names must be unique" in \
        one_line_error(code, err, "ptp")
    code, _, err = cli(capsys, "ptp", "--start", "0", "--goal", "1", "--unit", "m/s",
                       "--v-max", "1", "--a-max", "2", "--j-max", "10")
    assert "--unit: 'm/s' is not a unit name" in one_line_error(code, err, "ptp")


def test_option_that_needs_another_says_so(tmp_path, capsys):
    f = tmp_path / "p.yaml"
    f.write_text(PROGRAM)
    code, _, err = cli(capsys, "run", f, "--period", "0.01", "--inertia-ratio", "2")
    assert "--inertia-ratio only acts on the servo simulation: add --simulate" in \
        one_line_error(code, err, "run")


# ------------------------------------------------------------- outputs
def test_a_failed_output_leaves_none_of_the_others(tmp_path, capsys):
    f = tmp_path / "p.yaml"
    f.write_text(PROGRAM)
    blocker = tmp_path / "plots"
    blocker.write_text("a file, not a folder")
    csv_path = tmp_path / "out.csv"
    code, _, err = cli(capsys, "run", f, "--period", "0.01", "--csv", csv_path,
                       "--plot", blocker / "run.png")
    err = one_line_error(code, err, "run")
    assert "does not exist" in err and ".tmp" not in err
    assert not csv_path.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.yaml", "plots"]


def test_plot_into_a_missing_folder_creates_nothing(tmp_path, capsys):
    target = tmp_path / "missing" / "deeper" / "x.png"
    code, _, err = cli(capsys, *SADDLE, "--plot", target)
    err = one_line_error(code, err, "saddle")
    assert f"folder {target.parent} does not exist" in err
    assert not (tmp_path / "missing").exists()


def test_demo_out_under_a_missing_parent_creates_nothing(tmp_path, capsys):
    code, _, err = cli(capsys, "demo", "--out", tmp_path / "a" / "b")
    assert f"cannot create folder {tmp_path / 'a' / 'b'}: folder {tmp_path / 'a'} does not exist" \
        in one_line_error(code, err, "demo")
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "file").write_text("x")
    code, _, err = cli(capsys, "demo", "--out", tmp_path / "file")
    assert "it is a file, not a folder" in one_line_error(code, err, "demo")


def test_output_group_is_all_or_none(tmp_path):
    def text(s):
        return lambda tmp: open(tmp, "w").write(s)

    (tmp_path / "b.txt").write_text("old")
    with pytest.raises(RuntimeError):
        with output_group():
            write_file(tmp_path / "a.txt", text("new a"))
            write_file(tmp_path / "b.txt", text("new b"))
            assert len(list(tmp_path.glob(TEMP_GLOB))) == 2
            raise RuntimeError("a later output fails")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.txt"]
    assert (tmp_path / "b.txt").read_text() == "old"
    with output_group() as g:
        write_file(tmp_path / "a.txt", text("1"))
        write_file(tmp_path / "a.txt", text("2"))  # the later write wins
        assert g.targets == [str(tmp_path / "a.txt")]
        assert not (tmp_path / "a.txt").exists()
    assert (tmp_path / "a.txt").read_text() == "2"
    assert not list(tmp_path.glob(TEMP_GLOB))


# ------------------------------------------------------------- CSV and tables
def test_csv_names_are_neutralised_and_round_trip():
    assert safe_name("=cmd|' /C calc'!A0") == "'=cmd|' /C calc'!A0"
    assert safe_name("+1") == "'+1" and safe_name("@x") == "'@x" and safe_name("a\x00b") == "ab"
    x = np.array([0.1, 1 / 3, -2.5e-300])
    text = csv_text(["t_s", "=evil,name", "q"], [x, x, x])
    rows = list(csv.reader(text.splitlines()))
    assert rows[0] == ["t_s", "'=evil,name", "q"]
    np.testing.assert_array_equal(np.array(rows[1:], dtype=float)[:, 0], x)


def test_ptp_csv_header_style_and_hostile_names(tmp_path, capsys):
    path = tmp_path / "p.csv"
    code, _, err = cli(capsys, "ptp", "--start", "0,0", "--goal", "1,2", "--names", "=cmd|calc,B",
                       "--unit", "rad,mm", "--v-max", "1", "--a-max", "2", "--j-max", "10",
                       "--csv", path, "--period", "0.1")
    assert code == 0, err
    header = next(csv.reader(path.open()))
    assert header == ["t_s", "'=cmd|calc_position_rad", "'=cmd|calc_velocity_rad_s",
                      "'=cmd|calc_acceleration_rad_s2", "'=cmd|calc_jerk_rad_s3",
                      "B_position_mm", "B_velocity_mm_s", "B_acceleration_mm_s2", "B_jerk_mm_s3"]


def test_piped_tables_never_wrap(tmp_path):
    env = dict(os.environ, COLUMNS="40")
    proc = subprocess.run([sys.executable, "-m", "trajkit", "move", "--start", "0", "--goal", "1",
                           "--v-max", "1", "--a-max", "2", "--j-max", "10"],
                          capture_output=True, text=True, env=env, cwd=tmp_path, timeout=120)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert any("a_max, a_max_decel, v_max" in ln for ln in lines)
    head = next(ln for ln in lines if "duration [s]" in ln)
    assert "min duration [s]" in head and "peak dec [m/s^2]" in head


def test_python_dash_m_and_internal_errors(tmp_path, monkeypatch, capsys):
    proc = subprocess.run([sys.executable, "-m", "trajkit", "--version"], capture_output=True,
                          text=True, cwd=tmp_path, timeout=120)
    assert proc.returncode == 0 and proc.stdout.startswith("trajkit ")

    import trajkit.cli._core as core

    def broken(*a, **k):
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr(core, "plan_move", broken)
    code, _, err = cli(capsys, "move", "--start", "0", "--goal", "1", "--v-max", "1",
                       "--a-max", "2", "--j-max", "10")
    assert code == 3 and "\n" not in err
    assert err.startswith("trajkit move: internal error (ZeroDivisionError: float division by zero)")
    assert "please report the command and its input" in err
