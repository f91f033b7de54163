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


# ----------------------------------------------------------------------------- a real server
def free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class ServerThread:
    """An ASGI app served by uvicorn on 127.0.0.1 in a thread (context manager).

    ``url`` is its address once entered.
    """

    def __init__(self, app, port: int | None = None) -> None:
        import threading

        import uvicorn

        self.port = port or free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=self.port,
                                                    log_level="warning", ws="auto", lifespan="on"))
        self.thread = threading.Thread(target=self.server.run, daemon=True)

    def __enter__(self) -> ServerThread:
        import time

        self.thread.start()
        deadline = time.monotonic() + 20
        while not self.server.started:
            assert self.thread.is_alive() and time.monotonic() < deadline, "server did not start"
            time.sleep(0.02)
        return self

    def __exit__(self, *exc) -> None:
        self.server.should_exit = True
        self.thread.join(timeout=10)
        assert not self.thread.is_alive(), "server did not stop"


# ----------------------------------------------------------------------------- a flood of requests
def flood(port: int, threads: int, seconds: float) -> None:
    """Hammer the HMI on ``port`` from ``threads`` threads for ``seconds`` (run in a subprocess).

    Each thread keeps one connection busy with a mix of status reads,
    refused job loads, oversized bodies, malformed JSON and foreign-origin
    commands; prints ``flooding`` once every thread has sent a request and
    the request count at the end.
    """
    import http.client
    import threading
    import time

    stop = time.monotonic() + seconds
    counts = [0] * threads
    started = threading.Barrier(threads + 1)
    big = b"{" + b" " * (1 << 20) + b"}"
    reqs = [
        ("GET", "/api/status", None, {}),
        ("POST", "/api/job", b'{"kind": "pallet"}', {"X-Trajkit-CSRF": "wrong"}),
        ("POST", "/api/job", big, {}),
        ("POST", "/api/override", b'{"percent": 5, "percent": 6}', {}),
        ("GET", "/api/events", None, {}),
        ("POST", "/api/run/reset", b"", {"Origin": "http://evil.example"}),
        ("GET", "/static/hmi.js", None, {}),
    ]

    def worker(k: int) -> None:
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
        first = True
        i = k
        while time.monotonic() < stop:
            method, path, body, hdr = reqs[i % len(reqs)]
            i += 1
            try:
                conn.request(method, path, body=body, headers=hdr)
                conn.getresponse().read()
            except (OSError, http.client.HTTPException):
                conn.close()
                conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
            counts[k] += 1
            if first:
                first = False
                started.wait()

    ts = [threading.Thread(target=worker, args=(k,), daemon=True) for k in range(threads)]
    for t in ts:
        t.start()
    started.wait()
    print("flooding", flush=True)
    for t in ts:
        t.join()
    print(sum(counts), flush=True)
