"""First-order (appearance) similarity b_ij between the objects of the two views (paper §III-B.1)."""

from __future__ import annotations

import numpy as np

from matchers.core.problem import Problem


def appearance_similarity(problem: Problem) -> np.ndarray:
    """(n, m) cosine similarity of features1[i] and features2[j], clipped to [0, 1].

    No features (``features1 is None``) means uniform appearance: every entry is 1. A pair in
    which either feature row is all zeros has no appearance evidence and gets 0 (the convention of
    normalising a zero vector to zero, as scikit-learn's ``cosine_similarity`` does). Negative
    cosines (features that can be negative) are clipped to 0.
    """
    n, m = problem.n1, problem.n2
    if problem.features1 is None or n == 0 or m == 0:
        return np.ones((n, m))
    f1 = _unit_rows(problem.features1)
    f2 = _unit_rows(problem.features2)
    return np.clip(f1 @ f2.T, 0.0, 1.0)


def _unit_rows(features: np.ndarray) -> np.ndarray:
    """Rows scaled to unit length; all-zero rows stay zero. Each row is first divided by its
    largest magnitude, so rows with huge (1e200) or tiny (1e-200) entries neither overflow nor
    underflow the norm."""
    peak = np.abs(features).max(axis=1, keepdims=True)
    scaled = np.divide(features, peak, out=np.zeros_like(features), where=peak > 0)
    norms = np.linalg.norm(scaled, axis=1, keepdims=True)
    return np.divide(scaled, norms, out=np.zeros_like(scaled), where=norms > 0)
