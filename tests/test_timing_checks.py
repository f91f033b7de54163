"""The path-timing engine's limit checks: the compiled kernel (``timing._checks``)
against the engine's numpy formulation (``engine._evaluate``).

On random constant-jerk pieces over random grids, both give the same grid cell
of every sample and the same ratios to a few ulps (the kernel forms ``w**3`` and
``sdot**3`` as products, numpy with ``pow``), with every feature of the check:

* derivatives interpolated on the grid, towards the left-limits in a cell that
  ends at a breakpoint (``_Interp``), with the correction in the cells where the
  true derivatives were evaluated (``_Corrected``), or exact from a path with
  cheap derivatives;
* piece ends that land on a grid node (the cell below), samples past the end
  of the grid (clipped);
* joints at rest (a joint that never moves, pieces that start from rest): the
  leg of the piece's middle;
* the curvature in the path acceleration, a speed cap at the nodes (with
  infinite entries) and a cap function.

``_check`` and ``_zoom`` agree through either route, and so do whole timings.
The kernel's plain-Python body (``TRAJKIT_NO_JIT=1``) is compared too.
"""

from __future__ import annotations

import copy
import functools

import numpy as np
import pytest
from floatcmp import assert_ulp_close

from trajkit import AxisLimits
from trajkit.timing import _checks, engine, plan_path_timing
from trajkit.timing.engine import (
    _check,
    _Corrected,
    _evaluate,
    _evaluate_compiled,
    _Interp,
    _Limits,
    _recheck,
    _use_of,
    _zoom,
)
from trajkit.timing.waypoints import SplineJointPath

#: Compares two code paths (see floatcmp); CI runs it again with numpy SIMD off.
pytestmark = pytest.mark.codepaths

#: Grid spacing unit: nodes on multiples of it are exact binary fractions.
UNIT = 1.0 / 64.0


class _SinePath:
    """``q_j(s) = amp_j sin(freq_j s + phase_j)``; joint ``still`` does not move."""

    breakpoints = np.zeros(0)

    def __init__(self, rng, m: int, length: float, cheap: bool, still: int | None = None) -> None:
        self.length = length
        self.n_joints = m
        self.cheap_derivatives = cheap
        self.amp = rng.uniform(0.2, 1.0, m)
        if still is not None:
            self.amp[still] = 0.0
        self.freq = rng.uniform(0.5, 3.0, m)
        self.phase = rng.uniform(0.0, 2.0 * np.pi, m)

    def derivatives(self, s):
        x = self.freq * np.atleast_1d(np.asarray(s, dtype=float))[:, None] + self.phase
        a, f = self.amp, self.freq
        return a * np.sin(x), a * f * np.cos(x), -a * f**2 * np.sin(x), -a * f**3 * np.cos(x)


class _Opaque:
    """A path whose derivatives the engine treats as expensive (it interpolates them)."""

    cheap_derivatives = False

    def __init__(self, path) -> None:
        self.path = path
        self.length = path.length
        self.n_joints = path.n_joints
        self.breakpoints = path.breakpoints

    def derivatives(self, s):
        return self.path.derivatives(s)


