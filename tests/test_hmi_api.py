"""In-process tests of the HMI's JSON API (FastAPI TestClient): validation, state, files, token."""

from __future__ import annotations

import math
import re
import time
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("fastapi")
pytest.importorskip("httpx")

from fastapi.testclient import TestClient  # noqa: E402
from hmi_support import BASE_URL, page_client  # noqa: E402

from trajkit.errors import InvalidInputError  # noqa: E402
from trajkit.hmi.app import create_app  # noqa: E402
from trajkit.hmi.server import check_bind, url_of  # noqa: E402

#: Longest wait for a run to reach a state [s] (never asserted as a time).
WAIT_S = 30.0

#: A short saddle pass (about 2.3 s) on a coarse period.
FAST_SADDLE = {"kind": "saddle", "feed_mm_s": 300, "period_s": 0.01, "z_vmax_mm_s": 1000,
               "theta_vmax_deg_s": 720, "accel_mm_s2": 5000, "jerk_mm_s3": 100000,
               "theta_amax_deg_s2": 10000, "theta_jmax_deg_s3": 500000,
               "z_amax_mm_s2": 10000, "z_jmax_mm_s3": 500000}


@pytest.fixture
def client(tmp_path):
    app = create_app(programs_dir=tmp_path / "programs")
    with page_client(app) as c:
        yield c


def wait_state(client, *states):
    deadline = time.monotonic() + WAIT_S
    while time.monotonic() < deadline:
        st = client.get("/api/status").json()["state"]
        if st in states:
            return st
        time.sleep(0.01)
    raise AssertionError(f"state {st!r} never became one of {states}")


def error_of(resp, code):
    assert resp.status_code == code, resp.text
    return resp.json()["error"]


# ----------------------------------------------------------------- validation
@pytest.mark.parametrize("field, value, pattern", [
    ("feed_mm_s", -5, r"feed_mm_s: Input should be greater than 0 \(got -5\)"),
    ("feed_mm_s", "abc", r"feed_mm_s: Input should be a valid number.*\(got 'abc'\)"),
    ("feed_mm_s", "", r"feed_mm_s: Input should be a valid number"),
    ("period_s", 0.5, r"period_s: Input should be less than or equal to 0.1 \(got 0.5\)"),
    ("period_s", 1e-6, r"period_s: Input should be greater than or equal to 0.0001"),
    ("angle_deg", 180, r"angle_deg: Input should be less than 180"),
    ("tolerance_mm", "nan", r"tolerance_mm: Input should be a valid number \(got 'nan'\)"),
    ("feed_mm_s", "50", r"feed_mm_s: Input should be a valid number \(got '50'\)"),
    ("feed_mm_s", True, r"feed_mm_s: Input should be a valid number \(got True\)"),
    ("bogus", 1, r"bogus: Extra inputs are not permitted"),
])
def test_bad_saddle_value_is_refused_and_loads_nothing(client, field, value, pattern):
    msg = error_of(client.post("/api/job", json={"kind": "saddle", field: value}), 422)
    assert re.search(pattern, msg), msg
    assert client.session.job is None
    assert client.get("/api/job").json() == {"job": None}
    # the failed plan is logged (a warning) and nothing else happens
    events = client.get("/api/events").json()["events"]
    assert [e["level"] for e in events] == ["warning"]
    assert events[0]["text"] == "plan failed: " + msg


def test_library_refusal_names_values_in_mm(client):
    msg = error_of(client.post("/api/job", json={"kind": "saddle", "main_radius_mm": 90}), 400)
    assert "R=90.0" in msg and "r=100.0" in msg and msg.endswith("[mm]")
    assert client.session.job is None


def test_unknown_kind_and_bad_json(client):
    assert "kind must be one of saddle, pallet, program" in error_of(
        client.post("/api/job", json={"kind": "laser"}), 400)
    assert error_of(client.post("/api/job", content=b"{not json",
                                headers={"content-type": "application/json"}), 400)


def test_saddle_job_preview_starts_on_the_seam(client):
    res = client.post("/api/job", json={"kind": "saddle", "main_radius_mm": 150,
                                        "branch_radius_mm": 100, "feed_mm_s": 60})
    assert res.status_code == 200, res.text
    job = res.json()
    assert [a["name"] for a in job["axes"]] == ["theta", "Z"]
    assert [a["unit"] for a in job["axes"]] == ["deg", "mm"]
    p = np.array(job["path_mm"])
    # theta = 0: the seam point (r sin 0, r cos 0, sqrt(R^2 - 0)) = (0, 100, 150) mm
    np.testing.assert_allclose(p[0], [0.0, 100.0, 150.0], atol=1e-3)
    # every preview point lies on both pipes (branch: x^2 + y^2 = r^2; main along y: x^2 + z^2 = R^2)
    np.testing.assert_allclose(np.hypot(p[:, 0], p[:, 1]), 100.0, atol=1e-3)
    np.testing.assert_allclose(np.hypot(p[:, 0], p[:, 2]), 150.0, atol=1e-3)
    # the loaded table: setpoints every period, positions and the seed's Z(theta) agree
    tb = client.session.job
    assert np.allclose(np.diff(tb.t[:-1]), tb.period)
    th, z = tb.q[:, 0], tb.q[:, 1]
    np.testing.assert_allclose(z, np.sqrt(0.15 ** 2 - (0.1 * np.sin(th)) ** 2), atol=1e-12)
    assert job["summary"]["feed_mm_s"] == 60
    assert job["duration_s"] == pytest.approx(tb.duration)


