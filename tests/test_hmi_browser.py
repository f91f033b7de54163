"""End-to-end tests of the web HMI in headless Chromium (Debian's ``chromium`` + Playwright).

The server runs in this process on 127.0.0.1 (a free port) and is stopped
after each test. Skipped only when chromium (or playwright) is absent AND the
environment variable ``CI`` is unset; in CI a missing browser fails.
The screenshot is saved under ``test-artifacts/`` (git-ignored) and under
the test's tmp dir.
"""

from __future__ import annotations

import contextlib
import math
import os
import re
import shutil
import socket
import tempfile
import threading
import time
from pathlib import Path

import pytest

CHROMIUM = os.environ.get("TRAJKIT_CHROMIUM", "/usr/bin/chromium")
CHROMIUM_ARGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--host-resolver-rules=MAP evil.test 127.0.0.1",  # a DNS-rebinding name for one test
]
ARTIFACTS = Path(__file__).resolve().parent.parent / "test-artifacts"

#: Longest wait for something to appear in the page [ms] (a guard against hanging: the
#: suite runs in parallel workers, so a busy machine must not fail it).
WAIT_MS = 60_000


def _have_browser() -> str | None:
    """None when the browser stack is usable, else the reason."""
    if not (os.path.isfile(CHROMIUM) and os.access(CHROMIUM, os.X_OK)):
        return f"{CHROMIUM} not found (run .ci/install-browser)"
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        return "playwright is not installed"
    try:
        import fastapi  # noqa: F401
        import uvicorn  # noqa: F401
    except ImportError:
        return "fastapi/uvicorn are not installed"
    return None


_REASON = _have_browser()
if _REASON is not None:
    if os.environ.get("CI"):
        pytestmark = pytest.mark.usefixtures("_fail_in_ci")
    else:
        pytestmark = pytest.mark.skip(reason=_REASON)


@pytest.fixture
def _fail_in_ci():
    pytest.fail(f"browser tests must run in CI: {_REASON}")


@pytest.fixture
def hmi_server(tmp_path):
    """The HMI on 127.0.0.1 at a free port, in a thread; stopped after the test."""
    import uvicorn

    from trajkit.hmi.app import create_app

    app = create_app(programs_dir=tmp_path / "programs")
    with socket.socket() as s:  # a free port on loopback
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=port, log_level="warning",
                                           ws="auto", lifespan="on"))
    th = threading.Thread(target=server.run, daemon=True)
    th.start()
    # (the app compiles the runtime's kernels before it serves: minutes on a cold numba
    # cache with the other workers busy; the deadline only guards against a hang)
    deadline = time.monotonic() + 600
    while not server.started:
        assert th.is_alive() and time.monotonic() < deadline, "HMI server did not start"
        time.sleep(0.02)
    try:
        yield f"http://127.0.0.1:{port}", app
    finally:
        server.should_exit = True
        th.join(timeout=30)
        assert not th.is_alive(), "HMI server did not stop"


#: Chromium features that block requests from a public page to this machine (Private
#: Network Access); the DNS-rebinding test turns them off to reach the HMI's own check,
#: as a browser without them would.
PNA_FEATURES = ("BlockInsecurePrivateNetworkRequests,PrivateNetworkAccessSendPreflights,"
                "LocalNetworkAccessChecks")


@contextlib.contextmanager
def _browser_page(extra_args=()):
    from playwright.sync_api import sync_playwright

    profile = tempfile.mkdtemp(prefix="trajkit-chromium-")
    try:
        with sync_playwright() as pw:
            ctx = pw.chromium.launch_persistent_context(
                profile, executable_path=CHROMIUM, args=CHROMIUM_ARGS + list(extra_args), headless=True,
                viewport={"width": 1480, "height": 1000},
            )
            try:
                pg = ctx.pages[0] if ctx.pages else ctx.new_page()
                pg.set_default_timeout(WAIT_MS)
                errors: list[str] = []
                pg.on("pageerror", lambda e: errors.append(str(e)))
                pg.js_errors = errors
                yield pg
            finally:
                ctx.close()
    finally:
        shutil.rmtree(profile, ignore_errors=True)


@pytest.fixture
def page():
    with _browser_page() as pg:
        yield pg


@pytest.fixture
def page_without_pna():
    with _browser_page([f"--disable-features={PNA_FEATURES}"]) as pg:
        yield pg


def until(page, expr: str, timeout: int = WAIT_MS) -> None:
    """Wait until the JavaScript expression is true (passed as a function: the page's CSP forbids eval)."""
    page.wait_for_function(f"() => ({expr})", timeout=timeout)


