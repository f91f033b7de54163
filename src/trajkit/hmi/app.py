"""The FastAPI application of the web HMI (a thin shell over :mod:`trajkit.hmi.engine`).

Routes (JSON; units mm, deg, s as in :mod:`trajkit.hmi.models`):

==========================  ====================================================
``GET  /``                  the page (``?token=T`` when a token is set)
``GET  /api/status``        live snapshot (state, axes, progress, override)
``POST /api/job``           plan and load a job (saddle / pallet / program)
``GET  /api/job``           the loaded job's planned path and summary
``POST /api/run/{cmd}``     start, pause, resume, stop, estop, reset
``POST /api/override``      feed override ``{"percent": 0..150}``
``GET|POST /api/robot``     jog/teach robot and its current joints
``POST /api/jog``           jog one joint by a step (a jerk-limited move)
``POST /api/teach``         store the current joints as a named point
``POST /api/program/build`` program text from taught points
``GET|POST /api/programs``  list / save program files; ``GET /api/programs/{name}``
``GET  /api/events``        the event and fault log
``WS   /ws``                live values at :data:`WS_RATE_HZ`
==========================  ====================================================

Errors answer ``{"error": "<one line>"}``: 422 for a value that fails
validation (the field, the message and the value), 400 for a request the
library refuses (e.g. pipes that do not meet), 409 for a command the state
does not allow (start while a run is active), 401 for a missing or wrong
token. A failed request changes nothing.
"""

from __future__ import annotations

import asyncio
import hmac
import math
import os
import re
from importlib import resources

from fastapi import Body, Depends, FastAPI, Request, WebSocket, WebSocketDisconnect
from fastapi.exceptions import RequestValidationError
from fastapi.responses import HTMLResponse, JSONResponse
from fastapi.staticfiles import StaticFiles
from pydantic import ValidationError

from .._atomicio import atomic_write
from ..errors import InvalidInputError, TrajkitError
from .engine import ConflictError, Session
from .jobs import plan_jog, plan_job
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

__all__ = ["create_app", "WS_RATE_HZ"]

#: Live updates per second over the WebSocket.
WS_RATE_HZ = 25.0

#: Control period of a jog when no job is loaded [s].
JOG_PERIOD_S = 0.004

_JOB_MODELS = {"saddle": SaddleJob, "pallet": PalletJob, "program": ProgramJob}
_RUN_COMMANDS = ("start", "pause", "resume", "stop", "estop", "reset")


class _AuthError(TrajkitError):
    pass


def _static_dir() -> str:
    return str(resources.files("trajkit.hmi") / "static")


def _fmt_validation(exc: RequestValidationError) -> str:
    parts = []
    for err in exc.errors():
        loc = [str(x) for x in err.get("loc", ()) if x not in ("body",)]
        field = ".".join(loc) or "request"
        msg = err.get("msg", "invalid")
        msg = msg.removeprefix("Value error, ")
        got = err.get("input")
        tail = "" if isinstance(got, (dict, list)) or got is None else f" (got {got!r})"
        parts.append(f"{field}: {msg}{tail}")
    return "; ".join(parts) or "invalid request"


