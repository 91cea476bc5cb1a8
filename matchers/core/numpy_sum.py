"""numpy's summation order, reproduced in loops that numba compiles (:mod:`matchers.core.jit`).

A compiled kernel that replaces numpy code must add in numpy's order to give the same bits.
``np.add.reduce`` over the last axis of a C-contiguous float64 array sums each row pairwise
(:func:`row_sum`); over the first axis it adds the rows one after another, element by element —
except for a single column, which is contiguous and summed pairwise, so kernels that rely on
these orders accept 2 to :data:`PAIRWISE_BLOCK` columns and leave other shapes to numpy.
"""

from __future__ import annotations

import numpy as np

from matchers.core.jit import njit

PAIRWISE_BLOCK = 128
"""Longest row :func:`row_sum` reproduces (numpy splits longer rows recursively)."""


def row_sum(a: np.ndarray, n: int) -> float:
    """numpy's ``add.reduce`` of a contiguous float64 row of length n <= 128, operation for
    operation (its pairwise summation: a plain loop below 8 entries, else 8 interleaved partial
    sums combined as a tree, then the remainder)."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += a[i]
        return res
    r0, r1, r2, r3 = a[0], a[1], a[2], a[3]
    r4, r5, r6, r7 = a[4], a[5], a[6], a[7]
    i = 8
    stop = n - n % 8
    while i < stop:
        r0 += a[i]
        r1 += a[i + 1]
        r2 += a[i + 2]
        r3 += a[i + 3]
        r4 += a[i + 4]
        r5 += a[i + 5]
        r6 += a[i + 6]
        r7 += a[i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[i]
        i += 1
    return res


row_sum_jit = njit(row_sum)


def reproducible(mat: np.ndarray) -> bool:
    """Whether a kernel using these orders gives numpy's bits on ``mat``: C-contiguous float64
    with 2 to :data:`PAIRWISE_BLOCK` columns."""
    return (
        mat.dtype == np.float64 and mat.flags.c_contiguous and 2 <= mat.shape[1] <= PAIRWISE_BLOCK
    )
