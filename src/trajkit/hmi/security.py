"""Who may talk to the HMI, and how much: the request guard in front of every route.

The HMI drives a machine, so every request is treated as hostile until it
passes these checks, in this order (an ASGI middleware, :class:`Guard`, in
front of the whole app, the page and its files included):

1. **Host**: the ``Host`` header names one of the allowed hosts (the bound
   address and this machine's names; more with ``allowed_hosts``), else 403.
   This defeats DNS rebinding (a foreign name resolving to this machine).
2. **Origin**: a request that carries ``Origin`` (every browser request
   that could change something, and every WebSocket) comes from the HMI's
   own origin (scheme ``http``/``https`` and the same host and port as
   ``Host``) or from an allowed origin, else 403. ``Origin: null`` is
   refused.
3. **Fetch metadata**: a browser request another site made without
   ``Origin`` (``<img>``, ``<script>``, ``<link>``; ``Sec-Fetch-Site``
   ``cross-site`` or ``same-site``) is refused with 403; only a top-level
   navigation to the page itself passes (a link to the HMI works; a frame
   does not).
4. **Token** (when the HMI has one): header ``X-Trajkit-Token``,
   ``Authorization: Bearer``, ``?token=`` or the cookie the page sets;
   else 401 (the page, its files and the OpenAPI schema included). A
   WebSocket without it is accepted and closed at once with code
   :data:`WS_CLOSE_TOKEN`.
5. **Anti-CSRF header**: every request that changes something (any method
   but GET/HEAD) carries ``X-Trajkit-CSRF`` with this server's random
   per-run value (``GET /api/session``), else 403. A page from another
   origin cannot set a custom header without the server's consent (CORS),
   which the HMI never gives. The emergency stop is the one exception:
   it needs no CSRF header, so any local tool can always stop the machine
   (it still passes checks 1 to 4).
6. **Size**: a request body above :data:`MAX_BODY_BYTES` is refused with
   413 as soon as its declared length or the bytes received so far exceed
   the limit (nothing more is read); one that takes longer than
   :data:`BODY_TIMEOUT_S` to arrive with 408.

Every HTTP answer carries :data:`SECURITY_HEADERS` (CSP with
``frame-ancestors 'none'``, ``X-Frame-Options: DENY``,
``X-Content-Type-Options: nosniff``, no referrer, no caching). Error
answers are ``{"error": "<one line>"}`` of at most :data:`MAX_ERROR_CHARS`
characters and never echo more than :data:`MAX_ECHO_CHARS` characters of
a value.
"""

from __future__ import annotations

import asyncio
import hmac
import json
import logging
import secrets
from collections.abc import Iterable
from dataclasses import dataclass, field
from http.cookies import SimpleCookie
from typing import Any
from urllib.parse import parse_qs, urlsplit

from ..errors import InvalidInputError

__all__ = [
    "AccessPolicy", "Guard", "MAX_BODY_BYTES", "CSRF_HEADER", "TOKEN_HEADER", "WS_CLOSE_TOKEN",
    "WS_CLOSE_REFUSED", "LOOPBACK_HOSTS", "SECURITY_HEADERS", "MAX_ERROR_CHARS", "MAX_ECHO_CHARS",
    "one_line", "echo", "normalize_host", "normalize_origin", "MAX_JSON_DEPTH",
]

#: Largest request body [bytes] (1 MiB); larger answers 413.
MAX_BODY_BYTES = 1 << 20

#: Longest time a request body may take to arrive [s]; slower answers 408.
BODY_TIMEOUT_S = 30.0

#: Header that carries the anti-CSRF value on every changing request.
CSRF_HEADER = "x-trajkit-csrf"

#: Header that carries the access token (token mode).
TOKEN_HEADER = "x-trajkit-token"

#: WebSocket close code for a missing or wrong token.
WS_CLOSE_TOKEN = 4401

#: WebSocket close code sent before accepting a connection from a foreign
#: host or origin (a browser sees the handshake answered with HTTP 403).
WS_CLOSE_REFUSED = 4403

#: Host names that mean this machine only.
LOOPBACK_HOSTS = ("127.0.0.1", "localhost", "::1")

#: Longest error message sent back [characters].
MAX_ERROR_CHARS = 300

#: Longest part of a submitted value echoed in an error message [characters].
MAX_ECHO_CHARS = 40

#: Deepest nesting of a JSON request body (arrays and objects); the HMI's
#: requests need 3 levels.
MAX_JSON_DEPTH = 32

#: Requests that pass without the anti-CSRF header: the emergency stop.
CSRF_EXEMPT = frozenset({("POST", "/api/run/estop")})

