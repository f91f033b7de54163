"""Run every numbered example script (``examples/*.py``) in a subprocess.

Each example must run to completion with ``--out DIR`` (exit status 0), print
real numbers on stdout, and write its output files (plots, CSV) into DIR and
nowhere else. Examples added later are picked up by the glob.
"""

from __future__ import annotations

import fnmatch
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from trajkit._atomicio import TEMP_GLOB

EXAMPLES_DIR = Path(__file__).resolve().parent.parent / "examples"
EXAMPLES = sorted(EXAMPLES_DIR.glob("[0-9]*.py"))

#: Generous wall-clock guard per script on a slow CI machine [s] (a hang
#: guard, not a timing assertion).
EXAMPLE_TIMEOUT_S = 300

#: How often to look for a free slot while waiting for a script to start [s].
POLL_S = 0.05


#: Lines that known examples must print (closed forms checked by hand):
#: 01: 0.8 m at v 1, a 4, j 40 -> each leg a/j + v/a = 0.35 s covering
#: 0.175 m, cruise 0.45 m at 1 m/s -> T = 1.15 s.
EXPECTED = {
    "01_single_axis_move": ["symmetric : T = 1.150000 s, shape 7-phase",
                            "final position 0.8 m"],
    "02_multi_axis_ptp": ["sync=time : T = 1.350000 s", "spread of the normalised progress"],
    # override and pause act while moving (rate 0.40, at rest, back to 1.00)
    "08_runtime_stream": ["override 40 %   at cycle  100: rate 0.40 from cycle",
                          "rate 0.00 from cycle", "resume          at cycle",
                          "largest |v|/v_max = 1.0000"],
    # a blend too tight to pay off: it stops at every waypoint instead, never slower
    "10_waypoints": ["stops at waypoints [0, 1, 2, 3, 4, 5, 6], passes each within 0.0000 rad",
                     "final joints [deg]: [140.0, -30.0, 60.0, 0.0, 45.0, 120.0]"],
    "11_online_targets": ["200 targets at 100 Hz, then one at rest",
                          "final position [0.25, -0.5, 0.75], velocity [0.0, 0.0, 0.0]",
                          "at rest on 1.500000 m"],
}


def test_examples_are_found():
    names = [p.name for p in EXAMPLES]
    assert "01_single_axis_move.py" in names and "02_multi_axis_ptp.py" in names


#: Example scripts run at the same time (each is mostly single-threaded and
#: spends part of its time importing).
PARALLEL = min(4, (os.cpu_count() or 1) + 1)


class _Runs:
    """Start the selected example scripts a few at a time, in the background.

    Each test waits only for its own script, so failures are still reported
    per example while the scripts overlap (their start-up is mostly imports).
    """

    def __init__(self, scripts, base):
        self.pending = list(scripts)
        self.running = {}
        self.base = base
        self.env = dict(os.environ, MPLBACKEND="Agg")

    def _n_running(self):
        return sum(p.poll() is None for p, _ in self.running.values())

    def _start_more(self):
        while self.pending and self._n_running() < PARALLEL:
            script = self.pending.pop(0)
            root = self.base / script.stem
            cwd = root / "cwd"
            cwd.mkdir(parents=True)
            # output to files, not pipes: a chatty script can never block
            with open(root / "stdout.txt", "w") as fo, open(root / "stderr.txt", "w") as fe:
                proc = subprocess.Popen(
                    [sys.executable, str(script), "--out", str(root / "out")],
                    stdout=fo, stderr=fe, env=self.env, cwd=cwd,
                )
            self.running[script] = (proc, root)

    def result(self, script):
        """Wait for ``script``; return (CompletedProcess, out dir, cwd)."""
        if script not in self.running:  # run it next
            if script in self.pending:
                self.pending.remove(script)
            self.pending.insert(0, script)
        deadline = time.monotonic() + EXAMPLE_TIMEOUT_S
        while script not in self.running:
            self._start_more()
            if script not in self.running:
                if time.monotonic() > deadline:
                    pytest.fail(f"{script.name} never got a slot to run")
                time.sleep(POLL_S)
        proc, root = self.running[script]
        try:
            proc.wait(timeout=max(deadline - time.monotonic(), 1.0))
        finally:
            self._start_more()
        done = subprocess.CompletedProcess(
            proc.args, proc.returncode,
            (root / "stdout.txt").read_text(), (root / "stderr.txt").read_text(),
        )
        return done, root / "out", root / "cwd"

    def close(self):
        for proc, _ in self.running.values():
            if proc.poll() is None:
                proc.kill()
                proc.wait()


@pytest.fixture(scope="module")
def example_runs(request, tmp_path_factory):
    pytest.importorskip("matplotlib")
    selected = [item.callspec.params["script"] for item in request.session.items
                if getattr(item, "originalname", None) == "test_example_runs"
                and hasattr(item, "callspec")]
    runs = _Runs(selected, tmp_path_factory.mktemp("examples"))
    runs._start_more()
    yield runs
    runs.close()


@pytest.mark.parametrize("script", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_runs(script, example_runs):
    proc, out, cwd = example_runs.result(script)
    assert proc.returncode == 0, f"{script.name} failed:\n{proc.stdout}\n{proc.stderr}"
    assert "Traceback" not in proc.stderr
    assert any(ch.isdigit() for ch in proc.stdout), "an example prints real numbers"
    written = sorted(p.name for p in out.iterdir()) if out.exists() else []
    assert written, f"{script.name} wrote nothing into --out"
    for name in written:
        assert (out / name).stat().st_size > 0, name
        assert not fnmatch.fnmatch(name, TEMP_GLOB), name
    assert list(cwd.iterdir()) == [], "an example wrote into the working directory"
    for text in EXPECTED.get(script.stem, []):
        assert text in proc.stdout, text
    # every file the example says it wrote is in --out
    for line in proc.stdout.splitlines():
        if line.strip().startswith("wrote "):
            path = Path(line.strip()[len("wrote "):].split(" ")[0])
            assert path.parent == out and path.exists(), line


def test_benchmark_script_runs_small(tmp_path):
    """benchmarks/bench_profiles.py runs end to end on tiny sizes and its
    durations agree with ruckig (no timing is asserted)."""
    pytest.importorskip("ruckig")
    script = EXAMPLES_DIR.parent / "benchmarks" / "bench_profiles.py"
    proc = subprocess.run(
        [sys.executable, str(script), "--moves", "200", "--batch", "500", "--ptp", "30",
         "--samples", "2000", "--repeat", "1", "--json"],
        capture_output=True, text=True, timeout=EXAMPLE_TIMEOUT_S, cwd=tmp_path,
    )
    assert proc.returncode == 0, proc.stderr
    import json

    r = json.loads(proc.stdout)
    for key in ("scalar", "batch", "ptp6"):
        assert r[key]["max_rel_duration_diff"] < 1e-9, (key, r[key])
    assert r["sampling"]["profile_axis_samples_per_s"] > 0
    assert "WARNING" not in proc.stderr
