"""The FastAPI application of the web HMI (a thin shell over :mod:`trajkit.hmi.engine`).

Routes (JSON; units mm, deg, s as in :mod:`trajkit.hmi.models`):

==========================  ====================================================
``GET  /``                  the page (``?token=T`` when a token is set)
``GET  /api/session``       the anti-CSRF value for ``X-Trajkit-CSRF``
``GET  /api/status``        live snapshot (state, axes, progress, override)
``POST /api/job``           plan and load a job (saddle / pallet / program)
``GET  /api/job``           the loaded job's planned path and summary
``POST /api/run/{cmd}``     start, pause, resume, stop, estop, reset
``POST /api/override``      feed override ``{"percent": 0..100}``
``GET|POST /api/robot``     jog/teach robot and its current joints
``POST /api/jog``           jog one joint by a step (a jerk-limited move)
``POST /api/teach``         store the current joints as a named point
``POST /api/program/build`` program text from taught points
``GET|POST /api/programs``  list / save program files; ``GET /api/programs/{name}``
``GET  /api/events``        the event and fault log
``WS   /ws``                live values at :data:`WS_RATE_HZ`
==========================  ====================================================

Every request first passes the guard of :mod:`trajkit.hmi.security` (host,
origin, token, anti-CSRF header, body size). Request bodies are strict JSON
(no duplicate keys, UTF-8, bounded nesting) and numbers are strict (``true``
or ``"50"`` is not a number).

Errors answer ``{"error": "<one line>"}``: 422 for a value that fails
validation (the field, the message and the value), 400 for a request the
library refuses (e.g. pipes that do not meet) or a body that is not valid
JSON, 409 for a command the state does not allow (start while a run is
active), 401 for a missing or wrong token, 403 for a foreign host or origin
or a missing anti-CSRF header, 413 for a body above the size limit, 408 for
a body that does not arrive in time. A failed request changes nothing, except a failed ``POST /api/job``: it unloads the
previous job (what the operator planned is not what would run).
"""

from __future__ import annotations

import asyncio
import logging
import math
import os
import re
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from contextlib import asynccontextmanager
from importlib import resources
from typing import Any

from fastapi import Depends, FastAPI, Request, WebSocket, WebSocketDisconnect
from fastapi.exceptions import RequestValidationError
from fastapi.responses import HTMLResponse, JSONResponse
from fastapi.staticfiles import StaticFiles
from pydantic import ValidationError
from starlette.concurrency import run_in_threadpool

from .._atomicio import atomic_write
from ..errors import InvalidInputError, TrajkitError
from ..io.document import parse_document
from .engine import COMMAND_WAIT_S, ConflictError, Session
from .jobs import plan_job
from .models import (
    NAME_PATTERN,
    BuildProgramRequest,
    JogRequest,
    OverrideRequest,
    PalletJob,
    ProgramJob,
    RobotRequest,
    SaddleJob,
    SaveProgramRequest,
    TeachRequest,
)
from .security import (
    CSRF_HEADER,
    MAX_BODY_BYTES,
    MAX_ECHO_CHARS,
    MAX_JSON_DEPTH,
    AccessPolicy,
    Guard,
    echo,
    one_line,
)

__all__ = ["create_app", "WS_RATE_HZ", "MAX_WS_CLIENTS", "WS_CLOSE_BUSY"]

log = logging.getLogger("trajkit")

#: How long a jog waits for another request's jog to be applied [s].
JOG_LOCK_WAIT_S = 0.5

#: Live updates per second over the WebSocket.
WS_RATE_HZ = 25.0

#: Most WebSocket clients served at once; one more is closed with :data:`WS_CLOSE_BUSY`.
MAX_WS_CLIENTS = 16

#: WebSocket close code when :data:`MAX_WS_CLIENTS` are connected ("try again later").
WS_CLOSE_BUSY = 1013


_JOB_MODELS = {"saddle": SaddleJob, "pallet": PalletJob, "program": ProgramJob}
_RUN_COMMANDS = ("start", "pause", "resume", "stop", "estop", "reset")


def _static_dir() -> str:
    return str(resources.files("trajkit.hmi") / "static")


