"""How the tests compare floating-point results of two code paths.

The rule: results of two *different* code paths are compared to a few ulps
of the quantity's scale, never bit for bit. Different code paths are numba
vs Python, numpy's SIMD math (``np.power``, ``np.cbrt``, ``np.arctan2``, ...
with AVX2/AVX-512 kernels) vs the C library's ``math.pow``/``math.cbrt``,
and batch vs scalar formulations: their transcendental functions may round
differently by an ulp, and that difference then propagates.

Exact equality stays only where one code path does pure IEEE arithmetic on the
same inputs in the same order (``+ - * /`` and ``sqrt`` are correctly rounded
on every machine), or where a value is copied rather than computed (a
requested duration handed back). ``.ci/run`` runs the tests that compare code
paths a second time with numpy's SIMD dispatch switched off
(``NPY_DISABLE_CPU_FEATURES``), so both math paths are exercised on any
machine.
"""

from __future__ import annotations

import numpy as np

__all__ = ["ULPS", "assert_ulp_close", "ulp_distance"]

#: Default tolerance [ulps of the scale] between two code paths.
ULPS = 16


def ulp_distance(actual, desired, scale=None) -> np.ndarray:
    """``|actual - desired|`` in ulps of ``scale`` (default: the larger magnitude of the two).

    Infinities and NaNs compare equal to themselves (distance 0) and
    infinitely far from anything else.
    """
    a = np.asarray(actual, dtype=float)
    d = np.asarray(desired, dtype=float)
    a, d = np.broadcast_arrays(a, d)
    if scale is None:
        scale = np.maximum(np.abs(a), np.abs(d))
    scale = np.broadcast_to(np.abs(np.asarray(scale, dtype=float)), a.shape)
    with np.errstate(invalid="ignore", over="ignore"):
        same = (a == d) | (np.isnan(a) & np.isnan(d))
        finite = np.isfinite(a) & np.isfinite(d)
        unit = np.spacing(np.where(np.isfinite(scale), scale, 0.0))
        dist = np.where(finite, np.abs(a - d) / np.maximum(unit, np.finfo(float).tiny), np.inf)
    return np.where(same, 0.0, dist)


def assert_ulp_close(actual, desired, ulps: float = ULPS, scale=None, err_msg: str = "") -> None:
    """Assert that two code paths agree to ``ulps`` ulps of ``scale`` (see :func:`ulp_distance`)."""
    dist = ulp_distance(actual, desired, scale)
    if dist.size and not np.all(dist <= ulps):
        k = int(np.argmax(dist))
        a = np.ravel(np.broadcast_to(np.asarray(actual, dtype=float), dist.shape))[k]
        d = np.ravel(np.broadcast_to(np.asarray(desired, dtype=float), dist.shape))[k]
        raise AssertionError(
            f"{err_msg}: {int(np.sum(dist > ulps))} of {dist.size} values differ by more than "
            f"{ulps} ulps; worst at flat index {k}: {a!r} vs {d!r} ({dist.ravel()[k]:.3g} ulps)")
