"""The path-timing engine's bookkeeping: the grid problem's fixed-pattern matrix
assembly and the cache of path derivatives give exactly what a direct
construction gives."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from trajkit.timing import LinearJointPath
from trajkit.timing._socp import _JerkRows, _Layout
from trajkit.timing.engine import _Cached


def _random_block(rng, n_rows: int, nv: int, density: float):
    mask = rng.random((n_rows, nv)) < density
    rows, cols = np.nonzero(mask)
    order = rng.permutation(rows.size)  # any entry order
    return rows[order], cols[order]


@pytest.mark.parametrize("seed", range(6))
def test_layout_equals_stacking_the_blocks_with_the_rows_kept(seed):
    rng = np.random.default_rng(seed)
    nv = int(rng.integers(3, 12))
    sizes = [int(rng.integers(0, 8)) for _ in range(4)]
    select = int(rng.integers(0, 4))
    blocks = [(k, *_random_block(rng, k, nv, 0.4)) for k in sizes]
    layout = _Layout(nv, blocks, select)
    for _trial in range(4):
        values = [rng.normal(size=r.size) for _k, r, _c in blocks]
        values[0][:1] = 0.0  # an explicit zero stays an entry, as in a COO construction
        keep = rng.random(sizes[select]) < 0.6
        if _trial == 0:
            keep[:] = True
        got = layout.matrix(values, keep)
        parts = []
        for i, ((k, r, c), v) in enumerate(zip(blocks, values)):
            B = sp.coo_matrix((v, (r, c)), shape=(k, nv)).tocsr()
            parts.append(B[keep] if i == select else B)
        want = sp.vstack(parts, format="csc")
        assert got.shape == want.shape
        assert np.array_equal(got.indptr, want.indptr)
        assert np.array_equal(got.indices, want.indices)
        assert np.array_equal(got.data, want.data)


def test_jerk_rows_product_and_pattern_match_their_matrix():
    rng = np.random.default_rng(3)
    n, m = 7, 2
    cell = np.repeat(np.arange(n - 1), m)
    node = np.array([1, n - 2])
    rows = _JerkRows(rng.normal(size=(cell.size, 4)), cell, rng.normal(size=2), node,
                     rng.normal(size=cell.size + 2), n)
    nr, r, c = _JerkRows.pattern(cell, node, n)
    A = sp.csr_matrix((rows.values(), (r, c)), shape=(nr, 3 * n + n - 1))
    z = rng.normal(size=3 * n + n - 1)
    assert np.allclose(rows.times(z), A @ z, rtol=1e-15, atol=1e-15)


def test_derivative_cache_returns_the_paths_values_and_evaluates_each_once():
    calls = []

    class Counting(LinearJointPath):
        def derivatives(self, s):
            calls.append(np.size(s))
            return super().derivatives(s)

    reference = LinearJointPath(np.array([0.0, 1.0]), np.array([2.0, -1.0]))
    cached = _Cached(Counting(np.array([0.0, 1.0]), np.array([2.0, -1.0])))
    s1 = np.linspace(0.0, reference.length, 9)
    s2 = np.concatenate([s1[::2], 0.5 * (s1[:-1] + s1[1:])])
    for s in (s1, s2, s2[::-1]):
        got = cached.derivatives(s)
        want = reference.derivatives(s)
        for a, b in zip(got, want):
            assert a.shape == b.shape
            assert np.array_equal(a, b)
    assert sum(calls) == s1.size + (s1.size - 1)  # every distinct value once