#: Content-Security-Policy of every answer: the page's own files only.
CSP = ("default-src 'self'; script-src 'self'; style-src 'self'; img-src 'self' data:; "
       "connect-src 'self'; font-src 'self'; object-src 'none'; base-uri 'none'; "
       "form-action 'self'; frame-ancestors 'none'")

#: Headers added to every HTTP answer.
SECURITY_HEADERS = (
    ("content-security-policy", CSP),
    ("x-frame-options", "DENY"),
    ("x-content-type-options", "nosniff"),
    ("referrer-policy", "no-referrer"),
    ("cross-origin-opener-policy", "same-origin"),
    ("cross-origin-resource-policy", "same-origin"),
    ("cache-control", "no-store"),
)

_SAFE_METHODS = frozenset({"GET", "HEAD"})
_HEADER_NAMES = frozenset(n for n, _ in SECURITY_HEADERS)
_HEADER_BYTES = [(k.encode(), v.encode()) for k, v in SECURITY_HEADERS]
_log = logging.getLogger("trajkit")


# ---------------------------------------------------------------------------- messages
def one_line(text: Any, limit: int = MAX_ERROR_CHARS) -> str:
    """The first line of ``text``, cut to ``limit`` characters (``...`` marks a cut)."""
    s = str(text).strip().splitlines()[0] if str(text).strip() else ""
    return s if len(s) <= limit else s[: limit - 3] + "..."


def echo(value: Any, limit: int = MAX_ECHO_CHARS) -> str:
    """``repr(value)`` cut to ``limit`` characters, for error messages."""
    s = repr(value)
    return s if len(s) <= limit else s[: limit - 3] + "..."


# ---------------------------------------------------------------------------- hosts and origins
def normalize_host(value: str | None) -> str | None:
    """The host name of a ``Host`` header value (lower case, no port, no brackets), or None."""
    if not value:
        return None
    v = value.strip().lower()
    if v.startswith("["):
        end = v.find("]")
        if end < 0 or (len(v) > end + 1 and not v[end + 1:].startswith(":")):
            return None
        host, rest = v[1:end], v[end + 1:]
    elif v.count(":") == 1:
        host, rest = v.split(":")
        rest = ":" + rest
    elif ":" in v:
        return None  # a bare IPv6 address is not a valid Host header
    else:
        host, rest = v, ""
    if rest and not rest[1:].isdigit():
        return None
    host = host.rstrip(".")
    if not host or any(c.isspace() or c in "/\\@?#" for c in host):
        return None
    return host


def normalize_origin(value: str) -> str | None:
    """``scheme://host[:port]`` in lower case, or None for anything else (``null``, paths)."""
    v = value.strip().lower()
    try:
        u = urlsplit(v)
        port = u.port
    except ValueError:
        return None
    if u.scheme not in ("http", "https") or not u.hostname or u.path not in ("", "/") \
            or u.query or u.fragment or u.username or u.password:
        return None
    host = f"[{u.hostname}]" if ":" in u.hostname else u.hostname
    default = 80 if u.scheme == "http" else 443
    return f"{u.scheme}://{host}" + (f":{port}" if port is not None and port != default else "")


@dataclass(frozen=True)
class AccessPolicy:
    """What the guard lets through.

    Attributes
    ----------
    token : str or None
        Access token (None: no token, the HMI listens on this machine only).
    allowed_hosts : frozenset of str
        Host names the ``Host`` header may carry (lower case, no port).
    allowed_origins : frozenset of str
        Origins (``scheme://host[:port]``) allowed besides the HMI's own.
    csrf_token : str
        This server's anti-CSRF value (random, new at every start).
    max_body_bytes : int
        Largest request body [bytes].
    """

    token: str | None = None
    allowed_hosts: frozenset = frozenset(LOOPBACK_HOSTS)
    allowed_origins: frozenset = frozenset()
    csrf_token: str = field(default_factory=lambda: secrets.token_urlsafe(32))
    max_body_bytes: int = MAX_BODY_BYTES

    @classmethod
    def build(cls, token: str | None = None, allowed_hosts: Iterable[str] | None = None,
              allowed_origins: Iterable[str] | None = None,
              max_body_bytes: int = MAX_BODY_BYTES) -> AccessPolicy:
        """Validate and normalise the settings.

        Raises
        ------
        InvalidInputError
            A host or origin that cannot be one (the value is named).
        """
        hosts = set()
        for h in (LOOPBACK_HOSTS if allowed_hosts is None else allowed_hosts):
            n = normalize_host(f"[{h}]" if ":" in str(h) and not str(h).startswith("[") else str(h))
            if n is None or n in ("*", "0.0.0.0", "::"):
                raise InvalidInputError(f"allowed host must be a host name or address, got {echo(h)}")
            hosts.add(n)
        origins = set()
        for o in allowed_origins or ():
            n = normalize_origin(str(o))
            if n is None:
                raise InvalidInputError(
                    f"allowed origin must look like http://host[:port] or https://host[:port], got {echo(o)}")
            origins.add(n)
        if not isinstance(max_body_bytes, int) or max_body_bytes < 1024:
            raise InvalidInputError(f"max_body_bytes must be an integer >= 1024, got {echo(max_body_bytes)}")
        return cls(token, frozenset(hosts), frozenset(origins), max_body_bytes=max_body_bytes)

    # -------------------------------------------------------------- checks
    def token_ok(self, given: str | None) -> bool:
        """True without a token, or when ``given`` equals it (constant-time comparison)."""
        if self.token is None:
            return True
        return given is not None and hmac.compare_digest(given.encode("utf-8", "replace"),
                                                         self.token.encode("utf-8"))

    def csrf_ok(self, given: str | None) -> bool:
        return given is not None and hmac.compare_digest(given.encode("utf-8", "replace"),
                                                         self.csrf_token.encode("utf-8"))

    def origin_ok(self, origin: str, host_header: str) -> bool:
        """``origin`` is the HMI's own (same host and port as ``Host``) or an allowed one."""
        n = normalize_origin(origin)
        if n is None:
            return False
        if n in self.allowed_origins:
            return True
        netloc = n.split("://", 1)[1]
        own = host_header.strip().lower()
        scheme = n.split("://", 1)[0]
        # browsers leave the default port out of Origin; a proxy may leave it out of Host
        for default in ((":80",) if scheme == "http" else (":443",)):
            if own.endswith(default):
                own = own[: -len(default)]
        return netloc == own


