"""The compiled kernels made ready before a machine moves.

With numba installed (the ``fast`` extra) every kernel is compiled the first
time it is called, and the machine code is kept in numba's disk cache for
the next process. On a fresh install that first call takes minutes (the
state-to-state kernel alone about a hundred seconds on a 2-core machine):
without a warm-up it would come from inside a control cycle -- the first
controlled stop, the first online target, the first moving cycle of the
safety look-ahead -- and hold the cycle (and an emergency stop queued behind
it) for that long. :func:`warm_up` makes the calls before anything moves: a
:class:`~trajkit.runtime.Streamer` does it when it is made, ``trajkit
warmup`` after an install, ``trajkit hmi`` before it listens. In a process
where the kernels are ready it returns at once; from the disk cache it takes
about a second.
"""

from __future__ import annotations

import threading
import time

import numpy as np

from ..limits import AxisLimits
from ..profiles._compile import ENABLED

__all__ = ["warm_up", "warm_up_pending", "WARM_UP_PARTS"]

#: What :func:`warm_up` can prepare: ``"runtime"`` (the minimum-time brake of
#: every controlled stop and of the safety look-ahead, the state-to-state
#: planner of online targets with both synchronisations, rest-to-rest PTP
#: moves of a re-entry), ``"paths"`` (the path-timing engine: LIN/CIRC chains
#: with blends on the built-in arms, a saddle seam, joint-space waypoints).
WARM_UP_PARTS = ("runtime", "paths")

_LOCK = threading.Lock()
_READY: set[str] = set()

# two axes with separate accel and decel legs, one symmetric: every leg of the kernels
_LIMITS = (AxisLimits(1.0, 4.0, 40.0, 2.0, 15.0, name="w1"), AxisLimits(0.5, 2.0, 30.0, name="w2"))


def _runtime() -> None:
    from ..sync import plan_ptp, plan_ptp_states
    from ._brake import brake_profile, stop_position

    lims = list(_LIMITS)
    for lm in lims:  # a stop of each leg, with a reversal and an acceleration past its limit
        for v, a in ((0.4, 0.5), (-0.3, 1.0), (0.1, -3.0 * lm.a_max)):
            stop_position(0.0, v, a, lm)
            brake_profile(0.0, v, a, lm)
    plan_ptp(np.zeros(2), np.array([0.5, -0.2]), lims)
    start = np.array([[0.0, 0.3, 0.5], [0.1, -0.2, 0.0]])
    goal = np.array([[0.4, -0.1, 0.0], [-0.2, 0.1, 0.0]])
    for sync in ("time", "none"):
        plan_ptp_states(start, goal, lims, sync=sync)
        plan_ptp_states(start, np.column_stack([goal[:, 0], np.zeros((2, 2))]), lims, sync=sync)


def _paths() -> None:
    import math

    from ..interpolation import SaddleMachine, plan_saddle
    from ..paths import SaddleCurve
    from ..robot import CartesianTarget, Circ, Lin, run_motions
    from ..robot.models import robot_by_name
    from ..timing import plan_waypoints

    for name in ("arm6", "scara"):
        rob = robot_by_name(name)
        q0 = rob.home
        p0 = rob.fk(q0)

        def at(d, p0=p0):
            return CartesianTarget(type(p0).trusted(p0.position + np.asarray(d, dtype=float), p0.rotation))

        run_motions(rob, [Lin(at([0.0, 0.05, 0.0]), 0.5, 0.01),
                          Circ(at([0.03, 0.08, 0.0]), at([0.06, 0.05, 0.0]), 0.5)], q0)
    machine = SaddleMachine(AxisLimits(2.0, 10.0, 100.0, name="theta"),
                            AxisLimits(0.04, 0.4, 4.0, name="z_axis"))
    plan_saddle(SaddleCurve(0.150, 0.100, math.radians(60), 0.020), 0.06, 0.5, 5.0, machine,
                1e-5, 0.004)
    wp = np.array([[0.0, 0.0], [0.3, 0.2], [0.1, 0.5], [0.4, 0.3]])
    for blend in (0.0, 0.05):
        plan_waypoints(wp, list(_LIMITS), blend=blend)
    from ..timing import _checks

    if _checks.AVAILABLE:  # (a check's samples evaluated again: not every motion above needs it)
        z = np.zeros((1, 2))
        _checks.splice_ratios(np.zeros(1, dtype=np.int64), z.copy(), z.copy(), z.copy(), np.zeros(1),
                              z, z, z, np.zeros(1))


_WORK = {"runtime": _runtime, "paths": _paths}


def _names(parts: str | tuple[str, ...] | list[str]) -> list[str]:
    """``parts`` as a list of names (one name given alone too)."""
    return [parts] if isinstance(parts, str) else list(parts)


def warm_up_pending(parts: tuple[str, ...] | list[str] = WARM_UP_PARTS) -> bool:
    """True when :func:`warm_up` of ``parts`` still has work to do in this process
    (numba installed and a part not yet ready)."""
    return ENABLED and not set(_names(parts)) <= _READY


def warm_up(parts: tuple[str, ...] | list[str] = ("runtime",)) -> dict[str, float]:
    """Compile (or load from numba's disk cache) the kernels of ``parts`` now.

    Parameters
    ----------
    parts : sequence of str
        Names from :data:`WARM_UP_PARTS`.

    Returns
    -------
    dict
        Seconds each part took in this call (``0.0`` for a part already
        ready in this process); empty when the kernels run as plain Python
        (numba not installed, or ``TRAJKIT_NO_JIT`` set): nothing to compile.

    Raises
    ------
    InvalidInputError
        An unknown part.

    Notes
    -----
    Thread-safe: a second caller waits for the first one's work instead of
    doing it again.
    """
    from ..errors import InvalidInputError

    names = _names(parts)
    for p in names:
        if p not in _WORK:
            raise InvalidInputError(f"warm-up part must be one of {list(WARM_UP_PARTS)}, got {p!r}")
    if not ENABLED:
        return {}
    out: dict[str, float] = {}
    with _LOCK:
        for p in names:
            if p in _READY:
                out[p] = 0.0
                continue
            t0 = time.perf_counter()
            _WORK[p]()
            _READY.add(p)
            out[p] = time.perf_counter() - t0
    return out
