"""An episode-bootstrap interval for a pooled ROC AUC.

The AUC pools every candidate pair of a dataset (true pairs against false ones), but candidate
pairs of one simulation episode share their scene, light and objects, so they are not
independent. Each resample draws the *episodes* with replacement and recomputes the pooled AUC
(Mann–Whitney, ties counted one half) over the drawn episodes' candidates; the interval is the
2.5 and 97.5 percentiles. Vectorised: for every positive score and episode, the (tie-halved)
count of that episode's negatives below it is computed once; a resample is then a weighting of
episodes.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def episode_auc_interval(
    positives: Sequence[np.ndarray],
    negatives: Sequence[np.ndarray],
    resamples: int = 2000,
    seed: int = 0,
    level: float = 0.95,
) -> tuple[float, float, float]:
    """(AUC, low, high) of positive against negative scores, ``positives[e]`` and
    ``negatives[e]`` being episode e's; (nan, nan, nan) when either class is empty and nan
    bounds with fewer than two episodes."""
    pos = [np.asarray(p, float).ravel() for p in positives]
    neg = [np.sort(np.asarray(n, float).ravel()) for n in negatives]
    if len(pos) != len(neg):
        raise ValueError(f"{len(pos)} episodes of positives against {len(neg)} of negatives")
    scores = np.concatenate(pos) if pos else np.zeros(0)
    owner = np.repeat(np.arange(len(pos)), [len(p) for p in pos])
    n_neg = np.array([len(n) for n in neg], float)
    if not scores.size or not n_neg.sum():
        return (float("nan"),) * 3
    below = np.stack(
        [
            np.searchsorted(n, scores, "left") + 0.5 * (np.searchsorted(n, scores, "right")
                                                       - np.searchsorted(n, scores, "left"))
            for n in neg
        ]
    )  # (episodes, positives)  # fmt: skip

    def auc(weights: np.ndarray) -> np.ndarray:
        """AUC for each row of episode ``weights`` (resamples, episodes)."""
        u = ((weights @ below) * weights[:, owner]).sum(axis=1)
        count = weights[:, owner].sum(axis=1) * (weights @ n_neg)
        with np.errstate(invalid="ignore", divide="ignore"):
            return u / count

    point = float(auc(np.ones((1, len(pos))))[0])
    if len(pos) < 2:
        return point, float("nan"), float("nan")
    draws = np.random.default_rng(seed).integers(0, len(pos), size=(resamples, len(pos)))
    weights = np.zeros((resamples, len(pos)))
    np.add.at(weights, (np.arange(resamples)[:, None], draws), 1.0)
    values = auc(weights)
    tail = 100 * (1 - level) / 2
    low, high = np.nanpercentile(values, [tail, 100 - tail])
    return point, float(low), float(high)
