"""Web HMI of trajkit: FastAPI app, page and live WebSocket.

Start it with ``trajkit hmi`` or :func:`trajkit.hmi.server.serve`; build the
app with :func:`create_app` (needs the ``hmi`` extra: fastapi, uvicorn).
The HMI holds no motion math: jobs are planned by the public library
(:mod:`trajkit.hmi.jobs`) and played back by :mod:`trajkit.hmi.engine`.
"""

from __future__ import annotations

__all__ = ["create_app", "serve"]


def create_app(*args, **kwargs):
    """Build the FastAPI app; see :func:`trajkit.hmi.app.create_app`."""
    from .app import create_app as _create

    return _create(*args, **kwargs)


def serve(*args, **kwargs):
    """Run the HMI server; see :func:`trajkit.hmi.server.serve`."""
    from .server import serve as _serve

    return _serve(*args, **kwargs)
