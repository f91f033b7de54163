"""Coarse stage: chord-error-bounded discretisation of a path (Chen et al., 2013).

A chord of length L on a circle of radius K deviates from the arc by the
sagitta (Chen et al., 2013, eq. 11)

    E = K - sqrt(K^2 - L^2 / 4)

so the longest chord for a tolerance E is (eq. 13, with K for the paper's r)

    L = sqrt(8 K E - 4 E^2).

For a general curve the stepper uses the smallest radius of curvature over
the step, then every chord is checked densely against the exact curve and
split if it breaks the tolerance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._validate import check_positive
from ..errors import InvalidInputError
from ._tolerances import (
    CHORD_CHECK_SAMPLES,
    CHORD_REFINE_ITER,
    CHORD_TARGET_FRACTION,
    SNAP_FRACTION,
)
from .base import Path

__all__ = [
    "chord_error",
    "max_chord_length",
    "arc_step_for_tolerance",
    "chord_deviations",
    "ChordSet",
    "discretize",
    "uniform_chord_count",
]

_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0
#: Upper bound on the chords one discretisation may produce.
MAX_CHORDS = 2_000_000


def chord_error(chord_length: Any, radius: Any) -> np.ndarray | float:
    """Sagitta of a chord on a circle (Chen et al., 2013, eq. 11).

    Parameters
    ----------
    chord_length : float or array_like
        L [m], 0 <= L <= 2 K.
    radius : float or array_like
        Radius of curvature K [m], > 0.

    Returns
    -------
    float or ndarray
        E = K - sqrt(K^2 - L^2 / 4) [m], computed without cancellation as
        (L^2 / 4) / (K + sqrt(K^2 - L^2 / 4)).
    """
    L = np.asarray(chord_length, dtype=float)
    K = np.asarray(radius, dtype=float)
    if np.any(~np.isfinite(L)) or np.any(L < 0):
        raise InvalidInputError(f"chord length must be finite and >= 0, got {chord_length!r}")
    if np.any(~np.isfinite(K)) or np.any(K <= 0):
        raise InvalidInputError(f"radius of curvature must be finite and > 0, got {radius!r}")
    if np.any(L > 2 * K):
        raise InvalidInputError(
            f"chord length {chord_length!r} is longer than the diameter 2K of radius {radius!r}"
        )
    q = L * L / 4.0
    out = q / (K + np.sqrt(K * K - q))
    return float(out) if out.ndim == 0 else out


def max_chord_length(radius: Any, tolerance: float) -> np.ndarray | float:
    """Longest chord whose sagitta is ``tolerance`` (Chen et al., 2013, eq. 13).

    Parameters
    ----------
    radius : float or array_like
        Radius of curvature K [m], > 0 (``inf`` for a straight line).
    tolerance : float
        E [m], > 0.

    Returns
    -------
    float or ndarray
        L = sqrt(8 K E - 4 E^2) [m] for E < K; the diameter 2K for E >= K;
        ``inf`` for K = inf.
    """
    E = check_positive(tolerance, "chord tolerance")
    K = np.asarray(radius, dtype=float)
    if np.any(np.isnan(K)) or np.any(K <= 0):
        raise InvalidInputError(f"radius of curvature must be > 0, got {radius!r}")
    with np.errstate(invalid="ignore"):
        Ec = np.minimum(E, K)
        out = np.where(np.isinf(K), np.inf, np.sqrt(np.maximum(8.0 * K * Ec - 4.0 * Ec * Ec, 0.0)))
    return float(out) if out.ndim == 0 else out


def arc_step_for_tolerance(radius: Any, tolerance: float) -> np.ndarray | float:
    """Arc length of a circular arc whose chord has sagitta ``tolerance``.

    Returns
    -------
    float or ndarray
        2 K acos(1 - E/K) [m] for E < K, pi K for E >= K, inf for K = inf.
    """
    E = check_positive(tolerance, "chord tolerance")
    K = np.asarray(radius, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        x = np.clip(1.0 - E / K, -1.0, 1.0)
        out = np.where(np.isinf(K), np.inf, 2.0 * K * np.arccos(x))
    return float(out) if out.ndim == 0 else out


def _segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance of points p from segments a-b (all broadcast, last axis 3)."""
    d = b - a
    dd = np.sum(d * d, axis=-1)
    t = np.clip(np.sum((p - a) * d, axis=-1) / np.where(dd > 0, dd, 1.0), 0.0, 1.0)
    return np.linalg.norm(p - a - t[..., None] * d, axis=-1)