def _jog(page, joint: str, step: str, shows: str) -> None:
    """Jog ``joint`` by ``step`` and wait until the run ended with the joints showing
    ``shows``. The jog's reply ("jogging J3") may arrive after the run: wait for
    both, so the page does not re-render under the next click."""
    page.select_option("#jog-joint", joint)
    page.fill("#jog-step", step)
    page.click("#jog-plus")
    until(page, "document.getElementById('state').textContent === 'idle'"
                f" && document.querySelector('#joints').textContent.includes('{shows}')"
                f" && document.getElementById('msg').textContent === 'jogging {joint}'")


def _axis_value(page, axis: str, what: str) -> float:
    txt = page.locator(f'#axes tr[data-axis="{axis}"] .axis-{what}').inner_text()
    return float(re.match(r"\s*(-?[0-9.]+)", txt).group(1))


def _wait_state(page, state: str) -> None:
    until(page, f"document.getElementById('state').textContent === '{state}'", timeout=WAIT_MS)


def test_saddle_run_end_to_end(hmi_server, page, tmp_path):
    base, app = hmi_server
    page.goto(base + "/")
    until(page, "document.getElementById('conn').textContent === 'live'")
    assert "trajkit" in page.title()

    # set saddle parameters; a bad value first: clear message, nothing loaded
    page.fill('#pane-saddle input[name="feed_mm_s"]', "-5")
    page.click("#plan-saddle")
    page.wait_for_selector("#msg.error")
    assert "feed_mm_s" in page.inner_text("#msg") and "greater than 0" in page.inner_text("#msg")
    assert app.state.session.job is None
    assert page.is_disabled("#btn-start")

    page.fill('#pane-saddle input[name="main_radius_mm"]', "160")
    page.fill('#pane-saddle input[name="feed_mm_s"]', "20")
    page.fill('#pane-saddle input[name="period_s"]', "0.002")
    page.click("#plan-saddle")
    until(page, "document.getElementById('msg').textContent.startsWith('planned')")
    job = app.state.session.job
    assert job is not None and job.kind == "saddle" and job.period == 0.002
    assert page.locator("#axes tbody tr").count() == 2

    # start: live values change
    page.click("#btn-start")
    _wait_state(page, "running")
    until(page,
        "document.querySelector('#axes tr[data-axis=\"theta\"] .axis-pos').textContent.startsWith('-') === false"
        " && parseFloat(document.querySelector('#axes tr[data-axis=\"theta\"] .axis-pos').textContent) > 1")
    th1 = _axis_value(page, "theta", "pos")
    page.wait_for_timeout(400)
    th2 = _axis_value(page, "theta", "pos")
    assert th2 > th1 > 0.0
    assert _axis_value(page, "theta", "vel") > 0.0

    # pause: the axes come to rest and stay; resume: they move again
    page.click("#btn-pause")
    _wait_state(page, "paused")
    # (at rest once the stop ramp has run and the page has the last values: on a
    # loaded machine that can take longer than any fixed wait)
    until(page, "parseFloat(document.querySelector('#axes tr[data-axis=\"theta\"] .axis-vel')"
                ".textContent) === 0")
    page.wait_for_timeout(200)
    p1 = _axis_value(page, "theta", "pos")
    page.wait_for_timeout(400)
    assert _axis_value(page, "theta", "pos") == p1
    assert _axis_value(page, "theta", "vel") == 0.0
    page.click("#btn-resume")
    _wait_state(page, "running")
    until(page,
        f"parseFloat(document.querySelector('#axes tr[data-axis=\"theta\"] .axis-pos').textContent) > {p1 + 1}")

    # emergency stop: fault shown, axes frozen, start refused until reset
    page.click("#btn-estop")
    _wait_state(page, "E-STOP")
    page.wait_for_selector("#events li.fault")
    assert "EMERGENCY STOP" in page.inner_text("#events li.fault")
    sess = app.state.session
    assert sess.state == "fault"
    assert 0.0 <= sess.last_estop_latency_s <= job.period
    assert page.is_disabled("#btn-start") and page.is_enabled("#btn-reset")
    tau = sess.drive.tau
    page.wait_for_timeout(300)
    assert sess.drive.tau == tau
    page.screenshot(path=str(tmp_path / "hmi_estop.png"), full_page=True)

    page.click("#btn-reset")
    _wait_state(page, "idle")
    assert page.is_enabled("#btn-start")
    assert not page.js_errors, page.js_errors

    shot = tmp_path / "hmi_saddle.png"
    page.click("#btn-start")
    _wait_state(page, "running")
    # the live tool speed of the seam, read while the run certainly goes on (a seam of
    # about 33 s: the screenshots below may take seconds on a loaded machine)
    until(page, "parseFloat(document.getElementById('tool-speed').textContent) > 1")
    page.wait_for_timeout(1500)
    page.screenshot(path=str(shot), full_page=True)
    ARTIFACTS.mkdir(exist_ok=True)
    shutil.copy(shot, ARTIFACTS / "hmi_saddle.png")
    shutil.copy(tmp_path / "hmi_estop.png", ARTIFACTS / "hmi_estop.png")
    assert shot.stat().st_size > 20_000

    # an operator panel of 1024 x 768: nothing sticks out sideways, the axes table and the
    # charts fit their panels, the emergency stop is on screen without scrolling
    page.set_viewport_size({"width": 1024, "height": 768})
    page.wait_for_timeout(600)  # the charts follow their panel's new width
    box = lambda sel: page.locator(sel).bounding_box()  # noqa: E731
    assert page.evaluate("() => document.documentElement.scrollWidth") <= 1024
    axes_panel = page.locator("#axes").locator("xpath=..").bounding_box()
    assert box("#axes")["x"] + box("#axes")["width"] <= axes_panel["x"] + axes_panel["width"] + 0.5
    for chart in ("#chart-pos", "#chart-vel"):
        canvas = page.locator(chart + " canvas").bounding_box()
        assert canvas["x"] + canvas["width"] <= box(chart)["x"] + box(chart)["width"] + 0.5
        assert canvas["width"] > 400
    estop = box("#btn-estop")
    assert estop["y"] >= 0 and estop["y"] + estop["height"] <= 768 and estop["x"] + estop["width"] <= 1024
    # summary rows with units
    summary = page.inner_text("#summary")
    assert "Planned duration" in summary and re.search(r"Programmed feed\s+20 mm/s", summary), summary
    page.screenshot(path=str(tmp_path / "hmi_1024x768.png"))
    shutil.copy(tmp_path / "hmi_1024x768.png", ARTIFACTS / "hmi_1024x768.png")
    page.click("#btn-stop")
    _wait_state(page, "idle")

    # a failed plan unloads the job: Start is off and every view says so
    page.fill('#pane-saddle input[name="main_radius_mm"]', "90")
    page.click("#plan-saddle")
    page.wait_for_selector("#msg.error")
    until(page, "document.getElementById('job-title').textContent === 'no job loaded'")
    assert sess.job is None and page.is_disabled("#btn-start")
    until(page, "document.querySelector('#axes tbody').textContent === 'no job loaded'")
    assert page.inner_text("#summary").split() == ["Job", "none"]
    assert not page.js_errors, page.js_errors


