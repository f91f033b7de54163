"""Fixed-period sample grids with a cap on their size.

A typo in a period (1e-7 s) or a slowed plan (a limit 1000x lower than the
nominal feed) must not allocate gigabytes: every fixed-period grid that
trajkit builds is counted from the planned duration first and refused above
``max_samples``.
"""

from __future__ import annotations

import math

import numpy as np

from ._constants import PERIOD_RTOL
from ._validate import check_positive
from .errors import InvalidInputError

__all__ = ["MAX_SAMPLES", "count_samples", "period_times"]

#: Largest fixed-period grid built by default (5,000,000 samples: 83 min at 1 ms).
MAX_SAMPLES = 5_000_000


def count_samples(duration: float, period: float, max_samples: int | None = MAX_SAMPLES,
                  what: str = "samples") -> int:
    """Number of grid intervals ``ceil(duration / period)``, refused above ``max_samples``.

    Parameters
    ----------
    duration : float
        Planned duration [s] (>= 0).
    period : float
        Grid period [s] (> 0).
    max_samples : int or None
        Cap on the number of samples; ``None`` for no cap.
    what : str
        Name of the samples in the message (``"setpoints"``, ``"CSV rows"``).

    Raises
    ------
    InvalidInputError
        More samples than ``max_samples``; the message gives the count, the cap
        and how to change it.
    """
    dt = check_positive(period, "period")
    if not math.isfinite(duration) or duration < 0:
        raise InvalidInputError(f"duration must be finite and >= 0, got {duration!r}")
    n = duration / dt
    if max_samples is not None and n + 1 > max_samples:
        raise InvalidInputError(
            f"{duration:.6g} s at a period of {dt:.6g} s is {n + 1:.3g} {what}, more than the cap "
            f"of {max_samples:,}: choose a longer period, or raise the cap "
            f"(max_samples=, or --max-samples on the command line)")
    return int(math.ceil(n)) if duration > 0 else 0


def period_times(duration: float, period: float, *, end: str = "exact",
                 max_samples: int | None = MAX_SAMPLES, what: str = "samples") -> np.ndarray:
    """Times ``0, dt, 2 dt, ...`` covering ``[0, duration]``.

    Parameters
    ----------
    duration, period : float
        [s].
    end : {"exact", "after"}
        ``"exact"``: the last sample is ``duration`` itself (appended when the
        grid does not land on it within :data:`~trajkit._constants.PERIOD_RTOL`
        of a period). ``"after"``: the grid continues to the first multiple of
        the period at or after ``duration``, so consecutive samples are always
        exactly one period apart (a streaming controller's setpoints).
    max_samples : int or None
        See :func:`count_samples`.

    Returns
    -------
    ndarray, shape (n,) [s]
    """
    count_samples(duration, period, max_samples, what)
    dt = float(period)
    if end == "after":
        n = int(math.ceil(duration / dt)) if duration > 0 else 0
        if n * dt < duration:  # round-off in the division
            n += 1
        return np.arange(n + 1) * dt
    if end != "exact":
        raise InvalidInputError(f"end must be 'exact' or 'after', got {end!r}")
    n = int(math.floor(duration / dt + PERIOD_RTOL))
    t = np.arange(n + 1) * dt
    if t[-1] < duration:
        t = np.append(t, duration)
    return t
