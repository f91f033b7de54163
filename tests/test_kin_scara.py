"""SCARA: FK/IK round trips for both configurations, reach and tilt errors."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

from trajkit.errors import InvalidInputError, UnreachableError
from trajkit.kinematics.base import Pose, rot_x, wrap_angle
from trajkit.kinematics.scara import default_scara

N = 5000 if os.environ.get("TRAJKIT_SWEEP") else 500


@pytest.fixture(scope="module")
def scara():
    return default_scara()


def test_fk_known_values(scara):
    p = scara.fk(np.array([0.0, 0.0, 0.05, 0.0]))
    assert np.allclose(p.position, [0.6, 0.0, 0.15], atol=1e-15)
    p = scara.fk(np.array([math.pi / 2, -math.pi / 2, 0.0, 0.3]))
    assert np.allclose(p.position, [0.275, 0.325, 0.2], atol=1e-15)
    assert p.abc[0] == pytest.approx(0.3, abs=1e-15)


def test_round_trip_both_configurations(scara):
    rng = np.random.default_rng(11)
    seen = set()
    for _ in range(N):
        q = np.array([rng.uniform(l.position_min, l.position_max) for l in scara.limits])
        pose = scara.fk(q)
        sols = scara.ik_all(pose)
        assert [c for c, _ in sols] == ["lefty", "righty"]
        for cfg, qs in sols:
            dp, da = pose.distance(scara.fk(qs))
            assert dp < 1e-9 * scara.length_scale and da < 1e-9
            seen.add(cfg)
        own = scara.ik(pose, seed=q)
        d = own - q
        d[[0, 1, 3]] = wrap_angle(d[[0, 1, 3]])
        assert np.abs(d).max() < 1e-9
    assert seen == {"lefty", "righty"}


def test_out_of_reach_and_tilt(scara):
    with pytest.raises(UnreachableError, match="outside the workspace"):
        scara.ik(Pose.from_xyz_abc([0.7, 0.0, 0.1]))
    with pytest.raises(UnreachableError, match="outside the workspace"):
        scara.ik(Pose(np.array([0.4, 0.1, 0.1]), rot_x(0.2)))
    with pytest.raises(UnreachableError, match=r"joint J3 would be at -100\.000 mm"):
        scara.ik(Pose.from_xyz_abc([0.4, 0.1, 0.3]))


def test_bad_config_and_joints(scara):
    with pytest.raises(InvalidInputError, match="'elbowup' is not one of"):
        scara.ik(Pose.from_xyz_abc([0.4, 0.1, 0.1]), "elbowup")
    with pytest.raises(InvalidInputError, match=r"joints: joint J3 = 300 mm is outside its range \[0, 200\] mm"):
        scara.check_joints([0.0, 0.0, 0.3, 0.0])
