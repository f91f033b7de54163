"""Input checks shared by the multi-axis planners (one place for every message)."""

from __future__ import annotations

import math
import sys
from collections.abc import Sequence
from typing import Any

import numpy as np

from .._validate import check_array
from ..errors import InvalidInputError
from ..limits import AxisLimits
from ..profiles._range import (
    REST_POSITION_MAX,
    check_distance_range,
    check_duration_range,
    check_position_range,
)

__all__ = ["coerce_limits", "float_list", "check_positions", "check_distances", "coerce_states",
           "check_duration"]


def coerce_limits(
    limits: AxisLimits | Sequence[AxisLimits], n: int, named: bool = False
) -> list[AxisLimits]:
    """One AxisLimits per axis: the same objects, or with ``named=True`` copies of
    the unnamed ones carrying their axis index (for messages)."""
    if isinstance(limits, AxisLimits):
        if named and limits.name is None:
            return [_named(limits, i) for i in range(n)]
        return [limits] * n
    try:
        lims = list(limits)
    except TypeError:
        raise InvalidInputError(
            f"limits must be an AxisLimits or a sequence of them, got {type(limits).__name__}"
        ) from None
    if len(lims) != n:
        raise InvalidInputError(
            f"limits has {len(lims)} entries but start/goal have {n} axes"
        )
    for i, lim in enumerate(lims):
        if not isinstance(lim, AxisLimits):
            raise InvalidInputError(
                f"limits[{i}] must be an AxisLimits, got {type(lim).__name__}"
            )
        if named and lim.name is None:
            lims[i] = _named(lim, i)
    return lims


def _named(lim: AxisLimits, i: int) -> AxisLimits:
    """``lim.with_name(i)``, the same object on every call (cached on ``lim``, which
    is frozen): the copy keeps what the planners cached on it after validating it."""
    cache = lim.__dict__.get("_named")
    if cache is None:
        cache = {}
        object.__setattr__(lim, "_named", cache)
    out = cache.get(i)
    if out is None:
        out = cache[i] = lim.with_name(i)
    return out


def state_tuples(x: Any) -> list[tuple[float, float, float]] | None:
    """Fast path of :func:`coerce_states`: states given as a list/tuple (or a
    float64 array) of ``n_axes`` rows of 3 finite floats, as a list of tuples of
    floats; None for anything else (then :func:`coerce_states` decides)."""
    if isinstance(x, np.ndarray):
        if x.dtype != np.float64 or x.ndim != 2 or x.shape[1] != 3:
            return None
        x = x.tolist()
    elif type(x) is not list and type(x) is not tuple:
        return None
    out = []
    for r in x:
        if (type(r) is not tuple and type(r) is not list) or len(r) != 3:
            return None
        p, v, a = r
        if (type(p) is not float or type(v) is not float or type(a) is not float
                or not (abs(p) <= _FMAX and abs(v) <= _FMAX and abs(a) <= _FMAX)):
            return None
        out.append(r if type(r) is tuple else (p, v, a))
    return out


_FMAX = sys.float_info.max


def float_list(value: Any, field: str) -> list[float]:
    """A 1-D sequence of numbers as a list of floats (fast path for lists and
    1-D arrays; everything else goes through :func:`check_array`)."""
    if isinstance(value, np.ndarray) and value.ndim == 1 and value.dtype.kind in "fiu":
        return value.astype(np.float64, copy=False).tolist()
    if isinstance(value, (list, tuple)) and all(type(x) in (float, int) for x in value):
        return [float(x) for x in value]
    return check_array(value, field, ndim=1, finite=False).tolist()


def check_positions(values: list[float], lims: list[AxisLimits], field: str) -> list[float]:
    """Finite, inside each axis' range and the supported range of the
    rest-to-rest planners (:mod:`trajkit.profiles._range`); messages name the
    axis (its name or index)."""
    for i, (x, lim) in enumerate(zip(values, lims)):
        if not (lim.position_min <= x <= lim.position_max) or not math.isfinite(x):
            (lim if lim.name is not None else lim.with_name(i)).check_position(x, field)
        if not (-REST_POSITION_MAX <= x <= REST_POSITION_MAX):
            check_position_range(x, field, lim.name if lim.name is not None else i, states=False)
    return values


def check_distances(starts: list[float], goals: list[float], lims: list[AxisLimits]) -> None:
    """Every non-zero distance resolvable (:func:`~trajkit.profiles._range.check_distance_range`)."""
    for i, (a, b, lim) in enumerate(zip(starts, goals, lims)):
        check_distance_range(a, b, lim.name if lim.name is not None else i)


def coerce_states(x: Any, field: str) -> np.ndarray:
    """States per axis as an (n_axes, 3) array: ``(position, velocity, acceleration)``.

    A 1-D array gives positions at rest.
    """
    arr = check_array(x, field, ndim=None)
    if arr.ndim == 1:
        out = np.zeros((arr.size, 3))
        out[:, 0] = arr
        return out
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise InvalidInputError(
            f"{field} must have shape (n_axes, 3) (position, velocity, acceleration "
            f"per axis) or (n_axes,), got shape {arr.shape}"
        )
    return arr


def check_duration(duration: Any, sync: str, states: bool = False) -> float | None:
    """The requested common duration [s] (None: minimum), validated (the range
    of the rest-to-rest planners, or with ``states`` of the state planners)."""
    if duration is None:
        return None
    try:
        d = float(duration)
    except (TypeError, ValueError):
        raise InvalidInputError(f"duration must be a number of seconds, got {duration!r}") from None
    if not math.isfinite(d) or d < 0:
        raise InvalidInputError(f"duration must be finite and >= 0 s, got {d!r}")
    if sync == "none":
        raise InvalidInputError('duration cannot be given with sync="none"')
    check_duration_range(d, None, states=states)
    return d