def test_pallet_job_matches_the_library(client):
    from trajkit.palletizing import plan_cycle, seed_scenario

    res = client.post("/api/job", json={"kind": "pallet", "planner": "ptp", "layers": 1})
    assert res.status_code == 200, res.text
    job = res.json()
    from trajkit.kinematics import CylindricalPalletizer
    from trajkit.runtime.streamer import override_limits

    machine = seed_scenario(layers=1).robot
    # HMI jobs are planned with the override reserve (the monitors keep the machine's limits)
    robot = CylindricalPalletizer(tuple(override_limits(machine.limits)), name=machine.name)
    ref = plan_cycle(seed_scenario(layers=1, robot=robot), "ptp")
    assert ref.total_s > plan_cycle(seed_scenario(layers=1), "ptp").total_s
    assert job["summary"]["boxes"] == 5
    assert job["summary"]["duration_s"] == pytest.approx(ref.total_s, rel=1e-12)
    assert [a["name"] for a in job["axes"]] == ["A", "B", "C", "D"]
    assert "layers: Input should be less than or equal to 5 (got 6)" in error_of(
        client.post("/api/job", json={"kind": "pallet", "layers": 6}), 422)
    assert "planner: Input should be 'ptp', 'merged' or 'optimal'" in error_of(
        client.post("/api/job", json={"kind": "pallet", "planner": "fast"}), 422)


def test_bad_program_names_line_and_field(client):
    text = ("robot: arm6\npoints:\n  a: {joints_deg: [0, 20, 10, 0, 60, 0]}\n"
            "program:\n  - PTP: a\n  - LIN: a\n    speed_mm_s: 0\n")
    msg = error_of(client.post("/api/job", json={"kind": "program", "text": text}), 400)
    assert msg.startswith("program:7: program[1].speed_mm_s: Input should be greater than 0"), msg
    assert client.session.job is None


# ----------------------------------------------------------------- run control
def test_one_run_at_a_time_and_estop(client):
    assert "no job loaded" in error_of(client.post("/api/run/start"), 409)
    assert client.post("/api/job", json=FAST_SADDLE).status_code == 200
    job = client.session.job
    assert client.post("/api/run/start").json()["state"] == "running"
    assert "cannot start while a run is running" in error_of(client.post("/api/run/start"), 409)
    msg = error_of(client.post("/api/job", json={"kind": "pallet"}), 409)
    assert "cannot load a job while a run is" in msg
    assert client.session.job is job
    assert "cannot jog" in error_of(client.post("/api/jog", json={"joint": "J1", "step": 5}), 409)
    assert "cannot teach" in error_of(client.post("/api/teach", json={"name": "p1"}), 409)
    assert "nothing to reset" in error_of(client.post("/api/run/reset"), 409)

    client.post("/api/run/estop")
    assert wait_state(client, "fault") == "fault"
    sess = client.session
    assert 0.0 <= sess.last_estop_latency_s <= job.period
    tau, q = sess.drive.tau, sess.drive.last.position.copy()
    estops = [e for e in sess.drive.streamer.events if e.kind == "estop"]
    assert len(estops) == 1
    time.sleep(5 * job.period)
    assert sess.drive.tau == tau  # nothing moves after the emergency stop
    np.testing.assert_array_equal(sess.drive.last.position, q)
    np.testing.assert_array_equal(sess.drive.last.velocity, 0.0)
    st = client.get("/api/status").json()
    assert all(a["velocity"] == 0.0 for a in st["axes"])
    assert "reset first" in error_of(client.post("/api/run/start"), 409)
    assert any(e["level"] == "fault" and "EMERGENCY STOP" in e["text"]
               for e in client.get("/api/events").json()["events"])
    assert client.post("/api/run/reset").json()["state"] == "idle"
    assert client.post("/api/run/start").json()["state"] == "running"
    client.post("/api/run/stop")
    assert wait_state(client, "idle") == "idle"


def test_estop_latency_counts_from_the_queueing(client, monkeypatch):
    """An emergency stop is applied in the first control period after it is
    queued, and its latency counts from there: the request thread building the
    command can lose the interpreter to the run loop, which then runs periods
    the command is not in yet (here made to happen: building it waits 25 ms,
    two and a half periods of this job). Stamped before it was built, the stop showed 11 ms of latency
    with a period of 2 ms in a loaded test run."""
    from trajkit.hmi import engine

    assert client.post("/api/job", json=FAST_SADDLE).status_code == 200
    job = client.session.job
    assert client.post("/api/run/start").json()["state"] == "running"

    class SlowCommand(engine._Command):
        def __init__(self, *args, **kwargs):
            time.sleep(0.025)
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(engine, "_Command", SlowCommand)
    client.post("/api/run/estop")
    assert wait_state(client, "fault") == "fault"
    assert 0.0 <= client.session.last_estop_latency_s <= job.period


def test_estop_at_rest_latches_a_fault(client):
    assert client.post("/api/run/estop").json()["state"] == "fault"
    assert "reset first" in error_of(client.post("/api/jog", json={"joint": "J1", "step": 5}), 409)
    assert client.post("/api/run/reset").json()["state"] == "idle"


def test_pause_resume_and_run_to_the_end(client):
    client.post("/api/job", json=FAST_SADDLE)
    client.post("/api/run/start")
    client.post("/api/run/pause")
    assert wait_state(client, "paused") == "paused"
    tau = client.session.drive.tau
    time.sleep(0.1)
    assert client.session.drive.tau == tau
    assert "cannot pause" in error_of(client.post("/api/run/pause"), 409)
    client.post("/api/run/resume")
    assert wait_state(client, "idle") == "idle"
    st = client.get("/api/status").json()
    assert st["progress"] == pytest.approx(1.0)
    ev = [e["text"] for e in client.get("/api/events").json()["events"]]
    assert any(t.startswith("run 1 complete") for t in ev)


@pytest.mark.parametrize("value, pattern", [
    (101, r"percent: Input should be less than or equal to 100"),
    (-1, r"percent: Input should be greater than or equal to 0"),
    ("fast", r"percent: Input should be a valid number"),
])
def test_override_validation(client, value, pattern):
    assert re.search(pattern, error_of(client.post("/api/override", json={"percent": value}), 422))
    assert client.get("/api/status").json()["override_pct"] == 100.0


def test_override_accepted(client):
    assert client.post("/api/override", json={"percent": 40}).json()["override_pct"] == 40.0


