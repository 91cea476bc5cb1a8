"""Correspondence-identification metrics (DESIGN §3) — the one canonical implementation.

G = ground-truth covisible pairs, M = predicted pairs, TP = |M ∩ G|; all pairs are (i, j) with i
indexing view 1 (n objects) and j indexing view 2 (m objects).

- precision = TP / |M|; 1 when |M| = 0 = |G|, 0 when |M| = 0 < |G|.
- recall = TP / |G|; 1 when |G| = 0 (nothing to retrieve, nothing missed).
- accuracy = fraction of the n + m objects whose decision is right: a covisible object matched to
  its true partner, or a non-covisible object left unmatched; 1 when n + m = 0. It rewards
  abstention in proportion to the non-covisible share: declaring nothing scores that share.
- balanced accuracy = ½ · (share of the 2|G| covisible objects of both views matched to their true
  partner, which equals recall, + share of the n + m − 2|G| non-covisible objects left unmatched).
  A pair with only one of the two classes takes that class's share alone; 1 when n + m = 0.
  Declaring nothing scores exactly ½ and a perfect matching 1, whatever the non-covisible share.
- F1 = 2PR / (P + R), 0 when P + R = 0.

Per frame pair first, then as the paper aggregates: per-run mean over frame pairs, then mean ± std
over runs (:func:`summarise_runs`). Pooled over a run's frame pairs instead (DMGM's aggregation,
:func:`summarise_pooled`): precision_pooled = ΣTP/Σ|M|, recall_pooled = ΣTP/Σ|G|, f1_pooled their
harmonic mean, then mean ± std over runs; pairs with many objects weigh more.

Threshold sweeps: a matcher's full Hungarian assignment with its scores is ranked once; keeping
the pairs with score ≥ τ gives the prediction at τ. :func:`metrics_at_thresholds` evaluates every
frame pair at many τ at once, :func:`pooled_pr_curve` gives the threshold-free view (all frame pairs
of a run pooled) and :func:`average_precision` its area.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from eval.core.cache_checks import first_not_one_to_one

METRICS = ("accuracy", "balanced_accuracy", "precision", "recall", "f1")


def _pairs_array(name: str, pairs, n1: int, n2: int) -> np.ndarray:
    """Validate a (k, 2) one-to-one index array against view sizes n1, n2."""
    arr = np.asarray(pairs)
    if arr.size == 0:
        return np.zeros((0, 2), dtype=np.int64)
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise ValueError(
            f"{name}: expected a (k, 2) array of (i, j) indices, got shape {arr.shape}"
        )
    if not np.issubdtype(arr.dtype, np.integer):
        if not np.all(np.equal(np.mod(arr, 1), 0)):
            raise ValueError(f"{name}: indices must be integers")
    arr = arr.astype(np.int64)
    if arr.min(initial=0) < 0 or arr[:, 0].max() >= n1 or arr[:, 1].max() >= n2:
        raise ValueError(f"{name}: index out of range for views of {n1} and {n2} objects")
    if np.bincount(arr[:, 0]).max() > 1 or np.bincount(arr[:, 1]).max() > 1:
        raise ValueError(f"{name}: not one-to-one (an object index repeats)")
    return arr


def _partner(gt: np.ndarray, n1: int) -> np.ndarray:
    """(n1,) view-2 partner of each view-1 object under the one-to-one pairs `gt`, -1 for none."""
    partner = np.full(n1, -1, dtype=np.int64)
    partner[gt[:, 0]] = gt[:, 1]
    return partner


def _covered(n: int, *indices: np.ndarray) -> np.ndarray:
    """(n,) bool: the objects named in any of `indices`."""
    mask = np.zeros(n, dtype=bool)
    for idx in indices:
        mask[idx] = True
    return mask


def _precision(tp, n_pred, n_gt):
    """Vectorised precision with the DESIGN §3 conventions for |M| = 0."""
    tp, n_pred, n_gt = np.broadcast_arrays(
        *(np.asarray(a, dtype=float) for a in (tp, n_pred, n_gt))
    )
    empty = np.where(n_gt == 0, 1.0, 0.0)
    return np.where(n_pred > 0, tp / np.maximum(n_pred, 1), empty)


def _recall(tp, n_gt):
    tp, n_gt = np.broadcast_arrays(np.asarray(tp, dtype=float), np.asarray(n_gt, dtype=float))
    return np.where(n_gt > 0, tp / np.maximum(n_gt, 1), 1.0)


def _f1(precision, recall):
    total = precision + recall
    return np.where(total > 0, 2 * precision * recall / np.where(total > 0, total, 1), 0.0)


def _balanced_accuracy(tp, n_gt, negatives_right, n_negatives):
    """Mean of the covisible share (TP / |G|, the recall) and the non-covisible share
    (negatives_right / n_negatives) over the classes a pair has; 1 when it has neither."""
    tp, n_gt, right, n_neg = np.broadcast_arrays(
        *(np.asarray(a, dtype=float) for a in (tp, n_gt, negatives_right, n_negatives))
    )
    has_pos, has_neg = n_gt > 0, n_neg > 0
    positive = np.where(has_pos, tp / np.maximum(n_gt, 1), 0.0)
    negative = np.where(has_neg, right / np.maximum(n_neg, 1), 0.0)
    classes = has_pos.astype(float) + has_neg
    return np.where(classes > 0, (positive + negative) / np.maximum(classes, 1), 1.0)


def _accuracy(correct, n_objects):
    correct, n_objects = np.broadcast_arrays(
        np.asarray(correct, dtype=float), np.asarray(n_objects, dtype=float)
    )
    return np.where(n_objects > 0, correct / np.maximum(n_objects, 1), 1.0)


@dataclass(frozen=True)
class PairMetrics:
    """Metrics of one frame pair. Counts: n1, n2 objects per view; n_gt = |G|, n_pred = |M|,
    tp = |M ∩ G|, correct = objects (of both views) whose decision is right. Rates in [0, 1]."""

    n1: int
    n2: int
    n_gt: int
    n_pred: int
    tp: int
    correct: int
    accuracy: float
    balanced_accuracy: float
    precision: float
    recall: float
    f1: float


def pair_metrics(predicted, ground_truth, n1: int, n2: int) -> PairMetrics:
    """Metrics of predicted pairs M against ground-truth pairs G for views of n1 and n2 objects.

    predicted, ground_truth: (k, 2) integer arrays of (i, j) pairs, each one-to-one.
    """
    pred = _pairs_array("predicted", predicted, n1, n2)
    gt = _pairs_array("ground_truth", ground_truth, n1, n2)
    tp = int(np.count_nonzero(_partner(gt, n1)[pred[:, 0]] == pred[:, 1]))
    # Objects decided right: 2 per true positive, plus non-covisible objects left unmatched.
    unmatched_negative1 = n1 - int(np.count_nonzero(_covered(n1, pred[:, 0], gt[:, 0])))
    unmatched_negative2 = n2 - int(np.count_nonzero(_covered(n2, pred[:, 1], gt[:, 1])))
    correct = 2 * tp + unmatched_negative1 + unmatched_negative2
    negatives = n1 + n2 - 2 * len(gt)
    # the vectorised conventions above, for one pair in plain floats (the same operations in
    # the same order, so the same bits; a tenth of the time, which re-scoring cached runs feels)
    n_gt, n_pred, right = len(gt), len(pred), unmatched_negative1 + unmatched_negative2
    precision = tp / n_pred if n_pred > 0 else (1.0 if n_gt == 0 else 0.0)
    recall = tp / n_gt if n_gt > 0 else 1.0
    total = precision + recall
    positive = tp / n_gt if n_gt > 0 else 0.0
    negative = right / negatives if negatives > 0 else 0.0
    classes = float(n_gt > 0) + float(negatives > 0)
    return PairMetrics(
        n1=int(n1),
        n2=int(n2),
        n_gt=n_gt,
        n_pred=n_pred,
        tp=int(tp),
        correct=int(correct),
        accuracy=correct / (n1 + n2) if n1 + n2 > 0 else 1.0,
        balanced_accuracy=(positive + negative) / classes if classes > 0 else 1.0,
        precision=float(precision),
        recall=float(recall),
        f1=2 * precision * recall / total if total > 0 else 0.0,
    )


@dataclass(frozen=True)
class RankedAssignments:
    """Hungarian assignments of many frame pairs, flattened for threshold sweeps.

    Per assigned pair e (E in all): frame (index of its frame pair, 0..P-1), score, correct (it is
    a ground-truth pair), cov1/cov2 (its view-1 / view-2 object is covisible). Per frame pair:
    n1, n2, n_gt.
    """

    frame: np.ndarray
    score: np.ndarray
    correct: np.ndarray
    cov1: np.ndarray
    cov2: np.ndarray
    n1: np.ndarray
    n2: np.ndarray
    n_gt: np.ndarray

    @property
    def n_frames(self) -> int:
        return len(self.n1)

    @classmethod
    def from_frames(cls, frames: Sequence[tuple]) -> RankedAssignments:
        """frames: (assigned (k, 2), assigned_scores (k,), ground_truth (g, 2), n1, n2) per pair.
        Every frame is checked as :func:`pair_metrics` checks it (ValueError naming the first
        frame at fault); the common case — integer (k, 2) arrays — in one vectorised pass."""
        frames = list(frames)
        fast = _from_integer_frames(frames)
        if fast is not None:
            return cls(**fast)
        parts = {k: [] for k in ("frame", "score", "correct", "cov1", "cov2")}
        n1s, n2s, n_gts = [], [], []
        for f, (assigned, scores, gt, n1, n2) in enumerate(frames):
            a = _pairs_array(f"assigned[{f}]", assigned, n1, n2)
            g = _pairs_array(f"ground_truth[{f}]", gt, n1, n2)
            s = np.asarray(scores, dtype=float).reshape(-1)
            if len(s) != len(a):
                raise ValueError(f"assigned_scores[{f}]: {len(s)} scores for {len(a)} pairs")
            partner = _partner(g, n1)[a[:, 0]]
            parts["frame"].append(np.full(len(a), f, dtype=np.int64))
            parts["score"].append(s)
            parts["correct"].append(partner == a[:, 1])
            parts["cov1"].append(partner >= 0)
            parts["cov2"].append(_covered(n2, g[:, 1])[a[:, 1]])
            n1s.append(n1)
            n2s.append(n2)
            n_gts.append(len(g))
        empty = {"frame": np.int64, "score": float, "correct": bool, "cov1": bool, "cov2": bool}
        flat = {
            k: np.concatenate(v) if v else np.zeros(0, dtype=empty[k]) for k, v in parts.items()
        }
        return cls(
            **flat,
            n1=np.asarray(n1s, dtype=np.int64),
            n2=np.asarray(n2s, dtype=np.int64),
            n_gt=np.asarray(n_gts, dtype=np.int64),
        )


def _integer_pairs(pairs) -> np.ndarray | None:
    """`pairs` as an (k, 2) int64 array when it is an integer (k, 2) array or empty; else None."""
    arr = np.asarray(pairs)
    if arr.size == 0:
        return np.zeros((0, 2), dtype=np.int64)
    if arr.ndim != 2 or arr.shape[1] != 2 or arr.dtype.kind not in "iu":
        return None
    return arr


def _from_integer_frames(frames: list[tuple]) -> dict | None:
    """:meth:`RankedAssignments.from_frames`' fields for frames whose arrays are all integer
    (k, 2) arrays inside their views, one-to-one, with a score per assigned pair, in one pass
    over all frames; None when some frame is not (the per-frame path then names it)."""
    assigned = [_integer_pairs(f[0]) for f in frames]
    truth = [_integer_pairs(f[2]) for f in frames]
    if any(a is None for a in assigned) or any(g is None for g in truth):
        return None
    scores = [np.asarray(f[1], dtype=float).reshape(-1) for f in frames]
    k_a = np.array([len(a) for a in assigned], dtype=np.int64)
    if any(len(s) != k for s, k in zip(scores, k_a, strict=True)):
        return None
    n1 = np.array([f[3] for f in frames], dtype=np.int64).reshape(-1)
    n2 = np.array([f[4] for f in frames], dtype=np.int64).reshape(-1)
    if (n1 < 0).any() or (n2 < 0).any():
        return None
    k_g = np.array([len(g) for g in truth], dtype=np.int64)
    frame_of = np.arange(len(frames), dtype=np.int64)
    fa, fg = np.repeat(frame_of, k_a), np.repeat(frame_of, k_g)
    a = np.concatenate([np.zeros((0, 2), np.int64), *assigned]).astype(np.int64, copy=False)
    g = np.concatenate([np.zeros((0, 2), np.int64), *truth]).astype(np.int64, copy=False)
    for pairs in (assigned, truth):  # inside the views, one-to-one: the cache's own check
        if first_not_one_to_one(pairs, n1, n2)[1] is not None:
            return None
    start1 = np.concatenate([[0], np.cumsum(n1)])[:-1]
    start2 = np.concatenate([[0], np.cumsum(n2)])[:-1]
    partner = np.full(int(n1.sum()), -1, dtype=np.int64)  # every frame's _partner, end to end
    partner[start1[fg] + g[:, 0]] = g[:, 1]
    covered2 = np.zeros(int(n2.sum()), dtype=bool)  # every frame's _covered(n2, g[:, 1])
    covered2[start2[fg] + g[:, 1]] = True
    mate = partner[start1[fa] + a[:, 0]]
    return {
        "frame": fa,
        "score": np.concatenate([np.zeros(0), *scores]),
        "correct": mate == a[:, 1],
        "cov1": mate >= 0,
        "cov2": covered2[start2[fa] + a[:, 1]],
        "n1": n1,
        "n2": n2,
        "n_gt": k_g,
    }


def _kept_counts(ranked: RankedAssignments, weights: np.ndarray, thresholds: np.ndarray):
    """(P, T) sums of `weights` over the assigned pairs with score ≥ thresholds[t], per frame."""
    order = np.argsort(thresholds)
    sorted_t = thresholds[order]
    n_t = len(sorted_t)
    # Entry e is kept for every threshold ≤ its score: sorted indices 0 .. last[e].
    last = np.searchsorted(sorted_t, ranked.score, side="right") - 1
    hist = np.bincount(
        ranked.frame[last >= 0] * (n_t + 1) + last[last >= 0],
        weights=weights[last >= 0].astype(float),
        minlength=ranked.n_frames * (n_t + 1),
    ).reshape(ranked.n_frames, n_t + 1)[:, :n_t]
    counts = np.cumsum(hist[:, ::-1], axis=1)[:, ::-1]
    out = np.empty_like(counts)
    out[:, order] = counts
    return out


def metrics_at_thresholds(ranked: RankedAssignments, thresholds) -> dict[str, np.ndarray]:
    """Every frame pair's metrics when keeping the assigned pairs with score ≥ τ, for each τ.

    Returns (P, T) arrays keyed by every name of :data:`METRICS`, 'tp' and 'n_pred'.
    """
    t = np.asarray(thresholds, dtype=float).reshape(-1)
    n_pred = _kept_counts(ranked, np.ones_like(ranked.score), t)
    tp = _kept_counts(ranked, ranked.correct, t)
    kept_negative1 = _kept_counts(ranked, ~ranked.cov1, t)
    kept_negative2 = _kept_counts(ranked, ~ranked.cov2, t)
    n1, n2, n_gt = (a[:, None].astype(float) for a in (ranked.n1, ranked.n2, ranked.n_gt))
    negatives_right = (n1 - n_gt - kept_negative1) + (n2 - n_gt - kept_negative2)
    correct = 2 * tp + negatives_right
    precision = _precision(tp, n_pred, n_gt)
    recall = _recall(tp, n_gt)
    return {
        "accuracy": _accuracy(correct, n1 + n2),
        "balanced_accuracy": _balanced_accuracy(tp, n_gt, negatives_right, n1 + n2 - 2 * n_gt),
        "precision": precision,
        "recall": recall,
        "f1": _f1(precision, recall),
        "tp": tp,
        "n_pred": n_pred,
    }


def candidate_thresholds(ranked: RankedAssignments) -> np.ndarray:
    """Every τ at which some prediction changes: the distinct assigned scores, descending, plus
    one above the maximum (nothing kept)."""
    scores = np.unique(ranked.score)[::-1]
    top = scores[0] + 1.0 if len(scores) else 1.0
    return np.concatenate([[top], scores])


@dataclass(frozen=True)
class PRCurve:
    """Pooled precision–recall curve: thresholds descending, with precision and recall of the
    pooled counts (ΣTP/Σ|M|, ΣTP/Σ|G| over the frame pairs) at each."""

    thresholds: np.ndarray
    precision: np.ndarray
    recall: np.ndarray


def pooled_pr_curve(ranked: RankedAssignments) -> PRCurve:
    """Precision–recall over τ with all frame pairs pooled; candidates are the Hungarian
    assignments' pairs, so a ground-truth pair the assignment misses is never retrieved."""
    thresholds = np.unique(ranked.score)[::-1]
    # Pairs kept at thresholds[t] are those with score ≥ thresholds[t].
    rank = np.searchsorted(-thresholds, -ranked.score, side="left")
    kept = np.cumsum(np.bincount(rank, minlength=len(thresholds)))
    tp = np.cumsum(
        np.bincount(rank, weights=ranked.correct.astype(float), minlength=len(thresholds))
    )
    total_gt = float(ranked.n_gt.sum())
    precision = tp / np.maximum(kept, 1)
    recall = tp / total_gt if total_gt > 0 else np.ones_like(tp)
    return PRCurve(thresholds=thresholds, precision=precision, recall=recall)