def cookie_name(host_header: str | None) -> str:
    """Name of the token cookie: one per port, so HMIs on one host keep their own."""
    port = "80"
    if host_header:
        tail = host_header.rsplit("]", 1)[-1]
        if ":" in tail and tail.rsplit(":", 1)[1].isdigit():
            port = tail.rsplit(":", 1)[1]
    return f"trajkit-token-{port}"


def _token_from(headers: dict, query: str) -> tuple[str | None, str]:
    """The token a request carries and where (``header``, ``query``, ``cookie`` or ``""``)."""
    auth = headers.get("authorization", "")
    if auth[:7].lower() == "bearer ":
        return auth[7:].strip(), "header"
    if TOKEN_HEADER in headers:
        return headers[TOKEN_HEADER], "header"
    q = parse_qs(query, keep_blank_values=True).get("token")
    if q:
        return q[0], "query"
    raw = headers.get("cookie")
    if raw:
        try:
            c = SimpleCookie()
            c.load(raw)
        except Exception:  # noqa: BLE001 - a malformed cookie is no token
            return None, ""
        m = c.get(cookie_name(headers.get("host")))
        if m is not None:
            return m.value, "cookie"
    return None, ""


# ---------------------------------------------------------------------------- middleware
class _Refused(Exception):
    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status
        self.message = message