def test_unknown_run_command(client):
    assert "run command must be one of" in error_of(client.post("/api/run/explode"), 400)


# ----------------------------------------------------------------- jog, teach, programs
def test_jog_teach_build_and_files(client, tmp_path):
    sess = client.session
    info = client.get("/api/robot").json()
    assert info["robot"] == "scara" and [j["name"] for j in info["joints"]] == ["J1", "J2", "J3", "J4"]
    q0 = sess.q.copy()
    msg = error_of(client.post("/api/jog", json={"joint": "J3", "step": -10}), 400)
    assert "J3" in msg and "-10.000 mm" in msg and "[0.000, 200.000] mm" in msg
    assert "joint must be one of J1, J2, J3, J4" in error_of(
        client.post("/api/jog", json={"joint": "A1", "step": 5}), 400)
    assert "jog step must not be zero" in error_of(client.post("/api/jog", json={"joint": "J1", "step": 0}), 422)
    np.testing.assert_array_equal(sess.q, q0)

    # home has the elbow bent (a line between points with the arm stretched, a
    # singularity, cannot be followed: tested below)
    assert math.degrees(sess.q[1]) == pytest.approx(90.0)
    assert client.post("/api/jog", json={"joint": "J2", "step": -30}).status_code == 200
    wait_state(client, "idle")
    client.post("/api/teach", json={"name": "home"})
    assert client.post("/api/jog", json={"joint": "J3", "step": 40}).status_code == 200
    wait_state(client, "idle")
    assert sess.q[2] == pytest.approx(0.04, abs=1e-12)  # jogs land exactly on the target
    client.post("/api/jog", json={"joint": "J1", "step": 30})
    wait_state(client, "idle")
    assert math.degrees(sess.q[0]) == pytest.approx(30.0, abs=1e-9)
    client.post("/api/teach", json={"name": "p2"})
    assert "name: String should match pattern" in error_of(
        client.post("/api/teach", json={"name": "../x"}), 422)

    assert "point 'p9' is not taught" in error_of(client.post(
        "/api/program/build", json={"steps": [{"op": "PTP", "point": "p9"}]}), 400)
    assert "CIRC to p2 needs a via point" in error_of(client.post(
        "/api/program/build", json={"steps": [{"op": "CIRC", "point": "p2"}]}), 400)
    text = client.post("/api/program/build", json={"steps": [
        {"op": "PTP", "point": "home"}, {"op": "LIN", "point": "p2", "speed_mm_s": 100}]}).json()["text"]
    assert "J3_mm: 40.0" in text and "J1_deg: 30.0" in text

    # the built program plays back to the taught points (joint space)
    res = client.post("/api/job", json={"kind": "program", "text": text})
    assert res.status_code == 200, res.text
    tb = sess.job
    np.testing.assert_allclose(tb.q[0], [0, math.radians(60), 0, 0], atol=1e-9)
    np.testing.assert_allclose(tb.q[-1], [math.radians(30), math.radians(60), 0.04, 0], atol=1e-7)
    # a line that leaves the stretched arm along the arm is refused, with the reason
    stretched = text.replace("J2_deg: 60.0", "J2_deg: 0.0")
    assert stretched != text
    msg = error_of(client.post("/api/job", json={"kind": "program", "text": stretched}), 400)
    assert "singularity" in msg and "cannot follow" in msg

    # files: a bad program is not saved; a good one round-trips
    pdir = Path(sess.programs_dir)
    assert error_of(client.post("/api/programs", json={"name": "bad", "text": "robot: scara\n"}), 400)
    assert not (pdir / "bad.yaml").exists()
    assert "name: String should match pattern" in error_of(
        client.post("/api/programs", json={"name": "../evil", "text": text}), 422)
    assert client.post("/api/programs", json={"name": "cell_1", "text": text}).json()["saved"]
    assert (pdir / "cell_1.yaml").read_text() == text
    assert client.get("/api/programs").json() == {"programs": ["cell_1"]}
    assert client.get("/api/programs/cell_1").json()["text"] == text
    assert "no program named 'nope'" in error_of(client.get("/api/programs/nope"), 400)
    assert "program name must match" in error_of(client.get("/api/programs/.hidden"), 400)
    assert client.get("/api/programs/..%2Fcell_1").status_code in (400, 404)


def test_jog_steps_while_moving_chain_on_one_online_target(client):
    """A jog step while the joint still moves re-plans from the commanded state (no stop between)."""
    sess = client.session
    q0 = sess.q.copy()
    assert client.post("/api/jog", json={"joint": "J1", "step": 40, "speed_pct": 50}).status_code == 200
    run = sess.run_id
    assert client.get("/api/status").json()["motion"] == "online target"
    # two more steps while it moves: one ahead, one back
    assert client.post("/api/jog", json={"joint": "J1", "step": 20, "speed_pct": 50}).status_code == 200
    assert client.post("/api/jog", json={"joint": "J1", "step": -50, "speed_pct": 50}).status_code == 200
    assert wait_state(client, "idle", "fault") == "idle"
    assert sess.run_id == run  # one run: the steps were targets of the same streamer
    evs = sess.drive.streamer.events
    assert [e.kind for e in evs].count("target") == 3 and evs[-1].kind == "target_reached"
    assert not [e for e in evs if e.kind in ("fault", "rejected", "stop")]
    assert math.degrees(sess.q[0] - q0[0]) == pytest.approx(10.0, abs=1e-9)
    np.testing.assert_array_equal(sess.q[1:], q0[1:])
    # a step past the range is refused against the goal, not the current position
    assert client.post("/api/jog", json={"joint": "J3", "step": 150}).status_code == 200
    msg = error_of(client.post("/api/jog", json={"joint": "J3", "step": 60}), 400)
    assert "210.000 mm leaves its range" in msg
    assert wait_state(client, "idle", "fault") == "idle"
    assert sess.q[2] == pytest.approx(0.15, abs=1e-12)


