"""Transcendental functions whose results do not depend on the CPU numpy runs on.

numpy dispatches float64 ``exp``, ``log``, ``tan``, ``arctan``, ``arctan2``, ``power``, … to
AVX-512 code when the CPU has it (``tanh`` already to AVX2 code), and that code differs from the
C library's in the last bit on some inputs (``sin``, ``cos``, ``hypot``, ``sqrt`` and the
arithmetic operators gave the same bits at every dispatch level; tests/cpu_dispatch.py lists what
was measured). Anything that reaches a dataset file — poses, yaws, sizes — is computed
here instead, through Python's :mod:`math` (the C library, one element at a time), so the same
scenario and seed give the same bytes with and without AVX-512 (docs/dataset.md, "Byte-stable
datasets"). The scope is numpy's dispatch levels on x86-64 with one C library; other CPU
families and C libraries are not tested.

The functions take scalars or arrays like their numpy namesakes and return a Python float for
scalar input, a float64 array otherwise. They are slow per element (≈ 100 ns): use them for the
world's few hundred poses, never for per-pixel work.

Example:
    >>> from cadsim import portable_math as pm
    >>> pm.arctan2(1.0, 1.0) == math.atan2(1.0, 1.0)
    True
    >>> pm.exp([0.0, 1.0]).dtype
    dtype('float64')
"""

from __future__ import annotations

import math
import sys
import types

import numpy as np

__all__ = [
    "arccos", "arccosh", "arcsin", "arcsinh", "arctan", "arctan2", "arctanh", "cbrt", "cosh",
    "exp", "exp2", "expm1", "log", "log10", "log1p", "log2", "power", "sinh", "tan", "tanh",
]  # fmt: skip


def _portable(fn, nin: int):
    """A numpy-broadcasting version of the scalar C-library function ``fn``; a domain error
    gives nan and an overflow inf, as numpy's would, instead of raising."""

    def safe(*xs: float) -> float:
        try:
            return fn(*xs)
        except ValueError:
            return math.nan
        except OverflowError:
            return math.inf

    ufunc = np.frompyfunc(safe, nin, 1)

    def apply(*args):
        arrays = [np.asarray(a, dtype=np.float64) for a in args]
        if all(a.ndim == 0 for a in arrays):
            return safe(*(float(a) for a in arrays))
        with np.errstate(over="ignore"):
            return ufunc(*arrays).astype(np.float64)

    apply.__name__ = fn.__name__
    apply.__doc__ = f"``math.{fn.__name__}`` elementwise (C library), broadcasting like numpy."
    return apply


def _log(x: float) -> float:
    return -math.inf if x == 0.0 else math.log(x)


def _log2(x: float) -> float:
    return -math.inf if x == 0.0 else math.log2(x)


def _log10(x: float) -> float:
    return -math.inf if x == 0.0 else math.log10(x)


arctan2 = _portable(math.atan2, 2)
power = _portable(math.pow, 2)
arctan = _portable(math.atan, 1)
arcsin = _portable(math.asin, 1)
arccos = _portable(math.acos, 1)
arctanh = _portable(math.atanh, 1)
arcsinh = _portable(math.asinh, 1)
arccosh = _portable(math.acosh, 1)
tan = _portable(math.tan, 1)
sinh = _portable(math.sinh, 1)
cosh = _portable(math.cosh, 1)
tanh = _portable(math.tanh, 1)
exp = _portable(math.exp, 1)
exp2 = _portable(math.exp2, 1)
expm1 = _portable(math.expm1, 1)
log = _portable(_log, 1)
log2 = _portable(_log2, 1)
log10 = _portable(_log10, 1)
log1p = _portable(math.log1p, 1)
cbrt = _portable(math.cbrt, 1)


class _NumpyWithPortableMath(types.ModuleType):
    """numpy, except that the functions above are the portable ones (see :func:`numpy_namespace`)."""

    def __getattr__(self, name: str):
        return getattr(np, name)


def numpy_namespace() -> types.ModuleType:
    """A stand-in for the ``numpy`` module whose dispatched transcendental functions are the
    portable ones; every other attribute is numpy's. Third-party simulators whose state we write
    (highway-env) get it as their ``np`` (:func:`use_portable_math_in`)."""
    namespace = _NumpyWithPortableMath("numpy_portable_math")
    for name in __all__:
        setattr(namespace, name, globals()[name])
    return namespace


def use_portable_math_in(package: str) -> int:
    """Give every imported module of ``package`` that refers to numpy as ``np`` the portable
    namespace instead; returns how many modules were changed. Idempotent."""
    namespace = numpy_namespace()
    changed = 0
    for name, module in list(sys.modules.items()):
        if (name == package or name.startswith(package + ".")) and getattr(
            module, "np", None
        ) is np:
            module.np = namespace
            changed += 1
    return changed


def matmul(a, b) -> np.ndarray:
    """``a @ b`` (float64; 1-D and batched operands as for ``@``) without BLAS: each product's
    terms are summed in index order by numpy's own reduction. ``@`` hands float matrices to BLAS,
    and OpenBLAS picks its kernel — and with it the summation order and the use of fused
    multiply-adds — by CPU model, so ``@`` may differ in the last bit between two machines
    (measured: a detection's position on an AVX-512 CPU against an AVX2 one). For the small
    products (3 x 3 rotations, a few hundred points) of what reaches a dataset file or a
    result."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if a.ndim == 1 and b.ndim == 1:
        return np.sum(a * b)
    if b.ndim == 1:
        return np.sum(a * b, axis=-1)
    if a.ndim == 1:
        return np.sum(a[:, None] * b, axis=-2)
    return np.sum(a[..., :, :, None] * b[..., None, :, :], axis=-2)