def average_precision(curve: PRCurve) -> float:
    """Area under the pooled PR curve as a step sum, Σ (R_k − R_{k−1}) · P_k (thresholds
    descending, R_0 = 0) — the definition scikit-learn uses. 0 when nothing can be retrieved."""
    if len(curve.recall) == 0:
        return 0.0
    delta = np.diff(np.concatenate([[0.0], curve.recall]))
    return float(np.sum(delta * curve.precision))


def summarise_runs(per_pair: pd.DataFrame, by: Sequence[str], run: str = "seed") -> pd.DataFrame:
    """Aggregate as the paper does: per-run mean over frame pairs, then mean and std over runs.

    per_pair: one row per (run, frame pair) with the `by` and `run` columns and metric columns
    (those of :data:`METRICS` it has; files written before a metric existed lack it). Returns one
    row per `by` group with `<metric>_mean`, `<metric>_std` (sample std over runs, ddof=1; 0 for
    a single run) and `runs`.
    """
    metrics = [m for m in METRICS if m in per_pair.columns]
    missing = [c for c in (*by, run) if c not in per_pair.columns] or ([] if metrics else METRICS)
    if missing:
        raise ValueError(f"per_pair: missing columns {list(missing)}")
    per_run = per_pair.groupby([*by, run], sort=False)[metrics].mean()
    grouped = per_run.groupby(level=list(range(len(by))), sort=False)
    mean = grouped.mean().add_suffix("_mean")
    std = grouped.std(ddof=1).fillna(0.0).add_suffix("_std")
    runs = grouped.size().rename("runs")
    out = pd.concat([mean, std, runs], axis=1).reset_index()
    return out[[*by, *(f"{m}_{s}" for m in metrics for s in ("mean", "std")), "runs"]]


