"""exp(x) for x <= 0 with the same bits on every CPU, from numpy or compiled code.

numpy's float64 ``exp`` is its own AVX-512 code on CPUs that have it and the C library's
elsewhere, and the two differ in the last bit for some inputs; a compiled loop calls the C
library's. The tensor builder's values exp(-d / sigma) feed every hypergraph matcher, so they
are computed here instead: x = k ln 2 + r with k = floor(x / ln 2 + 1/2) and ln 2 split in two
(Cody–Waite: k * LN2_HI is exact), exp(r) by its Taylor polynomial of degree 13 on
|r| <= ln 2 / 2 (truncation below 2e-18, relative), times 2^k assembled from its bits. Only
additions, multiplications and a floor, each correctly rounded by IEEE 754 and applied in one
order (no fused multiply-add: numba does not contract without fastmath), so the numpy function
and the compiled loop give the same bits everywhere (``tests/test_jit_kernels.py``). Accurate
to about 2 ulp (tested against numpy's exp); exp of x < :data:`LOW` is 0.
"""

from __future__ import annotations

import numpy as np

from matchers.core.jit import njit

LN2_HI = 0.693147180369123816490  # ln 2 rounded to 32 significant bits: k * LN2_HI is exact
LN2_LO = 1.90821492927058770002e-10  # ln 2 - LN2_HI
INV_LN2 = 1.44269504088896338700
LOW = -708.0
"""Below this exp(x) would be subnormal: 0 instead."""
_COEFFS = tuple(1.0 / float(np.prod(np.arange(1, j + 1, dtype=float))) for j in range(13, 1, -1))
"""1/13!, 1/12!, ..., 1/2! (Horner order; the 1 + r + ... tail is added last)."""


def exp_nonpositive(x: np.ndarray) -> np.ndarray:
    """exp of a float64 array of non-positive numbers (module docstring), elementwise."""
    x = np.maximum(np.asarray(x, dtype=np.float64), LOW)
    k = np.floor(x * INV_LN2 + 0.5)
    r = (x - k * LN2_HI) - k * LN2_LO
    p = np.full_like(r, _COEFFS[0])
    for c in _COEFFS[1:]:
        p = p * r + c
    p = (p * r + 1.0) * r + 1.0
    scale = ((k.astype(np.int64) + 1023) << 52).view(np.float64)
    return np.where(x > LOW, p * scale, 0.0)


def _exp_into(x: np.ndarray, divisor: float, out: np.ndarray) -> None:
    # out = exp_nonpositive(-x / divisor), the same operations per element
    count = x.shape[0]
    bits = np.empty(count, dtype=np.int64)
    for i in range(count):
        v = max(-x[i] / divisor, LOW)
        k = np.floor(v * INV_LN2 + 0.5)
        r = (v - k * LN2_HI) - k * LN2_LO
        p = _C0
        p = p * r + _C1
        p = p * r + _C2
        p = p * r + _C3
        p = p * r + _C4
        p = p * r + _C5
        p = p * r + _C6
        p = p * r + _C7
        p = p * r + _C8
        p = p * r + _C9
        p = p * r + _C10
        p = p * r + _C11
        out[i] = (p * r + 1.0) * r + 1.0
        bits[i] = (np.int64(k) + 1023) << 52
        if not v > LOW:
            out[i] = 0.0
            bits[i] = 1023 << 52
    scale = bits.view(np.float64)
    for i in range(count):
        out[i] = out[i] * scale[i]


_C0, _C1, _C2, _C3, _C4, _C5, _C6, _C7, _C8, _C9, _C10, _C11 = _COEFFS
_exp_into_jit = njit(_exp_into)


def decay(x: np.ndarray, divisor: float, out: np.ndarray) -> None:
    """``out[:] = exp_nonpositive(-x / divisor)`` for non-negative 1-D ``x`` and a positive
    divisor (the tensor values exp(-d / sigma)): compiled when numba is available, the same bits
    either way."""
    if _exp_into_jit is None:
        out[:] = exp_nonpositive(-x / divisor)
    else:
        _exp_into_jit(x, float(divisor), out)
