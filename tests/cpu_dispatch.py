"""Run a command as it would run on another CPU: numpy without its AVX-512 code paths, numpy
whose transcendental functions move a seeded share of their results by one ulp, or (through the
environment, :func:`other_blas_env`) OpenBLAS with another CPU's kernels.

    python tests/cpu_dispatch.py [--ulp-faults] MODULE ARG...   # runs ``python -m MODULE ARG...``
    python tests/cpu_dispatch.py [--ulp-faults] --path SCRIPT ARG...
    python tests/cpu_dispatch.py --avx512-features   # what to disable (empty without AVX-512)

``NPY_DISABLE_CPU_FEATURES`` (:func:`avx512_env`) shows the real difference where the CPU has
AVX-512; the fault injection makes a difference of the same kind visible on any CPU
(``../shared/DESIGN.md`` §10). Both are used by tests/test_cpu_independence.py; the injection
needs the command to run in this process (``--workers 1``).
"""

from __future__ import annotations

import os
import platform
import runpy
import sys

import numpy as np

# numpy's float64 functions whose SIMD versions differ from the C library in the last bit (measured
# with numpy 2.4 on x86-64, AVX-512 against AVX2 against SSE4.2; tanh already at AVX2). sin, cos,
# hypot, sqrt and float_power gave the same bits at every level (test_cpu_independence checks it).
TRANSCENDENTAL = (
    "exp", "exp2", "expm1", "log", "log2", "log10", "log1p", "power", "tan", "arcsin", "arccos",
    "arctan", "arctan2", "sinh", "cosh", "tanh", "arcsinh", "arccosh", "arctanh", "cbrt",
)  # fmt: skip
SAME_EVERYWHERE = ("sin", "cos", "hypot", "sqrt", "float_power")


def avx512_features() -> list[str]:
    """The AVX-512 dispatch targets numpy would use on this CPU (empty without AVX-512)."""
    from numpy._core import _multiarray_umath as core

    found = core.__cpu_features__
    return [
        name
        for name in core.__cpu_dispatch__
        if (name.startswith("AVX512") or name == "X86_V4") and found.get(name)
    ]


def avx512_env() -> dict[str, str]:
    """This process's environment with numpy's AVX-512 dispatch disabled (unchanged without it)."""
    features = avx512_features()
    env = dict(os.environ)
    if features:
        env["NPY_DISABLE_CPU_FEATURES"] = " ".join(features)
    return env


OTHER_BLAS_KERNEL = "Nehalem"  # OpenBLAS's SSE kernels: run on every x86-64 CPU


def other_blas_env() -> dict[str, str] | None:
    """This process's environment with OpenBLAS forced to another kernel than the one it picks
    for this CPU (its summation order and use of fused multiply-adds differ by kernel, which is
    how BLAS results differ between machines); None off x86-64, where the kernel names differ."""
    if platform.machine().lower() not in ("x86_64", "amd64"):
        return None
    return dict(os.environ) | {"OPENBLAS_CORETYPE": OTHER_BLAS_KERNEL}


def inject_ulp_faults(share: float = 0.3, seed: int = 0) -> None:
    """Replace numpy's transcendental functions (module attributes) by versions that move about
    `share` of their float64 results up by one ulp, the draws seeded by `seed`."""
    rng = np.random.default_rng(seed)

    class Faulty:
        """The ufunc, its float64 results moved by one ulp at seeded places; attributes (nin,
        reduce, outer, …) are the ufunc's own."""

        def __init__(self, ufunc: np.ufunc) -> None:
            self.ufunc = ufunc
            self.__name__ = ufunc.__name__

        def __getattr__(self, name: str):
            return getattr(self.ufunc, name)

        def __call__(self, *args, **kwargs):
            result = self.ufunc(*args, **kwargs)
            if isinstance(result, np.ndarray) and result.dtype == np.float64 and result.size:
                moved = rng.random(result.shape) < share
                result[moved] = np.nextafter(result[moved], np.inf)
            elif isinstance(result, np.float64) and rng.random() < share:
                result = np.nextafter(result, np.inf)
            return result

    for name in TRANSCENDENTAL:
        setattr(np, name, Faulty(getattr(np, name)))


def main(argv: list[str]) -> None:
    if argv == ["--avx512-features"]:  # for the Makefile: what NPY_DISABLE_CPU_FEATURES gets
        print(" ".join(avx512_features()))
        return
    if argv and argv[0] == "--ulp-faults":
        # numba cannot compile a kernel that calls the wrapped functions: the numpy kernels run,
        # which also puts the compiled-vs-numpy difference under test.
        os.environ["CADSIM_NO_JIT"] = "1"
        # lightgbm imports dask.array when it is installed, which checks numpy's ufuncs at
        # import: imported first, it keeps the real ones (the suite's own code gets the faults)
        import lightgbm  # noqa: F401

        inject_ulp_faults()
        argv = argv[1:]
    if argv[0] == "--path":  # a script file instead of a module
        sys.argv = argv[1:]
        runpy.run_path(argv[1], run_name="__main__")
        return
    module, *args = argv
    sys.argv = [module, *args]
    runpy.run_module(module, run_name="__main__", alter_sys=True)


if __name__ == "__main__":
    main(sys.argv[1:])
