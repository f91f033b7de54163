"""The compiled kernels are ready before a machine moves (runtime.warm_up).

A kernel compiled from inside a control cycle would hold that cycle -- and an
emergency stop queued behind it -- for as long as numba takes (minutes on a
fresh install). Each check runs a fresh process that records every kernel
signature it builds or loads from the disk cache (numba's dispatcher gains
an overload: on a fresh install, a compilation), so the result does not
depend on what the test process, or the cache, already holds.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import pytest

from trajkit import InvalidInputError
from trajkit.profiles import _compile
from trajkit.runtime import WARM_UP_PARTS, warm_up

compiled = pytest.mark.skipif(not _compile.ENABLED, reason="numba is not installed (nothing is compiled)")

# a recorder of every new kernel signature, then the scenario (``new`` is cleared by ``mark``)
_RECORDER = textwrap.dedent("""
    import json, sys
    import numpy as np
    from numba.core import dispatcher, sigutils
    new, log = [], {}
    _orig = dispatcher.Dispatcher.compile
    def _compile(self, sig):
        args, _ = sigutils.normalize_signature(sig)
        if tuple(args) not in self.overloads:
            new.append(self.py_func.__module__ + "." + self.py_func.__qualname__)
        return _orig(self, sig)
    dispatcher.Dispatcher.compile = _compile
    def mark(stage):
        log[stage] = list(new)
        new.clear()
""")


def _run(body: str) -> dict:
    code = _RECORDER + textwrap.dedent(body) + "\nprint(json.dumps(log))\n"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=900,
                          env={**os.environ, "TRAJKIT_NO_JIT": ""})
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


@compiled
def test_a_streamer_compiles_nothing_once_it_is_made():
    log = _run("""
        from trajkit import AxisLimits, plan_ptp
        from trajkit.runtime import SafetyConfig, ServoParams, Streamer
        lims = [AxisLimits(1.0, 4.0, 40.0, 2.0, 15.0, name="X"), AxisLimits(0.5, 2.0, 30.0, name="Y")]
        prog = plan_ptp([0.0, 0.0], [0.5, 0.3], lims)
        mark("import")
        # (a following error brakes under control: the fault's brake)
        st = Streamer(prog, 1e-3, servo=ServoParams(),
                      safety=SafetyConfig(reactions={"following error": "controlled"}))
        mark("made")

        def steps(n, until=None):
            for _ in range(n):
                st.step()
                if st.state == until:
                    break
            assert until is None or st.state == until, st.state

        st.start()
        steps(300)
        mark("moving (safety look-ahead)")
        st.stop()
        steps(3000, "idle")
        mark("controlled stop (brake)")
        st.set_target([0.1, 0.2], [0.3, -0.1], sync="time")
        steps(50)
        st.set_target([0.4, 0.0], sync="none",
                      limits=[AxisLimits(0.2, 1.0, 10.0, 0.5, 5.0), AxisLimits(0.3, 2.0, 30.0)])
        steps(200)
        mark("online targets")
        st.start()
        steps(100)
        mark("re-entry move")
        st.estop()
        steps(1)
        st.reset()
        steps(1)
        st.start()
        steps(50)
        st.inject_encoder_jump(0, 0.5)
        steps(3000, "fault")
        mark("emergency stop, fault brake")
    """)
    assert log["made"], "the streamer made nothing ready (the check would be empty)"
    after = {stage: sigs for stage, sigs in log.items() if stage not in ("import", "made")}
    assert len(after) == 5
    assert after == {stage: [] for stage in after}, after


@compiled
def test_warm_up_of_the_paths_leaves_nothing_to_compile_in_planning():
    log = _run("""
        import math
        from trajkit import AxisLimits
        from trajkit.interpolation import SaddleMachine, plan_saddle
        from trajkit.paths import SaddleCurve
        from trajkit.robot import CartesianTarget, Circ, Lin, Ptp, JointTarget, run_motions
        from trajkit.robot.models import robot_by_name
        from trajkit.runtime import warm_up
        from trajkit.timing import plan_waypoints
        mark("import")
        warm_up(("runtime", "paths"))
        mark("warm-up")
        for name in ("arm6", "scara"):
            rob = robot_by_name(name)
            q0 = rob.home
            p0 = rob.fk(q0)
            at = lambda d: CartesianTarget(type(p0).trusted(p0.position + np.asarray(d), p0.rotation))
            run = run_motions(rob, [Lin(at([0.02, 0.1, -0.03]), 0.8, 0.02),
                                    Lin(at([0.06, 0.12, 0.0]), 0.8),
                                    Circ(at([0.1, 0.1, 0.0]), at([0.12, 0.06, 0.0]), 0.4),
                                    Ptp(JointTarget(q0), 0.5)], q0)
            run.sample(0.004)
        machine = SaddleMachine(AxisLimits(1.5, 9.0, 80.0, name="theta"),
                                AxisLimits(0.05, 0.5, 5.0, name="z_axis"))
        plan_saddle(SaddleCurve(0.2, 0.1), 0.05, 0.5, 5.0, machine, 2e-5, 0.004)
        rng = np.random.default_rng(3)
        lims = [AxisLimits(1.0, 4.0, 40.0), AxisLimits(2.0, 5.0, 60.0, 3.0, 30.0), AxisLimits(1.5, 3.0, 20.0)]
        for blend in (0.0, 0.1):
            plan_waypoints(rng.uniform(-1, 1, (7, 3)), lims, blend=blend)
        mark("planning")
    """)
    assert log["warm-up"]
    assert log["planning"] == [], log["planning"]


def test_warm_up_parts_and_errors():
    assert WARM_UP_PARTS == ("runtime", "paths")
    with pytest.raises(InvalidInputError, match="warm-up part must be one of"):
        warm_up(("runtime", "everything"))
    warm_up()
    again = warm_up(("runtime",))
    # ready in this process: nothing done again (no numba: nothing to do at all)
    assert again == ({"runtime": 0.0} if _compile.ENABLED else {})


def test_without_numba_there_is_nothing_to_warm_up():
    code = ("from trajkit.runtime import warm_up; import json; "
            "print(json.dumps(warm_up(('runtime', 'paths'))))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300,
                          env={**os.environ, "TRAJKIT_NO_JIT": "1"})
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout) == {}


def test_cli_warmup(capsys):
    from trajkit.cli import main

    assert main(["warmup", "--part", "runtime", "--part", "runtime"]) == 0
    out = capsys.readouterr().out.splitlines()
    if _compile.ENABLED:
        assert len(out) == 1 and out[0].startswith("runtime: ready in "), out
    else:
        assert out == ["numba is not installed (or TRAJKIT_NO_JIT is set): the kernels run as plain "
                       "Python, nothing to compile"]
    with pytest.raises(SystemExit) as exc:
        main(["warmup", "--part", "everything"])
    assert exc.value.code == 2
