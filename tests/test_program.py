"""YAML robot programs: parsing to SI, and errors that name the line and the field."""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import numpy as np
import pytest

from trajkit.errors import InvalidInputError, UnreachableError
from trajkit.io.program import load_program, parse_program
from trajkit.robot import Circ, JointTarget, Lin, Ptp, Wait

EXAMPLES = Path(__file__).resolve().parent.parent / "examples" / "data"

BASE = """\
robot: arm6
defaults: {speed_mm_s: 150, zone_mm: 5}
points:
  home: {joints_deg: [0, 20, 10, 0, 60, 0]}
  p1: {xyz_mm: [560, 100, 500], abc_deg: [0, 0, 180], config: front-up-noflip}
  p2: {xyz_mm: [600, 150, 500], abc_deg: [0, 0, 180]}
  p3: {xyz_mm: [560, 200, 500], abc_deg: [0, 0, 180]}
program:
  - PTP: home
    speed_pct: 40
  - LIN: p1
    speed_mm_s: 100
    zone_mm: 0
  - CIRC: p3
    via: p2
  - WAIT: {time_s: 0.25}
"""


def _parse(text: str):
    return parse_program(textwrap.dedent(text), source="prog.yaml")


def test_parse_to_si():
    prog = _parse(BASE)
    m = prog.motions
    assert [type(x) for x in m] == [Ptp, Lin, Circ, Wait]
    assert m[0].speed_pct == 40 and m[0].zone == pytest.approx(0.005)  # default zone
    assert m[1].speed == pytest.approx(0.1) and m[1].zone == 0.0
    assert m[2].speed == pytest.approx(0.15) and m[2].zone == pytest.approx(0.005)  # defaults
    assert m[3].time == 0.25
    assert isinstance(prog.points["home"], JointTarget)
    assert np.allclose(prog.points["home"].q, np.radians([0, 20, 10, 0, 60, 0]))
    assert np.allclose(prog.points["p1"].pose.position, [0.56, 0.1, 0.5])
    assert prog.points["p1"].config == "front-up-noflip"
    assert np.allclose(prog.start, prog.points["home"].q)  # start = first PTP target
    assert prog.lines == [9, 11, 14, 16]
    assert "line 14" in m[2].label and "CIRC p3" in m[2].label


def test_program_runs_and_reaches_points():
    prog = _parse(BASE)
    run = prog.run()
    smp = run.sample(run.times(0.004))
    p3 = prog.points["p3"].pose
    dp, da = prog.robot.fk(smp.q[-1]).distance(p3)
    assert dp < 1e-9 and da < 1e-9
    assert [sg.kind for sg in run.segments] == ["PTP", "CP", "CP", "WAIT"]
    assert run.segments[0].duration == 0.0  # already at home
    assert run.segments[-1].duration == 0.25


@pytest.mark.parametrize("old,new,pattern", [
    ("    speed_mm_s: 100\n", "    speed_mm_s: -5\n",
     r"prog\.yaml:12: program\[1\]\.speed_mm_s: Input should be greater than 0 \(got -5\)"),
    ("  - CIRC: p3\n    via: p2\n", "  - CIRC: p3\n    via: p9\n",
     r"prog\.yaml:15: program\[2\]\.via: unknown point 'p9' \(known: home, p1, p2, p3\)"),
    ("[0, 20, 10, 0, 60, 0]", "[0, 20, 10, 0, 60]",
     r"prog\.yaml:4: points\.home\.joints_deg: needs 6 values \(A1, A2, A3, A4, A5, A6\), got 5"),
    ("[0, 20, 10, 0, 60, 0]", "[0, 200, 10, 0, 60, 0]",
     r"prog\.yaml:4: points\.home: joints of point home: joint A2 = 200 deg is outside its range "
     r"\[-?[0-9.]+, [0-9.]+\] deg$"),
    ("config: front-up-noflip", "config: front-sideways-noflip",
     r"prog\.yaml:5: points\.p1: configuration 'front-sideways-noflip' of arm6 must look like"),
    ("  - WAIT: {time_s: 0.25}\n", "  - WAIT: {time_s: -1}\n",
     r"prog\.yaml:16: program\[3\]\.WAIT\.time_s: Input should be greater than or equal to 0 \(got -1\)"),
    ("  - WAIT: {time_s: 0.25}\n", "  - JUMP: p1\n",
     r"prog\.yaml:16: program\[3\]: an instruction needs exactly one of PTP, LIN, CIRC, WAIT"),
    ("    speed_pct: 40\n", "    speed_pct: 40\n    speed_mm_s: 3\n",
     r"prog\.yaml:11: program\[0\]\.speed_mm_s: Extra inputs are not permitted"),
    ("robot: arm6", "robot: puma",
     r"robot must be one of \['arm6', 'scara', 'palletizer'\] or a URDF spec, got 'puma'"),
    ("  p2: {xyz_mm: [600, 150, 500], abc_deg: [0, 0, 180]}",
     "  p2: {xyz_mm: [600, 150], abc_deg: [0, 0, 180]}",
     r"prog\.yaml:6: points\.p2\.xyz_mm: List should have at least 3 items"),
    ("  p2: {xyz_mm: [600, 150, 500], abc_deg: [0, 0, 180]}",
     "  p2: {joints_deg: [0, 0, 0, 0, 0, 0], xyz_mm: [600, 150, 500]}",
     r"prog\.yaml:6: points\.p2: .*exactly one of joints_deg, joints, xyz_mm"),
    ("defaults: {speed_mm_s: 150, zone_mm: 5}", "defaults: {speed_mm_s: .nan, zone_mm: 5}",
     r"prog\.yaml:2: defaults\.speed_mm_s: Input should be a finite number"),
])
def test_errors_name_line_and_field(old, new, pattern):
    assert old in BASE
    with pytest.raises(InvalidInputError, match=pattern):
        _parse(BASE.replace(old, new))


