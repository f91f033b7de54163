"""Input validation shared by every public entry point.

Kernels assume valid input; these helpers raise :class:`InvalidInputError`
with messages that name the field, the axis, the value and the bound.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .errors import InvalidInputError

__all__ = ["check_finite", "check_positive", "check_array", "axis_label"]


def axis_label(axis: int | str | None) -> str:
    """Return ``" of axis X"`` for messages, or an empty string."""
    if axis is None:
        return ""
    return f" of axis {axis}"


def _as_float(value: Any, field: str, axis: int | str | None) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        raise InvalidInputError(
            f"{field}{axis_label(axis)} must be a number, got {value!r}"
        ) from None


def check_finite(value: Any, field: str, axis: int | str | None = None) -> float:
    """Return ``value`` as a float; raise if it is NaN or infinite."""
    x = _as_float(value, field, axis)
    if not math.isfinite(x):
        raise InvalidInputError(f"{field}{axis_label(axis)} must be finite, got {x!r}")
    return x


def check_positive(
    value: Any, field: str, axis: int | str | None = None, allow_inf: bool = False
) -> float:
    """Return ``value`` as a float; raise unless it is > 0 (and finite unless allowed)."""
    x = _as_float(value, field, axis)
    if math.isnan(x):
        raise InvalidInputError(f"{field}{axis_label(axis)} must be a number, got nan")
    if math.isinf(x) and not (allow_inf and x > 0):
        raise InvalidInputError(
            f"{field}{axis_label(axis)} must be finite and larger than zero, got {x!r}"
        )
    if x <= 0.0:
        raise InvalidInputError(
            f"{field}{axis_label(axis)} should be larger than zero, got {x!r}"
        )
    return x


def check_array(
    value: Any, field: str, ndim: int | None = 1, size: int | None = None,
    finite: bool = True,
) -> np.ndarray:
    """Coerce to a float64 array of the expected shape (finite by default).

    Parameters
    ----------
    value : array_like
        Input.
    field : str
        Name used in messages.
    ndim, size : int, optional
        Required number of dimensions / of entries.
    finite : bool
        Reject NaN/inf entries (set False when the caller checks each entry
        itself with a better message, e.g. naming the axis).

    Raises
    ------
    InvalidInputError
        On a wrong dimension or size, or on NaN/inf entries (the message names
        the first bad index).
    """
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{field} must be an array of numbers, got {value!r}") from None
    if ndim is not None and arr.ndim != ndim:
        raise InvalidInputError(
            f"{field} must have {ndim} dimension(s), got shape {arr.shape}"
        )
    if size is not None and arr.size != size:
        raise InvalidInputError(
            f"{field} must have {size} entries (one per axis), got {arr.size}"
        )
    bad = ~np.isfinite(arr) if finite else np.zeros(arr.shape, dtype=bool)
    if bad.any():
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        where = idx[0] if len(idx) == 1 else idx
        raise InvalidInputError(
            f"{field}[{where}] must be finite, got {float(arr[idx])!r}"
        )
    return arr
