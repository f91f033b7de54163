"""Per-axis kinematic limits."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ._validate import axis_label, check_positive
from .errors import InvalidInputError

__all__ = ["AxisLimits"]


def _leg_threshold(a: float, j: float) -> float:
    """Velocity ``a^2/j`` above which a velocity ramp reaches ``a`` (cached per limits)."""
    if a == math.inf:
        return math.inf
    if j == math.inf:
        return 0.0
    return a * a / j


@dataclass(frozen=True, init=False)
class AxisLimits:
    """Kinematic limits of one axis, validated at construction.

    The *accel* limits (``a_max``, ``j_max``) apply while the axis speeds up
    (|v| grows), the *decel* limits (``a_max_decel``, ``j_max_decel``) while it
    slows down (|v| shrinks), whatever the direction of motion (patent CN105892402:
    J1, A1 versus J2, A2).

    Parameters
    ----------
    v_max : float
        Velocity limit [unit/s], > 0; ``math.inf`` for none.
    a_max : float
        Acceleration limit while speeding up [unit/s^2], > 0; ``math.inf``
        allowed only with a finite ``j_max``.
    j_max : float
        Jerk limit while speeding up [unit/s^3], > 0; ``math.inf`` gives the
        acceleration-limited (trapezoidal) profile.
    a_max_decel, j_max_decel : float or None
        The same while slowing down; ``None`` means "same as the accel leg".
    position_min, position_max : float
        Position range [unit]; ``-inf``/``inf`` for none.
    name : str or int or None
        Axis name used in error messages (e.g. ``"B"`` or ``2``).

    Raises
    ------
    InvalidInputError
        For a non-positive or NaN limit, for ``a`` and ``j`` both infinite on
        one leg, or for ``position_min > position_max``. The message names the
        field, the axis and the value.
    """

    # After construction every limit is a float: a ``None`` decel limit has been
    # replaced by the accel one, hence the explicit ``__init__`` below.
    v_max: float
    a_max: float
    j_max: float
    a_max_decel: float
    j_max_decel: float
    position_min: float
    position_max: float
    name: str | int | None = field(compare=False)
    # derived once per instance (not parameters, not compared, not shown):
    # the velocity ``a^2/j`` of each leg (accel, decel), the larger acceleration
    # limit of both legs and ``1/(2 j)`` for the smaller jerk limit (0 for none)
    _thresholds: tuple[float, float] = field(init=False, repr=False, compare=False)
    _amax: float = field(init=False, repr=False, compare=False)
    _kmin2: float = field(init=False, repr=False, compare=False)

    def __init__(
        self,
        v_max: float,
        a_max: float,
        j_max: float,
        a_max_decel: float | None = None,
        j_max_decel: float | None = None,
        position_min: float = -math.inf,
        position_max: float = math.inf,
        name: str | int | None = None,
    ) -> None:
        ax = name
        object.__setattr__(self, "name", name)
        v = check_positive(v_max, "maximum velocity limit v_max", ax, allow_inf=True)
        a = check_positive(a_max, "maximum acceleration limit a_max", ax, allow_inf=True)
        j = check_positive(j_max, "maximum jerk limit j_max", ax, allow_inf=True)
        ad = a if a_max_decel is None else check_positive(
            a_max_decel, "maximum deceleration limit a_max_decel", ax, allow_inf=True
        )
        jd = j if j_max_decel is None else check_positive(
            j_max_decel, "maximum deceleration jerk limit j_max_decel", ax, allow_inf=True
        )
        if math.isinf(a) and math.isinf(j):
            raise InvalidInputError(
                f"a_max and j_max{axis_label(ax)} cannot both be infinite "
                "(the velocity would jump)"
            )
        if math.isinf(ad) and math.isinf(jd):
            raise InvalidInputError(
                f"a_max_decel and j_max_decel{axis_label(ax)} cannot both be infinite "
                "(the velocity would jump)"
            )
        try:
            pmin = float(position_min)
            pmax = float(position_max)
        except (TypeError, ValueError):
            raise InvalidInputError(
                f"position range{axis_label(ax)} must be numbers, got "
                f"[{position_min!r}, {position_max!r}]"
            ) from None
        if math.isnan(pmin) or math.isnan(pmax):
            raise InvalidInputError(
                f"position range{axis_label(ax)} must not be NaN, got [{pmin}, {pmax}]"
            )
        if pmin == math.inf or pmax == -math.inf:
            raise InvalidInputError(
                f"position range{axis_label(ax)} is empty: [{pmin}, {pmax}]"
            )
        if pmin > pmax:
            raise InvalidInputError(
                f"position_min {pmin} is above position_max {pmax}{axis_label(ax)}"
            )
        object.__setattr__(self, "v_max", v)
        object.__setattr__(self, "a_max", a)
        object.__setattr__(self, "j_max", j)
        object.__setattr__(self, "a_max_decel", ad)
        object.__setattr__(self, "j_max_decel", jd)
        object.__setattr__(self, "position_min", pmin)
        object.__setattr__(self, "position_max", pmax)
        object.__setattr__(self, "_thresholds", (_leg_threshold(a, j), _leg_threshold(ad, jd)))
        object.__setattr__(self, "_amax", max(a, ad))
        jm = min(j, jd)
        object.__setattr__(self, "_kmin2", 0.5 / jm if jm < math.inf else 0.0)

    @property
    def symmetric(self) -> bool:
        """True when the decel leg has the same limits as the accel leg."""
        return self.a_max == self.a_max_decel and self.j_max == self.j_max_decel

    def with_name(self, name: str | int | None) -> AxisLimits:
        """Return a copy carrying ``name`` for error messages (no re-validation)."""
        new = object.__new__(AxisLimits)
        for f in ("v_max", "a_max", "j_max", "a_max_decel", "j_max_decel",
                  "position_min", "position_max", "_thresholds", "_amax", "_kmin2"):
            object.__setattr__(new, f, getattr(self, f))
        object.__setattr__(new, "name", name)
        return new

    def scaled(self, factor: float) -> AxisLimits:
        """Return limits for a coordinate scaled by ``factor`` > 0 (unit change).

        Velocity, acceleration, jerk and the range are all multiplied by
        ``factor``; e.g. ``limits_deg.scaled(math.pi / 180)`` gives radians.
        """
        f = check_positive(factor, "scale factor")
        return AxisLimits(
            self.v_max * f, self.a_max * f, self.j_max * f,
            self.a_max_decel * f, self.j_max_decel * f,
            self.position_min * f, self.position_max * f, self.name,
        )

    def derated(self, accel: float = 1.0, jerk: float = 1.0, velocity: float = 1.0) -> AxisLimits:
        """Return limits reduced by factors in (0, 1] (a planning reserve).

        Both legs are scaled: ``a_max`` and ``a_max_decel`` by ``accel``,
        ``j_max`` and ``j_max_decel`` by ``jerk``, ``v_max`` by ``velocity``;
        the position range and the name are kept. Used to plan programs that
        are streamed with a feed override
        (:data:`trajkit.runtime.OVERRIDE_RESERVE`): the unused part of the
        machine's limits is what a change of the rate may use.

        Parameters
        ----------
        accel, jerk, velocity : float
            Factors in (0, 1] (dimensionless).

        Returns
        -------
        AxisLimits

        Raises
        ------
        InvalidInputError
            A factor that is not a finite number in (0, 1]; the message names
            the factor, the axis and the value.
        """
        fs = []
        for nm, f in (("accel", accel), ("jerk", jerk), ("velocity", velocity)):
            try:
                x = float(f)
            except (TypeError, ValueError):
                raise InvalidInputError(
                    f"derating factor {nm}{axis_label(self.name)} must be a number in (0, 1], "
                    f"got {f!r}") from None
            if not 0.0 < x <= 1.0:  # NaN fails too
                raise InvalidInputError(
                    f"derating factor {nm}{axis_label(self.name)} must be in (0, 1], got {x!r}")
            fs.append(x)
        fa, fj, fv = fs
        return AxisLimits(
            self.v_max * fv, self.a_max * fa, self.j_max * fj,
            self.a_max_decel * fa, self.j_max_decel * fj,
            self.position_min, self.position_max, self.name,
        )

    def check_position(self, value: float, field_name: str = "position") -> float:
        """Raise unless ``value`` is a finite number inside the position range."""
        try:
            x = float(value)
        except (TypeError, ValueError):
            raise InvalidInputError(
                f"{field_name}{axis_label(self.name)} must be a number, got {value!r}"
            ) from None
        if not math.isfinite(x):
            raise InvalidInputError(f"{field_name}{axis_label(self.name)} must be finite, got {x!r}")
        if x < self.position_min or x > self.position_max:
            raise InvalidInputError(
                f"{field_name} {x!r}{axis_label(self.name)} is outside the position range "
                f"[{self.position_min}, {self.position_max}]"
            )
        return x