def test_change_robot(client):
    assert client.post("/api/robot", json={"robot": "arm6"}).json()["robot"] == "arm6"
    assert len(client.session.q) == 6
    assert "robot: Input should be" in error_of(client.post("/api/robot", json={"robot": "kuka"}), 422)


# ----------------------------------------------------------------- page, token, binding
def test_page_is_self_contained(client):
    html = client.get("/").text
    assert "<title>trajkit HMI</title>" in html
    srcs = [s for s in re.findall(r'(?:src|href)="([^"]+)"', html) if s != "data:,"]  # no favicon
    assert srcs and all(s.startswith("/static/") for s in srcs), srcs
    for s in srcs:
        assert client.get(s).status_code == 200, s
    js = client.get("/static/hmi.js").text
    assert "http://" not in js and "https://" not in js
    assert client.get("/static/vendor/uPlot.LICENSE").status_code == 200


TOKEN = "s3cret-token-4567"


def test_token_required_everywhere(tmp_path):
    app = create_app(token=TOKEN, programs_dir=tmp_path)
    with TestClient(app, base_url=BASE_URL) as c:
        assert error_of(c.get("/api/status"), 401) == "missing or wrong token"
        assert c.get("/api/status", headers={"X-Trajkit-Token": "wrong-token"}).status_code == 401
        assert c.get("/api/status", headers={"X-Trajkit-Token": TOKEN}).status_code == 200
        assert c.get("/api/status", headers={"Authorization": f"Bearer {TOKEN}"}).status_code == 200
        assert c.get(f"/api/status?token={TOKEN}").status_code == 200
        assert c.post("/api/run/estop").status_code == 401
        assert app.state.session.state == "idle"
        # the page, its files, the schema and the docs are behind the token too
        for path in ("/", "/static/hmi.js", "/static/vendor/uPlot.iife.min.js", "/openapi.json",
                     "/docs", "/api/session"):
            r = c.get(path)
            assert r.status_code == 401, path
            assert "uPlot" not in r.text and "paths" not in r.text
        assert c.get("/openapi.json", headers={"X-Trajkit-Token": TOKEN}).status_code == 200
        # opening the page with ?token= sets a cookie (HttpOnly, SameSite=Strict) for its files
        r = c.get(f"/?token={TOKEN}")
        assert r.status_code == 200
        cookie = r.headers["set-cookie"]
        assert cookie.startswith(f"trajkit-token-8765={TOKEN};")
        assert "HttpOnly" in cookie and "SameSite=Strict" in cookie
        assert c.get("/static/hmi.js").status_code == 200  # the cookie carries the token
        c.cookies.clear()
        assert c.get("/static/hmi.js").status_code == 401
        # the token alone does not allow a change: the anti-CSRF header is needed as well
        hdr = {"X-Trajkit-Token": TOKEN}
        assert "X-Trajkit-CSRF" in error_of(c.post("/api/run/reset", headers=hdr), 403)
        csrf = c.get("/api/session", headers=hdr).json()["csrf_token"]
        assert c.post("/api/override", json={"percent": 50},
                      headers={**hdr, "X-Trajkit-CSRF": csrf}).status_code == 200


@pytest.mark.parametrize("token, pattern", [
    ("abc", r"at least 16 characters, got 3"),
    ("a" * 40, r"too easy to guess: it needs at least 6 different characters, got 1"),
    ("abababababababab", r"at least 6 different characters, got 2"),
    (" " * 20, r"printable ASCII characters without spaces"),
    ("good-token with space", r"printable ASCII characters without spaces"),
    ("t\u00f6ken-1234567890", r"printable ASCII"),
])
def test_weak_tokens_are_refused(token, pattern):
    with pytest.raises(InvalidInputError, match=pattern) as exc:
        check_bind("0.0.0.0", 8765, token)
    assert token.strip() == "" or token not in str(exc.value)  # the token is never shown


def test_check_bind():
    check_bind("127.0.0.1", 8765, None)
    check_bind("::1", 0, None)
    check_bind("localhost", 8765, None)
    with pytest.raises(InvalidInputError, match=r"host '0.0.0.0' .* requires --token"):
        check_bind("0.0.0.0", 8765, None)
    with pytest.raises(InvalidInputError, match=r"host '192.168.1.5' .* requires --token"):
        check_bind("192.168.1.5", 8765, None)
    check_bind("0.0.0.0", 8765, "long-enough-token")
    with pytest.raises(InvalidInputError, match=r"port must be an integer in 0..65535, got 70000"):
        check_bind("127.0.0.1", 70000, None)
    assert url_of("127.0.0.1", 8765, None) == "http://127.0.0.1:8765/"
    assert url_of("::1", 80, "tok") == "http://[::1]:80/?token=tok"


def test_default_allowed_hosts():
    from trajkit.hmi.server import default_allowed_hosts

    assert default_allowed_hosts("127.0.0.1") == ["127.0.0.1", "localhost", "::1"]
    hosts = default_allowed_hosts("192.168.1.5", ["hmi.plant.example"])
    assert hosts[:3] == ["127.0.0.1", "localhost", "::1"]
    assert "192.168.1.5" in hosts and hosts[-1] == "hmi.plant.example"
    assert "0.0.0.0" not in default_allowed_hosts("0.0.0.0")


def test_cli_refuses_public_bind_without_token(capsys):
    from trajkit.cli import main

    assert main(["hmi", "--host", "0.0.0.0", "--port", "8765"]) == 2
    err = capsys.readouterr().err
    assert err.strip() == ("trajkit hmi: error: host '0.0.0.0' is not this machine only (127.0.0.1): "
                           "binding to it requires --token")


@pytest.mark.parametrize("args, message", [
    (["--host", "0.0.0.0", "--token", "aaaaaaaaaaaaaaaaaaaa"],
     "token is too easy to guess: it needs at least 6 different characters, got 1"),
    (["--token", "short"], "token must have at least 16 characters, got 5"),
    (["--allow-origin", "evil"], "allowed origin must look like http://host[:port] or https://host[:port], "
                                 "got 'evil'"),
    (["--allow-host", "*"], "allowed host must be a host name or address, got '*'"),
    (["--robots-dir", "/nonexistent/robots"], "--robots-dir '/nonexistent/robots' is not a folder"),
])
def test_cli_refuses_bad_settings_in_one_line(capsys, args, message):
    from trajkit.cli import main

    assert main(["hmi", *args]) == 2
    assert capsys.readouterr().err.strip() == f"trajkit hmi: error: {message}"


