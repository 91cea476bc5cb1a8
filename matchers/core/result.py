"""Turning a matcher's raw relaxed solution into the shared :class:`Matching` output."""

from __future__ import annotations

import time

import numpy as np

from matchers.core.discretise import canonical_scores, discretise
from matchers.core.matching import Matching


def max_normalised(x: np.ndarray, n: int, m: int) -> np.ndarray:
    """(n, m) scores in [0, 1]: the non-negative part of x divided by its maximum.

    The best candidate of a problem scores 1, so a threshold tau reads "keep pairs with at least
    tau times the support of the most confident pair". All-zero (or empty) x gives all-zero
    scores: no evidence, nothing passes a positive threshold. NaN/inf entries count as 0.
    """
    x = np.nan_to_num(np.asarray(x, dtype=float).reshape(n, m), nan=0.0, posinf=0.0, neginf=0.0)
    x = np.maximum(x, 0.0)
    top = x.max() if x.size else 0.0
    if not top > 0.0:
        return np.zeros((n, m))
    return np.clip(x / top, 0.0, 1.0)


def finish(
    name: str,
    scores: np.ndarray,
    threshold: float | None,
    started: float,
    iterations: int = 0,
    info: dict | None = None,
) -> Matching:
    """Discretise ``scores`` (already in [0, 1]) and wrap everything in a :class:`Matching`.

    ``started`` is the ``time.perf_counter()`` value taken when the matcher was called. A tensor
    search reused from another matcher (``info["tensor"]["reused_s"]``,
    :mod:`matchers.hypergraph.tensor_sharing`) is charged its time, as if done here.
    """
    scores = canonical_scores(scores)  # the same bits on every CPU (matchers.core.discretise)
    pairs = discretise(scores, threshold)
    tensor = (info or {}).get("tensor")
    charged = tensor.get("reused_s", 0.0) if isinstance(tensor, dict) else 0.0
    return Matching(
        pairs=pairs,
        scores=scores,
        name=name,
        iterations=int(iterations),
        time_s=time.perf_counter() - started + charged,
        info=dict(info or {}),
    )
