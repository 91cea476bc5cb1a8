"""The one discretisation every matcher shares: Hungarian assignment, then the acceptance threshold."""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import linear_sum_assignment


def discretise(scores: np.ndarray, threshold: float | None = None) -> np.ndarray:
    """(k, 2) int array of matched (i, j) pairs from an (n, m) score matrix.

    Hungarian assignment maximising the total score (scipy ``linear_sum_assignment``); it has
    min(n, m) pairs. With ``threshold=None`` all of them are returned; with a number tau, pairs
    whose score is below tau are dropped (partial matching: the dropped objects are declared
    non-covisible). Pairs are sorted by i.
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
    safe = np.nan_to_num(scores, nan=0.0, posinf=0.0, neginf=0.0)
    rows, cols = linear_sum_assignment(safe, maximize=True)
    if threshold is not None:
        keep = safe[rows, cols] >= threshold
        rows, cols = rows[keep], cols[keep]
    return np.stack([rows, cols], axis=1).astype(np.int64)
