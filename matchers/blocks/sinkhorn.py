"""Bistochastic (Sinkhorn) normalisation with slack rows/columns for rectangular matrices."""

from __future__ import annotations

import numpy as np

from matchers.core.jit import njit
from matchers.core.numpy_sum import reproducible, row_sum_jit


def sinkhorn(
    matrix: np.ndarray, max_iter: int = 100, tol: float = 1e-3, slack: bool = True
) -> tuple[np.ndarray, int]:
    """Alternately normalise rows and columns of a non-negative (n, m) matrix to sum 1.

    For n != m the matrix is padded to max(n, m) x max(n, m) with slack rows (or columns) that are
    filled with the matrix's smallest positive entry — a slack cell is "as good as the worst candidate" —
    so that the objects of the larger view that have no good partner can send their mass to the
    slack instead of being forced onto a real one; the real (n, m) block is returned. Without
    slack, the smaller side's sums become 1 and the larger side's min(n, m)/max(n, m).

    Stops when every row and column sum is within ``tol`` of its target (RRWM's tolerance 1e-3)
    or after ``max_iter`` row+column sweeps (the reference RRWHM code has no cap; we cap).
    All-zero rows/columns stay zero. Returns (normalised matrix, sweeps run).

    A strictly positive matrix (every walk's exp(...) jump is) takes a lean loop of in-place
    operations — the same sums, reciprocals and products in the same order, so bit-identical
    to the general loop at a fraction of its per-sweep overhead (peaked matrices often run all
    ``max_iter`` sweeps).
    """
    mat = np.asarray(matrix, dtype=float)
    n, m = mat.shape
    if n == 0 or m == 0:
        return mat.copy(), 0
    size = max(n, m)
    if slack and n != m:
        positive = mat[mat > 0]
        fill = positive.min() if positive.size else 0.0
        work = np.full((size, size), fill)
        work[:n, :m] = mat
        row_target, col_target = 1.0, 1.0
    else:
        work = mat.copy()
        short = min(n, m) / size
        row_target = 1.0 if n <= m else short
        col_target = 1.0 if m <= n else short
    if work.min() > 0:
        fast = positive_sweeps(work.copy(), max_iter, tol, row_target, col_target)
        if fast is not None:
            return fast[0][:n, :m], fast[1]
    sweeps = 0
    for sweeps in range(1, max_iter + 1):  # noqa: B007 - sweeps is reported
        rows = work.sum(axis=1, keepdims=True)
        if sweeps > 1:  # columns are exact after the previous sweep: test the rows
            deviation = np.abs(rows - row_target)
            deviation[rows == 0] = 0.0
            if deviation.max() <= tol:
                sweeps -= 1
                break
        work *= np.divide(row_target, rows, out=np.zeros_like(rows), where=rows > 0)
        cols = work.sum(axis=0, keepdims=True)
        work *= np.divide(col_target, cols, out=np.zeros_like(cols), where=cols > 0)
    return work[:n, :m], sweeps


def _positive_sweeps(
    work: np.ndarray, max_iter: int, tol: float, row_target: float, col_target: float
) -> tuple[np.ndarray, int] | None:
    """The sweeps of :func:`sinkhorn` for a strictly positive matrix, in place.

    max_i |r_i - t| <= tol is tested as (max r - t <= tol and t - min r <= tol): floating-point
    subtraction is monotone and t - r = -(r - t) exactly, so the two tests agree bit for bit.
    Returns None if a sum vanished or overflowed (the general loop then handles it)."""
    size_r, size_c = work.shape
    rows, cols = np.empty(size_r), np.empty(size_c)
    row_factor = rows[:, None]
    # ufuncs bound once and called positionally: on a 20 x 20 matrix the call overhead is the cost
    add, divide, multiply = np.add.reduce, np.divide, np.multiply
    largest, smallest = np.maximum.reduce, np.minimum.reduce
    sweeps = 0
    for sweeps in range(1, max_iter + 1):  # noqa: B007 - sweeps is reported
        add(work, 1, None, rows)
        if sweeps > 1 and largest(rows) - row_target <= tol and row_target - smallest(rows) <= tol:
            sweeps -= 1
            break
        divide(row_target, rows, rows)
        multiply(work, row_factor, work)
        add(work, 0, None, cols)
        divide(col_target, cols, cols)
        multiply(work, cols, work)
    if not (np.isfinite(rows).all() and np.isfinite(cols).all()):
        return None
    return work, sweeps


def _positive_kernel(
    work: np.ndarray, max_iter: int, tol: float, row_target: float, col_target: float
) -> tuple[int, bool]:
    """:func:`_positive_sweeps` as one compiled loop, in place: the same sums (rows pairwise as
    numpy, columns row after row as numpy), reciprocals and products in the same order.
    Returns (sweeps, whether every sum stayed finite)."""
    size_r, size_c = work.shape
    rows = np.empty(size_r)
    cols = np.empty(size_c)
    sweeps = 0
    for sweep in range(1, max_iter + 1):
        sweeps = sweep
        for r in range(size_r):
            rows[r] = row_sum_jit(work[r], size_c)
        if sweep > 1:
            hi, lo, nan = rows[0], rows[0], False
            for r in range(size_r):
                v = rows[r]
                if v != v:
                    nan = True
                hi = max(hi, v)
                lo = min(lo, v)
            if not nan and hi - row_target <= tol and row_target - lo <= tol:
                sweeps = sweep - 1
                break
        for r in range(size_r):
            rows[r] = row_target / rows[r]
            for c in range(size_c):
                work[r, c] = work[r, c] * rows[r]
        for c in range(size_c):
            cols[c] = work[0, c]
        for r in range(1, size_r):
            for c in range(size_c):
                cols[c] += work[r, c]
        for c in range(size_c):
            cols[c] = col_target / cols[c]
        for r in range(size_r):
            for c in range(size_c):
                work[r, c] = work[r, c] * cols[c]
    finite = bool(np.isfinite(rows).all() and np.isfinite(cols).all())
    return sweeps, finite


_positive_kernel_jit = njit(_positive_kernel) if row_sum_jit is not None else None


def positive_sweeps(
    work: np.ndarray, max_iter: int, tol: float, row_target: float, col_target: float
) -> tuple[np.ndarray, int] | None:
    """:func:`_positive_sweeps`, compiled when numba is available (:mod:`matchers.core.jit`) and the
    matrix is C-contiguous float64 with 2 to 128 columns (numpy sums a single column, and rows
    longer than 128, differently); bit-identical either way."""
    if _positive_kernel_jit is None or not reproducible(work):
        return _positive_sweeps(work, max_iter, tol, row_target, col_target)
    sweeps, finite = _positive_kernel_jit(work, max_iter, float(tol), row_target, col_target)
    return (work, sweeps) if finite else None
