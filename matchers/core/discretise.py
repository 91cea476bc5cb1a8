"""The one discretisation every matcher shares: Hungarian assignment, then the acceptance threshold.

Scores are first put on a fixed grid (:func:`canonical_scores`): two scores that are equal in
exact arithmetic but were computed with different last bits (another CPU's SIMD ``exp``, another
summation order) become equal, so the Hungarian breaks the tie the same way on every machine
(``../shared/DESIGN.md`` §10) — a 2 × 2 block of scores 1.0 / 0.9999999999999987 otherwise picks
a different assignment on an AVX-512 CPU."""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import linear_sum_assignment

SCORE_GRID = (
    2.0**-40
)  # ≈ 9.1e-13: far above last-bit noise of scores in [0, 1], far below any real gap


def canonical_scores(scores: np.ndarray) -> np.ndarray:
    """`scores` rounded to the nearest multiple of :data:`SCORE_GRID` (a power of two, so the
    rounding is exact); nan and ±inf are kept. Idempotent."""
    scores = np.asarray(scores, dtype=float)
    with np.errstate(invalid="ignore"):
        out = np.rint(scores / SCORE_GRID) * SCORE_GRID
    return np.where(np.isfinite(scores), out, scores)


def hungarian(scores: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns of the assignment maximising the total canonical score (scipy's
    ``linear_sum_assignment``; non-finite scores count as 0)."""
    safe = np.nan_to_num(canonical_scores(scores), nan=0.0, posinf=0.0, neginf=0.0)
    return linear_sum_assignment(safe, maximize=True)


def discretise(scores: np.ndarray, threshold: float | None = None) -> np.ndarray:
    """(k, 2) int array of matched (i, j) pairs from an (n, m) score matrix.

    Hungarian assignment maximising the total canonical score (:func:`hungarian`); it has
    min(n, m) pairs. With ``threshold=None`` all of them are returned; with a number tau, pairs
    whose canonical score is below tau are dropped (partial matching: the dropped objects are
    declared non-covisible). Pairs are sorted by i.
    """
    scores = np.asarray(scores, dtype=float)
    if scores.ndim != 2:
        raise ValueError(f"scores: expected an (n, m) matrix, got shape {scores.shape}")
    if threshold is not None and (
        isinstance(threshold, bool)
        or not isinstance(threshold, int | float | np.number)
        or not math.isfinite(threshold)
    ):
        raise ValueError(f"threshold: expected None or a finite number, got {threshold!r}")
    if scores.size == 0:
        return np.zeros((0, 2), dtype=np.int64)
    rows, cols = hungarian(scores)
    if threshold is not None:
        safe = np.nan_to_num(canonical_scores(scores), nan=0.0, posinf=0.0, neginf=0.0)
        keep = safe[rows, cols] >= threshold
        rows, cols = rows[keep], cols[keep]
    return np.stack([rows, cols], axis=1).astype(np.int64)
