"""Step pulses (patent CN105892402): no drift, no lost position, rate check, edge times."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import sweep_size

from trajkit import AxisLimits, InvalidInputError, plan_move, plan_ptp
from trajkit.runtime import (
    PulseAxis,
    PulseRateFault,
    Streamer,
    edge_times,
    pulse_count,
    pulse_counts,
)


def test_count_equals_position_rounded_over_many_moves():
    rng = np.random.default_rng(7)
    eq = 2.5e-6
    lim = AxisLimits(0.5, 3.0, 30.0, a_max_decel=2.0, j_max_decel=15.0)
    ax = PulseAxis(eq, position=0.0)
    emitted = 0
    x = 0.0
    n_moves = sweep_size(60)
    for _ in range(n_moves):
        goal = float(rng.uniform(-0.3, 0.3))
        prof = plan_move(x, goal, lim)
        t = np.arange(1, int(math.ceil(prof.duration / 0.001)) + 1) * 0.001
        for p in prof.sample(t).position:
            n = ax.update(p, 0.001)
            emitted += n
            assert ax.count == math.floor(p / eq + 0.5)  # rounded to one pulse, every period
        x = goal
    assert ax.count == emitted  # nothing lost: the emitted pulses sum to the count
    assert abs(ax.position - x) <= eq / 2
    # and back home: exactly zero pulses left
    emitted += ax.update(0.0, 0.001)
    assert ax.count == 0 and emitted == 0


def test_increment_accumulation_would_drift_but_absolute_count_does_not():
    """A naive generator rounding each period's increment loses position; ours cannot."""
    eq = 1e-3
    steps = np.full(10_000, 0.4e-3)  # 0.4 pulse per period
    naive = int(np.sum(np.floor(steps / eq + 0.5)))
    ax = PulseAxis(eq)
    pos = np.cumsum(steps)
    ours = sum(ax.update(p, 0.001) for p in pos)
    assert naive == 0  # the naive one never moves
    assert ours == pulse_count(pos[-1], eq) == 4000


def test_rate_check_edges_and_vectorised_counts():
    ax = PulseAxis(1e-6, max_rate=100_000.0, name="Z")
    assert ax.update(50e-6, 0.001) == 50 and ax.direction == 1
    with pytest.raises(PulseRateFault, match=r"pulse rate 200000\.0 pulses/s of axis Z exceeds "
                                             r"the maximum pulse rate 100000\.0"):
        ax.update(250e-6, 0.001)
    assert ax.count == 50  # not updated by a refused period
    assert ax.update(20e-6, 0.001) == -30 and ax.direction == -1
    e = edge_times(-4, 0.001, t0=2.0)
    assert np.allclose(e, 2.0 + np.array([0.125, 0.375, 0.625, 0.875]) * 1e-3)
    assert edge_times(0, 0.001).size == 0
    x = np.random.default_rng(1).uniform(-1, 1, 1000)
    assert np.array_equal(pulse_counts(x, 1e-4), [pulse_count(v, 1e-4) for v in x])
    with pytest.raises(InvalidInputError, match="pulse_equivalent of axis 0 should be larger than zero, got 0.0"):
        PulseAxis(0.0, name=0)


def test_streamed_pulses_sum_to_the_count_for_a_multi_axis_move():
    lims = [AxisLimits(1.0, 4.0, 40.0, name=n) for n in "AB"]
    tr = plan_ptp([0.1, -0.2], [-0.35, 0.77], lims)
    eqs = [1e-6, 3e-6]
    sps = list(Streamer(tr, 0.001, pulse_equivalents=eqs))
    total = np.sum([s.pulses for s in sps], axis=0)
    start = np.array([pulse_count(0.1, eqs[0]), pulse_count(-0.2, eqs[1])])
    assert np.array_equal(start + total, sps[-1].pulse_count)
    assert np.array_equal(sps[-1].pulse_count, [pulse_count(-0.35, 1e-6), pulse_count(0.77, 3e-6)])
    for s in sps:
        assert np.array_equal(s.pulse_count, [pulse_count(s.position[0], 1e-6),
                                              pulse_count(s.position[1], 3e-6)])
