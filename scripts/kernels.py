"""The SIMD kernels NumPy and OpenBLAS run on this machine, and the environment that turns
their AVX-512 kernels off (issue 40: `make test-noavx512`, which CI runs after `make test`).

NumPy and OpenBLAS pick their kernels by CPU when they load, so the last bits of a sum, a
dot product or a sparse LU (SciPy's SuperLU calls OpenBLAS) differ from one machine to the
next. The compiled core does its own arithmetic and is not affected; a test of anything
that goes through NumPy or BLAS holds a tolerance instead of an exact value. CI proves both
paths on one machine: the tests with the kernels it picks, then the unit tier again with

- NumPy's AVX-512 dispatch targets disabled (NPY_DISABLE_CPU_FEATURES). The names are this
  NumPy's own (X86_V4, AVX512_ICL, AVX512_SPR from NumPy 2.3; AVX512F, AVX512_SKX, ...
  before): NumPy ignores a name it does not know without a word, so they are read from it;
- OpenBLAS held to its AVX2 kernels (OPENBLAS_CORETYPE=Haswell; only where the CPU has
  AVX2). This is the one that matters most: the sealed pool of
  tests/state/test_volume_phases.py lets go of a wall on OpenBLAS's SkylakeX kernels and
  not on its Haswell ones.

    python scripts/kernels.py env     # the assignments, for `env $(python scripts/kernels.py env) ...`
    python scripts/kernels.py check   # what runs now; exit 1 if an AVX-512 kernel still does
"""

from __future__ import annotations

import importlib
import sys

import numpy
from threadpoolctl import threadpool_info

try:  # NumPy >= 2
    umath = importlib.import_module("numpy._core._multiarray_umath")
except ImportError:  # NumPy 1.x
    umath = importlib.import_module("numpy.core._multiarray_umath")

# OpenBLAS's cores with AVX-512 kernels (threadpoolctl's "architecture", case aside)
OPENBLAS_AVX512 = {"skylakex", "cooperlake", "sapphirerapids"}


def avx512_targets() -> list[str]:
    """NumPy's dispatch targets that use AVX-512, by this NumPy's names."""
    return [f for f in umath.__cpu_dispatch__ if "AVX512" in f or f == "X86_V4"]


def environment() -> dict[str, str]:
    """The variables that leave NumPy and OpenBLAS without AVX-512 kernels here."""
    env = {"NPY_DISABLE_CPU_FEATURES": ",".join(avx512_targets())}
    if umath.__cpu_features__.get("AVX2"):
        env["OPENBLAS_CORETYPE"] = "Haswell"
    return env


def running() -> tuple[list[str], list[str]]:
    """(NumPy's dispatch targets enabled now, the OpenBLAS cores loaded)."""
    import scipy.sparse.linalg  # noqa: F401  (loads SciPy's OpenBLAS, SuperLU's BLAS)

    features = umath.__cpu_features__
    numpy_on = [f for f in umath.__cpu_dispatch__ if features.get(f)]
    blas = [
        str(lib.get("architecture"))
        for lib in threadpool_info()
        if lib.get("internal_api") == "openblas"
    ]
    return numpy_on, blas


def main(argv: list[str]) -> int:
    if argv == ["env"]:
        print(" ".join(f"{k}={v}" for k, v in environment().items() if v))
        return 0
    if argv == ["check"]:
        numpy_on, blas = running()
        print(
            f"NumPy {numpy.__version__}: dispatch targets on {' '.join(numpy_on) or 'none'}; "
            f"OpenBLAS cores {' '.join(blas) or 'none loaded'}"
        )
        left = [f for f in numpy_on if f in avx512_targets()]
        left += [b for b in blas if b.lower() in OPENBLAS_AVX512]
        if left:
            print(f"AVX-512 kernels still on: {' '.join(left)}", file=sys.stderr)
            return 1
        return 0
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