def test_jog_teach_build_save_load(hmi_server, page):
    base, app = hmi_server
    page.goto(base + "/")
    until(page, "document.getElementById('conn').textContent === 'live'")
    until(page, "document.querySelectorAll('#jog-joint option').length === 4")
    sess = app.state.session
    q0 = sess.q.copy()

    # a jog beyond the joint range is refused with the range in the message
    page.select_option("#jog-joint", "J3")
    page.fill("#jog-step", "300")
    page.click("#jog-plus")
    page.wait_for_selector("#msg.error")
    assert "J3" in page.inner_text("#msg") and "range" in page.inner_text("#msg")
    assert (sess.q == q0).all()

    _jog(page, "J3", "50", "50.000 mm")
    assert sess.q[2] == pytest.approx(0.05, abs=1e-12)
    # home has the elbow bent (90 deg; a line between points with the arm
    # stretched, a singularity, cannot be followed)
    _jog(page, "J2", "-45", "45.000 deg")
    page.click("#btn-teach")  # p1
    until(page, "document.querySelectorAll('#step-point option').length === 1")
    _jog(page, "J1", "20", "20.000 deg")
    page.click("#btn-teach")  # p2
    until(page, "document.querySelectorAll('#step-point option').length === 2")
    # jog steps while the jog moves are taken as new targets of the same run
    run = sess.run_id
    page.fill("#jog-speed", "2")
    page.fill("#jog-step", "10")
    page.click("#jog-plus")
    until(page, "document.getElementById('state').textContent === 'running'"
                " && !document.getElementById('jog-plus').disabled")
    # the three steps in one go from the page: a click each from here may take longer
    # than the jog itself on a loaded machine, and a late step would start a new run
    page.evaluate("() => { for (const id of ['jog-plus', 'jog-minus', 'jog-plus'])"
                  " document.getElementById(id).click(); }")
    try:
        until(page, "document.getElementById('state').textContent === 'idle'"
                    " && document.querySelector('#joints').textContent.includes('40.000 deg')")
    except Exception as exc:
        raise AssertionError((page.inner_text("#msg"), sess.events[-8:])) from exc
    assert sess.run_id == run + 1 and math.degrees(sess.q[0]) == pytest.approx(40.0, abs=1e-9)
    assert [e.kind for e in sess.drive.streamer.events].count("target") == 4
    page.fill("#jog-speed", "20")
    page.fill("#jog-step", "-20")
    page.click("#jog-plus")
    until(page, "document.getElementById('state').textContent === 'idle'"
                " && document.querySelector('#joints').textContent.includes('20.000 deg')")
    assert set(sess.points) == {"p1", "p2"}

    page.select_option("#step-op", "PTP")
    page.select_option("#step-point", "p1")
    page.click("#btn-add-step")
    page.select_option("#step-op", "LIN")
    page.select_option("#step-point", "p2")
    page.click("#btn-add-step")
    page.click("#btn-build")
    until(page, "document.getElementById('program-text').value.includes('LIN: p2')")

    page.fill("#program-name", "cell_1")
    page.click("#btn-save")
    until(page, "document.getElementById('msg').textContent === 'saved cell_1.yaml'")
    saved = Path(sess.programs_dir) / "cell_1.yaml"
    assert saved.is_file() and "LIN: p2" in saved.read_text()

    page.fill("#program-text", "robot: scara\n")
    page.click("#btn-load")
    until(page, "document.getElementById('program-text').value.includes('LIN: p2')")
    page.click("#plan-program")
    until(page, "document.getElementById('msg').textContent.startsWith('planned')")
    assert sess.job.kind == "program" and sess.job.robot == "scara"
    assert not page.js_errors, page.js_errors


