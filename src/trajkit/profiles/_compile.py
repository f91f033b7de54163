"""One switch for the compiled kernels: numba when it is installed, else plain Python.

Kernel modules decorate their scalar functions with :func:`jit`. With numba
(``pip install trajkit[fast]``) and without ``TRAJKIT_NO_JIT`` in the
environment, every decorated function is compiled on first use (IEEE
arithmetic, no fast-math; the machine code is cached on disk); otherwise the
same source runs as Python. There is one source: the tests run both paths
and compare them to a few ulps.
"""

from __future__ import annotations

import os

try:  # pragma: no cover - depends on the install
    import numba
except ImportError:  # pragma: no cover
    numba = None

__all__ = ["ENABLED", "jit"]

#: True when the decorated kernels are compiled by numba.
ENABLED = numba is not None and os.environ.get("TRAJKIT_NO_JIT", "") in ("", "0")


def jit(fn):
    """Compile ``fn`` with ``numba.njit`` (cached, no fast-math) when :data:`ENABLED`."""
    if not ENABLED:
        return fn
    return numba.njit(cache=True, nogil=True)(fn)
