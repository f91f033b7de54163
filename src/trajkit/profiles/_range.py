"""The supported numeric range of the profile planners, checked at their boundary.

Like ruckig, trajkit documents the range of inputs its planners are made
and tested for, and refuses anything outside it with an
:class:`~trajkit.errors.InvalidInputError` naming the field, the axis, the
value and the bound (instead of returning overflowed, NaN or meaningless
profiles).

=====================================  ========================  ========================
input                                  rest to rest              between moving states
                                       (``plan_move``,           (``plan_state_to_state``,
                                       ``min_duration``,         ``plan_velocity``,
                                       ``plan_moves``, ``plan_   ``feasible_durations``,
                                       ptp`` at rest)            ``plan_ptp`` with states)
=====================================  ========================  ========================
finite limits (``v_max``, ``a_max``,   ``[1e-152, 1e152]``       ``[1e-30, 1e30]``
``j_max``, decel leg; ``inf`` where
:class:`AxisLimits` allows it)
decel leg / accel leg (A and J)        ``[1e-6, 1e6]``           ``[1e-6, 1e6]``
``v_max j_max / a_max^2`` (each leg,   --                        ``[1e-9, 1e9]``
all finite)
``|position|``                         ``<= 1e100``              ``<= 1e15``
non-zero ``|distance|``                ``>= 1e-100``              ``>= 1e-100``
requested duration [s]                 ``[0, 1e300]``, at most   ``[0, 1e50]``
                                       ``1e100`` times the move's
                                       minimum, and a cruise
                                       velocity ``v`` with ``v/a``,
                                       ``v/j >= 1e-303``
state ``|v| / v_max``, ``|a| / a_max``  --                       ``<= 1e6``
speed a state forces,                  --                        ``<= 1e6 v_max``
``|v| + a^2 / (2 min(j_max,
j_max_decel))``
=====================================  ========================  ========================

(A start state outside the limits is braked first; the brake ends on the
limits to round-off of the speed the state forces, hence that bound.)

Inside the range the planners are exact to ``1e-9`` (relative) and every
profile passes :mod:`trajkit.verify`; the fuzz sweep of the tests
(``tests/test_numeric_range.py``, exponents -300..300 of every input) and
the extreme-magnitude grids check both sides.
"""

from __future__ import annotations

import math

from .._validate import axis_label
from ..errors import InvalidInputError

__all__ = [
    "MAGNITUDE_MIN", "MAGNITUDE_MAX", "LEG_RATIO_MAX", "SHAPE_RATIO_MAX", "POSITION_MAX",
    "STATE_RATIO_MAX", "DISTANCE_ABS_MIN", "DURATION_MAX",
    "REST_MAGNITUDE_MIN", "REST_MAGNITUDE_MAX", "REST_POSITION_MAX", "REST_DURATION_MAX",
    "REST_DURATION_RATIO_MAX", "REST_CRUISE_MIN", "check_rest_duration_ratio", "check_rest_cruise",
    "check_limits_range",
    "check_position_range", "check_distance_range", "check_state_range", "check_duration_range",
]

#: Smallest finite limit [unit/s, unit/s^2, unit/s^3] between moving states.
MAGNITUDE_MIN = 1e-30

#: Largest finite limit between moving states.
MAGNITUDE_MAX = 1e30

#: Smallest and largest finite limit of the rest-to-rest closed forms.
REST_MAGNITUDE_MIN = 1e-152
REST_MAGNITUDE_MAX = 1e152

#: Largest |position| [unit] of the rest-to-rest planners.
REST_POSITION_MAX = 1e100

#: Largest requested duration [s] of the rest-to-rest planners.
REST_DURATION_MAX = 1e300

#: Largest requested duration of a rest-to-rest move relative to its minimum
#: (a slower cruise would underflow).
REST_DURATION_RATIO_MAX = 1e100

#: Smallest cruise velocity of a fixed-duration rest-to-rest move relative to
#: each finite acceleration and jerk limit (``v / j`` and ``v / a`` [s^2, s]
#: stay normal floats).
REST_CRUISE_MIN = 1e-303

#: Largest ratio between a decel-leg limit and the accel-leg one (either way).
LEG_RATIO_MAX = 1e6

#: Largest ``v_max j_max / a_max^2`` (and its inverse) with all three finite.
SHAPE_RATIO_MAX = 1e9

