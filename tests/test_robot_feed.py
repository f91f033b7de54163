"""The feed with varying speed caps: never above a cap, exact length, jerk-limited, from rest to rest."""

from __future__ import annotations

import os
import pathlib

import numpy as np
import pytest

from trajkit.robot._feed import Run, plan_feed, speed_change

EXAMPLES_DATA = pathlib.Path(__file__).resolve().parents[1] / "examples" / "data"

N = 2000 if os.environ.get("TRAJKIT_SWEEP") else 150


def test_speed_change_closed_form():
    tj, ta = speed_change(0.2, 5.0, 50.0)  # dv = 0.2 < a^2/j = 0.5: no constant-accel phase
    assert ta == 0.0 and tj == pytest.approx((0.2 / 50.0) ** 0.5, rel=1e-15)
    tj, ta = speed_change(2.0, 5.0, 50.0)
    assert tj == pytest.approx(0.1) and ta == pytest.approx(2.0 / 5.0 - 0.1)
    assert speed_change(0.0, 1.0, 1.0) == (0.0, 0.0)


def _random_runs(rng):
    n = int(rng.integers(1, 7))
    edges = np.concatenate([[0.0], np.cumsum(rng.uniform(0.005, 0.4, n))])
    return [Run(float(edges[i]), float(edges[i + 1]), float(rng.uniform(0.01, 1.0)),
                float(rng.uniform(0.5, 10.0)), float(rng.uniform(5.0, 200.0))) for i in range(n)]


def test_feed_random_sweep():
    rng = np.random.default_rng(21)
    for _ in range(N):
        runs = _random_runs(rng)
        feed = plan_feed(runs)
        L = runs[-1].s1
        assert abs(feed.end_error) < 1e-12 * max(L, 1.0)
        # exact states at the piece boundaries and dense samples in between
        t = np.union1d(np.linspace(0.0, feed.duration, 3001), feed._t0)
        s, v, a = feed.sample(t)
        assert s[0] == 0.0 and s[-1] == L and v[0] == 0.0 and v[-1] == 0.0
        assert (np.diff(s) >= -1e-15).all()
        assert (v >= 0).all()
        for r in runs:
            assert r.speed <= r.cap * (1 + 1e-12)
            inside = (s >= r.s0) & (s <= r.s1)
            assert (v[inside] <= r.cap * (1 + 1e-9)).all()
        # path acceleration and jerk within the largest run limits
        assert np.abs(a).max() <= max(r.accel for r in runs) * (1 + 1e-9)
        jerks = np.abs(feed._st[:, 4])
        assert jerks.max() <= max(r.jerk for r in runs) * (1 + 1e-12)
        # acceleration is continuous (jerk-limited): states agree across boundaries
        for k in range(1, feed._st.shape[0]):
            t0, s0, v0, a0, _ = feed._st[k - 1]
            d = feed._st[k, 0] - t0
            jk = feed._st[k - 1, 4]
            assert a0 + d * jk == pytest.approx(feed._st[k, 3], abs=1e-9)
            assert v0 + d * (a0 + d * jk / 2) == pytest.approx(feed._st[k, 2], abs=1e-9)


def test_long_run_reaches_its_cap_and_short_run_is_lowered():
    runs = [Run(0.0, 1.0, 0.5, 5.0, 50.0)]
    plan_feed(runs)
    assert runs[0].speed == 0.5
    runs = [Run(0.0, 0.001, 0.5, 5.0, 50.0)]
    feed = plan_feed(runs)
    assert runs[0].speed < 0.5
    assert feed.end_error == pytest.approx(0.0, abs=1e-15)


def test_ptp_tool_speed_is_defined_for_repeated_and_single_times():
    """Tool speed of PTP samples comes from FK along qd, not from the sample spacing
    (repeated times used to give NaN through np.gradient)."""
    import warnings

    from trajkit.io.program import load_program

    run = load_program(EXAMPLES_DATA / "arm6_weld.yaml").run()
    ptp = next(sg for sg in run.segments if sg.kind == "PTP" and sg.duration > 0)
    t_mid = ptp.t0 + 0.5 * ptp.duration
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rep = run.sample([t_mid, t_mid, t_mid])
        one = run.sample(t_mid)
        dense = run.sample(np.linspace(t_mid - 1e-4, t_mid + 1e-4, 3))
    assert np.all(np.isfinite(rep.tool_speed)) and rep.tool_speed[0] > 0
    assert rep.tool_speed[0] == one.tool_speed[0]
    # the central difference of the FK positions over +-0.1 ms agrees
    fd = np.linalg.norm(dense.xyz[2] - dense.xyz[0]) / 2e-4
    assert rep.tool_speed[0] == pytest.approx(fd, rel=1e-5)
