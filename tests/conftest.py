"""Shared fixtures of the core tests: seeded random move generators, sweep sizes.

Sweeps run a CI-sized number of cases by default; ``TRAJKIT_SWEEP=1`` in the
environment multiplies them (see :func:`sweep_size`).
"""

from __future__ import annotations

import math
import os
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

# make ``import reference`` work from every test module
sys.path.insert(0, str(Path(__file__).parent))

#: ``TRAJKIT_SWEEP=1`` runs the long sweeps.
LONG_SWEEP = os.environ.get("TRAJKIT_SWEEP", "") not in ("", "0")

#: Factor applied to the sweep sizes when ``TRAJKIT_SWEEP=1``.
LONG_SWEEP_FACTOR = 20


def sweep_size(ci: int) -> int:
    """Number of random cases: ``ci`` in CI, ``ci * LONG_SWEEP_FACTOR`` with ``TRAJKIT_SWEEP=1``."""
    return ci * LONG_SWEEP_FACTOR if LONG_SWEEP else ci


@dataclass(frozen=True)
class Case:
    """One random rest-to-rest move with its limits (as plain floats)."""

    start: float
    goal: float
    v_max: float
    a_max: float
    j_max: float
    a_max_decel: float
    j_max_decel: float
    kind: str

    @property
    def distance(self) -> float:
        return abs(self.goal - self.start)

    def limits(self):
        from trajkit import AxisLimits

        return AxisLimits(self.v_max, self.a_max, self.j_max, self.a_max_decel, self.j_max_decel)

    def as_tuple(self):
        return (self.start, self.goal, self.v_max, self.a_max, self.j_max,
                self.a_max_decel, self.j_max_decel)


#: Kinds of generated cases and their shares (the rest are "general").
KINDS = (
    ("symmetric", 0.15),
    ("trapezoid", 0.08),        # j_max = j_max_decel = inf
    ("trapezoid_accel", 0.04),  # only the accel leg jerk-free
    ("no_a_limit", 0.08),       # a_max = a_max_decel = inf
    ("no_a_limit_decel", 0.04), # only the decel leg without acceleration limit
    ("no_v_limit", 0.08),       # v_max = inf
    ("zero", 0.02),             # zero distance
)


def _log_uniform(rng, lo, hi, size=None):
    return np.exp(rng.uniform(math.log(lo), math.log(hi), size))


def random_case(rng: np.random.Generator) -> Case:
    """Draw one case covering the region boundaries of the profile.

    Limits are log-uniform over 1e-3..1e3 (so their ratios span 1e-6..1e6,
    covering 1e-3..1e3), decel/accel ratios J2/J1 and A2/A1 log-uniform over
    0.05..20, distances log-uniform over 1e-6..1e6 in either direction
    (tiny moves that never build up acceleration to huge ones that cruise
    for hours), starts anywhere in [-10, 10].
    """
    v = float(_log_uniform(rng, 1e-3, 1e3))
    a = float(_log_uniform(rng, 1e-3, 1e3))
    j = float(_log_uniform(rng, 1e-3, 1e3))
    a2 = a * float(_log_uniform(rng, 0.05, 20.0))
    j2 = j * float(_log_uniform(rng, 0.05, 20.0))
    r = rng.random()
    kind = "general"
    acc = 0.0
    for name, share in KINDS:
        acc += share
        if r < acc:
            kind = name
            break
    if kind == "symmetric":
        a2, j2 = a, j
    elif kind == "trapezoid":
        j = j2 = math.inf
    elif kind == "trapezoid_accel":
        j = math.inf
    elif kind == "no_a_limit":
        a = a2 = math.inf
    elif kind == "no_a_limit_decel":
        a2 = math.inf
    elif kind == "no_v_limit":
        v = math.inf
    start = float(rng.uniform(-10.0, 10.0))
    if kind == "zero":
        d = 0.0
    else:
        d = float(_log_uniform(rng, 1e-6, 1e6)) * (1.0 if rng.random() < 0.5 else -1.0)
    return Case(start, start + d, v, a, j, a2, j2, kind)


def random_cases(seed: int, n: int) -> list[Case]:
    """``n`` cases from ``numpy.random.default_rng(seed)``."""
    rng = np.random.default_rng(seed)
    return [random_case(rng) for _ in range(n)]


@pytest.fixture
def rng() -> np.random.Generator:
    """A seeded generator (each test gets the same stream)."""
    return np.random.default_rng(20261122)
