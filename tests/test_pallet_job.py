"""Job files: the shipped seed job, validation errors that name the field."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml

from trajkit.errors import InvalidInputError, UnreachableError
from trajkit.io import load_job, parse_job, scenario_from_job, seed_job_path
from trajkit.palletizing import plan_cycle, seed_scenario


def _seed_dict():
    return yaml.safe_load(seed_job_path().read_text())


def _write(tmp_path, data, name="job.yaml"):
    p = tmp_path / name
    p.write_text(yaml.safe_dump(data) if not isinstance(data, str) else data)
    return p


def test_seed_job_file_equals_seed_scenario():
    a, b = load_job(seed_job_path()), seed_scenario()
    assert a.place_poses() == pytest.approx(b.place_poses(), abs=1e-15)
    assert a.pick == pytest.approx(b.pick, abs=1e-15)
    for la, lb in zip(a.robot.limits, b.robot.limits):
        assert la == lb
    assert (a.lift, a.approach, a.layers, a.n_boxes) == (b.lift, b.approach, b.layers, 25)
    assert plan_cycle(a, "ptp").total_s == pytest.approx(plan_cycle(b, "ptp").total_s, rel=1e-15)


def test_defaults_and_custom_pattern(tmp_path):
    d = _seed_dict()
    del d["robot"], d["lift_mm"], d["gripper"]
    d["pattern"] = {"name": "custom", "alternate": "mirror",
                    "boxes": [{"x_mm": -300, "y_mm": 0}, {"x_mm": 300, "y_mm": 0, "yaw_deg": 180}]}
    d["layers"] = 2
    sc = load_job(_write(tmp_path, d))
    assert sc.n_boxes == 4 and sc.lift == pytest.approx(0.4)
    assert sc.robot.limits[0].v_max == pytest.approx(math.radians(160))
    assert sc.place_poses()[:, 2] == pytest.approx([0.6, 0.6, 0.8, 0.8])
    # mirrored 2nd layer: y -> -y of the pallet frame
    assert sc.place_poses()[2, 1] == pytest.approx(1.4)


@pytest.mark.parametrize("patch,match", [
    ({"pallet": {"centre_mm": [0, 1400, 400], "length_mm": -5, "width_mm": 1000}},
     r"field pallet.length_mm: Input should be greater than 0 \(got -5\)"),
    ({"layers": 0}, r"field layers: Input should be greater than or equal to 1 \(got 0\)"),
    ({"colour": "red"}, r"field colour: Extra inputs are not permitted"),
    ({"pattern": {"name": "spiral"}}, r"field pattern.name: Input should be"),
    ({"box": {"length_mm": 600, "width_mm": 400, "height_mm": "tall"}}, r"field box.height_mm"),
    ({"gripper": {"grip_s": -1}}, r"field gripper.grip_s: .*greater than or equal to 0"),
    ({"robot": {"joints": {"B": {"v_max": 0, "a_max": 1, "j_max": 1, "min": 0, "max": 1}}}},
     r"field robot.joints.B.v_max"),
    ({"pallet": {"centre_mm": [0, 1400, "nan"], "length_mm": 1200, "width_mm": 1000}},
     r"field pallet.centre_mm"),
])
def test_validation_errors_name_the_field(tmp_path, patch, match):
    d = _seed_dict()
    d.update(patch)
    with pytest.raises(InvalidInputError, match=match):
        load_job(_write(tmp_path, d))


def test_domain_errors(tmp_path):
    d = _seed_dict()
    d["layers"] = 8
    with pytest.raises(UnreachableError, match=r"stack top 2000.0 mm \+ approach 200 mm = 2200.0 mm "
                                               r"is above the robot's reach: joint B range ends at 2000 mm"):
        load_job(_write(tmp_path, d))
    d = _seed_dict()
    d["pallet"]["length_mm"] = 1100
    with pytest.raises(InvalidInputError, match=r"job.yaml: box 0 of layer pattern 'seed' is over the pallet edge"):
        load_job(_write(tmp_path, d))
    d = _seed_dict()
    d["pallet"]["centre_mm"] = [0, 2000, 400]
    with pytest.raises(UnreachableError, match=r"place\[\d+\]: joint C = \d+.* mm is outside its range "
                                               r"\[300, 2200\] mm"):
        load_job(_write(tmp_path, d))
    d = _seed_dict()
    d["pattern"] = {"name": "custom"}
    with pytest.raises(InvalidInputError, match="field pattern.boxes: a custom pattern needs boxes"):
        load_job(_write(tmp_path, d))
    d = _seed_dict()
    d["pattern"]["boxes"] = [{"x_mm": 0, "y_mm": 0}]
    with pytest.raises(InvalidInputError, match="only a custom pattern takes boxes"):
        load_job(_write(tmp_path, d))
    d = _seed_dict()
    d["pattern"] = {"name": "custom", "boxes": [{"x_mm": 0, "y_mm": 0}, {"x_mm": 100, "y_mm": 0}]}
    with pytest.raises(InvalidInputError, match="boxes 0 and 1 of layer pattern 'custom' overlap"):
        load_job(_write(tmp_path, d))


def test_bad_files(tmp_path):
    with pytest.raises(InvalidInputError, match=r"job\.yaml:2: not valid YAML"):
        load_job(_write(tmp_path, "name: x\n  bad: [1,\n"))
    with pytest.raises(InvalidInputError, match=r"expected a mapping of fields, got list"):
        load_job(_write(tmp_path, "- 1\n- 2\n"))
    with pytest.raises(OSError):
        load_job(tmp_path / "missing.yaml")
    with pytest.raises(InvalidInputError, match="field pick: Field required"):
        parse_job({k: v for k, v in _seed_dict().items() if k != "pick"})
    sc = scenario_from_job(_seed_dict())
    assert sc.n_boxes == 25 and np.isfinite(sc.place_joints()).all()
