"""Run the HMI with uvicorn: localhost by default, a token for any other address."""

from __future__ import annotations

import ipaddress
import os
import socket

from ..errors import InvalidInputError

__all__ = ["serve", "check_bind", "make_server", "LOOPBACK_NAMES", "MIN_TOKEN_CHARS"]

#: Host names that mean this machine only.
LOOPBACK_NAMES = ("localhost", "127.0.0.1", "::1")

#: Shortest accepted token.
MIN_TOKEN_CHARS = 8


def _is_loopback(host: str) -> bool:
    if host in LOOPBACK_NAMES:
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def check_bind(host: str, port: int, token: str | None) -> None:
    """Refuse a bind that would expose the HMI without a token.

    Raises
    ------
    InvalidInputError
        A non-loopback ``host`` without ``token``, a token shorter than
        :data:`MIN_TOKEN_CHARS`, or a port outside 0..65535.
    """
    if not isinstance(port, int) or not 0 <= port <= 65535:
        raise InvalidInputError(f"port must be an integer in 0..65535, got {port!r}")
    if token is not None and len(token) < MIN_TOKEN_CHARS:
        raise InvalidInputError(f"token must have at least {MIN_TOKEN_CHARS} characters, got {len(token)}")
    if not _is_loopback(host) and token is None:
        raise InvalidInputError(
            f"host {host!r} is not this machine only (127.0.0.1): binding to it requires --token"
        )


def make_server(host: str = "127.0.0.1", port: int = 8765, token: str | None = None,
                programs_dir: str | os.PathLike | None = None, log_level: str = "warning"):
    """A configured ``uvicorn.Server`` for the HMI (not started); ``server.config.app`` is the app."""
    import uvicorn

    from .app import create_app

    check_bind(host, port, token)
    app = create_app(token=token, programs_dir=programs_dir)
    config = uvicorn.Config(app, host=host, port=port, log_level=log_level, ws="auto")
    return uvicorn.Server(config)


def url_of(host: str, port: int, token: str | None) -> str:
    """The address to open in a browser."""
    h = f"[{host}]" if ":" in host else host
    q = f"/?token={token}" if token else "/"
    return f"http://{h}:{port}{q}"


def serve(host: str = "127.0.0.1", port: int = 8765, token: str | None = None,
          programs_dir: str | os.PathLike | None = None, announce=print) -> None:
    """Start the HMI and block until interrupted.

    Parameters
    ----------
    host : str
        Address to bind (default 127.0.0.1: this machine only). Any other
        address needs ``token``.
    port : int
        TCP port (0: any free port).
    token : str, optional
        Access token (at least 8 characters).
    programs_dir : path, optional
        Folder for saved programs (default ``./trajkit-programs``).
    announce : callable
        Called with the address once the server listens.
    """
    import asyncio

    server = make_server(host, port, token, programs_dir)

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
