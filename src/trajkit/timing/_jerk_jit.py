"""Compiled jerk rows of the path-timing rounds.

Every round of the grid problem (:mod:`._socp`) linearises the joints' jerk
at both ends of every free interval around the previous round's node states
(both signs; the leg where ``qdot * qddot`` has one sign at both ends of the
interval, else, or where asked, the tighter of both; the node terms at the speed factor
``rho``, the node's speed over the interval's mean speed, or ``(1 + rho) / 2``
at the interval's slower end where the node terms add to the row's value at
the previous round's states), and the path's jerk; :func:`jerk_rows` writes those rows,
normalised, in one pass over the intervals and joints, in the order and with
the operations of the numpy formulation (``_socp._jerk_coefs_numpy``): the
same rows to a few ulps (the tests compare the two). Compiled by numba when
it is installed and enabled (``TRAJKIT_NO_JIT``); the engine uses the numpy
formulation otherwise. Pure math: arrays in, arrays out.
"""

from __future__ import annotations

import math

import numpy as np

from ..profiles._compile import ENABLED, numba
from ..profiles._compile import jit as _jit

__all__ = ["AVAILABLE", "jerk_rows"]

#: Whether the compiled rows are available (numba installed and enabled).
AVAILABLE = ENABLED and numba is not None


@_jit
def jerk_rows(x_bar, u_bar, ecorr, g, sig, d1, d2, d3, j_acc, j_dec, j_both, mixed, D, j_path, tiny):
    """The jerk rows at ``(x_bar, u_bar)``.

    Parameters
    ----------
    x_bar, u_bar : ndarray, shape (n,)
        Node states of the previous round (``sdot^2``, ``sddot``).
    ecorr : ndarray, shape (n - 1,)
        The intervals' correction of the mean speed.
    g : ndarray of int, shape (G,)
        The free intervals.
    sig, d1, d2, d3 : ndarray, shape (n, m)
        Sign of ``q'`` and the path derivatives at the nodes.
    j_acc, j_dec, j_both : ndarray, shape (n, m)
        The joints' jerk limits (speeding up, slowing down, the smaller).
    mixed : ndarray of bool, shape (n - 1, m)
        Intervals whose joint takes the smaller limit whatever its leg.
    D : ndarray, shape (n - 1,)
        Interval lengths.
    j_path : float
        The path's jerk limit (inf: no rows).
    tiny : float
        Node speeds^2 below ``tiny * max(max(x_bar), tiny)`` count as that floor.

    Returns
    -------
    C : ndarray, shape (r, 4)
        Coefficients on ``(x_i, x_{i+1}, u_i, u_{i+1})``, every row divided by
        its largest magnitude (coefficients and right-hand side).
    b : ndarray, shape (r,)
        Right-hand sides, divided likewise.
    """
    G = g.size
    m = d1.shape[1]
    n = x_bar.size
    xmax = -math.inf
    for k in range(n):
        xmax = max(xmax, x_bar[k])
    floor = tiny * max(xmax, tiny)
    path = abs(j_path) < math.inf
    nr = 4 * G * m + (2 * G if path else 0)
    C = np.empty((nr, 4))
    b = np.empty(nr)
    for e in range(2):
        for kg in range(G):
            i = g[kg]
            si = math.sqrt(max(x_bar[i], floor))
            sj = math.sqrt(max(x_bar[i + 1], floor))
            S = max(si + sj + 2.0 * ecorr[i], 0.5 * (si + sj))
            S2 = S * S
            xi = x_bar[i]
            xj = x_bar[i + 1]
            nd = i + e
            # the node terms' speed factor: the node's speed over the mean
            rs = 2.0 * (si if e == 0 else sj) / S
            half = 0.5 * (1.0 + rs)
            for k in range(m):
                # the leg of the interval: where the joint speeds up (slows down)
                # at both of its ends, else (a leg change inside) the tighter of both
                sp0 = sig[i, k] * (d2[i, k] * x_bar[i] + d1[i, k] * u_bar[i])
                sp1 = sig[i + 1, k] * (d2[i + 1, k] * x_bar[i + 1] + d1[i + 1, k] * u_bar[i + 1])
                if mixed[i, k]:
                    jl = j_both[nd, k]
                elif sp0 > 0.0 and sp1 > 0.0:
                    jl = j_acc[nd, k]
                elif sp0 < 0.0 and sp1 < 0.0:
                    jl = j_dec[nd, k]
                else:
                    jl = j_both[nd, k]
                f = 2.0 * jl / S
                gi = -jl / (S2 * si)
                gj = -jl / (S2 * sj)
                r = f - gi * xi - gj * xj
                # (the node terms at the previous round's states: a row whose node
                # terms add to its value takes the larger factor, one whose node
                # terms subtract the node's own, so that each bounds both)
                nt = d3[nd, k] * x_bar[nd] + 3.0 * d2[nd, k] * u_bar[nd]
                for h in range(2):
                    sgn = 1.0 if h == 0 else -1.0
                    fac = max(rs, half) if sgn * nt > 0.0 else min(rs, half)
                    w = sgn * d1[nd, k] / D[i]
                    c3 = sgn * fac * d3[nd, k]
                    c2 = sgn * fac * 3.0 * d2[nd, k]
                    row = (2 * e + h) * G * m + kg * m + k
                    if e == 0:
                        C[row, 0] = c3 - gi
                        C[row, 1] = -gj
                        C[row, 2] = c2 - w
                        C[row, 3] = w
                    else:
                        C[row, 0] = -gi
                        C[row, 1] = c3 - gj
                        C[row, 2] = -w
                        C[row, 3] = c2 + w
                    b[row] = r
    if path:
        for kg in range(G):
            i = g[kg]
            si = math.sqrt(max(x_bar[i], floor))
            sj = math.sqrt(max(x_bar[i + 1], floor))
            S = max(si + sj + 2.0 * ecorr[i], 0.5 * (si + sj))
            f1 = 2.0 * j_path / S
            gi1 = -j_path / (S * S * si)
            gj1 = -j_path / (S * S * sj)
            r1 = f1 - gi1 * x_bar[i] - gj1 * x_bar[i + 1]
            for h in range(2):
                sgn = 1.0 if h == 0 else -1.0
                w1 = sgn / D[i]
                row = 4 * G * m + h * G + kg
                C[row, 0] = -gi1
                C[row, 1] = -gj1
                C[row, 2] = -w1
                C[row, 3] = w1
                b[row] = r1
    for row in range(nr):
        big = max(abs(C[row, 0]), abs(C[row, 1]), abs(C[row, 2]), abs(C[row, 3]), abs(b[row]), 1e-300)
        for a in range(4):
            C[row, a] = C[row, a] / big
        b[row] = b[row] / big
    return C, b
