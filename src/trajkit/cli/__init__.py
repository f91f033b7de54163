"""The ``trajkit`` command: a thin shell over the public API.

Each group of sub-commands lives in its own module exposing
``register(subparsers)``; a sub-command sets ``func(args) -> int`` with
:meth:`argparse.ArgumentParser.set_defaults`. Errors the user can fix
(:class:`trajkit.TrajkitError`, bad files) print one line on stderr and exit
with status 2, without a traceback. Every file a command writes appears only
when the whole command succeeds (:func:`trajkit._atomicio.output_group`). An
unexpected exception (a defect) also prints one line, asks for a report and
exits with status 3; ``TRAJKIT_DEBUG=1`` shows its traceback.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Sequence
from typing import NoReturn

from .. import __version__
from .._atomicio import output_group
from ..errors import TrajkitError

__all__ = ["main", "build_parser"]

#: Modules that add sub-commands, in the order they appear in ``--help``.
_COMMAND_MODULES = (
    "trajkit.cli._demo",
    "trajkit.cli._core",
    "trajkit.cli._paths",
    "trajkit.cli._pallet",
    "trajkit.cli._run",
    "trajkit.cli._hmi",
    "trajkit.cli._warmup",
)


class UsageError(TrajkitError):
    """A command-line problem the user can fix (bad file, bad option mix)."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:  # one line, exit 2
        self.exit(2, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    """Return the ``trajkit`` argument parser with every available sub-command."""
    parser = _Parser(
        prog="trajkit",
        description="Time-optimal, jerk-limited motion planning for robots and CNC machines.",
    )
    parser.add_argument("--version", action="version", version=f"trajkit {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name in _COMMAND_MODULES:
        try:
            mod = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name == name:  # that command group is not part of this build
                continue
            raise
        mod.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``trajkit`` console command; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        with output_group():  # every file the command writes appears, or none does
            return int(args.func(args) or 0)
    except BrokenPipeError:  # e.g. `trajkit ... --json | head`
        try:
            sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - silence the final flush
        except OSError:
            pass
        return 0
    except (TrajkitError, OSError) as exc:
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        print(f"trajkit {args.command}: error: {msg}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # a defect in trajkit, not in the input: still one line
        if os.environ.get("TRAJKIT_DEBUG"):
            raise
        msg = " ".join(str(exc).split())
        msg = msg if len(msg) <= 160 else msg[:157] + "..."
        print(f"trajkit {args.command}: internal error ({type(exc).__name__}: {msg}); this is a "
              "defect in trajkit, please report the command and its input "
              "(TRAJKIT_DEBUG=1 shows the traceback)", file=sys.stderr)
        return 3


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