def test_yaml_syntax_and_duplicate_keys():
    with pytest.raises(InvalidInputError, match=r"prog\.yaml:4: not valid YAML: (did not find )?expected .,. or .\]."):
        _parse("robot: arm6\npoints:\n  home: [1, 2\nprogram: []\n")
    with pytest.raises(InvalidInputError, match=r"prog\.yaml:3: duplicate key 'robot'"):
        _parse("robot: arm6\npoints: {}\nrobot: scara\n")


def test_start_point_and_first_instruction():
    text = BASE.replace("robot: arm6\n", "robot: arm6\nstart: p1\n")
    prog = _parse(text)
    assert np.allclose(prog.robot.fk(prog.start).position, [0.56, 0.1, 0.5])
    text = BASE.replace("  - PTP: home\n    speed_pct: 40\n", "")
    with pytest.raises(InvalidInputError, match=r"program\[0\]: without a start point the first "
                                                 r"instruction must be a PTP"):
        _parse(text)
    far = BASE.replace("[560, 100, 500]", "[1560, 100, 500]").replace("robot: arm6\n", "robot: arm6\nstart: p1\n")
    with pytest.raises(UnreachableError, match=r"prog\.yaml:2: start: start point p1: pose at \(1560"):
        _parse(far)


def test_scara_joint_mapping_units():
    text = """\
    robot: scara
    points:
      home: {joints: {J1_deg: 10, J2_deg: 90, J3_mm: 50, J4_deg: 0}}
      bad: {joints_deg: [0, 0, 0, 0]}
    program:
      - PTP: home
    """
    with pytest.raises(InvalidInputError, match=r"prog\.yaml:4: points\.bad\.joints_deg: robot scara has "
                                                 r"prismatic joints"):
        _parse(text)
    prog = _parse(text.replace("      bad: {joints_deg: [0, 0, 0, 0]}\n", ""))
    assert np.allclose(prog.start, [math.radians(10), math.radians(90), 0.05, 0.0])
    with pytest.raises(InvalidInputError, match=r"points\.home\.joints: must name every joint with its "
                                                 r"unit: \['J1_deg', 'J2_deg', 'J3_mm', 'J4_deg'\]"):
        _parse(text.replace("J3_mm", "J3_deg").replace("      bad: {joints_deg: [0, 0, 0, 0]}\n", ""))


def test_runtime_error_names_instruction_line():
    text = BASE.replace("  p2: {xyz_mm: [600, 150, 500]", "  p2: {xyz_mm: [600, 150, 500]").replace(
        "  - WAIT: {time_s: 0.25}\n", "  - LIN: far\n").replace(
        "points:\n", "points:\n  far: {xyz_mm: [1500, 0, 500], abc_deg: [0, 0, 180]}\n")
    prog = _parse(text)
    with pytest.raises(UnreachableError, match=r"instruction 3 \(LIN far, line 17\): point .* unreachable"):
        prog.run()


@pytest.mark.parametrize("name", ["arm6_weld.yaml", "scara_pick.yaml"])
def test_shipped_examples_load(name):
    prog = load_program(EXAMPLES / name)
    assert prog.motions