#: Largest |position| [unit] between moving states.
POSITION_MAX = 1e15

#: Smallest non-zero |distance| [unit] (absolute).
DISTANCE_ABS_MIN = 1e-100

#: Largest requested duration [s] between moving states.
DURATION_MAX = 1e50

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
    lo, hi = (MAGNITUDE_MIN, MAGNITUDE_MAX) if states else (REST_MAGNITUDE_MIN, REST_MAGNITUDE_MAX)
    fields = (("v_max", limits.v_max), ("a_max", limits.a_max), ("j_max", limits.j_max),
              ("a_max_decel", limits.a_max_decel), ("j_max_decel", limits.j_max_decel))
    for f, x in fields:
        if x != math.inf and not (lo <= x <= hi):
            _bad(f, x, (lo, hi), name, "finite limits must lie in")
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


def check_position_range(x: float, field: str, name, states: bool = True) -> None:
    """Raise unless ``|x| <= POSITION_MAX`` (``REST_POSITION_MAX`` with ``states=False``)."""
    pm = POSITION_MAX if states else REST_POSITION_MAX
    if not (-pm <= x <= pm):
        _bad(field, x, pm, name, "|position| must be at most")


def check_distance_range(start: float, goal: float, name) -> None:
    """Raise for a non-zero distance below :data:`DISTANCE_ABS_MIN`.

    (A distance of a few ulp of the positions is planned exactly: the motion
    is planned relative to the start, where the distance is exact.)
    """
    d = abs(goal - start)
    if d != 0.0 and d < DISTANCE_ABS_MIN:
        _bad("distance", goal - start, DISTANCE_ABS_MIN, name, "a non-zero |distance| must be at least")


def check_duration_range(T: float, name, states: bool = True) -> None:
    """Raise for a requested duration above :data:`DURATION_MAX`
    (``REST_DURATION_MAX`` with ``states=False``)."""
    tm = DURATION_MAX if states else REST_DURATION_MAX
    if T > tm:
        _bad("duration", T, tm, name, "a requested duration [s] must be at most")


def check_state_range(v: float, a: float, field: str, limits) -> None:
    """Raise for a state velocity/acceleration beyond STATE_RATIO_MAX times its limit."""
    name = limits.name
    if limits.v_max < math.inf and abs(v) > STATE_RATIO_MAX * limits.v_max:
        _bad(f"{field} velocity", v, STATE_RATIO_MAX * limits.v_max, name, "|velocity| must be at most")
    am = max(limits.a_max, limits.a_max_decel)
    if am < math.inf and abs(a) > STATE_RATIO_MAX * am:
        _bad(f"{field} acceleration", a, STATE_RATIO_MAX * am, name, "|acceleration| must be at most")
    # the speed the state forces (its acceleration ramped to zero at the smaller
    # jerk limit): a brake from far beyond v_max cannot end on it to 1e-9
    jm = min(limits.j_max, limits.j_max_decel)
    if limits.v_max < math.inf and jm < math.inf:
        vn = abs(v) + 0.5 * a * a / jm
        if vn > STATE_RATIO_MAX * limits.v_max:
            _bad(f"{field} speed forced by the acceleration |v| + a^2 / (2 j)", vn,
                 STATE_RATIO_MAX * limits.v_max, name, "must be at most")


def check_rest_duration_ratio(T: float, tmin: float, name) -> None:
    """Raise for a rest-to-rest duration above ``REST_DURATION_RATIO_MAX`` times its minimum."""
    if T > REST_DURATION_RATIO_MAX * tmin:
        _bad("duration", T, REST_DURATION_RATIO_MAX * tmin, name,
             f"a requested duration [s] must be at most {REST_DURATION_RATIO_MAX!r} times the "
             "minimum duration of the move,")


def check_rest_cruise(vc: float, T: float, limits, name) -> None:
    """Raise when the cruise velocity ``vc`` of a fixed-duration rest-to-rest
    move is below ``REST_CRUISE_MIN`` times a finite acceleration or jerk limit."""
    for x in (limits.a_max, limits.j_max, limits.a_max_decel, limits.j_max_decel):
        if x < math.inf and vc < REST_CRUISE_MIN * x:
            _bad("duration", T, REST_CRUISE_MIN, name,
                 f"a requested duration [s] this long gives a cruise velocity {vc!r} whose "
                 "ratio to every finite acceleration and jerk limit must be at least")
