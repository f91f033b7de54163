"""Safety configuration, the runtime fault type and the per-cycle limit monitors.

Monitors (every cycle, on the *candidate* setpoint before it is output):

- ``position``: the commanded position outside the soft range, or the
  position where the minimum-time brake from the commanded state would end
  outside it (look-ahead, so the stop itself stays inside the range);
- ``velocity``: ``|v| > v_max``, or, while ``|v|`` grows, the velocity the
  jerk-limited ramp-down of the acceleration would reach,
  ``|v| + a^2 / (2 j_max)``, above ``v_max`` (look-ahead, so the brake from
  the last good state never overspeeds);
- ``acceleration``: ``|a|`` above ``a_max`` while ``|v|`` grows
  (``v a > 0``), above ``a_max_decel`` while it shrinks;
- ``following error``: ``|commanded - measured|`` above the configured limit
  (needs the servo simulation);
- ``pulse rate``: more pulses in a period than ``max_pulse_rate`` allows;
- ``in position``: an exact stop waited longer than the servo's
  ``settle_timeout`` for in-position (value and limit in seconds).

All comparisons allow the relative tolerance :data:`MONITOR_RTOL`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._constants import LIMIT_RTOL
from ..errors import InvalidInputError, SafetyFault
from ._brake import stop_position

__all__ = ["MONITOR_RTOL", "QUANTITIES", "REACTIONS", "RuntimeFault", "SafetyConfig"]

#: Relative tolerance of the monitors (float round-off of planned profiles).
MONITOR_RTOL = LIMIT_RTOL

#: Quantities the monitors check.
QUANTITIES = ("position", "velocity", "acceleration", "following error", "pulse rate",
              "in position")

#: Fault reactions: ``"controlled"`` (minimum-time brake / stop on the path)
#: or ``"emergency"`` (output buffer cleared, drives off, brakes engaged).
REACTIONS = ("controlled", "emergency")

_DEFAULT_REACTIONS = {
    "position": "controlled",
    "velocity": "controlled",
    "acceleration": "controlled",
    "following error": "emergency",
    "pulse rate": "controlled",
    "in position": "controlled",
    "emergency stop": "emergency",
}


class RuntimeFault(SafetyFault):
    """A monitor tripped on a given cycle.

    Attributes
    ----------
    axis : str
        Axis name.
    quantity : str
        One of :data:`QUANTITIES` (or ``"emergency stop"``).
    value, limit : float
        The offending value and the limit it crossed [axis units].
    cycle : int
        Cycle on which it was detected (its setpoint was not output).
    t : float
        Time of that cycle [s].
    """

    def __init__(self, axis: str, quantity: str, value: float, limit: float,
                 cycle: int, t: float, detail: str = "") -> None:
        msg = (f"{quantity} {value!r}{detail} of axis {axis} exceeds the limit {limit!r} "
               f"at cycle {cycle} (t = {t:.6g} s)")
        if quantity == "emergency stop":
            msg = f"emergency stop at cycle {cycle} (t = {t:.6g} s){detail}"
        super().__init__(msg)
        self.axis = axis
        self.quantity = quantity
        self.value = value
        self.limit = limit
        self.cycle = cycle
        self.t = t


@dataclass(frozen=True)
class SafetyConfig:
    """Monitor limits and fault reactions.

    Parameters
    ----------
    following_error : float or sequence of float or None
        Largest following error per axis [unit] (``inf``: off). ``None``:
        50 times the servo in-position window.
    reactions : dict, optional
        ``quantity -> "controlled" | "emergency"``, overriding the defaults
        (``"following error"`` -> emergency, everything else -> controlled).
    look_ahead : bool
        Use the braking look-ahead of the position and velocity monitors.
    """

    following_error: Any = None
    reactions: dict = field(default_factory=dict)
    look_ahead: bool = True

    def __post_init__(self) -> None:
        for q, r in self.reactions.items():
            if q not in _DEFAULT_REACTIONS:
                raise InvalidInputError(
                    f"reaction for unknown quantity {q!r}; expected one of {QUANTITIES}")
            if r not in REACTIONS:
                raise InvalidInputError(
                    f"reaction {r!r} for {q} must be one of {REACTIONS}")

    def reaction(self, quantity: str) -> str:
        """The configured reaction to a fault of ``quantity``."""
        return self.reactions.get(quantity, _DEFAULT_REACTIONS[quantity])


class Monitors:
    """Vectorised per-cycle limit checks of a machine's axes (internal)."""

    def __init__(self, limits, names, fe_max: np.ndarray, look_ahead: bool) -> None:
        self.limits = limits
        self.names = names
        r = 1.0 + MONITOR_RTOL
        self.vmax = np.array([lm.v_max for lm in limits]) * r
        self.vmax_raw = np.array([lm.v_max for lm in limits])
        self.amax = np.array([lm.a_max for lm in limits]) * r
        self.adec = np.array([lm.a_max_decel for lm in limits]) * r
        self.jmax = np.array([lm.j_max for lm in limits])
        self.pmin = np.array([lm.position_min for lm in limits])
        self.pmax = np.array([lm.position_max for lm in limits])
        span = np.where(np.isfinite(self.pmax - self.pmin), np.abs(self.pmax - self.pmin), 1.0)
        self.ptol = MONITOR_RTOL * np.maximum(span, 1.0)
        self.ranged = [k for k in range(len(limits))
                       if math.isfinite(limits[k].position_min) or math.isfinite(limits[k].position_max)]
        self.fe_max = fe_max
        self.look_ahead = look_ahead
        self._lo = (self.pmin - self.ptol).tolist()
        self._hi = (self.pmax + self.ptol).tolist()
        self._pmin = self.pmin.tolist()
        self._pmax = self.pmax.tolist()
        self._vm = self.vmax.tolist()
        self._vraw = self.vmax_raw.tolist()
        self._am = self.amax.tolist()
        self._ad = self.adec.tolist()
        self._jm = self.jmax.tolist()
        self._fe = [float(x) for x in fe_max]
        self._h_jm = [0.5 / lm.j_max for lm in limits]
        self._ij = [1.0 / lm.j_max + 1.0 / lm.j_max_decel for lm in limits]
        self._iad = [1.0 / lm.a_max_decel for lm in limits]
        self._tad = [2.0 * lm.a_max_decel / lm.j_max_decel for lm in limits]

    def check(self, q, v, a, measured=None):
        """First violation as ``(axis index, quantity, value, limit[, detail])`` or None.

        Scalar Python over the axes (faster than numpy for a handful of axes).
        """
        ql, vl, al = q.tolist(), v.tolist(), a.tolist()
        for k in range(len(ql)):
            x = ql[k]
            if x < self._lo[k] or x > self._hi[k]:
                lim = self._pmin[k] if x < self._lo[k] else self._pmax[k]
                return k, "position", x, lim
        if self.look_ahead:
            for k in self.ranged:
                vk, ak = vl[k], al[k]
                if vk == 0.0 and ak == 0.0:
                    continue
                x = ql[k]
                # cheap bound of the stopping distance first (_reach, inlined);
                # the exact brake only when near the range ends
                room = min(x - self._lo[k], self._hi[k] - x)
                av, aa = abs(vk), abs(ak)
                vpk = av + aa * aa * self._h_jm[k]
                if room > vpk * (aa * self._ij[k] + vpk * self._iad[k] + self._tad[k]):
                    continue
                xs = stop_position(x, vk, ak, self.limits[k])
                if xs < self._lo[k] or xs > self._hi[k]:
                    lim = self._pmin[k] if xs < self._lo[k] else self._pmax[k]
                    return k, "position", xs, lim, " (where its minimum-time brake would end)"
        for k in range(len(vl)):
            vk, ak = vl[k], al[k]
            av = abs(vk)
            if av > self._vm[k]:
                return k, "velocity", av, self._vraw[k]
            if self.look_ahead and vk * ak > 0.0:
                pk = av + ak * ak / (2.0 * self._jm[k])
                if pk > self._vm[k]:
                    return (k, "velocity", pk, self._vraw[k],
                            " (peak of the jerk-limited ramp-down of its acceleration)")
            if vk * ak < 0.0:
                if abs(ak) > self._ad[k]:
                    return k, "acceleration", ak, self.limits[k].a_max_decel
            elif abs(ak) > self._am[k]:
                return k, "acceleration", ak, self.limits[k].a_max
        if measured is not None:
            fe = np.abs(q - measured)
            if (fe > self.fe_max).any():
                k = int(np.argmax(fe > self.fe_max))
                return k, "following error", float(fe[k]), self._fe[k]
        return None

    def _reach(self, k: int, v: float, a: float) -> float:
        """Upper bound of the stopping distance of axis ``k`` from ``(v, a)`` [unit]."""
        lm = self.limits[k]
        av, aa = abs(v), abs(a)
        vpk = av + aa * aa / (2.0 * lm.j_max)
        tb = aa / lm.j_max + aa / lm.j_max_decel + vpk / lm.a_max_decel + 2.0 * lm.a_max_decel / lm.j_max_decel
        return vpk * tb
