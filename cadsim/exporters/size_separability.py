"""How well box sizes alone tell true from false candidate pairs: the size-only AUC of what the
exporters write (:mod:`cadsim.exporters.view_boxes`), the leak check for per-object sizes
(docs/dataset.md, "Sizes in exported boxes").

Score of a candidate pair (i in view 1, j in view 2): −Σ_d |log s1[i, d] − log s2[j, d]| over
length, width and height (metres) — the closer two boxes' sizes in ratio, the higher. The AUC is
the probability that a true pair (the record's ground truth) scores above a false one (every
other (i, j) of the same record), pooled over the records; 0.5 is chance, 1 is a size that names
its object. Frame-pair datasets only (an N-view dataset: its (1, 2) pairs).
"""

from __future__ import annotations

import numpy as np

from cadsim import portable_math as pm
from cadsim.dataset.regime import roc_auc
from cadsim.exporters.view_boxes import snapshot_views


def size_similarity(sizes1: np.ndarray, sizes2: np.ndarray) -> np.ndarray:
    """(n, m) scores of (n, 3) against (m, 3) sizes in metres (module docstring)."""
    a = pm.log(np.maximum(np.asarray(sizes1, dtype=float).reshape(-1, 3), 1e-3))
    b = pm.log(np.maximum(np.asarray(sizes2, dtype=float).reshape(-1, 3), 1e-3))
    return -np.abs(a[:, None, :] - b[None, :, :]).sum(axis=2)


def size_pair_scores(dataset) -> tuple[np.ndarray, np.ndarray]:
    """(true-pair scores, false-pair scores) over every record of ``dataset``."""
    true, false = [], []
    for k in range(len(dataset)):
        views = snapshot_views(dataset, k)
        pair = dataset[k] if dataset.n_views == 2 else dataset.snapshot(k).pair(1, 2)
        score = size_similarity(views[0].sizes, views[1].sizes)
        is_true = np.zeros(score.shape, dtype=bool)
        gt = np.asarray(pair.gt_pairs, dtype=np.int64).reshape(-1, 2)
        is_true[gt[:, 0], gt[:, 1]] = True
        true.append(score[is_true])
        false.append(score[~is_true])
    if not true:
        return np.zeros(0), np.zeros(0)
    return np.concatenate(true), np.concatenate(false)


def size_only_auc(dataset) -> float | None:
    """The size-only AUC of ``dataset`` (module docstring); None without true or false pairs."""
    return roc_auc(*size_pair_scores(dataset))


__all__ = ["size_only_auc", "size_pair_scores", "size_similarity"]
