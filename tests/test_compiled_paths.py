"""One source, two paths: the compiled kernels (numba) and the pure-Python
fallback (``TRAJKIT_NO_JIT=1``) give the same results to a few ulps.

The Python path runs in a subprocess (the switch is read at import). Floats
from the two paths are compared in ulps, never bit for bit: libm and numpy's
SIMD ``pow``/``cbrt`` differ by an ulp on some machines, and a root polished
from a slightly different start may land an ulp away.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from floatcmp import assert_ulp_close

from trajkit.profiles import _compile

ROOT = Path(__file__).resolve().parents[1]

pytestmark = [pytest.mark.skipif(not _compile.ENABLED, reason="numba is not installed (one path only)"),
              pytest.mark.codepaths]

#: Durations of the two paths agree to this many ulps.
DURATION_ULPS = 64

_SCRIPT = textwrap.dedent("""
    import json, sys
    import numpy as np
    sys.path.insert(0, {tests!r})
    from state_reference import random_brake_case, random_case
    from trajkit import AxisLimits
    from trajkit.profiles.state import feasible_durations, plan_state_to_state, plan_velocity
    from trajkit.runtime._brake import brake_profile
    rng = np.random.default_rng(4242)
    out = []
    for i in range({n}):
        kind = i % 4
        if kind == 3:
            s, g, L = random_brake_case(rng, symmetric=bool(i % 8 == 3))
        else:
            s, g, L = random_case(rng, symmetric=bool(kind == 0))
        lim = AxisLimits(*L)
        p = plan_state_to_state(s, g, lim)
        fd = feasible_durations(s, g, lim)
        T = p.duration * 1.3 + 1e-3
        try:
            q = plan_state_to_state(s, g, lim, duration=T).duration
        except Exception as e:
            q = type(e).__name__
        vel = plan_velocity(s, g[1], g[2], limits=lim).duration
        b = brake_profile(s[0], s[1], s[2], lim).duration
        out.append(dict(d=p.duration, fam=p.family, ph=list(p.phase_durations),
                        jk=list(p.jerks), tmin=fd.minimum, blk=[list(x) for x in fd.blocked],
                        fixed=q, vel=vel, brake=b))
    print(json.dumps(out))
""")


#: Fixed durations of given moves (the families of step 2's last stage, forwards
#: and on the time-reversed move): family, phase durations and jerks.
_SCRIPT_FIXED = textwrap.dedent("""
    import json
    from trajkit import AxisLimits
    from trajkit.profiles.state import plan_state_to_state
    out = []
    for s, g, L, T in json.loads({cases!r}):
        q = plan_state_to_state(s, g, AxisLimits(*L), duration=T)
        out.append(dict(d=q.duration, fam=q.family, ph=list(q.phase_durations), jk=list(q.jerks)))
    print(json.dumps(out))
""")


def _run(n, no_jit, script=_SCRIPT, **fields):
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    if no_jit:
        env["TRAJKIT_NO_JIT"] = "1"
    else:
        env.pop("TRAJKIT_NO_JIT", None)
    code = script.format(tests=str(ROOT / "tests"), n=n, **fields)
    r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                       timeout=1800)
    assert r.returncode == 0, r.stderr[-3000:]
    return json.loads(r.stdout)


def test_state_planner_numba_equals_python():
    n = 160
    fast = _run(n, no_jit=False)
    slow = _run(n, no_jit=True)
    same_family = 0
    for i, (a, b) in enumerate(zip(fast, slow)):
        for key in ("d", "tmin", "vel", "brake"):
            assert_ulp_close(a[key], b[key], DURATION_ULPS, err_msg=f"case {i} {key}")
        if isinstance(a["fixed"], str) or isinstance(b["fixed"], str):
            assert a["fixed"] == b["fixed"], (i, a["fixed"], b["fixed"])
        else:
            assert_ulp_close(a["fixed"], b["fixed"], DURATION_ULPS, err_msg=f"case {i} fixed")
        assert len(a["blk"]) == len(b["blk"]), (i, a["blk"], b["blk"])
        for x, y in zip(a["blk"], b["blk"]):
            np.testing.assert_allclose(x, y, rtol=1e-12)
        if a["fam"] == b["fam"] and len(a["ph"]) == len(b["ph"]):
            same_family += 1
            # the phase tables of the same shape agree to round-off of the shape parameter
            np.testing.assert_allclose(a["ph"], b["ph"], rtol=1e-9, atol=1e-12 * a["d"])
            assert_ulp_close(a["jk"], b["jk"], err_msg=f"case {i} jerks")
    assert same_family >= 0.95 * n


def test_step2_last_stage_numba_equals_python():
    """The holds through a velocity reversal and the time-reversed search (the
    moves of ``test_state_step2.MIDDLE_HOLDS``): both paths return the same
    family and phase table."""
    from test_state_step2 import MIDDLE_HOLDS

    cases = json.dumps([[s, g, L, T] for s, g, L, T, _, _ in MIDDLE_HOLDS])
    fast = _run(0, no_jit=False, script=_SCRIPT_FIXED, cases=cases)
    slow = _run(0, no_jit=True, script=_SCRIPT_FIXED, cases=cases)
    for i, (a, b) in enumerate(zip(fast, slow)):
        assert a["fam"] == b["fam"], (i, a["fam"], b["fam"])
        assert_ulp_close(a["d"], b["d"], DURATION_ULPS, err_msg=f"case {i}")
        np.testing.assert_allclose(a["ph"], b["ph"], rtol=1e-9, atol=1e-12 * a["d"])
        assert_ulp_close(a["jk"], b["jk"], err_msg=f"case {i} jerks")
    assert len(fast) == len(MIDDLE_HOLDS)



def test_a_kernel_is_compiled_once_per_type_not_per_constant(monkeypatch):
    """A compiled caller passing the constants 0, 1 and True gets one build of
    the callee for (float64, int64) and one for (float64, bool), not one per
    value (numba's literal types), and the values are those of each constant.
    (Built here without the disk cache: a cached caller holds its callees' code
    and compiles nothing.)"""
    numba = _compile.numba

    def add_constant(x, k):
        return x + k

    callee = _compile._unliteral_calls(numba.njit(add_constant))

    @numba.njit
    def three_constants(x):
        return callee(x, 0) + callee(x, 1) + callee(x, True)

    assert three_constants(2.0) == 2.0 + 3.0 + 3.0
    assert sorted(str(s) for s in callee.signatures) == ["(float64, bool)", "(float64, int64)"]
    # every kernel decorator builds its functions so
    seen = []
    monkeypatch.setattr(_compile, "_unliteral_calls", lambda d: seen.append(d) or d)
    for deco in (_compile.jit, _compile.jit_raw, _compile.jit_parallel):
        deco(add_constant)
    _compile.compiled_twins({"add_constant": add_constant}, ["add_constant"])
    assert len(seen) == 4