def _fmt_validation(errors: Sequence[Any]) -> str:
    parts = []
    for err in errors:
        loc = [str(x) if len(str(x)) <= MAX_ECHO_CHARS else echo(str(x))
               for x in err.get("loc", ()) if x not in ("body",)]
        field = ".".join(loc) or "request"
        msg = err.get("msg", "invalid")
        msg = msg.removeprefix("Value error, ")
        got = err.get("input")
        tail = "" if isinstance(got, (dict, list)) or got is None else f" (got {echo(got)})"
        parts.append(f"{field}: {msg}{tail}")
    return one_line("; ".join(parts) or "invalid request")


def _parse_body(data: bytes) -> Any:
    """The one place where the HMI decodes a request body: the library's safe loader (strict JSON)."""
    return parse_document(data, source="request body", kind="json", max_bytes=MAX_BODY_BYTES,
                          max_depth=MAX_JSON_DEPTH)


def _validate(model, data: Any):
    """``model`` from a decoded body; a bad field raises :class:`RequestValidationError` (422)."""
    if not isinstance(data, dict):
        raise InvalidInputError(f"request body: must be a JSON object, got {type(data).__name__}")
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        raise RequestValidationError(exc.errors()) from None


async def _raw_body(request: Request) -> bytes:
    return await request.body()


