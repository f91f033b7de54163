"""Tests of ``trajkit move`` and ``trajkit ptp`` (trajkit.cli._core)."""

from __future__ import annotations

import csv
import json
import math
import os
import re
import subprocess
import sys

import numpy as np
import pytest

from trajkit import AxisLimits, plan_move, plan_ptp
from trajkit.cli import main

MOVE = ["move", "--start", "0", "--goal", "1", "--v-max", "1", "--a-max", "2", "--j-max", "10"]
PTP = ["ptp", "--start", "0,0,0", "--goal", "1,2,3", "--v-max", "1", "--a-max", "2",
       "--j-max", "10"]


def run(capsys, *argv):
    rc = main(list(argv))
    out, err = capsys.readouterr()
    return rc, out, err


def run_json(capsys, *argv):
    rc, out, err = run(capsys, *argv, "--json")
    assert rc == 0, err
    return json.loads(out)


def read_csv(path):
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], np.array([[float(x) for x in r] for r in rows[1:]])


# ----------------------------------------------------------------- move
def test_move_table(capsys):
    rc, out, err = run(capsys, *MOVE)
    assert rc == 0 and err == ""
    # 1 m at v 1, a 2, j 10: T = 0.2+0.3+0.2 + 0.3 + 0.7 = 1.7 s, all limits reached
    assert "1.7" in out and "7-phase" in out
    assert "a_max, a_max_decel, v_max" in out
    for name in ("jerk_up", "const_accel", "jerk_down", "cruise", "decel_jerk_in",
                 "const_decel", "decel_jerk_out"):
        assert name in out
    assert "duration [s]" in out and "jerk [m/s^3]" in out  # units are not eaten as markup


def test_move_json_matches_library(capsys):
    d = run_json(capsys, *MOVE, "--a-max-decel", "1.5", "--j-max-decel", "5")
    lim = AxisLimits(1.0, 2.0, 10.0, 1.5, 5.0)
    prof = plan_move(0.0, 1.0, lim)
    assert d["duration_s"] == prof.duration
    assert d["shape"] == prof.shape == "7-phase"
    assert d["peak_deceleration"] == 1.5
    assert d["limits"]["j_max_decel"] == 5.0 and d["limits"]["position_max"] == "inf"
    assert [p["duration_s"] for p in d["phases"]] == list(prof.phase_durations)
    assert [p["jerk"] for p in d["phases"]] == list(prof.jerks)
    ends = [p["end_state"] for p in d["phases"]]
    assert ends[-1] == {"position": 1.0, "velocity": 0.0, "acceleration": 0.0}
    # end of the accel leg's constant phase: acceleration a_max, end of phase 3: zero
    assert ends[1]["acceleration"] == pytest.approx(2.0, abs=1e-12)
    assert ends[2]["acceleration"] == pytest.approx(0.0, abs=1e-12)
    assert ends[2]["velocity"] == pytest.approx(1.0, abs=1e-12)
    assert d["phases"][-1]["t_end_s"] == pytest.approx(prof.duration, rel=1e-15)


def test_move_negative_and_duration(capsys):
    d = run_json(capsys, *(MOVE[:1] + ["--start=-0.5", "--goal=-2.5"] + MOVE[5:]),
                 "--duration", "4")
    prof = plan_move(-0.5, -2.5, AxisLimits(1.0, 2.0, 10.0), duration=4.0)
    assert d["duration_s"] == 4.0 == prof.duration
    assert d["peak_velocity"] == prof.peak_velocity < 0
    assert d["min_duration_s"] < 4.0


def test_move_trapezoid_end_accelerations(capsys):
    d = run_json(capsys, *MOVE[:-1], "inf")
    # infinite jerk: the const-accel phase ends at a_max although the next starts at 0
    assert d["phases"][1]["end_state"]["acceleration"] == 2.0
    assert d["phases"][5]["end_state"]["acceleration"] == -2.0
    assert d["duration_s"] == pytest.approx(1.5, rel=1e-15)


def test_move_csv_samples(tmp_path, capsys):
    path = tmp_path / "m.csv"
    rc, out, err = run(capsys, *MOVE, "--a-max-decel", "1.5", "--csv", str(path),
                       "--period", "0.01")
    assert rc == 0, err
    assert f"wrote {path}" in out
    header, data = read_csv(path)
    assert header == ["t_s", "position_m", "velocity_m_s", "acceleration_m_s2", "jerk_m_s3"]
    prof = plan_move(0.0, 1.0, AxisLimits(1.0, 2.0, 10.0, 1.5))
    t = data[:, 0]
    assert t[0] == 0.0 and t[-1] == prof.duration
    assert np.allclose(np.diff(t)[:-1], 0.01, rtol=0, atol=1e-12)
    s = prof.sample(t)
    # written with 17 significant digits: exact round trip
    assert np.array_equal(data[:, 1], s.position)
    assert np.array_equal(data[:, 2], s.velocity)
    assert np.array_equal(data[:, 3], s.acceleration)
    assert np.array_equal(data[:, 4], s.jerk)
    assert data[-1, 1] == 1.0 and data[-1, 2] == 0.0
    assert sorted(os.listdir(tmp_path)) == ["m.csv"]


