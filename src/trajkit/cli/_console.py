"""Console helpers for the CLI: tables with rich when installed, plain text otherwise."""

from __future__ import annotations

import json
import sys
from collections.abc import Sequence
from typing import Any


def print_table(title: str, columns: Sequence[str], rows: Sequence[Sequence[Any]]) -> None:
    """Print a table to stdout (rich if available, aligned plain text otherwise).

    Cells are plain text (``[s]`` in a header is a unit, not rich markup). On a
    terminal the table fits the window, wrapping headers between words; piped
    or redirected, it is as wide as its widest cells and never wraps, so that
    ``grep``/``awk`` see one row per line.
    """
    cells = [[_fmt(c) for c in row] for row in rows]
    heads = [str(h) for h in columns]
    widths = [max([len(h)] + [len(r[i]) for r in cells]) for i, h in enumerate(heads)]
    try:
        from rich.console import Console
        from rich.table import Table
        from rich.text import Text
    except ImportError:
        print(title)
        print("  ".join(h.rjust(w) for h, w in zip(heads, widths)))
        for r in cells:
            print("  ".join(c.rjust(w) for c, w in zip(r, widths)))
        return
    piped = not sys.stdout.isatty()
    table = Table(title=Text(title))
    for h in heads:
        table.add_column(Text(h), justify="right", no_wrap=piped, overflow="fold")
    for r in cells:
        table.add_row(*(Text(c) for c in r))
    if piped:
        width = max(sum(widths) + 3 * len(widths) + 1, len(title))
        Console(width=width, soft_wrap=False).print(table)
    else:
        Console(soft_wrap=False).print(table)


def print_json(obj: Any) -> None:
    """Print ``obj`` as indented JSON on stdout."""
    json.dump(obj, sys.stdout, indent=2)
    sys.stdout.write("\n")


def _fmt(x: Any) -> str:
    if isinstance(x, float):
        return f"{x:.6g}"
    return str(x)
