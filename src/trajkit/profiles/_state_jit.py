"""Optional compiled kernel (numba) for the state-to-state planner.

:mod:`trajkit.profiles._state_kernel` scans one-parameter profile families
for roots of the end-position error and checks every candidate exactly. Its
fused residuals (:func:`~trajkit.profiles._state_kernel.f1_residual`,
:func:`~trajkit.profiles._state_kernel.f2_residual`,
:func:`~trajkit.profiles._state_kernel.fixed_residual`,
:func:`~trajkit.profiles._state_kernel.f2_hold_residual` and their helpers),
the scans over them (:func:`~trajkit.profiles._state_kernel.scan_family`),
the bump choice (:func:`~trajkit.profiles._state_kernel._bump_plan`) and the
exact check (:func:`~trajkit.profiles._state_kernel._verify_core`) are plain
scalar code. When numba is installed (``pip install trajkit[fast]``) and
``TRAJKIT_NO_JIT`` is unset, this module compiles that same source as it is
(same operations in the same order, IEEE arithmetic without fast-math). The
kernel is not a second implementation: the tests check that the compiled
and the Python functions agree bit for bit, and that planning gives the
same profiles with and without the compilation.

Compilation happens on first use (5-15 s); the machine code is cached on
disk by numba (``cache=True``, in ``__pycache__`` next to the kernel, or
numba's user cache when that is not writable), so later processes load it
in well under a second.
"""

from __future__ import annotations

import inspect
import os

import numpy as np

from . import _state_kernel

try:  # pragma: no cover - depends on the install
    import numba
except ImportError:  # pragma: no cover
    numba = None

__all__ = ["AVAILABLE", "enabled", "kernels", "scan_family", "verify_core"]

#: Scalar functions of :mod:`._state_kernel` compiled together (they call
#: each other by name).
_KERNELS = (
    "_part", "ramp_dv_dt", "_bump_select", "_seg_int", "_ramp_int", "_ramp_dv",
    "_bump_int", "_bump_int_t", "_seg_same_sign", "_ramp_same_sign", "_bump_same_sign",
    "_bump_plan", "_ramp_signed_plan", "f1_residual", "f2_residual", "fixed_residual",
    "_hold_build", "f2_hold_residual", "_fam", "_fam_root", "_fam_golden", "_promising",
    "scan_family", "_quad_roots2", "_verify_core", "_fam_time", "_f1_cruise_time",
)

AVAILABLE = numba is not None

_compiled = None
_failed = False


def enabled() -> bool:
    """True when the compiled kernel is to be used (numba present, no
    ``TRAJKIT_NO_JIT``, compilation not failed)."""
    return AVAILABLE and not _failed and not os.environ.get("TRAJKIT_NO_JIT")


def _compile():
    # the kernel module's own name: numba's disk cache re-imports it by name
    # when it loads the compiled functions
    ns: dict = {"__name__": _state_kernel.__name__}
    src = inspect.getsource(_state_kernel)
    exec(compile(src, _state_kernel.__file__, "exec"), ns)  # noqa: S102
    for name in _KERNELS:
        try:  # cached on disk next to the kernel (or numba's user cache)
            ns[name] = numba.njit(cache=True, nogil=True)(ns[name])
        except RuntimeError:  # pragma: no cover - no writable cache location
            ns[name] = numba.njit(cache=False, nogil=True)(ns[name])
    return {name: ns[name] for name in _KERNELS}


def _warm_up(k):
    """Compile every entry point now (one call each with typical types)."""
    P = (1.0, 0.0, 0.1, 0.0, 0.5, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0)
    grid = np.array([-1.0, 0.0, 1.0])
    for kind in range(6):
        k["scan_family"](kind, grid, P, 2, kind >= 4)
    k["_bump_plan"](0.1, 0.0, 0.5, 0.0, 1.0, 1.0, 1.0, 1.0)
    for kind in range(3):
        k["_fam_time"](kind, 0.1, P)
    k["_f1_cruise_time"](0.1, 0.5, P)
    for name in ("f1_residual", "fixed_residual", "f2_residual", "f2_hold_residual"):
        args = P[1:] if name in ("f1_residual", "f2_residual") else P
        k[name](0.1, *args, *((True,) if name.startswith("f2") else ()))
    ph = np.zeros((1, 3))
    k["_verify_core"](ph, 1, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1e-9, True)


def kernels() -> dict | None:
    """The compiled functions (compiled, or loaded from numba's cache, on the
    first call); ``None`` when the compilation fails (the Python kernel is
    then used, with the same results)."""
    global _compiled, _failed
    if _compiled is None and not _failed:
        try:
            k = _compile()
            _warm_up(k)
        except Exception:  # noqa: BLE001  # pragma: no cover - any numba failure: use Python
            _failed = True
            return None
        _compiled = k
    return _compiled


def scan_family(kind, grid, P, edge_steps, near):
    """The compiled :func:`~trajkit.profiles._state_kernel.scan_family`."""
    return kernels()["scan_family"](kind, np.asarray(grid, dtype=np.float64), P, edge_steps,
                                    near)


def verify_core(phases, p0, v0, a0, V, A1, J1, A2, J2, pg, vg, ag, rtol, check_goal):
    """The compiled :func:`~trajkit.profiles._state_kernel._verify_core` on a phase list."""
    ph = np.array(phases, dtype=np.float64).reshape(-1, 3)
    return kernels()["_verify_core"](ph, ph.shape[0], p0, v0, a0, V, A1, J1, A2, J2,
                                     pg, vg, ag, rtol, check_goal)