# ----------------------------------------------------------------- a page from another origin
ATTACK_PAGE = """<!doctype html><title>cat pictures</title>
<form id="f1" method="POST" action="HMI/api/run/reset" target="sink1" enctype="text/plain">
  <input name='{"x":' value='1}'></form>
<form id="f2" method="POST" action="HMI/api/run/start" target="sink2"></form>
<iframe name="sink1"></iframe><iframe name="sink2"></iframe>
<iframe id="framed" src="HMI/"></iframe>
<script>
window.results = {};
(async function attack() {
  const r = window.results, BASE = "HMI";
  for (const cmd of ["reset", "start"]) {  // the attack: no-cors posts
    try { await fetch(BASE + "/api/run/" + cmd, {method: "POST", mode: "no-cors"}); r[cmd] = "sent"; }
    catch (e) { r[cmd] = "error"; }
  }
  try { await fetch(BASE + "/api/run/reset", {method: "POST", headers: {"X-Trajkit-CSRF": "guess"}}); r.csrf = "answered"; }
  catch (e) { r.csrf = "blocked"; }
  try { const x = await fetch(BASE + "/api/status"); r.read = await x.text(); } catch (e) { r.read = "blocked"; }
  try { const x = await fetch(BASE + "/api/session", {mode: "no-cors"}); r.session = x.type; } catch (e) { r.session = "blocked"; }
  r.img = await new Promise((res) => { const i = new Image(); i.onload = () => res("loaded"); i.onerror = () => res("refused"); i.src = BASE + "/api/status"; });
  r.ws = await new Promise((res) => {
    const ws = new WebSocket(BASE.replace("http", "ws") + "/ws");
    ws.onmessage = (m) => { res("read " + m.data.slice(0, 40)); ws.close(); };
    ws.onerror = () => res("refused");
  });
  document.getElementById("f1").submit();
  document.getElementById("f2").submit();
  r.done = true;
})();
</script>"""


@pytest.fixture
def attacker_site():
    """A second origin (another port of this machine) serving the attack page."""
    import http.server

    pages: dict[str, bytes] = {}

    class Handler(http.server.BaseHTTPRequestHandler):
        def do_GET(self):  # noqa: N802 - http.server's name
            body = pages.get(self.path, b"not here")
            self.send_response(200 if self.path in pages else 404)
            self.send_header("Content-Type", "text/html; charset=utf-8")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, *a):
            pass

    srv = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    th = threading.Thread(target=srv.serve_forever, daemon=True)
    th.start()
    try:
        yield f"http://127.0.0.1:{srv.server_address[1]}", pages
    finally:
        srv.shutdown()
        srv.server_close()