def create_app(token: str | None = None, programs_dir: str | os.PathLike | None = None,
               session: Session | None = None, *, allowed_hosts=None, allowed_origins=None,
               robots_dir: str | os.PathLike | None = None,
               max_body_bytes: int = MAX_BODY_BYTES) -> FastAPI:
    """Build the HMI web application.

    Parameters
    ----------
    token : str, optional
        When set, every request needs it: the API, the WebSocket, the page,
        its files and the OpenAPI schema (header ``X-Trajkit-Token``,
        ``Authorization: Bearer T``, ``?token=T``, or the cookie the page
        sets when opened with ``?token=T``). Check it first with
        :func:`trajkit.hmi.server.check_bind` (weak tokens are refused there).
    programs_dir : path, optional
        Folder where program files are saved and loaded (created on the
        first save; default ``./trajkit-programs``).
    session : Session, optional
        The machine session (a new one by default). Its loop thread is
        stopped when the app shuts down.
    allowed_hosts : iterable of str, optional
        Host names the ``Host`` header may carry (default: this machine
        only, ``127.0.0.1``, ``localhost``, ``::1``).
    allowed_origins : iterable of str, optional
        Origins (``http://host:port``) allowed besides the HMI's own, e.g.
        a reverse proxy's public address.
    robots_dir : path, optional
        Folder of URDF files that programs may name (``robot: {urdf: ...}``);
        without it programs can use the built-in robots only.
    max_body_bytes : int
        Largest request body [bytes] (default 1 MiB).

    Returns
    -------
    fastapi.FastAPI
        ``app.state.session`` is the :class:`~trajkit.hmi.engine.Session`,
        ``app.state.policy`` the :class:`~trajkit.hmi.security.AccessPolicy`.

    Raises
    ------
    InvalidInputError
        A malformed allowed host or origin, or a robots folder that is not one.
    """
    policy = AccessPolicy.build(token, allowed_hosts, allowed_origins, max_body_bytes)
    sess = session or Session()
    pdir = os.fspath(programs_dir) if programs_dir is not None else os.path.join(os.getcwd(), "trajkit-programs")
    sess.programs_dir = pdir
    if robots_dir is not None and not os.path.isdir(robots_dir):
        raise InvalidInputError(f"robots folder {echo(os.fspath(robots_dir))} is not a folder")
    urdf_dirs = () if robots_dir is None else (os.fspath(robots_dir),)
    # stop, pause, resume, reset and override run on their own threads, so that a
    # flood of other requests (which share the default thread pool) cannot delay them
    safety_pool = ThreadPoolExecutor(max_workers=2, thread_name_prefix="trajkit-hmi-safety")

    @asynccontextmanager
    async def lifespan(app):
        # the runtime's compiled kernels before the first request: a run's streamer
        # is made under the session lock, which an emergency stop at rest takes
        from ..runtime import warm_up

        warm_up(("runtime",))
        yield
        sess.close()
        safety_pool.shutdown(wait=False)

    app = FastAPI(title="trajkit HMI", lifespan=lifespan, docs_url=None, redoc_url=None)
    app.add_middleware(Guard, policy=policy)
    app.state.session = sess
    app.state.token = token
    app.state.policy = policy
    ws_clients = 0

    async def on_safety_pool(fn, *args):
        return await asyncio.get_running_loop().run_in_executor(safety_pool, fn, *args)

    @app.exception_handler(RequestValidationError)
    async def _validation(request, exc):
        return JSONResponse({"error": _fmt_validation(exc.errors())}, status_code=422)

    @app.exception_handler(TrajkitError)
    async def _trajkit(request, exc):
        code = 409 if isinstance(exc, ConflictError) else 400
        return JSONResponse({"error": one_line(exc) or type(exc).__name__}, status_code=code)

    app.mount("/static", StaticFiles(directory=_static_dir()), name="static")

    @app.get("/", response_class=HTMLResponse)
    def index():
        with open(os.path.join(_static_dir(), "index.html"), encoding="utf-8") as fh:
            return HTMLResponse(fh.read())

    @app.get("/api/session")
    async def session_info() -> dict:
        """The anti-CSRF value that changing requests carry in ``X-Trajkit-CSRF``."""
        return {"csrf_header": CSRF_HEADER, "csrf_token": policy.csrf_token,
                "token_required": token is not None, "max_body_bytes": policy.max_body_bytes}

    @app.get("/api/status")
    async def status() -> dict:
        return sess.snapshot()

    @app.post("/api/job")
    def load_job(raw: bytes = Depends(_raw_body)) -> dict:
        sess.check_idle("load a job")  # refused before planning; the running job stays loaded
        if not sess.plan_lock.acquire(blocking=False):
            raise ConflictError("another job is being planned: wait for it")
        try:
            try:
                payload = _parse_body(raw)
                if not isinstance(payload, dict):
                    raise InvalidInputError(
                        f"request body: must be a JSON object, got {type(payload).__name__}")
                kind = payload.get("kind")
                if kind not in _JOB_MODELS:
                    raise InvalidInputError(
                        f"kind must be one of {', '.join(_JOB_MODELS)}, got {echo(kind)}")
                table = plan_job(_validate(_JOB_MODELS[kind], payload), urdf_dirs=urdf_dirs)
            except RequestValidationError as exc:
                sess.disarm(_fmt_validation(exc.errors()))
                raise
            except TrajkitError as exc:
                if not isinstance(exc, ConflictError):
                    sess.disarm(one_line(exc))
                raise
            sess.load(table)
        finally:
            sess.plan_lock.release()
        return table.preview()

    @app.get("/api/job")
    def get_job() -> dict:
        job = sess.job
        return {"job": None} if job is None else job.preview()

    @app.post("/api/run/estop")
    async def estop() -> dict:
        """Emergency stop: queued at once (no lock, no thread), applied in the next period."""
        cmd = sess.request_estop()
        if cmd is not None:
            loop = asyncio.get_running_loop()
            deadline = loop.time() + COMMAND_WAIT_S
            while not cmd.done.is_set() and loop.time() < deadline:
                await asyncio.sleep(0.001)
        return sess.snapshot()

    @app.post("/api/run/{cmd}")
    async def run_command(cmd: str) -> dict:
        if cmd not in _RUN_COMMANDS:
            raise InvalidInputError(f"run command must be one of {', '.join(_RUN_COMMANDS)}, "
                                    f"got {echo(cmd)}")
        if cmd == "start":
            await run_in_threadpool(sess.start)
        else:
            await on_safety_pool(sess.command, cmd)
        return sess.snapshot()

    @app.post("/api/override")
    async def override(raw: bytes = Depends(_raw_body)) -> dict:
        req = _validate(OverrideRequest, _parse_body(raw))
        await on_safety_pool(sess.command, "override", req.percent / 100.0)
        return sess.snapshot()

    @app.get("/api/robot")
    def robot() -> dict:
        return sess.joint_info()

    @app.post("/api/robot")
    def set_robot(raw: bytes = Depends(_raw_body)) -> dict:
        req = _validate(RobotRequest, _parse_body(raw))
        sess.set_robot(req.robot)
        return sess.joint_info()

    @app.post("/api/jog")
    def jog(raw: bytes = Depends(_raw_body)) -> dict:
        req = _validate(JogRequest, _parse_body(raw))
        rb = sess.robot
        if req.joint not in rb.joint_names:
            raise InvalidInputError(f"joint must be one of {', '.join(rb.joint_names)} of robot "
                                    f"{sess.robot_name}, got {echo(req.joint)}")
        k = rb.joint_names.index(req.joint)
        unit = math.pi / 180.0 if rb.joint_kinds[k] == "revolute" else 1e-3
        # a job being planned holds the lock for long (409); another jog only briefly
        if not sess.plan_lock.acquire(timeout=JOG_LOCK_WAIT_S):
            raise ConflictError("a job is being planned: wait for it")
        try:
            sess.jog(k, req.step * unit, req.speed_pct)
        finally:
            sess.plan_lock.release()
        return sess.joint_info()

    @app.post("/api/teach")
    def teach(raw: bytes = Depends(_raw_body)) -> dict:
        req = _validate(TeachRequest, _parse_body(raw))
        sess.teach(req.name)
        return sess.joint_info()

    @app.post("/api/program/build")
    def build(raw: bytes = Depends(_raw_body)) -> dict:
        req = _validate(BuildProgramRequest, _parse_body(raw))
        return {"text": sess.program_text(req.steps, req.speed_mm_s)}

    @app.get("/api/programs")
    def list_programs() -> dict:
        if not os.path.isdir(pdir):
            return {"programs": []}
        names = sorted(f[:-5] for f in os.listdir(pdir)
                       if f.endswith(".yaml") and re.fullmatch(NAME_PATTERN, f[:-5]))
        return {"programs": names}

    @app.get("/api/programs/{name}")
    def get_program(name: str) -> dict:
        if not re.fullmatch(NAME_PATTERN, name):
            raise InvalidInputError(f"program name must match {NAME_PATTERN}, got {echo(name)}")
        path = os.path.join(pdir, name + ".yaml")
        if not os.path.isfile(path):
            raise InvalidInputError(f"no program named {name!r} in the programs folder")
        with open(path, encoding="utf-8") as fh:
            return {"name": name, "text": fh.read()}

    @app.post("/api/programs")
    def save_program(raw: bytes = Depends(_raw_body)) -> dict:
        from ..io.program import parse_program

        req = _validate(SaveProgramRequest, _parse_body(raw))
        if not sess.plan_lock.acquire(blocking=False):
            raise ConflictError("a job is being planned: wait for it")
        try:  # a bad program is not saved
            parse_program(req.text, source=req.name + ".yaml", urdf_dirs=urdf_dirs)
        finally:
            sess.plan_lock.release()
        os.makedirs(pdir, exist_ok=True)
        atomic_write(os.path.join(pdir, req.name + ".yaml"), req.text)
        sess.event("info", f"saved program {req.name}.yaml")
        return {"name": req.name, "saved": True}

    @app.get("/api/events")
    def events(since: int = 0) -> dict:
        return {"events": sess.events_since(since)}

    @app.websocket("/ws")
    async def ws(websocket: WebSocket) -> None:
        nonlocal ws_clients
        # the guard has checked host, origin and token before this runs
        await websocket.accept()
        if ws_clients >= MAX_WS_CLIENTS:
            await websocket.close(code=WS_CLOSE_BUSY, reason=f"more than {MAX_WS_CLIENTS} live clients")
            return
        ws_clients += 1
        seq = 0
        last_event = 0
        run_seen, trail_seen = -1, 0
        period = 1.0 / WS_RATE_HZ
        loop = asyncio.get_running_loop()
        next_t = loop.time()
        try:
            while True:
                snap = sess.snapshot()
                evs = sess.events_since(last_event)
                if evs:
                    last_event = evs[-1]["id"]
                pts, trail_seen, reset = sess.trail_since(run_seen, trail_seen)
                if reset:
                    run_seen = sess.run_id
                seq += 1
                await websocket.send_json({"type": "live", "seq": seq, **snap, "events": evs,
                                           "trail": pts, "trail_reset": reset})
                next_t = max(next_t + period, loop.time() - period)
                await asyncio.sleep(max(0.0, next_t - loop.time()))
        except (WebSocketDisconnect, RuntimeError):
            return
        finally:
            ws_clients -= 1

    return app
