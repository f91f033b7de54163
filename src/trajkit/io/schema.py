"""Field types and error messages shared by the file schemas (jobs, programs, HMI bodies).

Numbers in files are strict: ``v_max: yes``, ``v_max: "1e3"`` and
``percent: true`` are refused instead of being read as 1.0, 1000.0 and 1.0.
Integers are accepted where a real number is expected.
"""

from __future__ import annotations

import math
from typing import Annotated, Any

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, Strict, ValidationError

__all__ = ["Real", "RealOrInf", "Count", "Coordinate_mm", "Length_mm", "PositiveLength_mm", "Angle_deg", "Time_s",
           "LimitValue", "MAX_LENGTH_MM", "MAX_ANGLE_DEG", "MAX_TIME_S", "MAX_LIMIT_VALUE", "FileModel",
           "validation_message", "short_repr"]

#: A real number field: int or float, never a bool or a string.
Real = Annotated[float, Strict()]

_INFINITIES = {"inf": math.inf, "+inf": math.inf, "-inf": -math.inf, "infinity": math.inf,
               "+infinity": math.inf, "-infinity": -math.inf}


def _spelled_infinity(value: Any) -> Any:
    if isinstance(value, str) and value.strip().lower() in _INFINITIES:
        return _INFINITIES[value.strip().lower()]
    return value


#: A real number that may also be infinite ("no limit"): a number, YAML's
#: ``.inf``/``-.inf``, or the strings ``"inf"``/``"-inf"`` (JSON has no infinity).
RealOrInf = Annotated[float, Strict(), BeforeValidator(_spelled_infinity)]

#: An integer field: never a bool, a float or a string.
Count = Annotated[int, Strict()]


#: Supported range of lengths and coordinates in files [mm] (1 km).
MAX_LENGTH_MM = 1e6

#: Supported range of angles in files [deg] (a thousand turns).
MAX_ANGLE_DEG = 360e3

#: Longest dwell, wait or gripper time in files [s] (one day).
MAX_TIME_S = 86400.0

#: Largest limit value (velocity, acceleration, jerk) in files, in the file's units.
MAX_LIMIT_VALUE = 1e12

#: A coordinate [mm] within +-MAX_LENGTH_MM.
Coordinate_mm = Annotated[Real, Field(ge=-MAX_LENGTH_MM, le=MAX_LENGTH_MM, allow_inf_nan=False)]

#: A length [mm] in [0, MAX_LENGTH_MM].
Length_mm = Annotated[Real, Field(ge=0, le=MAX_LENGTH_MM, allow_inf_nan=False)]

#: A length [mm] in (0, MAX_LENGTH_MM].
PositiveLength_mm = Annotated[Real, Field(gt=0, le=MAX_LENGTH_MM, allow_inf_nan=False)]

#: An angle [deg] within +-MAX_ANGLE_DEG.
Angle_deg = Annotated[Real, Field(ge=-MAX_ANGLE_DEG, le=MAX_ANGLE_DEG, allow_inf_nan=False)]

#: A time [s] in [0, MAX_TIME_S].
Time_s = Annotated[Real, Field(ge=0, le=MAX_TIME_S, allow_inf_nan=False)]

#: A limit (velocity, acceleration, jerk) in (0, MAX_LIMIT_VALUE].
LimitValue = Annotated[Real, Field(gt=0, le=MAX_LIMIT_VALUE, allow_inf_nan=False)]


class FileModel(BaseModel):
    """Base of the file schemas: unknown fields are refused, instances are frozen."""

    model_config = ConfigDict(extra="forbid", frozen=True)


def short_repr(value: Any, limit: int = 40) -> str:
    """``repr(value)`` cut to ``limit`` characters (error messages never echo a whole input)."""
    s = repr(value)
    return s if len(s) <= limit else s[: limit - 3] + "..."


def validation_message(exc: ValidationError, loc_skip: tuple = ()) -> str:
    """One line for the first error of a pydantic ``ValidationError``.

    ``field limits.1.v_max: Input should be greater than 0 (got -1)``, with
    ``(and N more)`` when there are several errors. Entries of ``loc_skip``
    (union branch names) are left out of the field path.
    """
    errs = exc.errors()
    e = errs[0]
    loc = [p for p in e.get("loc", ()) if p not in loc_skip
           and not (isinstance(p, str) and p.startswith("function-"))]
    where = ".".join(str(p) for p in loc) or "(top level)"
    got = e.get("input")
    shown = "" if isinstance(got, (dict, list)) else f" (got {short_repr(got)})"
    more = f" (and {len(errs) - 1} more)" if len(errs) > 1 else ""
    return f"field {where}: {e.get('msg', 'invalid')}{shown}{more}"