def test_a_page_from_another_origin_cannot_drive_or_read_the_machine(hmi_server, attacker_site, page, caplog):
    import logging

    base, app = hmi_server
    evil, pages = attacker_site
    sess = app.state.session
    sess.command("estop")  # a latched emergency stop: the attack tries reset + start
    assert sess.state == "fault"
    caplog.set_level(logging.INFO, logger="trajkit")
    pages["/cats.html"] = ATTACK_PAGE.replace("HMI", base).encode()
    page.goto(evil + "/cats.html")
    until(page, "window.results && window.results.done === true")
    page.wait_for_timeout(500)  # the two form posts
    res = page.evaluate("() => window.results")
    # the browser sent the posts (the server log below shows them) and the HMI refused
    # them; even the opaque answer is withheld (Cross-Origin-Resource-Policy)
    assert res["reset"] == "error" and res["start"] == "error"
    assert sess.state == "fault"
    assert res["csrf"] == "blocked"  # a custom header needs CORS consent, never given
    assert res["read"] == "blocked" and res["session"] == "blocked" and res["img"] == "refused"
    assert res["ws"] == "refused"
    refused = [r.getMessage() for r in caplog.records if r.getMessage().startswith("hmi: refused")]
    for what in ("POST /api/run/reset (403)", "POST /api/run/start (403)", "WEBSOCKET /ws (403)",
                 "GET /api/status (403)", "GET / (403)"):
        assert any(what in m for m in refused), (what, refused)
    assert sum("POST /api/run/reset (403)" in m for m in refused) == 2  # the fetch and the form
    # the HMI cannot be framed (clickjacking): no frame shows its page
    frames = [f for f in page.frames if f is not page.main_frame]
    assert len(frames) == 3
    for f in frames:
        assert not f.url.startswith(base)  # Chromium shows its error page instead
        assert f.evaluate("() => document.getElementById('btn-estop')") is None
    assert not [e for e in sess.events if e["text"] == "emergency stop reset"]


def test_dns_rebinding_is_refused(hmi_server, page_without_pna):
    """A foreign name that resolves to this machine (the browser maps evil.test to 127.0.0.1)."""
    page = page_without_pna
    base, app = hmi_server
    sess = app.state.session
    sess.command("estop")
    port = base.rsplit(":", 1)[1]
    rebound = f"http://evil.test:{port}"
    # the attacker's page, as if served by evil.test before its address changed to 127.0.0.1
    page.route(rebound + "/rebind.html", lambda route: route.fulfill(
        status=200, content_type="text/html", body="<!doctype html><title>x</title><script>"
        "window.r = {}; (async () => { for (const c of ['reset', 'start']) {"
        "  const x = await fetch('/api/run/' + c, {method: 'POST'}); window.r[c] = x.status; }"
        "  const s = await fetch('/api/status'); window.r.status = s.status; window.r.text = await s.text();"
        "  window.r.done = true; })();</script>"))
    page.goto(rebound + "/rebind.html")
    until(page, "window.r && window.r.done === true")
    r = page.evaluate("() => window.r")
    assert r["reset"] == 403 and r["start"] == 403 and r["status"] == 403, r
    assert "not allowed" in r["text"] and '"state"' not in r["text"]
    assert sess.state == "fault"


def test_token_mode_page_works_and_needs_the_token(page, tmp_path):
    """Opened with ?token=, the page loads its files (cookie), reads the live stream and commands."""
    from hmi_support import ServerThread

    from trajkit.hmi.app import create_app

    token = "pl4nt-floor-T0ken-7781"
    app = create_app(token=token, programs_dir=tmp_path)
    with ServerThread(app) as srv:
        r = page.goto(srv.url + "/")
        assert r.status == 401 and "needs its token" in page.inner_text("body")
        page.goto(srv.url + f"/?token={token}")
        until(page, "document.getElementById('conn').textContent === 'live'")
        page.click("#btn-estop")
        _wait_state(page, "E-STOP")
        page.click("#btn-reset")
        _wait_state(page, "idle")
        assert not page.js_errors, page.js_errors
        # the page's files came with the cookie it set; without it they are refused
        assert page.request.get(srv.url + "/static/hmi.js").status == 200
        page.context.clear_cookies()
        assert page.request.get(srv.url + "/static/hmi.js").status == 401
