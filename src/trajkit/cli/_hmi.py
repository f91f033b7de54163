"""Sub-command ``trajkit hmi``: the web HMI (needs the ``hmi`` extra: fastapi, uvicorn)."""

from __future__ import annotations

import argparse
import os
import sys

from .. import errors

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``hmi`` to the ``trajkit`` parser."""
    p = sub.add_parser(
        "hmi",
        help="start the web HMI (live axes, jobs, jog and teach) on 127.0.0.1",
        description=(
            "Start the web HMI: plan saddle, palletizing and robot-program jobs, run them in "
            "real time with pause, resume, stop, emergency stop and feed override, jog and "
            "teach points. Listens on 127.0.0.1 unless --host is given; any other address "
            "needs --token (then open the printed address, which carries the token). Only "
            "the HMI's own page may command it: requests naming another host or coming from "
            "another web origin are refused."
        ),
    )
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1)")
    p.add_argument("--port", type=int, default=8765, help="TCP port (default 8765; 0: any free port)")
    p.add_argument("--token", default=None,
                   help="access token, 16+ characters (required for a non-local --host)")
    p.add_argument("--programs-dir", default=None, metavar="DIR",
                   help="folder of saved program files (default ./trajkit-programs)")
    p.add_argument("--robots-dir", default=None, metavar="DIR",
                   help="folder of URDF files that programs may name (default: built-in robots only)")
    p.add_argument("--allow-host", action="append", default=[], metavar="NAME",
                   help="also accept this host name in requests (a DNS alias, a reverse proxy's "
                        "name); repeatable")
    p.add_argument("--allow-origin", action="append", default=[], metavar="URL",
                   help="also accept pages from this origin, e.g. https://hmi.example "
                        "(a reverse proxy's public address); repeatable")
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from ..hmi.security import AccessPolicy
    from ..hmi.server import check_bind

    check_bind(args.host, args.port, args.token)  # before importing the web stack
    AccessPolicy.build(args.token, args.allow_host or None, args.allow_origin)  # refuse bad names early
    if args.robots_dir is not None and not os.path.isdir(args.robots_dir):
        raise errors.InvalidInputError(f"--robots-dir {args.robots_dir!r} is not a folder")
    try:
        import fastapi  # noqa: F401
        import uvicorn  # noqa: F401

        from ..hmi.server import serve
    except ImportError as exc:
        raise errors.TrajkitError(
            f"the HMI needs fastapi and uvicorn ({exc.name} is missing): pip install 'trajkit[hmi]'"
        ) from None
    from ..runtime import WARM_UP_PARTS, warm_up, warm_up_pending

    if warm_up_pending(WARM_UP_PARTS):  # before it listens: no request waits for the compiler
        print("preparing the compiled kernels (minutes the first time after an install; "
              "`trajkit warmup` does it ahead)", file=sys.stderr, flush=True)
        warm_up(WARM_UP_PARTS)
    serve(args.host, args.port, args.token, args.programs_dir,
          announce=lambda s: print(s, flush=True, file=sys.stdout),
          allowed_hosts=args.allow_host, allowed_origins=args.allow_origin,
          robots_dir=args.robots_dir)
    return 0
