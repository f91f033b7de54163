"""Helpers shared by the HMI tests: a TestClient that speaks as the HMI's own page."""

from __future__ import annotations

from fastapi.testclient import TestClient

#: The address the in-process client pretends to use (an allowed host).
BASE_URL = "http://127.0.0.1:8765"


def page_client(app, **kw) -> TestClient:
    """A client on an allowed host that sends the anti-CSRF header like the page does.

    Use it as a context manager (it runs the app's lifespan).
    """
    c = TestClient(app, base_url=BASE_URL, **kw)
    c.headers["X-Trajkit-CSRF"] = app.state.policy.csrf_token
    c.session = app.state.session
    return c

#: WebSocket base address of the same host (TestClient's websocket_connect needs it whole).
WS_BASE = BASE_URL.replace("http://", "ws://")
