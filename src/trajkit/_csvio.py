"""CSV text with one header style for every export.

Header: ``quantity_unit`` in snake case, as the job-file fields are named
(``t_s``, ``x_mm``, ``A1_deg``, ``q0_velocity_m_s``, ``q0_acceleration_m_s2``).
Axis names from the user are neutralised for spreadsheets: a name that starts
like a formula (``=``, ``+``, ``-``, ``@``) gets a leading apostrophe, control
characters are dropped, and the csv module quotes commas and quotes. Numbers
are written with 17 significant digits (they read back bit for bit).
"""

from __future__ import annotations

import csv
import io
import re
from collections.abc import Sequence

import numpy as np

__all__ = ["csv_text", "safe_name", "unit_suffix"]

_FORMULA_START = ("=", "+", "-", "@", "\t", "\r")
_CONTROL = re.compile(r"[\x00-\x1f\x7f]")


def safe_name(name: object) -> str:
    """A header cell that no spreadsheet runs as a formula."""
    text = _CONTROL.sub("", str(name))
    return "'" + text if text.startswith(_FORMULA_START) else text


def unit_suffix(unit: str, per_second: int = 0) -> str:
    """``"m"`` -> ``"m"``, ``"m", 1`` -> ``"m_s"``, ``"m", 2`` -> ``"m_s2"`` (header style)."""
    if per_second == 0:
        return unit
    return f"{unit}_s" if per_second == 1 else f"{unit}_s{per_second}"


def csv_text(header: Sequence[str], columns: Sequence[np.ndarray]) -> str:
    """CSV text: one header row (cells neutralised by :func:`safe_name`), then the columns.

    Parameters
    ----------
    header : sequence of str, length m
    columns : sequence of m arrays of shape (n,)
        Numbers (written ``%.17g``).
    """
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow([safe_name(h) for h in header])
    if columns:
        data = np.column_stack([np.asarray(c, dtype=np.float64) for c in columns])
        np.savetxt(buf, data, delimiter=",", fmt="%.17g")
    return buf.getvalue()
