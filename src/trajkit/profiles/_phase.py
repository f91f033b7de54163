"""The one formula of a constant-jerk phase (exact integration).

Every motion of trajkit is a sequence of phases of constant jerk ``j``; a
phase of duration ``t`` from ``(p, v, a)`` ends at::

    p + t (v + t (a/2 + t j/6)),   v + t (a + t j/2),   a + t j

All planners, the motion type and the verifier integrate with these
functions (scalar :func:`phase_end`, vectorised :func:`phase_eval`).
"""

from __future__ import annotations

from ._compile import jit_raw

__all__ = ["phase_end", "phase_eval"]


@jit_raw
def phase_end(p, v, a, j, t):
    """State ``(p, v, a)`` after ``t`` [s] of constant jerk ``j`` from ``(p, v, a)``."""
    return (p + t * (v + t * (0.5 * a + t * j / 6.0)),
            v + t * (a + 0.5 * t * j),
            a + t * j)


def phase_eval(p, v, a, j, t):
    """:func:`phase_end` on numpy arrays (broadcasting); returns ``(p, v, a)``."""
    return (p + t * (v + t * (0.5 * a + t * j / 6.0)),
            v + t * (a + 0.5 * t * j),
            a + t * j)
