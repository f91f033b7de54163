"""Step/direction pulse output (patent CN105892402): commanded positions -> pulses per period.

The count is computed from the *absolute* commanded position every period,
``count = floor(position / pulse_equivalent + 1/2)`` (:func:`pulse_count`), and the pulses of a
period are the difference to the previous count. Nothing is accumulated from increments, so there is no drift
and no lost position over any number of moves: after every period the
accumulated pulse count equals the commanded position rounded to one pulse.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._validate import axis_label, check_finite, check_positive
from ..errors import InvalidInputError, SafetyFault

__all__ = ["PulseAxis", "PulseRateFault", "edge_times", "pulse_count", "pulse_counts"]


class PulseRateFault(SafetyFault):
    """More pulses in a period than the drive accepts.

    Attributes
    ----------
    axis : str or int or None
    quantity : str
        ``"pulse rate"``.
    value, limit : float
        Pulse rate and maximum pulse rate [pulses/s].
    """

    def __init__(self, message: str, axis, value: float, limit: float):
        super().__init__(message)
        self.axis = axis
        self.quantity = "pulse rate"
        self.value = value
        self.limit = limit


def pulse_count(position: float, pulse_equivalent: float) -> int:
    """Absolute pulse count of a position: ``floor(position / eq + 1/2)``.

    Parameters
    ----------
    position : float
        Commanded position [unit].
    pulse_equivalent : float
        Travel per pulse [unit/pulse], > 0.

    Returns
    -------
    int
        The position rounded to the nearest pulse (halves round up).
    """
    return int(math.floor(position / pulse_equivalent + 0.5))


def pulse_counts(positions: Any, pulse_equivalent: float) -> np.ndarray:
    """Vectorised :func:`pulse_count`: array_like (n,) [unit] -> int64 array (n,)."""
    x = np.asarray(positions, dtype=np.float64)
    return np.floor(x / pulse_equivalent + 0.5).astype(np.int64)


def edge_times(pulses: int, period: float, t0: float = 0.0) -> np.ndarray:
    """Evenly spread step-edge times of ``|pulses|`` pulses within one period.

    Edge ``k`` (0-based) of ``n`` is at ``t0 + (k + 1/2) * period / n`` [s].

    Returns
    -------
    ndarray, shape (abs(pulses),)
    """
    n = abs(int(pulses))
    return t0 + (np.arange(n) + 0.5) * (period / n) if n else np.empty(0)


class PulseAxis:
    """Pulse generator of one axis.

    Parameters
    ----------
    pulse_equivalent : float
        Travel per pulse [unit/pulse], > 0 (e.g. 1e-6 m).
    max_rate : float
        Largest pulse rate the drive accepts [pulses/s], > 0 (``inf`` for no
        check).
    position : float
        Initial commanded position [unit]; the count starts at its pulse count.
    name : str or int, optional
        Axis name for messages.

    Attributes
    ----------
    count : int
        Accumulated (absolute) pulse count.
    direction : int
        Direction of the last non-zero period: +1 or -1 (0 before any pulse).
    """

    def __init__(self, pulse_equivalent: float, max_rate: float = math.inf,
                 position: float = 0.0, name: str | int | None = None) -> None:
        self.pulse_equivalent = check_positive(pulse_equivalent, "pulse_equivalent", name)
        self.max_rate = check_positive(max_rate, "max_rate", name, allow_inf=True)
        self.name = name
        self.count = pulse_count(check_finite(position, "position", name), self.pulse_equivalent)
        self.direction = 0

    def update(self, position: float, period: float) -> int:
        """Pulses to emit for one period ending at the commanded ``position``.

        Parameters
        ----------
        position : float
            Commanded position at the end of the period [unit].
        period : float
            Period length [s] (for the rate check).

        Returns
        -------
        int
            Signed number of pulses (sign = direction).

        Raises
        ------
        PulseRateFault
            ``|pulses| / period`` above ``max_rate``; the count is not updated.
        """
        target = pulse_count(position, self.pulse_equivalent)
        n = target - self.count
        rate = abs(n) / period
        if rate > self.max_rate:
            raise PulseRateFault(
                f"pulse rate {rate!r} pulses/s{axis_label(self.name)} exceeds the maximum "
                f"pulse rate {self.max_rate!r} pulses/s",
                self.name, rate, self.max_rate,
            )
        self.count = target
        if n:
            self.direction = 1 if n > 0 else -1
        return n

    @property
    def position(self) -> float:
        """Position the accumulated count stands for [unit]."""
        return self.count * self.pulse_equivalent

    def __repr__(self) -> str:
        return (f"PulseAxis(pulse_equivalent={self.pulse_equivalent!r}, "
                f"max_rate={self.max_rate!r}, count={self.count})")


def check_pulse_equivalents(values: Any, n: int) -> list[float]:
    """Validate ``n`` pulse equivalents [unit/pulse] (positive, finite)."""
    if np.ndim(values) == 0:
        values = [values] * n
    vals = list(values)
    if len(vals) != n:
        raise InvalidInputError(f"pulse_equivalents must have {n} values, got {len(vals)}")
    return [check_positive(v, "pulse_equivalent", k) for k, v in enumerate(vals)]