def _setup(seed: int, m: int = 4, curved: bool = True, capped: bool = True, cap_fn: bool = True):
    """A grid (exact binary fractions) with breakpoints, a path, limits and random pieces,
    some ending on a grid node, some from rest."""
    rng = np.random.default_rng(seed)
    L = 4.0
    nodes = np.unique(np.concatenate([[0.0, L], rng.integers(1, int(L / UNIT), 40) * UNIT]))
    path = _SinePath(rng, m, L, cheap=False, still=int(rng.integers(m)) if seed % 2 else None)
    der = path.derivatives(nodes)
    breaks = nodes[rng.choice(np.arange(2, nodes.size - 2), 4, replace=False)]
    left = tuple(d * rng.uniform(0.9, 1.1, d.shape) for d in path.derivatives(breaks)[1:])
    k = 60
    dur = rng.uniform(0.02, 0.4, k)
    st = np.zeros((k + 1, 3))
    st[:-1, 0] = rng.uniform(0.0, L, k)
    st[:-1, 1] = rng.uniform(0.0, 3.0, k) * (rng.random(k) < 0.8)  # some from rest
    st[:-1, 2] = rng.normal(0.0, 4.0, k)
    jerk = rng.normal(0.0, 30.0, k)
    # pieces at constant speed from one node to another: the end lands on the node
    for i in range(0, k, 6):
        a, b = np.sort(rng.choice(nodes.size, 2, replace=False))
        st[i] = (nodes[a], 1.0, 0.0)
        jerk[i] = 0.0
        dur[i] = nodes[b] - nodes[a]
    # from rest at a node, speeding up
    st[1] = (nodes[3], 0.0, 0.0)
    jerk[1] = 5.0
    st[2] = (nodes[5], 0.0, 2.0)
    t = np.concatenate([[0.0], np.cumsum(dur)])
    vlim = rng.uniform(0.5, 2.0, m)
    aacc = rng.uniform(2.0, 8.0, m)
    jacc = rng.uniform(20.0, 80.0, m)
    kappa = rng.uniform(0.0, 3.0, nodes.size) if curved else None
    cap = None
    if capped:
        cap = rng.uniform(0.5, 3.0, nodes.size)
        cap[rng.random(nodes.size) < 0.2] = np.inf
    fn = (lambda S: 1.0 + 0.5 * np.sin(3.0 * S)) if cap_fn else None
    lim = _Limits(vlim, aacc, aacc * rng.uniform(0.5, 1.5, m), jacc, jacc * rng.uniform(0.5, 1.5, m),
                  7.0, 90.0, kappa, cap, fn)
    return rng, nodes, der, t, st, jerk, lim, path, breaks, left


def _samples(rng, t):
    """Pieces and times: both ends, the middle, random points, points past the end."""
    k = t.size - 1
    dur = np.diff(t)
    piece = np.concatenate([np.arange(k)] * 4 + [rng.integers(0, k, 300)])
    dt = np.concatenate([np.zeros(k), dur, 0.5 * dur, dur * 1.5, dur[piece[4 * k:]] * rng.random(300)])
    return piece, dt


def _compare(nodes, der, t, st, jerk, lim, src, piece, dt, ulps=16):
    ref = _evaluate(nodes, der, t, st, jerk, lim, src, piece, dt)
    rv, ra, rj, rs, acc, jk, cell = ref[:7]
    use_ref = _use_of(lim, rv, ra, rj, rs, acc, jk)
    use, cell2, rv2, ra2, rj2, rs2, worst = _evaluate_compiled(nodes, der, t, st, jerk, lim, src, piece, dt)
    np.testing.assert_array_equal(cell2, cell)
    for name, a, b in (("rv", rv2, rv), ("ra", ra2, ra), ("rj", rj2, rj)):
        # in ulps of the joint's largest ratio (terms of opposite signs cancel near zero)
        assert_ulp_close(a, b, ulps, scale=np.abs(b).max(axis=0), err_msg=name)
    assert_ulp_close(rs2, rs, ulps, scale=np.abs(rs).max(initial=0.0), err_msg="rs")
    np.testing.assert_array_equal(worst, np.max(np.column_stack([rv2, ra2, rj2, rs2[:, None]]), axis=1))
    for name in ("velocity", "acceleration", "jerk", "path_acceleration", "path_jerk", "path_speed"):
        assert_ulp_close(getattr(use, name), getattr(use_ref, name), ulps, err_msg=name)
    return rv, ra, rj, rs