def create_app(token: str | None = None, programs_dir: str | os.PathLike | None = None,
               session: Session | None = None) -> FastAPI:
    """Build the HMI web application.

    Parameters
    ----------
    token : str, optional
        When set, every API call, the WebSocket and the page need it
        (header ``X-Trajkit-Token``, ``Authorization: Bearer T``, or
        ``?token=T``).
    programs_dir : path, optional
        Folder where program files are saved and loaded (created on the
        first save; default ``./trajkit-programs``).
    session : Session, optional
        The machine session (a new one by default). Its loop thread is
        stopped when the app shuts down.

    Returns
    -------
    fastapi.FastAPI
        ``app.state.session`` is the :class:`~trajkit.hmi.engine.Session`.
    """
    sess = session or Session()
    pdir = os.fspath(programs_dir) if programs_dir is not None else os.path.join(os.getcwd(), "trajkit-programs")
    sess.programs_dir = pdir

    from contextlib import asynccontextmanager

    @asynccontextmanager
    async def lifespan(app):
        yield
        sess.close()

    app = FastAPI(title="trajkit HMI", lifespan=lifespan, docs_url=None, redoc_url=None)
    app.state.session = sess
    app.state.token = token

    def _token_ok(value: str | None) -> bool:
        return token is None or (value is not None and hmac.compare_digest(value.encode(), token.encode()))

    def _given(headers, query) -> str | None:
        auth = headers.get("authorization", "")
        if auth.lower().startswith("bearer "):
            return auth[7:].strip()
        return headers.get("x-trajkit-token") or query.get("token")

    async def auth(request: Request) -> None:
        if not _token_ok(_given(request.headers, request.query_params)):
            raise _AuthError("missing or wrong token")

    @app.exception_handler(RequestValidationError)
    async def _validation(request, exc):
        return JSONResponse({"error": _fmt_validation(exc)}, status_code=422)

    @app.exception_handler(TrajkitError)
    async def _trajkit(request, exc):
        code = 409 if isinstance(exc, ConflictError) else 401 if isinstance(exc, _AuthError) else 400
        return JSONResponse({"error": str(exc).splitlines()[0] if str(exc) else type(exc).__name__},
                            status_code=code)

    app.mount("/static", StaticFiles(directory=_static_dir()), name="static")

    @app.get("/", response_class=HTMLResponse)
    def index(request: Request):
        if not _token_ok(_given(request.headers, request.query_params)):
            return HTMLResponse("<h1>401</h1><p>This HMI needs its token: open /?token=...</p>",
                                status_code=401)
        with open(os.path.join(_static_dir(), "index.html"), encoding="utf-8") as fh:
            return HTMLResponse(fh.read())

    dep = [Depends(auth)]

    @app.get("/api/status", dependencies=dep)
    def status() -> dict:
        return sess.snapshot()

    @app.post("/api/job", dependencies=dep)
    def load_job(payload: dict = Body(...)) -> dict:
        kind = payload.get("kind")
        if kind not in _JOB_MODELS:
            raise InvalidInputError(f"kind must be one of {', '.join(_JOB_MODELS)}, got {kind!r}")
        try:
            job = _JOB_MODELS[kind].model_validate(payload)
        except ValidationError as exc:
            raise RequestValidationError(exc.errors()) from None
        sess.check_idle("load a job")  # refuse before planning (planning takes a while)
        table = plan_job(job)
        sess.load(table)
        return table.preview()

    @app.get("/api/job", dependencies=dep)
    def get_job() -> dict:
        if sess.job is None:
            return {"job": None}
        return sess.job.preview()

    @app.post("/api/run/{cmd}", dependencies=dep)
    def run_command(cmd: str) -> dict:
        if cmd not in _RUN_COMMANDS:
            raise InvalidInputError(f"run command must be one of {', '.join(_RUN_COMMANDS)}, got {cmd!r}")
        if cmd == "start":
            sess.start()
        else:
            sess.command(cmd)
        return sess.snapshot()

    @app.post("/api/override", dependencies=dep)
    def override(req: OverrideRequest) -> dict:
        sess.command("override", req.percent / 100.0)
        return sess.snapshot()

    @app.get("/api/robot", dependencies=dep)
    def robot() -> dict:
        return sess.joint_info()

    @app.post("/api/robot", dependencies=dep)
    def set_robot(req: RobotRequest) -> dict:
        sess.set_robot(req.robot)
        return sess.joint_info()

    @app.post("/api/jog", dependencies=dep)
    def jog(req: JogRequest) -> dict:
        rb = sess.robot
        if req.joint not in rb.joint_names:
            raise InvalidInputError(f"joint must be one of {', '.join(rb.joint_names)} of robot "
                                    f"{sess.robot_name}, got {req.joint!r}")
        k = rb.joint_names.index(req.joint)
        unit = math.pi / 180.0 if rb.joint_kinds[k] == "revolute" else 1e-3
        q_now = sess.check_idle("jog")
        period = sess.job.period if sess.job is not None else JOG_PERIOD_S
        table = plan_jog(rb, q_now, k, req.step * unit, req.speed_pct, period)
        sess.start(table)  # checks the state again (one run at a time)
        return sess.joint_info()

    @app.post("/api/teach", dependencies=dep)
    def teach(req: TeachRequest) -> dict:
        sess.teach(req.name)
        return sess.joint_info()

    @app.post("/api/program/build", dependencies=dep)
    def build(req: BuildProgramRequest) -> dict:
        return {"text": sess.program_text(req.steps, req.speed_mm_s)}

    @app.get("/api/programs", dependencies=dep)
    def list_programs() -> dict:
        if not os.path.isdir(pdir):
            return {"programs": []}
        names = sorted(f[:-5] for f in os.listdir(pdir)
                       if f.endswith(".yaml") and re.fullmatch(NAME_PATTERN, f[:-5]))
        return {"programs": names}

    @app.get("/api/programs/{name}", dependencies=dep)
    def get_program(name: str) -> dict:
        if not re.fullmatch(NAME_PATTERN, name):
            raise InvalidInputError(f"program name must match {NAME_PATTERN}, got {name!r}")
        path = os.path.join(pdir, name + ".yaml")
        if not os.path.isfile(path):
            raise InvalidInputError(f"no program named {name!r} in {pdir}")
        with open(path, encoding="utf-8") as fh:
            return {"name": name, "text": fh.read()}

    @app.post("/api/programs", dependencies=dep)
    def save_program(req: SaveProgramRequest) -> dict:
        from ..io.program import parse_program

        parse_program(req.text, source=req.name + ".yaml")  # a bad program is not saved
        os.makedirs(pdir, exist_ok=True)
        atomic_write(os.path.join(pdir, req.name + ".yaml"), req.text)
        sess.event("info", f"saved program {req.name}.yaml")
        return {"name": req.name, "saved": True}

    @app.get("/api/events", dependencies=dep)
    def events(since: int = 0) -> dict:
        return {"events": sess.events_since(since)}

    @app.websocket("/ws")
    async def ws(websocket: WebSocket) -> None:
        if not _token_ok(_given(websocket.headers, websocket.query_params)):
            await websocket.close(code=4401)
            return
        await websocket.accept()
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
                next_t += period
                await asyncio.sleep(max(0.0, next_t - loop.time()))
        except (WebSocketDisconnect, RuntimeError):
            return

    return app