class Guard:
    """ASGI middleware applying an :class:`AccessPolicy` to every request (see the module doc)."""

    def __init__(self, app, policy: AccessPolicy) -> None:
        self.app = app
        self.policy = policy

    async def __call__(self, scope, receive, send) -> None:
        kind = scope["type"]
        if kind not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        headers: dict[str, str] = {}
        dup_host = False
        for k, v in scope.get("headers", ()):
            name = k.decode("latin-1").lower()
            if name == "host" and name in headers:
                dup_host = True
            headers[name] = v.decode("latin-1")
        method = scope.get("method", "GET").upper() if kind == "http" else "GET"
        path = scope.get("path", "")
        try:
            if dup_host:
                raise _Refused(403, "more than one Host header")
            self._check_origin(kind, method, path, headers)
            token, where = _token_from(headers, scope.get("query_string", b"").decode("latin-1"))
            if not self.policy.token_ok(token):
                if kind == "websocket":
                    await self._ws_close(receive, send, WS_CLOSE_TOKEN, "missing or wrong token", accept=True)
                    return
                raise _Refused(401, "missing or wrong token")
            if kind == "http" and method not in _SAFE_METHODS and (method, path) not in CSRF_EXEMPT:
                if not self.policy.csrf_ok(headers.get(CSRF_HEADER)):
                    raise _Refused(403, "missing or wrong X-Trajkit-CSRF header (GET /api/session "
                                        "gives it; reload the page)")
        except _Refused as r:
            if _log.isEnabledFor(logging.INFO):
                _log.info("hmi: refused %s %s (%d): %s", "WEBSOCKET" if kind == "websocket" else method,
                          path[:80], r.status, r.message)
            if kind == "websocket":
                await self._ws_close(receive, send, WS_CLOSE_REFUSED, r.message, accept=False)
            elif path == "/" and r.status == 401:
                await self._answer(send, 401, "<!doctype html><title>trajkit HMI</title><h1>401</h1>"
                                   "<p>This HMI needs its token: open the address it printed "
                                   "(/?token=...).</p>", "text/html; charset=utf-8")
            else:
                await self._answer(send, r.status, json.dumps({"error": r.message}))
            return
        if kind == "websocket":
            await self.app(scope, receive, send)
            return
        set_cookie = None
        if where == "query" and self.policy.token is not None and path == "/":
            set_cookie = (f"{cookie_name(headers.get('host'))}={token}; Path=/; HttpOnly; "
                          "SameSite=Strict")
        if method not in _SAFE_METHODS:
            try:
                receive = await self._read_body(headers, receive)
            except _Refused as r:
                await self._answer(send, r.status, json.dumps({"error": r.message}))
                return

        started = False

        async def send_with_headers(message):
            nonlocal started
            if message["type"] == "http.response.start":
                started = True
                hdrs = [(k, v) for k, v in message.get("headers", [])
                        if k.decode("latin-1").lower() not in _HEADER_NAMES]
                hdrs += _HEADER_BYTES
                if set_cookie is not None:
                    hdrs.append((b"set-cookie", set_cookie.encode("latin-1")))
                message = dict(message, headers=hdrs)
            await send(message)

        try:
            await self.app(scope, receive, send_with_headers)
        except Exception as exc:  # noqa: BLE001 - one line to the client, the trace to the log
            _log.exception("hmi: %s %s", method, path)
            if not started:
                await self._answer(send, 500, json.dumps(
                    {"error": f"internal error ({type(exc).__name__}); the server log has the details"}))

    # -------------------------------------------------------------- pieces
    def _check_origin(self, kind: str, method: str, path: str, headers: dict) -> None:
        host = headers.get("host")
        name = normalize_host(host)
        if host is None or name is None:  # (no header gives no name)
            raise _Refused(403, "missing or malformed Host header")
        if name not in self.policy.allowed_hosts:
            raise _Refused(403, f"host {echo(name)} is not allowed (the HMI's operator can add it "
                                "with --allow-host)")
        origin = headers.get("origin")
        if origin is not None:
            if not self.policy.origin_ok(origin, host):
                raise _Refused(403, f"origin {echo(origin)} is not allowed")
            return
        site = headers.get("sec-fetch-site", "").lower()
        if site in ("cross-site", "same-site"):
            navigate = (kind == "http" and method == "GET" and path == "/"
                        and headers.get("sec-fetch-mode", "").lower() == "navigate"
                        and headers.get("sec-fetch-dest", "document").lower() == "document")
            if not navigate:
                raise _Refused(403, f"a request made by another site ({site}) is not allowed")

    async def _read_body(self, headers: dict, receive):
        limit = self.policy.max_body_bytes
        declared = headers.get("content-length")
        if declared is not None:
            if not declared.strip().isdigit():
                raise _Refused(400, "malformed Content-Length header")
            if int(declared) > limit:
                raise _Refused(413, f"request body of {int(declared)} bytes is larger than the "
                                    f"{limit} bytes allowed")
        chunks, size = [], 0
        loop = asyncio.get_running_loop()
        deadline = loop.time() + BODY_TIMEOUT_S
        while True:
            try:
                msg = await asyncio.wait_for(receive(), max(deadline - loop.time(), 0.0))
            except TimeoutError:
                raise _Refused(408, f"the request body did not arrive within {BODY_TIMEOUT_S:g} s") from None
            if msg["type"] == "http.disconnect":
                raise _Refused(400, "the client went away")
            body = msg.get("body", b"")
            size += len(body)
            if size > limit:
                raise _Refused(413, f"request body larger than the {limit} bytes allowed")
            chunks.append(body)
            if not msg.get("more_body", False):
                break
        data = b"".join(chunks)
        replayed = False

        async def replay():
            nonlocal replayed
            if not replayed:
                replayed = True
                return {"type": "http.request", "body": data, "more_body": False}
            return await receive()

        return replay

    @staticmethod
    async def _answer(send, status: int, body: str, ctype: str = "application/json") -> None:
        raw = body.encode("utf-8")
        hdrs = [(b"content-type", ctype.encode()), (b"content-length", str(len(raw)).encode())]
        hdrs += _HEADER_BYTES
        if status in (408, 413):
            hdrs.append((b"connection", b"close"))
        await send({"type": "http.response.start", "status": status, "headers": hdrs})
        await send({"type": "http.response.body", "body": raw})

    @staticmethod
    async def _ws_close(receive, send, code: int, reason: str, accept: bool) -> None:
        msg = await receive()
        if msg["type"] != "websocket.connect":
            return
        if accept:
            await send({"type": "websocket.accept"})
        await send({"type": "websocket.close", "code": code, "reason": reason[:120]})
