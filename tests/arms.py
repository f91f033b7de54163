"""Real arms for the tests: UR5 and Panda from PyPI ``example-robot-data``, through the URDF support."""

from __future__ import annotations

import importlib.metadata as md
import os

import pytest

from trajkit import AxisLimits

URDFS = {"ur5": ("ur_description/urdf/ur5_robot.urdf", "tool0"),
         "panda": ("panda_description/urdf/panda.urdf", "panda_hand")}


def robots_dir() -> str:
    try:
        dist = md.distribution("example-robot-data")
    except md.PackageNotFoundError:  # pragma: no cover - a test dependency
        pytest.skip("example-robot-data is not installed")
    return str(dist.locate_file("cmeel.prefix/share/example-robot-data/robots"))


def load_arm(name: str):
    """The arm with v from its URDF, a = 5 v, j = 50 v (the benchmark's limits)."""
    pytest.importorskip("pinocchio")
    from trajkit.kinematics.urdf import UrdfRobot

    rel, tip = URDFS[name]
    path = os.path.join(robots_dir(), rel)
    raw = UrdfRobot(path, tip)
    lims = [AxisLimits(lm.v_max, 5 * lm.v_max, 50 * lm.v_max, position_min=lm.position_min,
                       position_max=lm.position_max, name=lm.name) for lm in raw.limits]
    return UrdfRobot(path, tip, limits=lims, name=name)
