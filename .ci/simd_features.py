"""Print numpy's runtime-dispatched SIMD targets available on this machine (space separated).

Used by .ci/run to set NPY_DISABLE_CPU_FEATURES so the code-path comparison
tests run once with and once without numpy's SIMD kernels.
"""

try:
    from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__
except ImportError:  # numpy < 2
    from numpy.core._multiarray_umath import __cpu_dispatch__, __cpu_features__

print(" ".join(name for name in __cpu_dispatch__ if __cpu_features__.get(name)))