def _sources(path, nodes, der, breaks, left, rng):
    corrected = _Corrected(path, nodes, der, breaks, left)
    corrected.add(rng.choice(nodes.size - 1, nodes.size // 2, replace=False))
    exact = copy.copy(path)  # the same path, its derivatives at every sample
    exact.cheap_derivatives = True
    return {"grid": None, "interp": _Interp(nodes, der, breaks, left), "corrected": corrected, "exact": exact}


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("source", ["grid", "interp", "corrected", "exact"])
def test_kernel_matches_numpy(seed, source):
    rng, nodes, der, t, st, jerk, lim, path, breaks, left = _setup(seed, curved=seed % 3 != 0,
                                                                   capped=seed % 3 != 1, cap_fn=seed % 2 == 0)
    src = _sources(path, nodes, der, breaks, left, rng)[source]
    piece, dt = _samples(rng, t)
    rv, ra, rj, rs = _compare(nodes, der, t, st, jerk, lim, src, piece, dt)
    # the cases this covers
    S = np.clip(st[piece, 0] + dt * (st[piece, 1] + dt * (0.5 * st[piece, 2] + dt * jerk[piece] / 6.0)),
                0.0, nodes[-1])
    end = dt >= np.diff(t)[piece]
    assert np.isin(S[end], nodes[1:-1]).sum() >= 5  # piece ends on a grid node
    V = st[piece, 1] + dt * (st[piece, 2] + 0.5 * dt * jerk[piece])
    assert np.sum(V == 0.0) >= 2  # samples at rest
    if lim.cap is not None:
        assert rs.max() > 0.0


@pytest.mark.parametrize("seed", range(4))
def test_rest_takes_the_leg_of_the_piece_middle(seed):
    """A joint that never moves and samples from rest: the ratios use the leg of the
    piece's middle (with both legs' limits far apart, a wrong leg shows)."""
    rng, nodes, der, t, st, jerk, lim, path, breaks, left = _setup(2 * seed + 1)
    lim.alim_dec = lim.alim_acc * 0.25
    lim.jdec = lim.jacc * 0.25
    piece, dt = _samples(rng, t)
    for src in _sources(path, nodes, der, breaks, left, rng).values():
        _compare(nodes, der, t, st, jerk, lim, src, piece, dt)


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("source", ["interp", "corrected", "exact"])
def test_check_and_zoom_agree(seed, source):
    rng, nodes, der, t, st, jerk, lim, path, breaks, left = _setup(10 + seed)
    src = _sources(path, nodes, der, breaks, left, rng)[source]
    for per_piece in (None, 30):
        a = _check(nodes, der, t, st, jerk, lim, src, per_piece, compiled=True)
        b = _check(nodes, der, t, st, jerk, lim, src, per_piece, compiled=False)
        np.testing.assert_array_equal(a[1], b[1])
        for x, y in zip(a[2:], b[2:]):
            assert_ulp_close(x, y, scale=np.abs(y).max(axis=0))
        for name in ("velocity", "acceleration", "jerk", "path_acceleration", "path_jerk", "path_speed"):
            assert_ulp_close(getattr(a[0], name), getattr(b[0], name), err_msg=name)
    worst = b[6] / b[6].max()  # some pieces close to a limit
    npp = 32
    za = _zoom(nodes, der, t, st, jerk, lim, src, worst, npp, compiled=True)
    zb = _zoom(nodes, der, t, st, jerk, lim, src, worst, npp, compiled=False)
    for name in ("velocity", "acceleration", "jerk", "path_acceleration", "path_jerk", "path_speed"):
        assert_ulp_close(getattr(za, name), getattr(zb, name), err_msg=name)
    assert za.worst > 0.0


@pytest.mark.parametrize("seed", range(4))
def test_the_zoom_finds_the_largest_ratio_inside_the_close_pieces(seed):
    """The zoom's largest ratio inside a piece is at least the largest of 2000
    points over that piece (to 1e-9; above it where the maximum is the limit
    towards a piece's end, a grid node where the joint path's third derivative
    steps, which the dense points approach more slowly), on the eight pieces with
    the largest sampled ratios, whether the maximum lies inside the piece or at
    an end (where the zoom's brackets stop)."""
    rng, nodes, der, t, st, jerk, lim, path, breaks, left = _setup(30 + seed, curved=seed % 2 == 0)
    src = _sources(path, nodes, der, breaks, left, rng)["interp"]
    per_piece = 30
    npp = per_piece + 2
    b = _check(nodes, der, t, st, jerk, lim, src, per_piece)
    peak = b[6].reshape(-1, npp)
    where = []
    for piece in np.argsort(-peak.max(axis=1))[:8]:
        only = np.zeros_like(peak)
        only[piece] = peak[piece] / peak[piece].max()  # (this piece alone close to a limit)
        zoomed = _zoom(nodes, der, t, st, jerk, lim, src, only.ravel(), npp)
        dense = 2000 + 2
        d = _check(nodes, der, t, st, jerk, lim, src, dense - 2,
                   select=piece * dense + np.arange(dense))
        assert zoomed.worst >= d[6].max() * (1.0 - 1e-9)
        where.append(int(np.argmax(d[6])) in (0, dense - 1))
    assert any(where) and not all(where)  # (maxima at an end and inside)


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("compiled", [True, False])
def test_recheck_after_corrections_equals_a_full_check(seed, compiled):
    """The final check's passes after ``_Corrected.add``: evaluating again only the
    pieces in the cells whose derivatives changed gives what a full check gives
    (the same samples through the same route: equal values, equal limit use)."""
    rng, nodes, der, t, st, jerk, lim, path, breaks, left = _setup(20 + seed, curved=seed != 1,
                                                                   capped=seed != 2)
    corrected = _Corrected(path, nodes, der, breaks, left)
    per_piece = 14
    check = functools.partial(_check, compiled=compiled)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(engine, "_check", check)
        mp.setattr(_checks, "AVAILABLE", compiled)  # (the splice: compiled, or numpy)
        res = check(nodes, der, t, st, jerk, lim, corrected, per_piece)
        for full in (False, True):
            cells = corrected.add(rng.choice(nodes.size - 1, nodes.size // 3, replace=False), full=full)
            assert cells.size and np.all(np.diff(cells) > 0)
            before = tuple(np.copy(x) for x in res[1:])  # (the recheck updates in place)
            res = _recheck(res, cells, nodes, der, t, st, jerk, lim, corrected, per_piece)
            ref = check(nodes, der, t, st, jerk, lim, corrected, per_piece)
            for x, y in zip(res[1:], ref[1:]):
                np.testing.assert_array_equal(x, y)
            for name in ("velocity", "acceleration", "jerk", "path_acceleration", "path_jerk",
                         "path_speed"):
                np.testing.assert_array_equal(getattr(res[0], name), getattr(ref[0], name), err_msg=name)
            # the corrections changed some samples (the recheck did something)
            assert not np.array_equal(before[2], res[3])
        # nothing changed: the result as it was
        assert _recheck(res, np.zeros(0, dtype=int), nodes, der, t, st, jerk, lim, corrected,
                        per_piece) is res


def test_python_body_matches_numpy(monkeypatch):
    """The kernels' plain-Python source (what runs with ``TRAJKIT_NO_JIT=1``)."""
    for name in ("sample_ratios", "sample_ratios_into", "sample_states", "sample_positions",
                 "rest_pieces", "mid_products"):
        fn = getattr(_checks, name)
        monkeypatch.setattr(_checks, name, getattr(fn, "py_func", fn))
    rng, nodes, der, t, st, jerk, lim, path, breaks, left = _setup(3)
    piece, dt = _samples(rng, t)
    piece, dt = piece[::3], dt[::3]
    for src in _sources(path, nodes, der, breaks, left, rng).values():
        _compare(nodes, der, t, st, jerk, lim, src, piece, dt)


def _plan_both(monkeypatch, path, lims, **kw):
    compiled = plan_path_timing(path, lims, **kw)
    with monkeypatch.context() as mp:
        mp.setattr(engine, "_check", functools.partial(_check, compiled=False))
        mp.setattr(engine, "_zoom", functools.partial(_zoom, compiled=False))
        mp.setattr(engine, "_use_at", functools.partial(engine._use_at, compiled=False))
        reference = plan_path_timing(path, lims, **kw)
    return compiled, reference


@pytest.mark.parametrize("cheap", [True, False])
def test_timings_agree(monkeypatch, cheap):
    """Whole timings through either route: the same pieces, limit use and verified cells."""
    rng = np.random.default_rng(7)
    W = np.cumsum(rng.uniform(-0.6, 0.6, (6, 3)), axis=0)
    spline = SplineJointPath(W, np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(W, axis=0), axis=1))]))
    path = spline if cheap else _Opaque(spline)
    lims = [AxisLimits(1.0, 4.0, 40.0, a_max_decel=3.0, j_max_decel=30.0), AxisLimits(1.5, 5.0, 60.0),
            AxisLimits(0.8, 3.0, 25.0)]
    kw = dict(speed=lambda s: 1.0 + 0.3 * np.cos(s), accel=3.0, jerk=40.0,
              curvature=lambda s: 0.5 + 0.1 * np.sin(s))
    a, b = _plan_both(monkeypatch, path, lims, **kw)
    assert_ulp_close(a.duration, b.duration, 64)
    assert_ulp_close(a.t, b.t, 64, scale=b.duration)
    assert a.grid.size == b.grid.size and a.info == b.info
    assert_ulp_close(a.limit_use.worst, b.limit_use.worst, 64)
    assert a.limit_use.worst <= 1.0 + engine.CHECK_RTOL


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("source", ["interp", "corrected", "exact"])
def test_a_check_in_two_halves_on_two_threads_equals_one_pass(seed, source, monkeypatch):
    """A large check runs in two halves at once (a piece's samples in one half):
    every sample's values and the limit use are those of one pass, bit for bit
    (the same kernel on the same samples), whatever the number of cores."""
    if not _checks.AVAILABLE:
        pytest.skip("the two halves are a compiled check's")
    from concurrent.futures import ThreadPoolExecutor

    rng, nodes, der, t, st, jerk, lim, path, breaks, left = _setup(30 + seed, curved=seed != 1,
                                                                   capped=seed != 2, cap_fn=seed == 0)
    src = _sources(path, nodes, der, breaks, left, rng)[source]
    npp = 40
    assert jerk.size * (npp + 2) >= 2 * 400  # both halves hold many pieces
    monkeypatch.setattr(engine, "PARALLEL_SAMPLES", 10**12)
    one = _check(nodes, der, t, st, jerk, lim, src, npp)
    calls = []
    with ThreadPoolExecutor(max_workers=1) as pool:
        class _Pool:
            def submit(self, fn, *args):
                calls.append(args)
                return pool.submit(fn, *args)

        monkeypatch.setattr(engine, "PARALLEL_SAMPLES", 400)
        monkeypatch.setattr(engine, "_second_core", lambda: _Pool())
        two = _check(nodes, der, t, st, jerk, lim, src, npp)
        zoom = _zoom(nodes, der, t, st, jerk, lim, src, one[6] / one[6].max(), npp + 2)
    assert len(calls) == 1  # the check was split (the zoom's pieces repeat: one pass)
    lo, hi = calls[0]
    assert 0 < lo < hi and lo % (npp + 2) == 0  # at a piece boundary
    for x, y in zip(one[1:], two[1:]):
        np.testing.assert_array_equal(x, y)
    for name in ("velocity", "acceleration", "jerk", "path_acceleration", "path_jerk", "path_speed"):
        np.testing.assert_array_equal(getattr(one[0], name), getattr(two[0], name), err_msg=name)
    assert zoom.worst > 0.0


