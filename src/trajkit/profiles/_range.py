"""The supported numeric range of the profile planners, checked at their boundary.

Like ruckig, trajkit documents the range of inputs its planners are made
and tested for, and refuses anything outside it with an
:class:`~trajkit.errors.InvalidInputError` naming the field, the axis, the
value and the bound (instead of returning overflowed, NaN or meaningless
profiles):

* every finite limit (``v_max``, ``a_max``, ``j_max`` and the decel leg) in
  ``[MAGNITUDE_MIN, MAGNITUDE_MAX]`` (``inf`` where :class:`AxisLimits`
  allows it);
* the decel leg within a factor :data:`LEG_RATIO_MAX` of the accel leg;
* between moving states, the shape number ``v_max j_max / a_max^2`` (how the
  velocity limit compares with a full jerk ramp) in
  ``[1/SHAPE_RATIO_MAX, SHAPE_RATIO_MAX]``;
* positions within ``+-POSITION_MAX``; a distance of at least
  ``DISTANCE_MIN`` times the largest position moved, else zero (a smaller
  one is below the resolution of the positions themselves);
* state velocities and accelerations within :data:`STATE_RATIO_MAX` times
  their limit (a start state outside the limits is braked first).

Inside the range the planners are exact to ``1e-9`` (relative) and every
profile passes :mod:`trajkit.verify`; the fuzz sweep of the tests
(exponents -300..300 of every input) checks both sides.
"""

from __future__ import annotations

import math

from .._validate import axis_label
from ..errors import InvalidInputError

__all__ = [
    "MAGNITUDE_MIN", "MAGNITUDE_MAX", "LEG_RATIO_MAX", "SHAPE_RATIO_MAX", "POSITION_MAX",
    "STATE_RATIO_MAX", "DISTANCE_MIN", "check_limits_range", "check_position_range",
    "check_distance_range", "check_state_range",
]

#: Smallest finite limit [unit/s, unit/s^2, unit/s^3].
MAGNITUDE_MIN = 1e-30

#: Largest finite limit.
MAGNITUDE_MAX = 1e30

#: Largest ratio between a decel-leg limit and the accel-leg one (either way).
LEG_RATIO_MAX = 1e6

#: Largest ``v_max j_max / a_max^2`` (and its inverse) with all three finite.
SHAPE_RATIO_MAX = 1e9

#: Largest |position| [unit].
POSITION_MAX = 1e15

#: Smallest non-zero |distance| relative to the largest |position| involved.
DISTANCE_MIN = 1e-14

#: Largest |velocity| / v_max and |acceleration| / a_max of a state.
STATE_RATIO_MAX = 1e6


def _bad(field, value, bound, name, why):
    raise InvalidInputError(
        f"{field} {value!r}{axis_label(name)} is outside the supported range: {why} {bound!r}"
    )


def check_limits_range(limits, states: bool = False) -> None:
    """Raise unless ``limits`` lie in the supported range (result cached on the object).

    ``states=True`` adds the bound on the shape number (the planners between
    moving states); the rest-to-rest closed forms do not need it.
    """
    key = "_range_ok_states" if states else "_range_ok"
    if limits.__dict__.get(key, False):
        return
    name = limits.name
    fields = (("v_max", limits.v_max), ("a_max", limits.a_max), ("j_max", limits.j_max),
              ("a_max_decel", limits.a_max_decel), ("j_max_decel", limits.j_max_decel))
    for f, x in fields:
        if x != math.inf and not (MAGNITUDE_MIN <= x <= MAGNITUDE_MAX):
            _bad(f, x, (MAGNITUDE_MIN, MAGNITUDE_MAX), name, "finite limits must lie in")
    for f, x, y in (("a_max_decel", limits.a_max_decel, limits.a_max),
                    ("j_max_decel", limits.j_max_decel, limits.j_max)):
        if x < math.inf and y < math.inf and not (1.0 / LEG_RATIO_MAX <= x / y <= LEG_RATIO_MAX):
            _bad(f, x, LEG_RATIO_MAX, name,
                 f"the decel leg must be within a factor of the accel leg ({y!r}):")
    V = limits.v_max
    for A, J in ((limits.a_max, limits.j_max), (limits.a_max_decel, limits.j_max_decel)):
        if states and V < math.inf and A < math.inf and J < math.inf:
            r = V * J / (A * A)
            if not (1.0 / SHAPE_RATIO_MAX <= r <= SHAPE_RATIO_MAX):
                _bad("v_max j_max / a_max^2", r, (1.0 / SHAPE_RATIO_MAX, SHAPE_RATIO_MAX), name,
                     "the velocity limit compared with a full jerk ramp must lie in")
    object.__setattr__(limits, key, True)


def check_position_range(x: float, field: str, name) -> None:
    """Raise unless ``|x| <= POSITION_MAX``."""
    if not (-POSITION_MAX <= x <= POSITION_MAX):
        _bad(field, x, POSITION_MAX, name, "|position| must be at most")


def check_distance_range(start: float, goal: float, name) -> None:
    """Raise for a non-zero distance below the resolution of the positions."""
    d = abs(goal - start)
    if d != 0.0 and d < DISTANCE_MIN * max(abs(start), abs(goal)):
        _bad("distance", goal - start, DISTANCE_MIN, name,
             "a non-zero distance relative to the positions must be at least")


def check_state_range(v: float, a: float, field: str, limits) -> None:
    """Raise for a state velocity/acceleration beyond STATE_RATIO_MAX times its limit."""
    name = limits.name
    if limits.v_max < math.inf and abs(v) > STATE_RATIO_MAX * limits.v_max:
        _bad(f"{field} velocity", v, STATE_RATIO_MAX * limits.v_max, name, "|velocity| must be at most")
    am = max(limits.a_max, limits.a_max_decel)
    if am < math.inf and abs(a) > STATE_RATIO_MAX * am:
        _bad(f"{field} acceleration", a, STATE_RATIO_MAX * am, name, "|acceleration| must be at most")
