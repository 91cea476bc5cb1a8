"""Scores of a multi-way matching (one snapshot's N views) against the true objects.

Per snapshot, :func:`multiway_counts` counts; :func:`summarise_counts` pools them:

* **pairwise precision / recall / F1, pooled**: over every pair of views (i < j) of every
  snapshot, declared pairs that join detections of one object (true positives) over all declared
  pairs (precision) and over all pairs of detections of one object (recall); F1 of the two.
* **cycle-consistency violation rate**: over every ordered triple of distinct views (i, j, k) and
  every detection a of view i with a composed match i -> j -> k (a matched to b in j, b matched
  to c in k), the share whose direct match i -> k is not c (unmatched included). A fused result
  has none by construction, so for fused outputs it is an invariant to check (the multi-agent
  study reports it as one), not a figure of merit; only ``independent``'s raw pairs can break it.
* **count error**: |objects estimated - objects present| / objects present per snapshot (the
  objects present: distinct true objects among the views' detections), averaged over snapshots
  (:func:`count_errors` per snapshot). ``independent``'s objects are those of the fusions'
  clustering rule (:mod:`matchers.fusion.independent`).
* **universe clustering precision / recall**: over pairs of detections in different views, those
  in one estimated object that are one true object, over all in one estimated object
  (precision) and over all of one true object (recall).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import astuple, dataclass

import numpy as np

from matchers.fusion import Universe


@dataclass(frozen=True)
class MultiwayCounts:
    """One snapshot's counts (module docstring)."""

    true_positives: int
    declared: int
    true_pairs: int
    chains: int
    violations: int
    objects_estimated: int
    objects_present: int
    cluster_both: int
    cluster_estimated: int
    cluster_true: int


def _pairs_within(labels: np.ndarray, views: np.ndarray) -> int:
    """Pairs of rows with the same label, in different views."""
    labels, views = np.asarray(labels, dtype=np.int64), np.asarray(views, dtype=np.int64)
    if not labels.size:
        return 0
    _, per_label = np.unique(labels, return_counts=True)
    # (label, view) as one integer: a 1-D unique, far cheaper than a unique over rows
    combined = (labels - labels.min()) * (int(views.max()) + 1) + views
    _, per_label_view = np.unique(combined, return_counts=True)
    same = (per_label * (per_label - 1) // 2).sum()
    same_view = (per_label_view * (per_label_view - 1) // 2).sum()
    return int(same - same_view)


def _match_map(universe: Universe, i: int, j: int, n_i: int) -> np.ndarray:
    """Row of view j matched to each row of view i (-1: none), from either orientation."""
    out = np.full(n_i, -1, dtype=np.int64)
    if i < j:
        pairs = universe.pairs.get((i, j), np.empty((0, 2), np.int64))
        out[pairs[:, 0]] = pairs[:, 1]
    else:
        pairs = universe.pairs.get((j, i), np.empty((0, 2), np.int64))
        out[pairs[:, 1]] = pairs[:, 0]
    return out


def multiway_counts(universe: Universe, truth: Sequence[np.ndarray]) -> MultiwayCounts:
    """The counts of ``universe`` against ``truth``: per view, the true object of each detection
    (integers; the same number in two views is the same object)."""
    truth = [np.asarray(t, dtype=np.int64) for t in truth]
    sizes = [len(t) for t in truth]
    if [len(lab) for lab in universe.labels] != sizes:
        raise ValueError("universe and truth disagree on the views' sizes")
    n_views = len(truth)
    tp = declared = true_pairs = 0
    for i in range(n_views):
        for j in range(i + 1, n_views):
            pairs = universe.pairs.get((i, j), np.empty((0, 2), np.int64))
            declared += len(pairs)
            tp += int(np.count_nonzero(truth[i][pairs[:, 0]] == truth[j][pairs[:, 1]]))
            true_pairs += len(np.intersect1d(truth[i], truth[j]))
    maps = {
        (i, j): _match_map(universe, i, j, sizes[i])
        for i in range(n_views)
        for j in range(n_views)
        if i != j
    }
    chains = violations = 0
    for i in range(n_views):
        for j in range(n_views):
            for k in range(n_views):
                if len({i, j, k}) < 3:
                    continue
                via = maps[(i, j)]
                ok = via >= 0
                composed = np.full(sizes[i], -1, dtype=np.int64)
                composed[ok] = maps[(j, k)][via[ok]]
                chained = composed >= 0
                chains += int(chained.sum())
                violations += int(np.count_nonzero(maps[(i, k)][chained] != composed[chained]))
    flat_truth = np.concatenate(truth) if truth else np.empty(0, np.int64)
    flat_est = np.concatenate(universe.labels) if truth else np.empty(0, np.int64)
    views = np.repeat(np.arange(n_views), sizes)
    both = _pairs_within(
        flat_est * (flat_truth.max() + 1 if flat_truth.size else 1) + flat_truth, views
    )
    return MultiwayCounts(
        tp,
        declared,
        true_pairs,
        chains,
        violations,
        int(universe.count),
        int(len(np.unique(flat_truth))),
        both,
        _pairs_within(flat_est, views),
        _pairs_within(flat_truth, views),
    )


def count_errors(estimated, present) -> np.ndarray:
    """Per snapshot, |objects estimated - objects present| / objects present; NaN where no
    object is present (such a snapshot does not enter the mean)."""
    estimated = np.asarray(estimated, dtype=float)
    present = np.asarray(present, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(present > 0, np.abs(estimated - present) / present, np.nan)


def _ratio(num: float, den: float, empty: float) -> float:
    return float(num / den) if den > 0 else empty


def summarise_counts(counts: Sequence[MultiwayCounts]) -> dict[str, float]:
    """Pooled metrics (module docstring) of several snapshots' counts; fractions in [0, 1]. An
    empty denominator gives precision 1 (nothing declared, nothing wrong), recall 1 (nothing to
    find), violation rate 0 (no chain to break)."""
    totals = np.array([astuple(c) for c in counts], dtype=float).reshape(-1, 10).sum(axis=0)
    tp, declared, true_pairs, chains, violations = totals[:5]
    precision = _ratio(tp, declared, 1.0)
    recall = _ratio(tp, true_pairs, 1.0)
    f1 = _ratio(2 * precision * recall, precision + recall, 0.0)
    errors = count_errors(
        [c.objects_estimated for c in counts], [c.objects_present for c in counts]
    )
    errors = errors[np.isfinite(errors)]
    return {
        "precision_pooled": precision,
        "recall_pooled": recall,
        "f1_pooled": f1,
        "cycle_violation_rate": _ratio(violations, chains, 0.0),
        "count_error": float(np.mean(errors)) if len(errors) else 0.0,
        "cluster_precision": _ratio(totals[7], totals[8], 1.0),
        "cluster_recall": _ratio(totals[7], totals[9], 1.0),
    }
