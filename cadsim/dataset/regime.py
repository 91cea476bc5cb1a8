"""The regime card of a frame-pair dataset: how many objects each view holds, how many of them the
two views share, how informative appearance is and how well the views' geometry agrees.

DESIGN §3 asks every table to carry it, because a matcher's scores depend on the regime as much as
on the matcher (accuracy rewards abstention in proportion to the non-covisible share). One
function, :func:`dataset_regime`, used by ``cadsim info --json`` and by the evaluation's
``results/regime.csv``. Imports nothing beyond numpy and scipy; works on any sequence of frame
pairs that has ``view1``/``view2`` (``positions``, ``features``), ``gt_pairs`` and, for the
position error, ``camera_to_world`` (None where a record has no true poses).
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
from scipy.stats import rankdata

from cadsim import portable_math as pm
from cadsim.dataset.cues import CAMERA_CUES

REGIME_KEYS = (
    "objects_per_view",
    "covisible",
    "noncovisible_share",
    "covisible_share_of_smaller",
    "appearance_auc",
    "image_auc",
    "same_class_auc",
    "position_error_median_m",
)
IMAGE_BLOCKS = ("hog", "color")
"""The blocks of our feature layout that describe the image alone (no class, no size)."""


def cosine_similarity(f1: np.ndarray, f2: np.ndarray) -> np.ndarray:
    """(n, m) cosine similarity of the rows of ``f1`` (n, d) and ``f2`` (m, d), clipped to [0, 1];
    a zero row has similarity 0 with everything (as ``matchers.blocks.appearance_similarity``)."""
    a = np.asarray(f1, float)
    b = np.asarray(f2, float)
    if a.size == 0 or b.size == 0:
        return np.zeros((len(a), len(b)))
    na = np.linalg.norm(a, axis=1, keepdims=True)
    nb = np.linalg.norm(b, axis=1, keepdims=True)
    a = np.divide(a, na, out=np.zeros_like(a), where=na > 0)
    b = np.divide(b, nb, out=np.zeros_like(b), where=nb > 0)
    return np.clip(a @ b.T, 0.0, 1.0)


def roc_auc(positive: np.ndarray, negative: np.ndarray) -> float | None:
    """Probability that a positive score exceeds a negative one (ties count one half): the area
    under the ROC curve, by the Mann–Whitney rank sum. None when either class is empty."""
    pos = np.asarray(positive, float).ravel()
    neg = np.asarray(negative, float).ravel()
    if not pos.size or not neg.size:
        return None
    ranks = rankdata(np.concatenate([pos, neg]))
    u = ranks[: pos.size].sum() - pos.size * (pos.size + 1) / 2.0
    return float(u / (pos.size * neg.size))


def _position_errors(pair, gt: np.ndarray) -> np.ndarray | None:
    """3-D distances (metres) between the two views' positions of each covisible object, both
    taken to the world frame through the views' true camera poses; None without true poses."""
    poses = getattr(pair, "camera_to_world", None)
    if poses is None:
        return None
    if not len(gt):
        return np.zeros(0)
    t1, t2 = (np.asarray(t, float) for t in poses)
    p1 = pm.matmul(pair.view1.positions[gt[:, 0]], t1[:3, :3].T) + t1[:3, 3]
    p2 = pm.matmul(pair.view2.positions[gt[:, 1]], t2[:3, :3].T) + t2[:3, 3]
    return np.linalg.norm(p1 - p2, axis=1)


def image_similarity(f1: np.ndarray, f2: np.ndarray) -> np.ndarray:
    """(n, m) similarity of the image part of two views' features: for our layout
    (``cadsim.sensing.features``) the mean of the HOG and colour blocks' cosines — what an
    external image descriptor such as the DMGM pairs' HOG-like one measures, without the
    detector's class and size; for any other width (imported descriptors carry no attribute
    block) the cosine of the whole vector."""
    from cadsim.sensing.features import FEATURE_DIM, FEATURE_LAYOUT

    f1, f2 = np.asarray(f1, float), np.asarray(f2, float)
    if f1.ndim != 2 or f1.shape[1] != FEATURE_DIM or f2.shape[1:] != (FEATURE_DIM,):
        return cosine_similarity(f1, f2)
    blocks = [FEATURE_LAYOUT[name] for name in IMAGE_BLOCKS]
    return np.mean([cosine_similarity(f1[:, b], f2[:, b]) for b in blocks], axis=0)