def test_move_csv_unit_and_json_notes_on_stderr(tmp_path, capsys):
    path = tmp_path / "r.csv"
    rc, out, err = run(capsys, *MOVE, "--unit", "rad", "--csv", str(path), "--period", "0.5",
                       "--json")
    assert rc == 0
    json.loads(out)  # stdout is pure JSON
    assert f"wrote {path}" in err
    header, data = read_csv(path)
    assert header[1:3] == ["position_rad", "velocity_rad_s"]
    assert data.shape == (5, 5)  # 0, 0.5, 1.0, 1.5, 1.7


def test_move_plot(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    path = tmp_path / "m.png"
    rc, out, err = run(capsys, *MOVE, "--plot", str(path))
    assert rc == 0, err
    assert path.read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize("extra, match", [
    (["--v-max", "-1"], r"^trajkit move: error: maximum velocity limit v_max should be "
                        r"larger than zero, got -1\.0$"),
    (["--a-max", "fast"], r"^trajkit move: error: --a-max must be a number, got 'fast'$"),
    (["--j-max", "nan"], r"j_max must be a number, got nan$"),
    (["--start", "nan"], r"start must be finite, got nan$"),
    (["--duration", "1"], r"duration 1\.0 s is below the minimum duration 1\.7 s"),
    (["--duration", "-1"], r"duration must be finite and >= 0 s, got -1\.0"),
    (["--csv", "x.csv"], r"--csv needs --period DT"),
    (["--period", "0.1"], r"--period needs --csv FILE"),
    (["--csv", "x.csv", "--period", "0"], r"--period must be a finite time > 0 s, got 0\.0"),
    (["--csv", "x.csv", "--period", "1e-9"], r"1\.7 s at a period of 1e-09 s is 1\.7e\+09 CSV rows, "
                                             r"more than the cap of 5,000,000"),
    (["--plot", "x.jpg"], r"plot path must end in \.png, \.pdf or \.svg, got 'x\.jpg'"),
    (["--csv", "/nonexistent-dir/x.csv", "--period", "0.1"],
     r"--csv '/nonexistent-dir/x\.csv': directory '/nonexistent-dir' does not exist"),
    (["--a-max", "inf", "--j-max", "inf"], r"a_max and j_max cannot both be infinite"),
])
def test_move_bad_input(capsys, tmp_path, monkeypatch, extra, match):
    monkeypatch.chdir(tmp_path)
    rc, out, err = run(capsys, *MOVE, *extra)
    assert rc == 2
    assert out == ""
    assert err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith("trajkit move: error: ")
    assert re.search(match, err.strip()), err
    assert os.listdir(tmp_path) == []  # nothing written


def test_plot_without_matplotlib_is_one_line(capsys, monkeypatch, tmp_path):
    import trajkit.plot

    def missing():
        raise ImportError("plotting needs matplotlib: pip install 'trajkit[plot]'")

    monkeypatch.setattr(trajkit.plot, "require_matplotlib", missing)
    rc, out, err = run(capsys, *MOVE, "--plot", str(tmp_path / "m.png"))
    assert rc == 2 and out == ""
    assert err == ("trajkit move: error: --plot: plotting needs matplotlib: "
                   "pip install 'trajkit[plot]'\n")
    assert os.listdir(tmp_path) == []


def test_move_missing_option_is_usage_error(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["move", "--goal", "1", "--v-max", "1", "--a-max", "2", "--j-max", "10"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "the following arguments are required: --start" in err
    assert err.count("\n") == 1


# ------------------------------------------------------------------ ptp
def test_ptp_table(capsys):
    rc, out, err = run(capsys, *PTP, "--names", "A,B,C")
    assert rc == 0, err
    assert "ptp, 3 axes, sync=time: duration 3.7 s" in out
    assert out.count("phases (state at the end of each phase)") == 3
    assert "axis A" in out and "axis C" in out
    assert "no-const-accel+no-const-decel" in out  # full shape names, not truncated


@pytest.mark.parametrize("sync", ["time", "phase", "none"])
def test_ptp_json_matches_library(capsys, sync):
    d = run_json(capsys, *PTP, "--v-max", "1,1.5,2", "--j-max-decel", "5", "--sync", sync)
    lims = [AxisLimits(v, 2.0, 10.0, j_max_decel=5.0) for v in (1.0, 1.5, 2.0)]
    traj = plan_ptp([0, 0, 0], [1, 2, 3], lims, sync=sync)
    assert d["sync"] == sync
    assert d["duration_s"] == traj.duration
    assert [a["name"] for a in d["axes"]] == ["q0", "q1", "q2"]
    for a, p in zip(d["axes"], traj.axes):
        assert a["duration_s"] == p.duration
        assert [ph["duration_s"] for ph in a["phases"]] == list(p.phase_durations)
        assert a["limits"]["j_max_decel"] == 5.0
        assert a["phases"][-1]["end_state"]["position"] == p.goal


def test_ptp_duration_and_csv(tmp_path, capsys):
    path = tmp_path / "p.csv"
    rc, out, err = run(capsys, *PTP, "--names", "A,B,C", "--unit", "rad,m,m", "--duration", "5",
                       "--csv", str(path), "--period", "0.004")
    assert rc == 0, err
    header, data = read_csv(path)
    assert header[:5] == ["t_s", "A_position_rad", "A_velocity_rad_s",
                          "A_acceleration_rad_s2", "A_jerk_rad_s3"]
    assert header[5] == "B_position_m" and len(header) == 13
    assert data[-1, 0] == 5.0
    assert np.array_equal(data[-1, [1, 5, 9]], [1.0, 2.0, 3.0])
    traj = plan_ptp([0, 0, 0], [1, 2, 3], AxisLimits(1.0, 2.0, 10.0), duration=5.0)
    s = traj.sample(data[:, 0])
    assert np.array_equal(data[:, 6], s.velocity[:, 1])


def test_ptp_plot(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    path = tmp_path / "p.png"
    rc, out, err = run(capsys, *PTP, "--sync", "phase", "--plot", str(path))
    assert rc == 0, err
    assert path.read_bytes()[:4] == b"\x89PNG"


JOB_YAML = """\
start: [0, 0, 0]
goal: [1, 2, 3]
names: [A, B, C]
sync: phase
unit: [rad, m, m]
limits:
  - {v_max: 1, a_max: 2, j_max: 10}
  - {v_max: 1.5, a_max: 2, j_max: 10, a_max_decel: 1}
  - {v_max: 2, a_max: 3, j_max: inf}
"""


def test_ptp_file_yaml_and_json_agree(tmp_path, capsys):
    y = tmp_path / "job.yaml"
    y.write_text(JOB_YAML)
    d_yaml = run_json(capsys, "ptp", "--file", str(y))
    import yaml

    j = tmp_path / "job.json"
    data = yaml.safe_load(JOB_YAML)
    data["limits"][2]["j_max"] = "inf"
    j.write_text(json.dumps(data))
    d_json = run_json(capsys, "ptp", "--file", str(j))
    assert d_yaml == d_json
    lims = [AxisLimits(1, 2, 10), AxisLimits(1.5, 2, 10, a_max_decel=1),
            AxisLimits(2, 3, math.inf)]
    traj = plan_ptp([0, 0, 0], [1, 2, 3], lims, sync="phase")
    assert d_yaml["sync"] == "phase"
    assert d_yaml["duration_s"] == traj.duration
    assert [a["name"] for a in d_yaml["axes"]] == ["A", "B", "C"]
    assert [a["unit"] for a in d_yaml["axes"]] == ["rad", "m", "m"]
    # command-line --sync overrides the file
    d = run_json(capsys, "ptp", "--file", str(y), "--sync", "none")
    assert d["sync"] == "none"
    assert d["axes"][0]["duration_s"] == plan_move(0, 1, lims[0]).duration


def test_ptp_file_single_limits_mapping(tmp_path, capsys):
    j = tmp_path / "job.json"
    j.write_text(json.dumps({"start": [0, 0], "goal": [1, -1],
                             "limits": {"v_max": 1, "a_max": 2, "j_max": 10}}))
    d = run_json(capsys, "ptp", "--file", str(j))
    assert [a["duration_s"] for a in d["axes"]] == [1.7, 1.7]


@pytest.mark.parametrize("extra, match", [
    (["--goal", "1,2"], r"--goal has 2 values but --start has 3$"),
    (["--v-max", "1,2"], r"--v-max has 2 values but start/goal have 3 axes"),
    (["--v-max", "1,-2,1", "--names", "X,Y,Z"],
     r"maximum velocity limit v_max of axis Y should be larger than zero, got -2\.0$"),
    (["--a-max", "2,0,2"], r"a_max of axis 1 should be larger than zero, got 0\.0$"),
    (["--start", "0,,0"], r"--start must be a comma-separated list of numbers, got '0,,0'"),
    (["--start", "0,nan,0"], r"start of axis q1 must be finite, got nan$"),
    (["--goal", "1,2,inf", "--names", "A,B,C"], r"goal of axis C must be finite, got inf$"),
    (["--sync", "fast"], r"sync must be one of \('time', 'phase', 'none'\), got 'fast'"),
    (["--names", "A,B"], r"--names has 2 entries but --start has 3 axes"),
    (["--unit", "m,m"], r"--unit has 2 values but start/goal have 3 axes"),
    (["--sync", "none", "--duration", "9"], r'duration cannot be given with sync="none"'),
    (["--duration", "2"], r"below the minimum synchronised duration 3\.(7|69999)"),
    (["--file", "job.yaml"], r"--file cannot be combined with --start, --goal, --v-max, "
                             r"--a-max, --j-max"),
])
def test_ptp_bad_input(capsys, extra, match):
    argv = list(PTP)
    # later options override earlier ones in argparse
    rc, out, err = run(capsys, *argv, *extra)
    assert rc == 2 and out == ""
    assert err.startswith("trajkit ptp: error: ") and err.count("\n") == 1
    assert re.search(match, err.strip()), err


@pytest.mark.parametrize("content, suffix, match", [
    ("start: [0, 0]\ngoal: [1, 1]\nlimits:\n  - {v_max: 1, a_max: 2, j_max: 10}\n"
     "  - {v_max: fast, a_max: 2, j_max: 10}\n", ".yaml",
     r"job\.yaml: field limits\.1\.v_max: Input should be a valid number.*got 'fast'"),
    ("start: [0]\ngoal: [1]\nlimits: {v_max: 1, a_max: 2}\n", ".yaml",
     r"field limits\.0\.j_max: Field required"),
    ("start: [0]\ngoal: [1]\nlimits: {v_max: 1, a_max: 2, j_max: 3}\ncolour: red\n", ".yml",
     r"field colour: Extra inputs are not permitted \(got 'red'\)"),
    ("start: [0]\ngoal: [1]\nlimits: {v_max: 1, a_max: 2, j_max: 3}\nsync: fast\n", ".yaml",
     r"field sync: Input should be 'time', 'phase' or 'none' \(got 'fast'\)"),
    ("start: [0, 1]\ngoal: [1]\nlimits: {v_max: 1, a_max: 2, j_max: 3}\n", ".yaml",
     r"field goal has 1 values but start has 2"),
    ("start: [0, 1]\ngoal: [1, 2]\nlimits: {v_max: 1, a_max: 2, j_max: 3}\nnames: [A]\n",
     ".yaml", r"field names has 1 entries but start has 2 axes"),
    ("start: [0, 1]\ngoal: [1, 2]\nlimits: {v_max: 1, a_max: -2, j_max: 3}\nnames: [A, B]\n",
     ".yaml", r"maximum acceleration limit a_max of axis A should be larger than zero"),
    ("start: [0, .nan]\ngoal: [1, 1]\nlimits: {v_max: 1, a_max: 2, j_max: 3}\n", ".yaml",
     r"job\.yaml: field start of axis q1 must be finite, got nan$"),
    ("start: [0\n", ".yaml", r"job\.yaml:2: not valid YAML: "),
    ("{\"start\": [0],", ".json", r"not valid JSON: "),
    ("- 1\n- 2\n", ".yaml", r"expected a mapping of fields at the top level, got list"),
    ("start: [0]\n", ".txt", r"--file must end in \.yaml, \.yml or \.json"),
])
def test_ptp_bad_job_file(tmp_path, capsys, content, suffix, match):
    path = tmp_path / f"job{suffix}"
    path.write_text(content)
    rc, out, err = run(capsys, "ptp", "--file", str(path))
    assert rc == 2 and out == ""
    assert err.count("\n") == 1 and "Traceback" not in err
    assert re.search(match, err.strip()), err


def test_ptp_missing_file(capsys, tmp_path):
    rc, out, err = run(capsys, "ptp", "--file", str(tmp_path / "nope.yaml"))
    assert rc == 2 and "No such file or directory" in err and err.count("\n") == 1


# ------------------------------------------------------------ subprocess
def test_subprocess_console_entry(tmp_path):
    """The real command line: python -m trajkit.cli, one success and one error."""
    env = dict(os.environ, MPLBACKEND="Agg")
    ok = subprocess.run([sys.executable, "-m", "trajkit.cli", *MOVE, "--json"],
                        capture_output=True, text=True, timeout=120, env=env, cwd=tmp_path)
    assert ok.returncode == 0, ok.stderr
    assert json.loads(ok.stdout)["duration_s"] == pytest.approx(1.7, rel=1e-15)
    bad = subprocess.run([sys.executable, "-m", "trajkit.cli", "ptp", "--start", "0,0",
                          "--goal", "1", "--v-max", "1", "--a-max", "1", "--j-max", "1"],
                         capture_output=True, text=True, timeout=120, env=env, cwd=tmp_path)
    assert bad.returncode == 2
    assert bad.stdout == ""
    assert bad.stderr == "trajkit ptp: error: --goal has 1 values but --start has 2\n"