POOLED = ("precision_pooled", "recall_pooled", "f1_pooled")


def summarise_pooled(per_pair: pd.DataFrame, by: Sequence[str], run: str = "seed") -> pd.DataFrame:
    """Pooled precision, recall and F1 per run (ΣTP/Σ|M|, ΣTP/Σ|G| over its frame pairs, the
    DESIGN §3 conventions for empty sums), then mean and std over runs (ddof=1; 0 for one run).

    per_pair: one row per (run, frame pair) with columns `by`, `run`, ``tp``, ``n_pred``,
    ``n_gt``. Returns one row per `by` group with ``<name>_mean``/``<name>_std`` for each name of
    :data:`POOLED`.
    """
    missing = [c for c in (*by, run, "tp", "n_pred", "n_gt") if c not in per_pair.columns]
    if missing:
        raise ValueError(f"per_pair: missing columns {missing}")
    sums = per_pair.groupby([*by, run], sort=False)[["tp", "n_pred", "n_gt"]].sum()
    precision = _precision(sums["tp"], sums["n_pred"], sums["n_gt"])
    recall = _recall(sums["tp"], sums["n_gt"])
    per_run = pd.DataFrame(
        {"precision_pooled": precision, "recall_pooled": recall},
        index=sums.index,
    )
    per_run["f1_pooled"] = _f1(precision, recall)
    grouped = per_run.groupby(level=list(range(len(by))), sort=False)
    mean = grouped.mean().add_suffix("_mean")
    std = grouped.std(ddof=1).fillna(0.0).add_suffix("_std")
    out = pd.concat([mean, std], axis=1).reset_index()
    return out[[*by, *(f"{m}_{s}" for m in POOLED for s in ("mean", "std"))]]
