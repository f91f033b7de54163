"""``trajkit saddle`` and ``trajkit path``: JSON, CSV (units at the boundary), plots, errors."""

from __future__ import annotations

import csv
import json
import math
import re

import numpy as np
import pytest

from trajkit.cli import main

SADDLE = ["saddle", "--main-radius", "110", "--branch-radius", "100", "--feed", "100",
          "--tolerance", "0.01", "--period", "0.005", "--z-vmax", "50"]


def _json(capsys, argv):
    assert main(argv + ["--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_saddle_json_csv_and_plot(tmp_path, capsys):
    csv_file = tmp_path / "seam.csv"
    png = tmp_path / "seam.png"
    out = _json(capsys, SADDLE + ["--csv", str(csv_file), "--plot", str(png)])
    for key in ("path_length_mm", "chords", "max_chord_error_mm", "duration_s", "max_axis_speed"):
        assert key in out
    assert out["max_chord_error_mm"] <= 0.01
    assert out["chords"] < out["chords_uniform_theta"]
    assert out["max_axis_speed"]["z_axis_mm_s"] <= 50.0 * (1 + 1e-9)
    assert out["max_axis_speed"]["z_axis_mm_s"] >= 50.0 * 0.99  # the limit is used
    assert {z["reason"] for z in out["slowdowns"]} == {"z_axis velocity"}
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"
    rows = list(csv.reader(csv_file.open()))
    assert rows[0] == ["t_s", "x_mm", "y_mm", "z_mm", "theta_deg", "z_axis_mm"]
    data = np.array(rows[1:], dtype=float)
    assert data.shape[0] == out["setpoints"]
    t, x, y, z, th, za = data.T
    assert np.allclose(np.diff(t), 0.005)
    # units: mm and deg; the seam equation holds on every row (Chen et al., 2013, eq. 3)
    assert np.allclose(np.hypot(x, y), 100.0, atol=1e-9)
    assert np.allclose(z, np.sqrt(110.0**2 - x**2), atol=1e-9)
    assert np.allclose(z, za, atol=0)
    assert np.allclose(x, 100 * np.sin(np.radians(th)), atol=1e-9)
    assert th[0] == 0.0 and th[-1] == pytest.approx(360.0, abs=1e-9)
    # Z speed from the CSV never exceeds the 50 mm/s limit (finite differences are means)
    assert np.max(np.abs(np.diff(za)) / 0.005) <= 50.0 * (1 + 1e-6)


def test_saddle_oblique_offset_table_output(capsys):
    argv = ["saddle", "--main-radius", "150", "--branch-radius", "60", "--angle", "60",
            "--offset", "40", "--feed", "30", "--tolerance", "0.02", "--period", "0.01"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "path_length_mm" in out and "chords" in out


@pytest.mark.parametrize(
    "extra,match",
    [
        (["--main-radius", "100", "--branch-radius", "100"],
         r"branch radius r=100.0 plus \|offset\|=0.0 must be below the main radius R=100.0"),
        (["--main-radius", "100", "--branch-radius", "50", "--offset", "60"], r"\|offset\|=60.0"),
        (["--main-radius", "100", "--branch-radius", "50", "--angle", "0"], r"branch angle"),
        (["--main-radius", "100", "--branch-radius", "50", "--feed", "-5"], r"--feed must be larger than zero, got -5.0"),
        (["--main-radius", "100", "--branch-radius", "50", "--tolerance", "nan"], r"--tolerance must be finite"),
        (["--main-radius", "100", "--branch-radius", "50", "--period", "0"], r"period should be larger than zero"),
        (["--main-radius", "100", "--branch-radius", "50", "--z-vmax", "0"], r"v_max of axis z_axis"),
    ],
)
def test_saddle_bad_input_one_line_exit_2(capsys, extra, match):
    base = {"--feed": "10", "--tolerance": "0.01", "--period": "0.01"}
    argv = ["saddle"]
    for k, v in base.items():
        if k not in extra:
            argv += [k, v]
    argv += extra
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("trajkit saddle: error: ")
    assert re.search(match, err), err


def test_path_from_options_in_order(tmp_path, capsys):
    csv_file = tmp_path / "p.csv"
    # line along x, then a tangent quarter arc (centre (100, 50, 0), radius 50), then a line along y
    s2 = math.sqrt(0.5)
    argv = ["path", "--start", "0,0,0", "--line", "100,0,0",
            "--arc", f"{100 + 50 * s2},{50 - 50 * s2},0:150,50,0", "--line", "150,150,0",
            "--feed", "40", "--tolerance", "0.005", "--period", "0.002", "--csv", str(csv_file),
            "--plot", str(tmp_path / "p.png")]
    out = _json(capsys, argv)
    assert (tmp_path / "p.png").read_bytes()[:4] == b"\x89PNG"
    assert out["path_length_mm"] == pytest.approx(100 + 25 * math.pi + 100, rel=1e-12)
    assert out["corners"] == 0 and out["segments"] == 3
    assert out["max_tool_speed_mm_s"] == pytest.approx(40.0, rel=1e-12)
    rows = list(csv.reader(csv_file.open()))
    assert rows[0] == ["t_s", "x_mm", "y_mm", "z_mm"]
    data = np.array(rows[1:], dtype=float)
    assert np.allclose(data[0, 1:], [0, 0, 0]) and np.allclose(data[-1, 1:], [150, 150, 0], atol=1e-9)
    sp = np.linalg.norm(np.diff(data[:, 1:], axis=0), axis=1) / 0.002
    assert np.max(sp) <= 40.0 * (1 + 1e-9)


def test_path_from_yaml_file_with_circle(tmp_path, capsys):
    job = tmp_path / "job.yaml"
    job.write_text(
        "start: [0, 0, 0]\n"
        "segments:\n"
        "  - line: [100, 0, 0]\n"
        "  - circle: {via: [120, 20, 0], via2: [100, 40, 0]}\n"
        "feed: 50\ntolerance: 0.01\nperiod: 0.001\n"
    )
    out = _json(capsys, ["path", "--file", str(job)])
    assert out["path_length_mm"] == pytest.approx(100 + 2 * math.pi * 20, rel=1e-12)
    assert out["corners"] == 0  # the circle (centre (100, 20)) leaves along +x, tangent to the line
    # the command line overrides the file
    out2 = _json(capsys, ["path", "--file", str(job), "--feed", "25"])
    assert out2["feed_mm_s"] == 25.0 and out2["duration_s"] > out["duration_s"]


@pytest.mark.parametrize(
    "argv,match",
    [
        (["--start", "0,0,0", "--line", "0,0,0"], r"segment 0 \(line\) has zero length"),
        (["--start", "0,0,0", "--arc", "1,1,1:2,2,2"], r"segment 0 \(arc\): arc points .* are collinear"),
        (["--start", "0,0,0", "--arc", "0,0,0:2,2,0"], r"arc points p1=\[0.0, 0.0, 0.0\] and p2=\[0.0, 0.0, 0.0\] coincide"),
        (["--start", "0,0", "--line", "1,0,0"], r"start must be three numbers"),
        (["--start", "0,0,0"], r"needs at least one --line"),
        (["--line", "1,0,0"], r"--start is required"),
        (["--start", "0,0,0", "--line", "1,0,0", "--period", "0.5"], r"period 0.5 s is outside"),
        (["--start", "0,0,0", "--line", "1,0,0", "--tolerance", "-1"], r"--tolerance must be larger than zero"),
    ],
)
def test_path_bad_input_one_line_exit_2(capsys, argv, match):
    base = ["--feed", "10", "--tolerance", "0.01", "--period", "0.01"]
    full = ["path"] + argv
    for k, v in zip(base[::2], base[1::2]):
        if k not in argv:
            full += [k, v]
    assert main(full) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("trajkit path: error: ")
    assert re.search(match, err), err


def test_path_bad_yaml_files(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text("start: [0, 0, 0]\nsegments:\n  - spline: [1, 2, 3]\nfeed: 1\ntolerance: 0.1\nperiod: 0.01\n")
    assert main(["path", "--file", str(bad)]) == 2
    assert "segment 0 must be" in capsys.readouterr().err
    bad.write_text("start: [0, 0, 0\n")
    assert main(["path", "--file", str(bad)]) == 2
    assert "not valid YAML" in capsys.readouterr().err
    assert main(["path", "--file", str(tmp_path / "missing.yaml")]) == 2
    assert "No such file" in capsys.readouterr().err


def test_csv_is_not_half_written_on_error(tmp_path, capsys):
    target = tmp_path / "nodir" / "x.csv"
    assert main(SADDLE[:1] + ["--main-radius", "200", "--branch-radius", "100", "--feed", "20",
                              "--tolerance", "0.05", "--period", "0.05", "--csv", str(target)]) == 2
    assert not target.exists() and not list(tmp_path.iterdir())
    capsys.readouterr()


def test_path_rounded_tangent_points_are_not_corners(tmp_path, capsys):
    """Taught points rounded to 1 um make the line/arc junction turn by about
    1e-5 rad: below the default 0.01 deg it is passed through, with
    --corner-angle 0 the feed stops there."""
    job = tmp_path / "job.yaml"
    job.write_text(
        "start: [0, 0, 0]\n"
        "segments:\n"
        "  - line: [100, 0, 0]\n"
        "  - arc: {via: [135.355, 14.645, 0], end: [150, 50, 0]}\n"
        "feed: 50\ntolerance: 0.01\nperiod: 0.002\n"
    )
    smooth = _json(capsys, ["path", "--file", str(job)])
    strict = _json(capsys, ["path", "--file", str(job), "--corner-angle", "0"])
    assert smooth["corners"] == 0 and strict["corners"] == 1
    assert strict["duration_s"] > smooth["duration_s"]
