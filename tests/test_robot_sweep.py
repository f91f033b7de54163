"""Seeded random LIN/CIRC motions of the 6-axis arm: on the path, limits kept, or a clear error.

CI-sized by default; ``TRAJKIT_SWEEP=1`` runs many more.
"""

from __future__ import annotations

import os

import numpy as np

from trajkit.errors import UnreachableError
from trajkit.kinematics.arm6 import default_arm6
from trajkit.kinematics.base import Pose, rot_x, rot_z
from trajkit.paths.arc import circle_through
from trajkit.robot import CartesianTarget, Circ, Lin, run_motions

N = 60 if os.environ.get("TRAJKIT_SWEEP") else 6
#: FK of every sample lies on the programmed path to this fraction of the reach.
PATH_TOL = 1e-6


def test_random_lin_circ_sweep():
    arm = default_arm6()
    rng = np.random.default_rng(2024)
    vmax = np.array([lim.v_max for lim in arm.limits])
    amax = np.array([lim.a_max for lim in arm.limits])
    ok = refused = 0
    for case in range(N):
        q0 = np.array([lo + (hi - lo) * rng.uniform(0.3, 0.7)
                       for lo, hi in arm.joint_ranges])
        p0 = arm.fk(q0)
        d = rng.normal(size=3)
        d *= rng.uniform(0.05, 0.25) / np.linalg.norm(d)
        rot = rot_z(rng.uniform(-0.4, 0.4)) @ rot_x(rng.uniform(-0.3, 0.3))
        goal = Pose(p0.position + d, rot @ p0.rotation)
        v = rng.uniform(0.05, 0.5)
        label = f"case {case}"
        circ = case % 2 == 1
        if circ:
            n = np.cross(d, rng.normal(size=3))
            via = p0.position + 0.5 * d + 0.3 * np.linalg.norm(d) * n / np.linalg.norm(n)
            mot = Circ(CartesianTarget(Pose(via, p0.rotation)), CartesianTarget(goal), v, label=label)
        else:
            mot = Lin(CartesianTarget(goal), v, label=label)
        try:
            run = run_motions(arm, [mot], q0)
        except UnreachableError as exc:
            assert str(exc).startswith(label + ":")
            refused += 1
            continue
        ok += 1
        smp = run.sample(run.times(0.004))
        assert np.all(np.abs(smp.qd) <= vmax * (1 + 1e-9))
        assert np.all(np.abs(smp.qdd) <= amax * (1 + 1e-9))
        fd = np.abs(np.diff(smp.q, axis=0) / np.diff(smp.t)[:, None])
        assert np.all(fd <= vmax * 1.01)
        fk = np.array([arm.fk(q).position for q in smp.q])
        if circ:
            centre, radius, normal = circle_through(p0.position, via, goal.position)
            assert np.abs(np.linalg.norm(fk - centre, axis=1) - radius).max() < PATH_TOL * arm.length_scale
            assert np.abs((fk - centre) @ normal).max() < PATH_TOL * arm.length_scale
        else:
            u = np.clip((fk - p0.position) @ d / (d @ d), 0, 1)
            err = np.linalg.norm(fk - (p0.position + u[:, None] * d), axis=1)
            assert err.max() < PATH_TOL * arm.length_scale
        dp, da = arm.fk(smp.q[-1]).distance(goal)
        assert dp < 1e-9 and da < 1e-9
    assert ok >= N // 2, (ok, refused)
