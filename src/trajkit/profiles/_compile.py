"""One switch for the compiled kernels: numba when it is installed, else plain Python.

Kernel modules decorate their scalar functions with :func:`jit`. With numba
(``pip install trajkit[fast]``) and without ``TRAJKIT_NO_JIT`` in the
environment, every decorated function is compiled on first use (IEEE
arithmetic, no fast-math; the machine code is cached on disk next to the
sources); otherwise the same source runs as Python. There is one source:
the tests run both paths and compare them to a few ulps.

numba keys a cached function by its own source file only, but a compiled
caller contains its callees from other files; here the cache of every
kernel function is keyed by all kernel sources together (and this file's,
which sets how they are compiled), so editing any of them recompiles every
kernel (no stale machine code).
"""

from __future__ import annotations

import importlib
import os
import types

numba: types.ModuleType | None
try:  # pragma: no cover - depends on the install
    numba = importlib.import_module("numba")
except ImportError:  # pragma: no cover
    numba = None

__all__ = ["ENABLED", "KERNEL_MODULES", "compiled_twins", "jit", "jit_parallel", "jit_raw", "prange"]

#: True when the decorated kernels are compiled by numba.
ENABLED = numba is not None and os.environ.get("TRAJKIT_NO_JIT", "") in ("", "0")

#: Source files of the compiled kernels (next to this file).
KERNEL_MODULES = ("_phase.py", "_roots.py", "_check.py", "_brake.py", "_shapes.py", "_symfast.py", "_kernel.py",
                  "_batch_states.py", "_scalar.py", "_jit.py", "_compile.py")

_HERE = os.path.dirname(os.path.abspath(__file__))
_FILES = tuple(os.path.join(_HERE, f) for f in KERNEL_MODULES)


def _install_cache_locator() -> None:  # pragma: no cover - depends on numba internals
    """Key the disk cache of the kernels by every kernel source (see the module text)."""
    try:
        from numba.core import caching
    except ImportError:
        return

    class _KernelLocator(caching.InTreeCacheLocator):
        def get_source_stamp(self):
            out = []
            for p in _FILES:
                try:
                    st = os.stat(p)
                except OSError:
                    continue
                out.append((os.path.basename(p), st.st_mtime, st.st_size))
            return tuple(out)

        @classmethod
        def from_function(cls, py_func, py_file):
            if os.path.abspath(py_file) not in _FILES:
                return None
            return super().from_function(py_func, py_file)

    impl = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl", None)
    classes = getattr(impl, "_locator_classes", None)
    if isinstance(classes, list) and not any(c.__name__ == "_KernelLocator" for c in classes):
        classes.insert(0, _KernelLocator)


if ENABLED:
    _install_cache_locator()


def _unliteral_calls(disp):
    """``disp`` compiled once per argument type, not once per constant value.

    A compiled caller that passes a constant (``0``, ``True``) types it as a
    literal, and numba compiles the callee again for every such value
    (without this, one kernel function is compiled 14 times for one call of
    the state planner). The kernels never branch on a literal's value at
    typing time, so the callee is compiled for the plain types: the same
    machine code for every value, a fraction of the first compilation's
    time. A numba whose dispatcher lacks the hook gets ``disp`` unchanged
    (the same results, only more builds).
    """
    try:
        from numba.core.types import unliteral
    except ImportError:  # pragma: no cover - numba's layout changed
        return disp
    base = getattr(type(disp), "get_call_template", None)
    if base is None:  # pragma: no cover - numba's layout changed
        return disp

    def get_call_template(args, kws):
        return base(disp, tuple(unliteral(a) for a in args), {k: unliteral(v) for k, v in kws.items()})

    disp.get_call_template = get_call_template
    return disp


def _numba() -> types.ModuleType:
    """The numba module; called only when :data:`ENABLED` (which implies it is installed)."""
    if numba is None:  # pragma: no cover - ENABLED is False without numba
        raise RuntimeError("the compiled kernels need numba, which is not installed")
    return numba


def jit(fn):
    """Compile ``fn`` with ``numba.njit`` (cached, no fast-math, numpy's float
    error model: a division by zero gives inf/nan as in the Python path, where
    the kernels run on numpy floats) when :data:`ENABLED`."""
    if not ENABLED:
        return fn
    return _unliteral_calls(_numba().njit(cache=True, nogil=True, error_model="numpy")(fn))


def jit_raw(fn):
    """:func:`jit` without numba's reference-counted memory (``_nrt=False``).

    For kernels that never allocate an array or return one they did not get
    as an argument: they work on views of the caller's workspace, which numba
    would otherwise count in and out (an atomic operation) at every view and
    every call taking arrays -- the larger part of the time of the
    state-to-state kernel. The arithmetic is the same (no fast-math)."""
    if not ENABLED:
        return fn
    if not _RAW:  # a numba without the option: the counted build, same results
        return jit(fn)
    return _unliteral_calls(_numba().njit(cache=True, nogil=True, error_model="numpy", _nrt=False)(fn))


def _raw_supported() -> bool:
    """True when this numba's CPU target has the (private) ``_nrt`` option."""
    try:
        from numba.core.cpu import CPUTargetOptions
    except ImportError:  # pragma: no cover - numba's layout changed
        return False
    return hasattr(CPUTargetOptions, "_nrt")


_RAW = ENABLED and _raw_supported()


def jit_parallel(fn):
    """:func:`jit` with numba's ``parallel=True`` (loops over :func:`prange`
    run on every core); plain Python when not :data:`ENABLED`."""
    if not ENABLED:
        return fn
    return _unliteral_calls(_numba().njit(cache=True, nogil=True, parallel=True, error_model="numpy")(fn))


#: ``numba.prange`` when :data:`ENABLED`, else ``range``.
prange = _numba().prange if ENABLED else range


def compiled_twins(namespace: dict, names) -> dict:
    """Compiled twins of plain-Python functions that call each other.

    ``namespace`` is a module's globals, ``names`` the functions to compile.
    Each twin is the same code object with its globals pointing to the other
    twins, so compiled calls stay compiled while Python callers keep the plain
    functions (a call into compiled code costs more than these few
    operations). Returns ``{name: twin}`` (the plain functions when not
    :data:`ENABLED`).
    """
    if not ENABLED:
        return {n: namespace[n] for n in names}
    njit = _numba().njit
    g = dict(namespace)
    out = {}
    for n in names:
        f = namespace[n]
        twin = types.FunctionType(f.__code__, g, f.__name__, f.__defaults__, f.__closure__)
        twin.__module__ = f.__module__
        twin.__qualname__ = f.__qualname__
        out[n] = _unliteral_calls(njit(cache=True, nogil=True, error_model="numpy")(twin))
    g.update(out)  # compiled lazily: every call between twins resolves to a twin
    return out