def chord_deviations(path: Path, s_nodes: Any, samples: int = CHORD_CHECK_SAMPLES) -> np.ndarray:
    """Largest distance of the exact curve from each chord (dense check).

    Each chord ``[s_k, s_k+1]`` is sampled at ``samples`` equally spaced arc
    lengths; around the worst sample the maximum is refined by golden-section
    search on the exact curve, so the result is the true local maximum to
    about 1e-9 of the chord length (for the unimodal deviation of a short
    chord).

    Parameters
    ----------
    path : Path
    s_nodes : array_like, shape (n + 1,)
        Increasing arc lengths [m] of the chord end points.
    samples : int
        Samples per chord, >= 3.

    Returns
    -------
    ndarray, shape (n,)
        Deviation of each chord [m].
    """
    s = np.asarray(s_nodes, dtype=float)
    if s.ndim != 1 or s.size < 2 or np.any(np.diff(s) <= 0):
        raise InvalidInputError("chord nodes must be an increasing 1-D array of at least 2 arc lengths")
    n = s.size - 1
    P = path.point(s)
    a, b = P[:-1], P[1:]
    u = np.linspace(0.0, 1.0, samples)
    ss = s[:-1, None] + (s[1:] - s[:-1])[:, None] * u
    dev = _segment_distance(path.point(ss.ravel()).reshape(n, samples, 3), a[:, None], b[:, None])
    j = np.argmax(dev, axis=1)
    best = dev[np.arange(n), j]
    lo = ss[np.arange(n), np.maximum(j - 1, 0)]
    hi = ss[np.arange(n), np.minimum(j + 1, samples - 1)]

    def f(x):
        return _segment_distance(path.point(x), a, b)

    x1 = hi - _GOLDEN * (hi - lo)
    x2 = lo + _GOLDEN * (hi - lo)
    f1, f2 = f(x1), f(x2)
    for _ in range(CHORD_REFINE_ITER):
        left = f1 > f2  # maximum in [lo, x2]
        hi = np.where(left, x2, hi)
        lo = np.where(left, lo, x1)
        nx1 = hi - _GOLDEN * (hi - lo)
        nx2 = lo + _GOLDEN * (hi - lo)
        fn = f(np.where(left, nx1, nx2))  # one new evaluation per chord
        x1, x2 = np.where(left, nx1, x2), np.where(left, x1, nx2)
        f1, f2 = np.where(left, fn, f2), np.where(left, f1, fn)
    return np.maximum(best, np.maximum(f1, f2))


@dataclass(frozen=True)
class ChordSet:
    """Result of :func:`discretize`.

    Attributes
    ----------
    s : ndarray, shape (n + 1,)
        Arc lengths [m] of the chord end points (0 ... path length).
    points : ndarray, shape (n + 1, 3)
        Chord end points on the exact curve [m].
    errors : ndarray, shape (n,)
        Deviation of each chord from the curve [m] (dense check).
    tolerance : float
        The tolerance [m] every chord holds.
    """

    s: np.ndarray
    points: np.ndarray
    errors: np.ndarray
    tolerance: float

    @property
    def count(self) -> int:
        """Number of chords."""
        return int(self.errors.size)

    @property
    def max_error(self) -> float:
        """Largest chord deviation [m]."""
        return float(np.max(self.errors))

    def point_at(self, s: Any) -> np.ndarray:
        """Point on the chord polyline at curve arc length ``s`` (fine stage).

        Inside chord k, the point moves linearly from ``points[k]`` to
        ``points[k+1]`` while ``s`` goes from ``s[k]`` to ``s[k+1]``.

        Returns
        -------
        ndarray, shape (n, 3) [m]
        """
        x = np.atleast_1d(np.asarray(s, dtype=float))
        k = np.clip(np.searchsorted(self.s, x, side="right") - 1, 0, self.count - 1)
        u = np.clip((x - self.s[k]) / (self.s[k + 1] - self.s[k]), 0.0, 1.0)
        return self.points[k] + u[:, None] * (self.points[k + 1] - self.points[k])


