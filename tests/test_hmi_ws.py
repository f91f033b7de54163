"""In-process tests of the HMI's live WebSocket (FastAPI TestClient)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("fastapi")
pytest.importorskip("httpx")

from hmi_support import WS_BASE, page_client  # noqa: E402
from starlette.websockets import WebSocketDisconnect  # noqa: E402

from trajkit.hmi.app import MAX_WS_CLIENTS, WS_CLOSE_BUSY, WS_RATE_HZ, create_app  # noqa: E402
from trajkit.hmi.security import WS_CLOSE_REFUSED, WS_CLOSE_TOKEN  # noqa: E402

#: Largest number of messages read while waiting for something.
MAX_MESSAGES = 500

FAST_SADDLE = {"kind": "saddle", "feed_mm_s": 300, "period_s": 0.005, "z_vmax_mm_s": 1000,
               "theta_vmax_deg_s": 720, "accel_mm_s2": 5000, "jerk_mm_s3": 100000,
               "theta_amax_deg_s2": 10000, "theta_jmax_deg_s3": 500000,
               "z_amax_mm_s2": 10000, "z_jmax_mm_s3": 500000}


@pytest.fixture
def client(tmp_path):
    app = create_app(programs_dir=tmp_path)
    with page_client(app) as c:
        yield c


def read_until(ws, pred):
    """Messages up to and including the first that satisfies ``pred``."""
    out = []
    for _ in range(MAX_MESSAGES):
        m = ws.receive_json()
        out.append(m)
        if pred(m):
            return out
    raise AssertionError("condition never met on the live stream")


def test_rate_setting_is_at_least_20_hz():
    assert WS_RATE_HZ >= 20.0


def test_live_stream_follows_a_run(client):
    res = client.post("/api/job", json=FAST_SADDLE)
    assert res.status_code == 200, res.text
    tb = client.session.job
    with client.websocket_connect(WS_BASE + "/ws") as ws:
        first = ws.receive_json()
        assert first["type"] == "live" and first["state"] == "idle" and first["seq"] == 1
        client.post("/api/run/start")
        msgs = read_until(ws, lambda m: m["state"] == "running" and m.get("progress", 0) > 0.2)
        msgs += read_until(ws, lambda m: m["state"] == "idle" and m.get("progress", 0) == 1.0)
    seqs = [m["seq"] for m in [first] + msgs]
    assert seqs == list(range(1, len(seqs) + 1))  # no message lost or repeated
    running = [m for m in msgs if m.get("axes") and m["state"] == "running"]
    assert len(running) >= 5
    prog = [m["progress"] for m in running]
    assert all(b >= a for a, b in zip(prog, prog[1:])) and prog[-1] > prog[0]
    # the streamed command lies on the planned seam: Z = sqrt(R^2 - r^2 sin^2 theta) [mm]
    for m in running:
        th = np.radians(m["axes"][0]["position"])
        z = m["axes"][1]["position"]
        assert z == pytest.approx(np.sqrt(150.0 ** 2 - (100.0 * np.sin(th)) ** 2), abs=1e-6)
        assert abs(m["axes"][1]["following_error"]) < 0.01  # mm, servo simulation keeps up
    # the actual tool path streamed incrementally: points on the branch pipe (r = 100 mm)
    trail = [p for m in msgs for p in m["trail"]]
    assert len(trail) > 10
    assert np.allclose(np.hypot(*np.array(trail)[:, :2].T), 100.0, atol=1e-6)
    # the run ends at the end of the seam (within one period of travel: the
    # runtime's last setpoint is one control period before the goal)
    last = msgs[-1]
    one_period_deg = np.degrees(tb.v_max[0]) * tb.period
    assert abs(last["axes"][0]["position"] - np.degrees(tb.q[-1, 0])) <= one_period_deg
    # every event arrives exactly once, in order
    ev = [e for m in [first] + msgs for e in m["events"]]
    ids = [e["id"] for e in ev]
    assert ids == sorted(set(ids))
    assert any("complete" in e["text"] for e in ev)


def test_estop_on_the_stream(client):
    client.post("/api/job", json=FAST_SADDLE)
    with client.websocket_connect(WS_BASE + "/ws") as ws:
        client.post("/api/run/start")
        read_until(ws, lambda m: m["state"] == "running" and m.get("progress", 0) > 0.05)
        client.post("/api/run/estop")
        msgs = read_until(ws, lambda m: m["state"] == "fault")
        fault_msg = msgs[-1]
        assert all(a["velocity"] == 0.0 for a in fault_msg["axes"])
        ev = [e for m in msgs for e in m["events"] if e["level"] == "fault"]
        if not ev:
            more = read_until(ws, lambda m: any(e["level"] == "fault" for e in m["events"]))
            ev = [e for e in more[-1]["events"] if e["level"] == "fault"]
        assert "EMERGENCY STOP" in ev[0]["text"]
        held = [m["axes"][0]["position"] for m in [ws.receive_json() for _ in range(5)]]
        assert len(set(held)) == 1  # the command is held
        client.post("/api/run/reset")
        read_until(ws, lambda m: m["state"] == "idle")


def test_websocket_needs_the_token(tmp_path):
    app = create_app(token="ws-token-1234567", programs_dir=tmp_path)
    with page_client(app) as c:
        with pytest.raises(WebSocketDisconnect) as exc:
            with c.websocket_connect(WS_BASE + "/ws") as ws:
                ws.receive_json()
        assert exc.value.code == WS_CLOSE_TOKEN == 4401  # accepted, then closed with the code
        with pytest.raises(WebSocketDisconnect) as exc:
            with c.websocket_connect(WS_BASE + "/ws?token=ws-token-1234568") as ws:
                ws.receive_json()
        assert exc.value.code == 4401
        with c.websocket_connect(WS_BASE + "/ws?token=ws-token-1234567") as ws:
            assert ws.receive_json()["type"] == "live"


@pytest.mark.parametrize("headers", [
    {"origin": "http://evil.example"},
    {"origin": "http://127.0.0.1:9999"},  # another port of this machine is another origin
    {"origin": "null"},
    {"host": "evil.example:8765"},  # DNS rebinding
])
def test_websocket_refuses_foreign_origins_and_hosts(client, headers):
    with pytest.raises(WebSocketDisconnect) as exc:
        with client.websocket_connect(WS_BASE + "/ws", headers=headers) as ws:
            ws.receive_json()
    assert exc.value.code == WS_CLOSE_REFUSED  # refused before the handshake: HTTP 403 in a browser


def test_websocket_from_the_page_itself(client):
    with client.websocket_connect(WS_BASE + "/ws", headers={"origin": "http://127.0.0.1:8765"}) as ws:
        assert ws.receive_json()["type"] == "live"


def test_websocket_client_cap(client):
    from contextlib import ExitStack

    with ExitStack() as stack:
        for _ in range(MAX_WS_CLIENTS):
            ws = stack.enter_context(client.websocket_connect(WS_BASE + "/ws"))
            assert ws.receive_json()["type"] == "live"
        with pytest.raises(WebSocketDisconnect) as exc:
            with client.websocket_connect(WS_BASE + "/ws") as ws:
                ws.receive_json()
        assert exc.value.code == WS_CLOSE_BUSY
    with client.websocket_connect(WS_BASE + "/ws") as ws:  # a place is free again
        assert ws.receive_json()["type"] == "live"