def dataset_regime(dataset: Iterable) -> dict:
    """The regime card of ``dataset`` (a ``cadsim.dataset.Dataset`` or any iterable of frame
    pairs), a dict with the keys of ``REGIME_KEYS`` plus ``pairs``:

    - ``objects_per_view``: mean detections per view, over both views of every pair;
    - ``covisible``: mean ground-truth correspondences per pair;
    - ``noncovisible_share``: non-covisible detections / all detections, both views, pooled;
    - ``covisible_share_of_smaller``: mean over pairs of covisible / min(n1, n2);
    - ``appearance_auc``: ROC AUC of the features' cosine similarity for true vs false candidate
      pairs (every (i, j) of every pair, pooled; 0.5 = appearance carries no information);
    - ``image_auc``: the same for the image part alone (:func:`image_similarity`: HOG and colour,
      without the detector's class and size — comparable with an external image descriptor);
    - ``same_class_auc``: ``appearance_auc`` against only the false pairs whose two detections
      have the same *true* class (a statistic, never a matcher's input): how much appearance
      tells apart look-alikes, whatever the scene's class mix (the pooled AUC is high wherever
      most false pairs cross classes — a car against a sign — as on CAD-V2X; DMGM's false pairs
      are mostly one class);
    - ``position_error_median_m``: median 3-D distance (metres) between the two views' positions
      of a covisible object after both are taken to the world frame with the true camera poses;
      None when a pair has no true poses.

    Beside them ``cues``: what the detections carry (comma-separated) for matchers (``cadsim.dataset.cues``; the
    first pair's, camera cues for pairs without a record) — box-only data has no pixels and
    its "appearance" is the box size, so its AUCs measure how well size tells objects apart.

    Every value is None for an empty dataset. Example::

        from cadsim.dataset import Dataset
        from cadsim.dataset.regime import dataset_regime
        dataset_regime(Dataset("data/cad"))["covisible_share_of_smaller"]
    """
    sizes, covisible, shares, true_sim, false_sim, errors = [], [], [], [], [], []
    true_image, false_image, same_class = [], [], []
    poses_known = True
    cues = None
    for pair in dataset:
        if cues is None:
            cues = ", ".join(getattr(pair, "cues", None) or CAMERA_CUES)
        gt = np.asarray(pair.gt_pairs, dtype=np.int64).reshape(-1, 2)
        n1, n2 = len(pair.view1.positions), len(pair.view2.positions)
        sizes += [n1, n2]
        covisible.append(len(gt))
        if min(n1, n2) > 0:
            shares.append(len(gt) / min(n1, n2))
        sim = cosine_similarity(pair.view1.features, pair.view2.features)
        is_true = np.zeros(sim.shape, dtype=bool)
        is_true[gt[:, 0], gt[:, 1]] = True
        true_sim.append(sim[is_true])
        false_sim.append(sim[~is_true])
        c1 = np.asarray(pair.view1.true_classes, dtype=object)
        c2 = np.asarray(pair.view2.true_classes, dtype=object)
        alike = (c1[:, None] == c2[None, :]) & ~is_true if sim.size else is_true
        same_class.append(sim[alike])
        image = image_similarity(pair.view1.features, pair.view2.features)
        true_image.append(image[is_true])
        false_image.append(image[~is_true])
        if poses_known:
            err = _position_errors(pair, gt)
            poses_known = err is not None
            if poses_known:
                errors.append(err)
    if not covisible:
        return {"pairs": 0} | dict.fromkeys(REGIME_KEYS) | {"cues": None}
    total = float(sum(sizes))
    all_errors = np.concatenate(errors) if poses_known and errors else np.zeros(0)
    return {
        "pairs": len(covisible),
        "objects_per_view": float(np.mean(sizes)),
        "covisible": float(np.mean(covisible)),
        "noncovisible_share": (total - 2.0 * sum(covisible)) / total if total else None,
        "covisible_share_of_smaller": float(np.mean(shares)) if shares else None,
        "appearance_auc": roc_auc(np.concatenate(true_sim), np.concatenate(false_sim)),
        "image_auc": roc_auc(np.concatenate(true_image), np.concatenate(false_image)),
        "same_class_auc": roc_auc(np.concatenate(true_sim), np.concatenate(same_class)),
        "position_error_median_m": float(np.median(all_errors)) if all_errors.size else None,
        "cues": cues,
    }


__all__ = ["REGIME_KEYS", "cosine_similarity", "dataset_regime", "image_similarity", "roc_auc"]