def discretize(path: Path, tolerance: float, max_chord: float = math.inf) -> ChordSet:
    """Split ``path`` into chords that deviate from it by at most ``tolerance``.

    The step from each node is the arc whose circle-of-curvature sagitta is
    ``CHORD_TARGET_FRACTION * tolerance`` for the smallest radius of
    curvature K over the step (Chen et al., 2013: L = sqrt(8 K E - 4 E^2)), so steps
    are long where the path is straight and short where it bends. Then every
    chord is checked densely (:func:`chord_deviations`) and any chord over
    the tolerance is halved until all hold it. Corners of a composite path
    are always nodes.

    Parameters
    ----------
    path : Path
    tolerance : float
        Largest allowed chord deviation E [m], > 0.
    max_chord : float
        Optional upper bound on the arc length of one chord [m].

    Returns
    -------
    ChordSet

    Raises
    ------
    InvalidInputError
        For a non-positive tolerance, or when more than :data:`MAX_CHORDS`
        would be needed.
    """
    E = check_positive(tolerance, "chord tolerance")
    if not (max_chord > 0):
        raise InvalidInputError(f"max_chord must be > 0, got {max_chord!r}")
    sg, kg = path.curvature_grid()
    # largest curvature over each grid cell (both ends), padded by one cell
    cell = np.maximum(kg[:-1], kg[1:])
    cell = np.maximum(cell, np.concatenate([cell[1:], cell[-1:]]))
    cell = np.maximum(cell, np.concatenate([cell[:1], cell[:-1]]))
    ncell = cell.size
    target = CHORD_TARGET_FRACTION * E
    L = path.length
    forced = sorted(set(float(c) for c in path.corners()) | {L})
    nodes = [0.0]
    s0 = 0.0
    for stop in forced:
        while stop - s0 > 0.0:
            step = _next_step(sg, cell, ncell, s0, stop, target, max_chord)
            if stop - (s0 + step) <= SNAP_FRACTION * step:
                s0 = stop
            else:
                s0 = s0 + step
            nodes.append(s0)
            if len(nodes) > MAX_CHORDS:
                raise InvalidInputError(
                    f"chord tolerance {E!r} m needs more than {MAX_CHORDS} chords on a path of "
                    f"length {L!r} m"
                )
    s = np.array(nodes)
    while True:
        dev = chord_deviations(path, s)
        bad = dev > E
        if not np.any(bad):
            break
        mids = (s[:-1][bad] + s[1:][bad]) / 2.0
        s = np.sort(np.concatenate([s, mids]))
        if s.size > MAX_CHORDS:
            raise InvalidInputError(
                f"chord tolerance {E!r} m needs more than {MAX_CHORDS} chords"
            )
    return ChordSet(s=s, points=path.point(s), errors=dev, tolerance=E)


def _next_step(sg, cell, ncell, s0, stop, target, max_chord):
    """Longest step from s0 whose curvature bound (grid cells it touches) allows it."""
    i0 = min(max(int(np.searchsorted(sg, s0, side="right")) - 1, 0), ncell - 1)
    width = 64
    while True:
        i1 = min(i0 + width, ncell)
        run = np.maximum.accumulate(cell[i0:i1])
        with np.errstate(divide="ignore"):
            allowed = arc_step_for_tolerance(np.where(run > 0, 1.0 / run, np.inf), target)
        ends = sg[i0 + 1:i1 + 1] - s0
        bad = np.nonzero(ends > allowed)[0]
        if bad.size:
            k = int(bad[0])
            prev_end = ends[k - 1] if k > 0 else 0.0
            step = max(prev_end, float(allowed[k]))
            break
        if i1 >= ncell:
            step = math.inf
            break
        width *= 4
    return min(step, max_chord, stop - s0)


def uniform_chord_count(path: Path, tolerance: float, n_max: int = 1 << 20, start: int = 1) -> int:
    """Smallest number of equal parameter steps whose chords all hold ``tolerance``.

    Equal steps of the path's natural parameter (:meth:`Path.uniform_nodes`:
    equal theta steps on a saddle seam, as in the "points per turn" of Chen et al. (2013);
    equal arc lengths otherwise). Found by bisection on the dense check,
    starting from ``start`` (a guess, e.g. the adaptive chord count).

    Returns
    -------
    int
    """
    E = check_positive(tolerance, "chord tolerance")

    def ok(n):
        return float(np.max(chord_deviations(path, path.uniform_nodes(n)))) <= E

    lo, hi = 0, max(1, int(start))
    if ok(hi):
        while hi > 1 and ok(hi // 2):
            hi //= 2
        lo = hi // 2
    while not ok(hi):
        lo, hi = hi, hi * 2
        if hi > n_max:
            raise InvalidInputError(f"more than {n_max} uniform steps needed for tolerance {E!r} m")
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if ok(mid):
            hi = mid
        else:
            lo = mid
    return hi
