"""End-to-end tests of the web HMI in headless Chromium (Debian's ``chromium`` + Playwright).

The server runs in this process on 127.0.0.1 (a free port) and is stopped
after each test. Skipped only when chromium (or playwright) is absent AND the
environment variable ``CI`` is unset; in CI a missing browser fails.
The screenshot is saved under ``test-artifacts/`` (git-ignored) and under
the test's tmp dir.
"""

from __future__ import annotations

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
]
ARTIFACTS = Path(__file__).resolve().parent.parent / "test-artifacts"

#: Longest wait for something to appear in the page [ms].
WAIT_MS = 20_000


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
    deadline = time.monotonic() + 20
    while not server.started:
        assert th.is_alive() and time.monotonic() < deadline, "HMI server did not start"
        time.sleep(0.02)
    try:
        yield f"http://127.0.0.1:{port}", app
    finally:
        server.should_exit = True
        th.join(timeout=10)
        assert not th.is_alive(), "HMI server did not stop"


@pytest.fixture
def page():
    from playwright.sync_api import sync_playwright

    profile = tempfile.mkdtemp(prefix="trajkit-chromium-")
    try:
        with sync_playwright() as pw:
            ctx = pw.chromium.launch_persistent_context(
                profile, executable_path=CHROMIUM, args=CHROMIUM_ARGS, headless=True,
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


def until(page, expr: str, timeout: int = WAIT_MS) -> None:
    """Wait until the JavaScript expression is true (passed as a function: the page's CSP forbids eval)."""
    page.wait_for_function(f"() => ({expr})", timeout=timeout)


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
    page.fill('#pane-saddle input[name="feed_mm_s"]', "50")
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
    page.wait_for_timeout(1500)
    page.screenshot(path=str(shot), full_page=True)
    ARTIFACTS.mkdir(exist_ok=True)
    shutil.copy(shot, ARTIFACTS / "hmi_saddle.png")
    shutil.copy(tmp_path / "hmi_estop.png", ARTIFACTS / "hmi_estop.png")
    assert shot.stat().st_size > 20_000
    page.click("#btn-stop")
    _wait_state(page, "idle")


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

    page.fill("#jog-step", "50")
    page.click("#jog-plus")
    # the jog's reply ("jogging J3") may arrive after the run: wait for both, so the
    # page does not re-render under the next click
    until(page, "document.getElementById('state').textContent === 'idle'"
                           " && document.querySelector('#joints').textContent.includes('50.000 mm')"
                           " && document.getElementById('msg').textContent === 'jogging J3'")
    assert sess.q[2] == pytest.approx(0.05, abs=1e-12)
    page.click("#btn-teach")  # p1
    until(page, "document.querySelectorAll('#step-point option').length === 1")
    page.select_option("#jog-joint", "J1")
    page.fill("#jog-step", "20")
    page.click("#jog-plus")
    until(page, "document.getElementById('state').textContent === 'idle'"
                           " && document.querySelector('#joints').textContent.includes('20.000 deg')"
                           " && document.getElementById('msg').textContent === 'jogging J1'")
    page.click("#btn-teach")  # p2
    until(page, "document.querySelectorAll('#step-point option').length === 2")
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