def test_cli_serves_on_localhost_and_prints_its_address(tmp_path):
    import subprocess
    import sys

    import httpx

    proc = subprocess.Popen(
        [sys.executable, "-m", "trajkit.cli", "hmi", "--port", "0", "--programs-dir", str(tmp_path)],
        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        line = proc.stdout.readline()
        m = re.match(r"trajkit HMI on (http://127\.0\.0\.1:(\d+)/) ", line)
        assert m, line
        r = httpx.get(m.group(1) + "api/status", timeout=10)
        assert r.status_code == 200 and r.json()["state"] == "idle"
    finally:
        proc.terminate()
        proc.wait(timeout=10)


def test_jobs_are_planned_with_the_override_reserve(client):
    """100 % runs the planned speed; the slider and pause have the reserve's slack."""
    from trajkit.hmi.engine import RuntimeDrive
    from trajkit.runtime.streamer import OVERRIDE_RESERVE

    res = client.post("/api/job", json={"kind": "pallet", "planner": "optimal", "layers": 1})
    assert res.status_code == 200, res.text
    tb = client.session.job
    st = RuntimeDrive(tb).streamer
    machine = tb.machine_limits
    assert st.limits == tuple(machine)  # the monitors enforce the machine's limits
    planned = tb.source().limits
    for p, m in zip(planned, machine):
        assert p.a_max == pytest.approx(OVERRIDE_RESERVE * m.a_max)
        assert p.j_max == pytest.approx(OVERRIDE_RESERVE * min(m.j_max, m.j_max_decel))
        assert p.v_max == m.v_max
    assert st.rate_ceiling == 1.0 and st.max_rate == 1.0  # the planned speed at 100 %
    assert res.json()["summary"]["override_reserve"] == OVERRIDE_RESERVE


# ----------------------------------------------------------------- who may drive the machine
def _fault(client):
    assert client.post("/api/job", json=FAST_SADDLE).status_code == 200
    assert client.post("/api/run/estop").json()["state"] == "fault"


@pytest.mark.parametrize("headers", [
    {"Origin": "http://evil.example"},
    {"Origin": "http://127.0.0.1:9999"},  # another port of this machine is another origin
    {"Origin": "https://127.0.0.1:8765.evil.example"},
    {"Origin": "null"},  # sandboxed frames, file:// pages
    {"Host": "evil.example"},  # DNS rebinding: a foreign name resolving to this machine
    {"Host": "evil.example:8765", "Origin": "http://evil.example:8765"},
    {"Host": "127.0.0.1.evil.example"},
])
def test_foreign_origin_or_host_cannot_reset_start_or_read(client, headers):
    """Issue reproduction: reset then start from another origin took fault -> running."""
    _fault(client)
    for path in ("/api/run/reset", "/api/run/start", "/api/run/estop"):
        r = client.post(path, headers=headers)
        assert r.status_code == 403, (path, r.text)
        assert "not allowed" in r.json()["error"]
    assert client.session.state == "fault"
    for path in ("/api/status", "/api/session", "/api/job", "/api/events", "/", "/static/hmi.js"):
        assert client.get(path, headers=headers).status_code == 403, path


@pytest.mark.parametrize("site, path, code", [
    ("cross-site", "/api/status", 403),  # <img src>, <script src> from another site
    ("same-site", "/api/session", 403),  # another port of this machine
    ("cross-site", "/static/hmi.js", 403),
    ("same-origin", "/api/status", 200),
    ("none", "/api/status", 200),  # typed into the address bar
])
def test_fetch_metadata_refuses_reads_by_other_sites(client, site, path, code):
    assert client.get(path, headers={"Sec-Fetch-Site": site, "Sec-Fetch-Mode": "no-cors"}).status_code == code


def test_a_link_from_another_site_opens_the_page_only(client):
    nav = {"Sec-Fetch-Site": "cross-site", "Sec-Fetch-Mode": "navigate", "Sec-Fetch-Dest": "document"}
    assert client.get("/", headers=nav).status_code == 200
    assert client.get("/api/status", headers=nav).status_code == 403
    assert client.get("/", headers={**nav, "Sec-Fetch-Dest": "iframe"}).status_code == 403


def test_changing_requests_need_the_csrf_header(client):
    _fault(client)
    bare = {"X-Trajkit-CSRF": ""}
    for path in ("/api/run/reset", "/api/run/start"):
        # what a no-cors fetch or a form post can send: no custom header
        r = client.post(path, headers={**bare, "Content-Type": "text/plain"}, content=b"x")
        assert "X-Trajkit-CSRF" in error_of(r, 403)
        r = client.post(path, headers={"X-Trajkit-CSRF": "guessed-value"})
        assert "X-Trajkit-CSRF" in error_of(r, 403)
    assert client.session.state == "fault"
    for path, body in (("/api/job", {"kind": "pallet"}), ("/api/override", {"percent": 10}),
                       ("/api/teach", {"name": "p1"}), ("/api/robot", {"robot": "arm6"})):
        assert error_of(client.post(path, json=body, headers=bare), 403)
    assert client.get("/api/status").json()["override_pct"] == 100.0
    # the page's own requests pass
    assert client.post("/api/run/reset", headers={"Origin": BASE_URL}).json()["state"] == "idle"


def test_estop_needs_no_csrf_header_but_a_local_origin(client):
    assert client.post("/api/run/estop", headers={"X-Trajkit-CSRF": ""}).json()["state"] == "fault"
    client.post("/api/run/reset")
    assert client.post("/api/run/estop", headers={"X-Trajkit-CSRF": "", "Origin": BASE_URL}).status_code == 200
    client.post("/api/run/reset")
    assert client.post("/api/run/estop", headers={"Origin": "http://evil.example"}).status_code == 403
    assert client.session.state == "idle"


def test_session_gives_the_csrf_value(client):
    info = client.get("/api/session").json()
    assert info["csrf_header"] == "x-trajkit-csrf" and len(info["csrf_token"]) >= 32
    assert info["token_required"] is False and info["max_body_bytes"] == 1 << 20
    other = create_app(programs_dir="unused")
    assert other.state.policy.csrf_token != info["csrf_token"]  # a new value per server


def test_allowed_hosts_and_origins_behind_a_proxy(tmp_path):
    app = create_app(programs_dir=tmp_path, allowed_hosts=["127.0.0.1", "hmi.plant.example"],
                     allowed_origins=["https://hmi.plant.example"])
    with page_client(app) as c:
        hdr = {"Host": "hmi.plant.example", "Origin": "https://hmi.plant.example"}
        assert c.post("/api/override", json={"percent": 30}, headers=hdr).status_code == 200
        assert c.post("/api/override", json={"percent": 30},
                      headers={**hdr, "Origin": "https://evil.example"}).status_code == 403
        assert c.get("/api/status", headers={"Host": "localhost"}).status_code == 403
    for bad in (["*"], ["0.0.0.0"], ["a b"]):
        with pytest.raises(InvalidInputError, match="allowed host must be a host name"):
            create_app(allowed_hosts=bad)
    with pytest.raises(InvalidInputError, match="allowed origin must look like"):
        create_app(allowed_origins=["hmi.plant.example"])


def test_security_headers_on_every_answer(client):
    for r in (client.get("/"), client.get("/api/status"), client.get("/static/hmi.js"),
              client.get("/nope"), client.post("/api/run/start"),
              client.get("/api/status", headers={"Host": "evil.example"}),
              client.post("/api/job", content=b"x" * (2 << 20))):
        assert r.headers["x-frame-options"] == "DENY"
        assert r.headers["x-content-type-options"] == "nosniff"
        csp = r.headers["content-security-policy"]
        assert "frame-ancestors 'none'" in csp and "script-src 'self'" in csp
        assert "access-control-allow-origin" not in r.headers


# ----------------------------------------------------------------- hostile bodies
@pytest.mark.parametrize("body, pattern", [
    (b'{"kind": "pallet", "kind": "saddle"}', r"^request body: .*duplicate key 'kind'$"),
    (b'{"kind": "saddle", "feed_mm_s": 40\xff}', r"^request body: not UTF-8 .*34"),
    (b"[" * 100_000 + b"]" * 100_000, r"^request body: nested deeper than 32 levels$"),
    (b'{"a":' * 40 + b"1" + b"}" * 40, r"^request body: nested deeper than 32 levels$"),
    (b'{"kind": "saddle", "feed_mm_s": NaN}', r"^request body: .*NaN"),
    (b"[1, 2]", r"^request body: must be a JSON object, got list$"),
    (b"", r"^request body.*: not valid JSON"),
])
def test_hostile_job_bodies_answer_one_line(client, body, pattern):
    """Every body goes through the library's one safe loader (trajkit.io.document)."""
    msg = error_of(client.post("/api/job", content=body, headers={"Content-Type": "application/json"}), 400)
    assert re.search(pattern, msg), msg
    assert "\n" not in msg


def test_out_of_range_numbers_are_refused(client):
    r = client.post("/api/job", content=b'{"kind": "saddle", "feed_mm_s": 1e999}')
    assert error_of(r, 400) == "request body: not valid JSON: number 1e999 is out of the range of a float"
    r = client.post("/api/override", content=b'{"percent": ' + b"9" * 400 + b"}")
    assert error_of(r, 422).startswith("percent: Input should be")


@pytest.mark.parametrize("path", ["/api/override", "/api/jog", "/api/teach", "/api/robot",
                                  "/api/program/build", "/api/programs"])
def test_every_body_goes_through_the_strict_loader(client, path):
    msg = error_of(client.post(path, content=b'{"a": 1, "a": 2}'), 400)
    assert msg.startswith("request body: ") and msg.endswith("duplicate key 'a'")


@pytest.mark.parametrize("value", [True, "50", None, [50], {"v": 50}])
def test_override_numbers_are_strict(client, value):
    msg = error_of(client.post("/api/override", json={"percent": value}), 422)
    assert msg.startswith("percent: Input should be a valid number")
    assert client.post("/api/override", json={"percent": 50}).status_code == 200  # ints are numbers


def test_error_messages_do_not_echo_the_input(client):
    big = "x" * 150_000
    for body in ({"kind": "saddle", "feed_mm_s": big}, {"kind": big}, {"kind": "program", "text": big},
                 {"kind": "program", "text": "robot: arm6\n" + "# " + big + "\npoints: 3\n"},
                 {"kind": "saddle", big: 1}):
        r = client.post("/api/job", json=body)
        assert r.status_code in (400, 422)
        assert len(r.json()["error"]) <= 300 and "xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx" not in r.text


def test_body_limit_413(client):
    r = client.post("/api/job", content=b"{" + b" " * (1 << 20) + b"}")
    assert "larger than the 1048576 bytes allowed" in error_of(r, 413)
    ok = {"kind": "program", "text": "#" * 199_000, "period_s": 0.004}
    assert client.post("/api/job", json=ok).status_code == 400  # below the limit: read and parsed


def test_body_limit_is_checked_while_the_body_streams():
    """The guard stops reading at the first chunk past the limit (it never reads it all)."""
    import asyncio

    from trajkit.hmi.security import AccessPolicy, Guard

    async def app(scope, receive, send):  # pragma: no cover - must not be reached
        raise AssertionError("the app must not see an oversized body")

    policy = AccessPolicy.build(max_body_bytes=4096)
    chunk = b"x" * 1000
    served = []
    sent = []

    async def receive():
        served.append(len(chunk))
        return {"type": "http.request", "body": chunk, "more_body": True}  # endless

    async def send(msg):
        sent.append(msg)

    scope = {"type": "http", "method": "POST", "path": "/api/job", "query_string": b"",
             "headers": [(b"host", b"127.0.0.1:8765"), (b"x-trajkit-csrf", policy.csrf_token.encode()),
                         (b"transfer-encoding", b"chunked")]}
    asyncio.run(Guard(app, policy)(scope, receive, send))
    assert sent[0]["status"] == 413
    assert sum(served) == 5000  # stopped at the first chunk past 4096 bytes
    # a declared length above the limit is refused before reading anything
    served.clear()
    sent.clear()
    scope["headers"] = scope["headers"][:2] + [(b"content-length", b"5000000")]
    asyncio.run(Guard(app, policy)(scope, receive, send))
    assert sent[0]["status"] == 413 and served == []


def test_unexpected_errors_answer_one_line_500(client, monkeypatch):
    def boom():
        raise ZeroDivisionError("secret internals")

    monkeypatch.setattr(client.session, "joint_info", boom)
    r = client.get("/api/robot")
    assert r.status_code == 500
    assert r.json() == {"error": "internal error (ZeroDivisionError); the server log has the details"}
    assert r.headers["x-frame-options"] == "DENY"


# ----------------------------------------------------------------- URDF programs: no file-system probing
URDF = Path(__file__).parent / "data" / "arm6_test.urdf"


def _urdf_program(path: str) -> str:
    return (f"robot: {{urdf: '{path}', tip_link: tool0}}\npoints:\n"
            "  a: {joints_deg: [0, 20, 10, 0, 60, 0]}\n  b: {joints_deg: [10, 20, 10, 0, 60, 0]}\n"
            "program:\n  - PTP: a\n  - PTP: b\n")


def test_programs_cannot_probe_the_file_system(tmp_path):
    robots = tmp_path / "robots"
    robots.mkdir()
    (robots / "arm.urdf").write_text(URDF.read_text())
    (tmp_path / "outside.urdf").write_text(URDF.read_text())
    (robots / "link.urdf").symlink_to(tmp_path / "outside.urdf")
    app = create_app(programs_dir=tmp_path / "programs", robots_dir=robots)
    with page_client(app) as c:
        res = c.post("/api/job", json={"kind": "program", "text": _urdf_program("arm.urdf")})
        assert res.status_code == 200, res.text
        assert c.session.job.kind == "program"
        msgs = {}
        for path in ("/etc/passwd", "/etc/hostname.urdf", "/nonexistent/x.urdf", "../outside.urdf",
                     str(tmp_path / "outside.urdf"), "link.urdf", "missing.urdf", "arm"):
            for url, body in (("/api/job", {"kind": "program", "text": _urdf_program(path)}),
                              ("/api/programs", {"name": "probe", "text": _urdf_program(path)})):
                msg = error_of(c.post(url, json=body), 400)
                msgs[re.sub(r"'[^']*'", "PATH", msg).split(":", 2)[2]] = path
        # one message for every refused path, whether it exists or not
        assert list(msgs) == [" robot.urdf: PATH is not a URDF file of the robots folder"]
        assert not (tmp_path / "programs" / "probe.yaml").exists()
    app = create_app(programs_dir=tmp_path / "programs")  # no robots folder: built-in robots only
    with page_client(app) as c:
        msg = error_of(c.post("/api/job", json={"kind": "program", "text": _urdf_program(str(URDF))}), 400)
        assert msg.endswith("is not a URDF file of a robots folder (none is configured)")
    with pytest.raises(InvalidInputError, match="is not a folder"):
        create_app(robots_dir=tmp_path / "nope")


# ----------------------------------------------------------------- what runs is what is shown
def test_failed_plan_disarms(client):
    assert client.post("/api/job", json=FAST_SADDLE).status_code == 200
    assert client.get("/api/status").json()["job"].startswith("saddle")
    job_id = client.get("/api/status").json()["job_id"]
    msg = error_of(client.post("/api/job", json={"kind": "saddle", "main_radius_mm": 90}), 400)
    assert "R=90.0" in msg
    assert client.session.job is None
    assert client.get("/api/job").json() == {"job": None}
    st = client.get("/api/status").json()
    assert st["job"] is None and "axes" not in st and st["job_id"] > job_id
    assert "no job loaded" in error_of(client.post("/api/run/start"), 409)
    ev = client.get("/api/events").json()["events"][-1]
    assert ev["level"] == "warning" and ev["text"].startswith("plan failed: ") and "unloaded" in ev["text"]
    # a refused value disarms as well
    assert client.post("/api/job", json=FAST_SADDLE).status_code == 200
    error_of(client.post("/api/job", json={"kind": "saddle", "feed_mm_s": "fast"}), 422)
    assert client.session.job is None


def test_status_and_axes_follow_the_loaded_job(client):
    assert client.post("/api/job", json=FAST_SADDLE).status_code == 200
    client.post("/api/run/start")
    wait_state(client, "running")
    client.post("/api/run/stop")
    wait_state(client, "idle")
    st = client.get("/api/status").json()
    assert [a["name"] for a in st["axes"]] == ["theta", "Z"]
    res = client.post("/api/job", json={"kind": "pallet", "planner": "ptp", "layers": 1})
    assert res.status_code == 200, res.text
    st = client.get("/api/status").json()
    assert st["job"] == res.json()["title"] and st["job"].startswith("palletizing")
    assert [a["name"] for a in st["axes"]] == ["A", "B", "C", "D"]
    assert st["progress"] == 0.0 and st["plan_time_s"] == 0.0
    q0 = client.session.job.q[0]
    assert [a["position"] for a in st["axes"]] == pytest.approx(
        [float(x * s) for x, s in zip(q0, client.session.job.axis_scale)], abs=1e-12)
    assert all(a["following_error"] == 0.0 and a["velocity"] == 0.0 for a in st["axes"])
    # a jog shows the robot's joints while it moves; once it ends, the job that Start runs
    assert client.post("/api/jog", json={"joint": "J1", "step": 5}).status_code == 200
    wait_state(client, "idle")
    deadline = time.monotonic() + WAIT_S
    while client.session._snap.get("run_title", "").startswith("jog"):
        assert time.monotonic() < deadline
        time.sleep(0.01)
    st = client.get("/api/status").json()
    assert [a["name"] for a in st["axes"]] == ["A", "B", "C", "D"] and st["progress"] == 0.0


def test_servo_is_at_rest_on_the_command_after_estop_and_reset(client):
    """After an emergency stop the brakes stop every axis; after reset no following error stays."""
    assert client.post("/api/job", json={"kind": "pallet", "planner": "ptp", "layers": 1}).status_code == 200
    client.post("/api/run/start")
    sess = client.session
    deadline = time.monotonic() + WAIT_S
    while np.max(np.abs(sess.drive.streamer.servo.v)) < 0.2:  # moving at speed
        assert time.monotonic() < deadline
        time.sleep(0.01)
    client.post("/api/run/estop")
    assert client.post("/api/run/reset").json()["state"] == "idle"  # waits for the brakes
    wait_state(client, "idle")
    deadline = time.monotonic() + WAIT_S
    while sess._thread is not None and (sess._cmds or not sess.drive.at_rest()):
        assert time.monotonic() < deadline
        time.sleep(0.01)
    servo = sess.drive.streamer.servo
    assert not servo.braking
    # at rest: zero up to the round-off of one driven period at rest (the servo's
    # discrete step cancels position terms of the size of the axis position)
    np.testing.assert_allclose(servo.v, 0.0, rtol=0, atol=1e-12)
    st = client.get("/api/status").json()
    for a in st["axes"]:
        assert abs(a["following_error"]) <= 1e-9, a  # [mm or deg]: command and actual agree
        assert abs(a["velocity"]) <= 1e-9, a
    np.testing.assert_allclose(sess.drive.last.position, servo.measured, rtol=0, atol=1e-12)
    # the run continues from there (a re-entry move first) and ends at the goal
    assert client.post("/api/run/start").json()["state"] == "running"
    client.post("/api/run/stop")
    wait_state(client, "idle")


def test_setpoint_cap_is_checked_on_the_planned_duration(client):
    """Nominal feed: ~170 k setpoints; the slowed plan: 4.6 M, above the 2 M cap."""
    from trajkit.hmi.jobs import MAX_SETPOINTS

    body = {"kind": "saddle", "period_s": 0.0001, "z_vmax_mm_s": 0.5}
    msg = error_of(client.post("/api/job", json=body), 400)
    assert re.search(rf"the plan lasts \d+\.\d+ s: at period_s 0.0001 that is \d+ setpoints, more than "
                     rf"the {MAX_SETPOINTS} a job may have \(at most 200.0 s at this period\)", msg), msg
    assert client.session.job is None


def test_live_tool_speed_of_a_path_job(client):
    assert client.post("/api/job", json=FAST_SADDLE).status_code == 200
    client.post("/api/run/start")
    speeds = []
    deadline = time.monotonic() + WAIT_S
    while client.session.state != "idle" or not speeds:
        st = client.get("/api/status").json()
        if st["state"] == "running" and "tool_speed_mm_s" in st:
            speeds.append(st["tool_speed_mm_s"])
        assert time.monotonic() < deadline
        time.sleep(0.02)
    assert max(speeds) > 0.5 * FAST_SADDLE["feed_mm_s"]
    assert max(speeds) <= FAST_SADDLE["feed_mm_s"] * (1 + 1e-6)  # the torch never exceeds the feed


def test_a_body_that_never_arrives_answers_408(monkeypatch):
    import asyncio

    from trajkit.hmi import security

    monkeypatch.setattr(security, "BODY_TIMEOUT_S", 0.05)
    policy = security.AccessPolicy.build()
    sent = []

    async def app(scope, receive, send):  # pragma: no cover - must not be reached
        raise AssertionError("the app must not run")

    async def receive():
        await asyncio.sleep(3600)  # a client that sends nothing more

    async def send(msg):
        sent.append(msg)

    scope = {"type": "http", "method": "POST", "path": "/api/job", "query_string": b"",
             "headers": [(b"host", b"127.0.0.1:8765"), (b"x-trajkit-csrf", policy.csrf_token.encode())]}
    asyncio.run(security.Guard(app, policy)(scope, receive, send))
    assert sent[0]["status"] == 408


def test_estop_queued_as_the_run_is_unloaded_still_latches(client):
    """An emergency stop that raced with loading a job (which drops the old run) is not lost."""
    from trajkit.hmi.engine import _Command

    sess = client.session
    assert client.post("/api/job", json=FAST_SADDLE).status_code == 200
    client.post("/api/run/start")
    client.post("/api/run/stop")
    wait_state(client, "idle")
    with sess._lock:  # the stop is queued for the old run, then the job is replaced
        cmd = _Command("estop", sess._clock())
        sess._cmds.append(cmd)
        sess.drive = None
    sess._wake.set()
    assert cmd.done.wait(WAIT_S)
    assert client.get("/api/status").json()["state"] == "fault"
    assert client.post("/api/run/reset").json()["state"] == "idle"


def test_every_snapshot_of_a_loaded_or_running_job_has_its_axes(client):
    """The page rebuilds its axes table from the live values: they never lapse at a start."""
    sess = client.session
    assert client.post("/api/job", json=FAST_SADDLE).status_code == 200
    with sess._lock:  # a start whose first period has not run yet
        from trajkit.hmi.engine import RuntimeDrive

        sess.drive = RuntimeDrive(sess.job)
        sess._publish()
    st = client.get("/api/status").json()
    assert [a["name"] for a in st["axes"]] == ["theta", "Z"]
    assert st["axes"][0]["position"] == pytest.approx(float(np.degrees(sess.job.q[0, 0])), abs=1e-12)
