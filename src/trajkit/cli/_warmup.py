"""Sub-command ``trajkit warmup``: compile the kernels once after an install."""

from __future__ import annotations

import argparse
import sys
from typing import Any

__all__ = ["register"]


def register(subparsers: Any) -> None:
    from ..runtime import WARM_UP_PARTS

    p = subparsers.add_parser(
        "warmup",
        help="compile the numba kernels now (once after an install), not at their first use",
        description=(
            "With numba installed (the fast extra) every kernel is compiled the first time it "
            "is called and kept in numba's disk cache. Run this once after installing: it "
            "compiles the kernels of the runtime (controlled stops, online targets) and of the "
            "path-timing engine, so that no later plan or machine waits for the compiler "
            "(minutes on a fresh install; a second run loads them in seconds). A runtime "
            "streamer and the HMI make their own kernels ready before anything moves."
        ),
    )
    p.add_argument("--part", action="append", choices=WARM_UP_PARTS, default=None,
                   help="only this part (repeatable; default: all)")
    p.set_defaults(func=_cmd_warmup)


def _cmd_warmup(args: argparse.Namespace) -> int:
    from ..runtime import WARM_UP_PARTS, warm_up, warm_up_pending

    parts = tuple(dict.fromkeys(args.part)) if args.part else WARM_UP_PARTS
    if warm_up_pending(parts):
        print(f"compiling the kernels of {', '.join(parts)} (minutes the first time after an "
              "install)", file=sys.stderr, flush=True)
    took = warm_up(parts)
    if not took:
        print("numba is not installed (or TRAJKIT_NO_JIT is set): the kernels run as plain Python, "
              "nothing to compile")
        return 0
    for part, sec in took.items():
        print(f"{part}: ready in {sec:.1f} s")
    return 0
