"""Bistochastic (Sinkhorn) normalisation with slack rows/columns for rectangular matrices."""

from __future__ import annotations

import numpy as np


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