@pytest.mark.parametrize("seed", range(3))
def test_corrections_of_middles_and_full_cells_in_one_evaluation(seed):
    """``_Corrected.add_both``: the middles of some cells and every point of others
    in one evaluation of the path's derivatives give the corrections of the two
    ``add`` calls made one after the other (the full cells' replace their middles')."""
    rng, nodes, der, t, st, jerk, lim, path, breaks, left = _setup(40 + seed)
    middle = rng.choice(nodes.size - 1, nodes.size // 3, replace=False)
    full = np.concatenate([rng.choice(middle, middle.size // 3, replace=False),
                           rng.choice(nodes.size - 1, 3, replace=False)])
    one = _Corrected(path, nodes, der, breaks, left)
    changed = one.add_both(middle, full)
    two = _Corrected(path, nodes, der, breaks, left)
    a = two.add(middle)
    b = two.add(full, full=True)
    np.testing.assert_array_equal(changed, np.union1d(a, b))
    np.testing.assert_array_equal(one.done, two.done)
    np.testing.assert_array_equal(one.full, two.full)
    np.testing.assert_array_equal(one.err, two.err)
    # nothing left to evaluate: nothing changes
    assert one.add_both(middle, full).size == 0
    assert one.evaluated < two.evaluated  # (the full cells' middles once, not twice)
