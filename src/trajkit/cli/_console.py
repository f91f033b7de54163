"""Console helpers for the CLI: tables with rich when installed, plain text otherwise."""

from __future__ import annotations

import json
import sys
from typing import Any, Sequence


def print_table(title: str, columns: Sequence[str], rows: Sequence[Sequence[Any]]) -> None:
    """Print a table to stdout (rich if available, aligned plain text otherwise)."""
    cells = [[_fmt(c) for c in row] for row in rows]
    try:
        from rich.console import Console
        from rich.table import Table
    except ImportError:
        widths = [max(len(str(h)), *(len(r[i]) for r in cells)) if cells else len(str(h))
                  for i, h in enumerate(columns)]
        print(title)
        print("  ".join(str(h).ljust(w) for h, w in zip(columns, widths)))
        for r in cells:
            print("  ".join(c.rjust(w) for c, w in zip(r, widths)))
        return
    from rich.markup import escape

    table = Table(title=escape(title))
    for h in columns:
        table.add_column(escape(str(h)), justify="right", overflow="fold")
    for r in cells:
        table.add_row(*(escape(c) for c in r))
    Console(soft_wrap=False).print(table)


def print_json(obj: Any) -> None:
    """Print ``obj`` as indented JSON on stdout."""
    json.dump(obj, sys.stdout, indent=2)
    sys.stdout.write("\n")


def _fmt(x: Any) -> str:
    if isinstance(x, float):
        return f"{x:.6g}"
    return str(x)
