"""Planned vs simulated run time: a whole program through the servo model.

:func:`simulate` streams a program at full override through
:class:`~trajkit.runtime.Streamer` with the servo simulation and exact stops
(program time waits at every stop point until each axis has been inside its
in-position window for ``settle_cycles`` periods). The simulated time of a
motion runs from the end of the previous motion (after its settling) to the
end of this one (after its settling), so the sum over the motions is the
simulated run time of the program. This is the "measured run time" of
Cao et al. (2012, table 1): longer than the planned time because the servos
need time to remove the following error (see docs/references.md).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..limits import AxisLimits
from .safety import SafetyConfig
from .servo import ServoParams
from .streamer import Streamer

__all__ = ["MotionTiming", "SimulationReport", "simulate"]


@dataclass(frozen=True)
class MotionTiming:
    """Planned and simulated duration of one motion.

    Attributes
    ----------
    index : int
    label : str
    planned_s, simulated_s : float
        Durations [s].
    settle_s : float
        Time spent waiting for in-position at its end [s] (0 without an exact stop).
    max_following_error : tuple of float
        Largest |following error| per axis during the motion [unit].
    """

    index: int
    label: str
    planned_s: float
    simulated_s: float
    settle_s: float
    max_following_error: tuple[float, ...]


@dataclass
class SimulationReport:
    """Result of :func:`simulate`.

    Attributes
    ----------
    planned_s, simulated_s : float
        Planned and simulated run time of the program [s].
    motions : list of MotionTiming
    names : tuple of str
        Axis names.
    period : float [s]
    servo : tuple of ServoParams
    t : ndarray, shape (n,), or None
        Cycle times [s] (None when not recorded).
    following_error : ndarray, shape (n, n_axes), or None
        Commanded minus measured position [unit] (None when not recorded).
    """

    planned_s: float
    simulated_s: float
    motions: list[MotionTiming]
    names: tuple[str, ...]
    period: float
    servo: tuple[ServoParams, ...]
    t: np.ndarray | None = field(repr=False, default=None)
    following_error: np.ndarray | None = field(repr=False, default=None)

    @property
    def max_following_error(self) -> np.ndarray:
        """Largest |following error| per axis over the run, shape (n_axes,)."""
        return np.max(np.array([m.max_following_error for m in self.motions]), axis=0)

    def to_dict(self) -> dict:
        """JSON-ready summary (no per-cycle arrays)."""
        return {
            "planned_s": self.planned_s,
            "simulated_s": self.simulated_s,
            "extra_s": self.simulated_s - self.planned_s,
            "period_s": self.period,
            "axes": list(self.names),
            "servo": [p.__dict__ for p in self.servo],
            "max_following_error": [float(x) for x in self.max_following_error],
            "motions": [
                {"index": m.index, "label": m.label, "planned_s": m.planned_s,
                 "simulated_s": m.simulated_s, "settle_s": m.settle_s,
                 "max_following_error": list(m.max_following_error)}
                for m in self.motions
            ],
        }


def simulate(program: Any, period: float, servo: ServoParams | Sequence[ServoParams] | None = None,
             *, limits: Sequence[AxisLimits] | None = None, record: bool = True,
             exact_stop: bool = True) -> SimulationReport:
    """Run a program through the servo simulation; planned vs simulated time.

    Parameters
    ----------
    program : ProgramSource or anything :func:`~trajkit.runtime.as_source` accepts
    period : float
        Control (and servo update) period [s].
    servo : ServoParams or sequence of ServoParams, optional
        Default ``ServoParams()`` for every axis.
    limits : sequence of AxisLimits, optional
        Monitor limits (default: the program's).
    record : bool
        Keep the per-cycle following error (for plots).
    exact_stop : bool
        Wait for in-position at the program's stop points.

    Returns
    -------
    SimulationReport

    Raises
    ------
    RuntimeFault
        A monitor tripped (e.g. ``"in position"``: an axis never settled
        within ``settle_timeout``).
    """
    servo = ServoParams() if servo is None else servo
    st = Streamer(program, period, limits=limits, servo=servo,
                  safety=SafetyConfig(following_error=math.inf), wait_in_position=exact_stop)
    bank = st.servo
    assert bank is not None  # a servo is always given above
    src = st.source
    n = src.n_axes
    ts, taus, fes = [], [], []
    for sp in st:
        ts.append(sp.t)
        taus.append(sp.tau)
        fes.append(sp.following_error)
    if st.fault is not None:
        raise st.fault
    t = np.array(ts)
    tau = np.array(taus)
    fe = np.array(fes).reshape(-1, n)
    # keep settling to the window also at the very end when not waiting
    sim_total = t[-1] + period if t.size else 0.0
    released = {round(sp_tau, 12): (since, rel) for sp_tau, since, rel in st.stop_log}
    ends = src.motion_ends()
    motions = []
    prev_end_t = 0.0
    prev_plan = 0.0
    for i, me in enumerate(ends):
        key = round(float(me), 12)
        if key in released:
            since, t_end = released[key]
            settle = t_end - since
        else:
            hit = np.nonzero(tau >= me * (1 - 1e-12) - 1e-12)[0]
            t_end = float(t[hit[0]] + period) if hit.size else sim_total
            settle = 0.0
        m = (t >= prev_end_t) & (t < t_end)
        mfe = tuple(float(x) for x in (np.max(np.abs(fe[m]), axis=0) if m.any() else np.zeros(n)))
        motions.append(MotionTiming(i, src.motion_labels[i], float(me - prev_plan),
                                    float(t_end - prev_end_t), float(settle), mfe))
        prev_end_t, prev_plan = t_end, float(me)
    return SimulationReport(
        float(src.duration), float(prev_end_t), motions, src.names, float(period),
        tuple(bank.params), t if record else None, fe if record else None,
    )
