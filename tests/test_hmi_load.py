"""The emergency stop gets through while the HMI is flooded with requests.

A real uvicorn server (in this process, as in production: one process for
the web stack and the run loop) runs a palletizing job at a 4 ms control
period while another process floods it from :data:`FLOOD_THREADS`
connections (status reads, refused job loads, 1 MiB bodies, malformed
JSON, foreign-origin commands). Each emergency stop sent by a separate
client must be applied within :data:`MAX_ESTOP_CYCLES` control cycles of
the moment it was sent (counted by the run loop, not by a wall clock in
the test), and in the first period after the server received it.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time

import pytest

pytest.importorskip("fastapi")
pytest.importorskip("uvicorn")
httpx = pytest.importorskip("httpx")

from hmi_support import ServerThread  # noqa: E402

from trajkit.hmi.app import create_app  # noqa: E402

#: Connections of the flood.
FLOOD_THREADS = 16

#: Emergency stops sent during the flood.
TRIALS = 3

#: Largest number of control cycles between sending an emergency stop and
#: the cycle that applies it, during the flood.
MAX_ESTOP_CYCLES = 50

#: Longest wait for a state [s] (a guard against hanging, never asserted as a time).
WAIT_S = 30.0


def _wait(pred) -> None:
    deadline = time.monotonic() + WAIT_S
    while not pred():
        assert time.monotonic() < deadline, "condition never met"
        time.sleep(0.005)


def test_estop_gets_through_a_flood(tmp_path):
    app = create_app(programs_dir=tmp_path)
    sess = app.state.session
    with ServerThread(app) as srv:
        hdr = {"X-Trajkit-CSRF": app.state.policy.csrf_token}
        with httpx.Client(base_url=srv.url, headers=hdr, timeout=WAIT_S) as c:
            r = c.post("/api/job", json={"kind": "pallet", "planner": "ptp", "layers": 1})
            assert r.status_code == 200, r.text
            period = sess.job.period
            tests_dir = os.path.dirname(os.path.abspath(__file__))
            proc = subprocess.Popen(
                [sys.executable, "-c", f"import hmi_support; hmi_support.flood({srv.port}, "
                 f"{FLOOD_THREADS}, 60)"], cwd=tests_dir, stdout=subprocess.PIPE, text=True)
            try:
                assert proc.stdout.readline().strip() == "flooding"
                delays = []
                for _ in range(TRIALS):
                    assert c.post("/api/run/start").status_code == 200
                    _wait(lambda: sess.state == "running" and sess.drive.streamer.cycle > 100)
                    c0 = sess.drive.streamer.cycle  # the cycle running when the stop is sent
                    r = c.post("/api/run/estop")
                    assert r.status_code == 200 and r.json()["state"] == "fault", r.text
                    ev = [e for e in sess.drive.streamer.events if e.kind == "estop"][-1]
                    delays.append(ev.cycle - c0)
                    assert 0.0 <= sess.last_estop_latency_s <= period  # applied in the next period
                    assert c.post("/api/run/reset").json()["state"] == "idle"
            finally:
                proc.kill()
                proc.communicate()
            print(f"emergency stop under a flood of {FLOOD_THREADS} connections: applied "
                  f"{delays} cycles after it was sent (period {period * 1e3:g} ms)")
            assert max(delays) <= MAX_ESTOP_CYCLES, delays
