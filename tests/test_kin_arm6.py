"""6-axis arm: FK/IK round trips on every configuration, singularities, ranges, errors."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

from trajkit.errors import InvalidInputError, UnreachableError
from trajkit.kinematics.arm6 import ARM6_FLAGS, default_arm6
from trajkit.kinematics.base import (
    Pose,
    abc_from_rotation,
    rotation_from_abc,
    wrap_angle,
)

N = 3000 if os.environ.get("TRAJKIT_SWEEP") else 300
#: FK(IK(x)) must reproduce x to this fraction of the reach (and in rad).
POSE_TOL = 1e-9


@pytest.fixture(scope="module")
def arm():
    return default_arm6()


def _random_q(arm, rng):
    return np.array([rng.uniform(lim.position_min, lim.position_max) for lim in arm.limits])


def test_dimensions_documented_defaults(arm):
    # Stretched horizontally forward (q2 = 90 deg, forearm continuing): reach to the
    # flange = a1 + a2 + d4 + d6 with the a3 elbow offset as the only height.
    q = np.array([0.0, math.pi / 2, -math.pi / 2, 0.0, 0.0, 0.0])
    p = arm.fk(q).position
    assert p[0] == pytest.approx(0.025 + 0.455 + 0.420 + 0.080, abs=1e-12)
    assert p[1] == pytest.approx(0.0, abs=1e-12)
    assert p[2] == pytest.approx(0.400 + 0.035, abs=1e-12)
    assert len(arm.configs) == 8


def test_fk_ik_round_trip_every_configuration(arm):
    rng = np.random.default_rng(5)
    counts = {}
    for _ in range(N):
        q = _random_q(arm, rng)
        pose = arm.fk(q)
        sols = arm.ik_all(pose)
        assert len(sols) in (4, 8)
        assert len({c for c, _ in sols}) == len(sols)
        own = arm.config_of(q)
        hit = False
        for cfg, qs in sols:
            dp, da = pose.distance(arm.fk(qs))
            assert dp < POSE_TOL * arm.length_scale and da < POSE_TOL
            assert arm.config_of(qs) == cfg
            counts[cfg] = counts.get(cfg, 0) + 1
            if cfg == own:
                assert np.abs(wrap_angle(qs - q)).max() < 1e-9
                hit = True
        assert hit
    assert set(counts) == set(arm.configs)  # every branch exercised


def test_ik_pins_configuration_and_keeps_ranges(arm):
    rng = np.random.default_rng(6)
    for _ in range(100):
        q = _random_q(arm, rng)
        cfg = arm.config_of(q)
        qs = arm.ik(arm.fk(q), cfg)
        assert arm.config_of(qs) == cfg
        arm.check_joints(qs)
        # seeded: returns the same joints (A6 has a > 360 deg range: no 2 pi jump)
        assert np.allclose(arm.ik_near(arm.fk(q), q), q, atol=1e-9)


def test_config_flags_mapping_and_errors(arm):
    assert arm.parse_config({"shoulder": "back", "elbow": "down", "wrist": "flip"}) == "back-down-flip"
    assert arm.parse_config("FRONT/up/noflip") == "front-up-noflip"
    with pytest.raises(InvalidInputError, match="elbow.*'sideways'"):
        arm.parse_config({"shoulder": "front", "elbow": "sideways", "wrist": "flip"})
    with pytest.raises(InvalidInputError, match="must look like"):
        arm.parse_config("up-front")
    assert set(ARM6_FLAGS) == {"shoulder", "elbow", "wrist"}


def test_wrist_singularity_takes_q4_from_seed(arm):
    q = np.array([0.3, 0.2, 0.1, 0.7, 0.0, -0.4])
    pose = arm.fk(q)
    seed = np.array([0.3, 0.2, 0.1, 0.5, 0.01, 0.0])
    qs = arm.ik(pose, "front-up-noflip", seed=seed)
    assert qs[3] == pytest.approx(0.5, abs=1e-12)
    assert qs[3] + qs[5] == pytest.approx(0.7 - 0.4, abs=1e-9)
    dp, da = pose.distance(arm.fk(qs))
    assert dp < 1e-12 and da < 1e-9


def test_unreachable_pose_names_point(arm):
    pose = Pose.from_xyz_abc([2.0, 0.0, 0.4])
    with pytest.raises(UnreachableError, match=r"\(2000\.000, 0\.000, 400\.000\) mm.*outside the workspace"):
        arm.ik(pose)
    assert arm.ik_all(pose) == []


def test_joint_range_violation_is_unreachable(arm):
    # back shoulder needs A1 = 180 deg here: outside +-170 deg
    pose = arm.fk(np.array([0.0, 0.3, 0.2, 0.0, 0.5, 0.0]))
    with pytest.raises(UnreachableError, match="joint A1 .*outside its range"):
        arm.ik(pose, "back-up-noflip")


def test_abc_round_trip():
    rng = np.random.default_rng(7)
    for _ in range(200):
        abc = rng.uniform([-math.pi, -1.5, -math.pi], [math.pi, 1.5, math.pi])
        assert np.allclose(abc_from_rotation(rotation_from_abc(abc)), abc, atol=1e-12)


def test_pose_rejects_non_rotation():
    with pytest.raises(InvalidInputError, match="not a rotation matrix"):
        Pose(np.zeros(3), np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(InvalidInputError, match=r"pose position\[1\] must be finite"):
        Pose(np.array([0.0, np.nan, 0.0]), np.eye(3))
