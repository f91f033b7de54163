"""Tool speed of robot program samples."""

from __future__ import annotations

import pathlib

import numpy as np
import pytest

EXAMPLES_DATA = pathlib.Path(__file__).resolve().parents[1] / "examples" / "data"


def test_ptp_tool_speed_is_defined_for_repeated_and_single_times():
    """Tool speed of PTP samples comes from FK along qd, not from the sample spacing
    (repeated sample times: no NaN)."""
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
