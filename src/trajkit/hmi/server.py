"""Run the HMI with uvicorn: localhost by default, a strong token for any other address."""

from __future__ import annotations

import ipaddress
import os
import socket
from collections.abc import Iterable

from ..errors import InvalidInputError
from .security import LOOPBACK_HOSTS, echo

__all__ = ["serve", "check_bind", "check_token", "make_server", "default_allowed_hosts", "url_of",
           "LOOPBACK_NAMES", "MIN_TOKEN_CHARS", "MIN_TOKEN_DISTINCT"]

#: Host names that mean this machine only.
LOOPBACK_NAMES = LOOPBACK_HOSTS

#: Shortest accepted token [characters].
MIN_TOKEN_CHARS = 16

#: Fewest different characters in an accepted token.
MIN_TOKEN_DISTINCT = 6

#: Largest WebSocket message accepted from a client [bytes].
WS_MAX_MESSAGE_BYTES = 64 * 1024

_WILDCARDS = ("0.0.0.0", "::", "")


def _is_loopback(host: str) -> bool:
    if host in LOOPBACK_NAMES:
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def check_token(token: str) -> None:
    """Refuse a trivially weak token.

    A token has at least :data:`MIN_TOKEN_CHARS` printable ASCII characters
    without spaces, at least :data:`MIN_TOKEN_DISTINCT` of them different.
    ``python -c "import secrets; print(secrets.token_urlsafe(24))"`` makes a
    good one.

    Raises
    ------
    InvalidInputError
        The rule it breaks (the token itself is never shown).
    """
    if not isinstance(token, str):
        raise InvalidInputError(f"token must be a string, got {type(token).__name__}")
    if any(not 33 <= ord(c) <= 126 for c in token):
        raise InvalidInputError("token must be printable ASCII characters without spaces")
    if len(token) < MIN_TOKEN_CHARS:
        raise InvalidInputError(f"token must have at least {MIN_TOKEN_CHARS} characters, got {len(token)}")
    if len(set(token)) < MIN_TOKEN_DISTINCT:
        raise InvalidInputError(f"token is too easy to guess: it needs at least {MIN_TOKEN_DISTINCT} "
                                f"different characters, got {len(set(token))}")


def check_bind(host: str, port: int, token: str | None) -> None:
    """Refuse a bind that would expose the HMI without a token, or a weak token.

    Raises
    ------
    InvalidInputError
        A non-loopback ``host`` without ``token``, a weak token (see
        :func:`check_token`), or a port outside 0..65535.
    """
    if not isinstance(port, int) or isinstance(port, bool) or not 0 <= port <= 65535:
        raise InvalidInputError(f"port must be an integer in 0..65535, got {port!r}")
    if token is not None:
        check_token(token)
    if not _is_loopback(host) and token is None:
        raise InvalidInputError(
            f"host {echo(host)} is not this machine only (127.0.0.1): binding to it requires --token"
        )


def default_allowed_hosts(host: str, extra: Iterable[str] = ()) -> list[str]:
    """Host names a browser may use to reach an HMI bound to ``host``.

    Loopback: ``127.0.0.1``, ``localhost`` and ``::1``. A specific address:
    that address, this machine's name and the loopback names. A wildcard
    (``0.0.0.0``, ``::``): also every address this machine's name resolves
    to. ``extra`` names are added (e.g. a DNS alias or a proxy's name).
    """
    hosts = list(LOOPBACK_NAMES)
    if not _is_loopback(host):
        names = {socket.gethostname(), socket.getfqdn()}
        if host not in _WILDCARDS:
            names.add(host)
        else:
            for n in list(names):
                try:
                    for info in socket.getaddrinfo(n, None):
                        addr = info[4][0]
                        if isinstance(addr, str):  # IPv4/IPv6 (the only families a name resolves to)
                            names.add(addr.split("%", 1)[0])
                except OSError:
                    pass
        hosts += sorted(n.lower() for n in names if n)
    hosts += [h for h in extra]
    return list(dict.fromkeys(hosts))


def make_server(host: str = "127.0.0.1", port: int = 8765, token: str | None = None,
                programs_dir: str | os.PathLike | None = None, log_level: str = "warning", *,
                allowed_hosts: Iterable[str] = (), allowed_origins: Iterable[str] = (),
                robots_dir: str | os.PathLike | None = None):
    """A configured ``uvicorn.Server`` for the HMI (not started); ``server.config.app`` is the app.

    ``allowed_hosts`` are added to :func:`default_allowed_hosts`; see
    :func:`trajkit.hmi.app.create_app` for the other settings.
    """
    import uvicorn

    from .app import create_app

    check_bind(host, port, token)
    app = create_app(token=token, programs_dir=programs_dir,
                     allowed_hosts=default_allowed_hosts(host, allowed_hosts),
                     allowed_origins=allowed_origins, robots_dir=robots_dir)
    # the HMI never reads messages from its WebSocket clients: a small frame size bounds
    # what a client can make the server buffer
    config = uvicorn.Config(app, host=host, port=port, log_level=log_level, ws="auto",
                            server_header=False, ws_max_size=WS_MAX_MESSAGE_BYTES)
    return uvicorn.Server(config)


def url_of(host: str, port: int, token: str | None) -> str:
    """The address to open in a browser."""
    h = f"[{host}]" if ":" in host else host
    q = f"/?token={token}" if token else "/"
    return f"http://{h}:{port}{q}"


def serve(host: str = "127.0.0.1", port: int = 8765, token: str | None = None,
          programs_dir: str | os.PathLike | None = None, announce=print, *,
          allowed_hosts: Iterable[str] = (), allowed_origins: Iterable[str] = (),
          robots_dir: str | os.PathLike | None = None) -> None:
    """Start the HMI and block until interrupted.

    Parameters
    ----------
    host : str
        Address to bind (default 127.0.0.1: this machine only). Any other
        address needs ``token``.
    port : int
        TCP port (0: any free port).
    token : str, optional
        Access token (see :func:`check_token`).
    programs_dir : path, optional
        Folder for saved programs (default ``./trajkit-programs``).
    announce : callable
        Called with the address once the server listens.
    allowed_hosts : iterable of str
        Host names accepted besides :func:`default_allowed_hosts`.
    allowed_origins : iterable of str
        Origins (``https://hmi.example:443``) accepted besides the HMI's own.
    robots_dir : path, optional
        Folder of URDF files that programs may name.
    """
    import asyncio

    server = make_server(host, port, token, programs_dir, allowed_hosts=allowed_hosts,
                         allowed_origins=allowed_origins, robots_dir=robots_dir)

    async def main() -> None:
        task = asyncio.create_task(server.serve())
        while not server.started and not task.done():
            await asyncio.sleep(0.05)
        if server.started:
            real_port = port
            for s in server.servers:
                for sock in s.sockets:
                    if sock.family in (socket.AF_INET, socket.AF_INET6):
                        real_port = sock.getsockname()[1]
                        break
            announce(f"trajkit HMI on {url_of(host, real_port, token)}  (Ctrl-C to stop)")
        await task

    asyncio.run(main())
