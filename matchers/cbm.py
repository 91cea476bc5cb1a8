"""``cbm``: context-based matching (CBM; Song et al., context-based object association for
cooperative perception, 2023), implemented from the paper's description, pose-free.

1. Local context of every object: the distances to its ``neighbours`` nearest objects in its own
   view (:func:`~matchers.blocks.local_context.context_similarity`); two objects' context
   similarity S_ij in [0, 1] is the share of their neighbour distances that agree within the
   tolerance eps.
2. Hypotheses: from each of the ``anchors`` pairs of largest S, the anchor's neighbours are
   paired by distance agreement (Hungarian on |d1_ik − d2_jl|, pairs within eps kept), and the
   rigid motion of view 2 into view 1 is fitted to the anchor and its paired neighbours
   (Kabsch, ≥ 3 pairs).
3. The largest consistent set: each hypothesis moves all of view 2 into view 1; its support is
   the number of one-to-one pairs (Hungarian on the residuals) within eps. The hypothesis with the
   most support wins (ties: the smaller summed residual, then anchor order).

Declared pairs: the shared Hungarian on exp(−r² / (2 eps²)) of the residual r under the winning
motion (on S / max S where no hypothesis could be fitted).

Scores (:func:`supported_scores`): a declared pair's score is the share of the winning
hypothesis's inliers (its support: the one-to-one pairs within eps) that agree with it — for each
other inlier (k, l), w = exp(−2 (Δ / eps)²) if Δ = |d1_ik − d2_jl| ≤ eps, else 0 (0 for an inlier
sharing exactly one object with it), averaged over the inliers other than the pair itself. The
true pairs agree with every true inlier (scores near 1); a pair of objects seen in one view only
agrees with them only by chance (near 0), so a threshold abstains. Fewer than 3 inliers (or no
motion): the other declared pairs are the reference instead. Every other entry scores 0, and a
declared pair with no support scores :data:`~matchers.core.discretise.SCORE_GRID` (2⁻⁴⁰), so the
Hungarian on the scores returns the same pairs; no evidence at all (all residual scores 0): all 0.

Variant ``cbm_pose``: what a connected vehicle adds — anchors ranked by S times the prior's
likelihood (:func:`~matchers.blocks.prior.prior_likelihood`), and the motion the two noisy poses
imply (each view's detections against its own prior world positions) as one more hypothesis.
"""

from __future__ import annotations

import time

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial.distance import cdist

from matchers.blocks.local_context import (
    NEIGHBOURS,
    alignment_scores,
    checked_tolerance,
    context_similarity,
    prior_motion,
    prior_weights,
    rigid_fit,
    top_candidates,
)
from matchers.blocks.memory_models import context_memory
from matchers.blocks.prior import PRIOR_FIELDS
from matchers.core.discretise import SCORE_GRID, canonical_scores, hungarian
from matchers.core.matching import Matching
from matchers.core.memory_budget import budgeted
from matchers.core.problem import Problem
from matchers.core.result import finish


def anchor_motion(
    points1: np.ndarray, points2: np.ndarray, d1: np.ndarray, d2: np.ndarray, anchor, eps: float
):
    """The motion (R, t) fitted to an anchor pair and its neighbours paired by distance agreement,
    or None (fewer than 3 pairs, or collinear)."""
    i, j = anchor
    cost = np.abs(d1[i][:, None] - d2[j][None, :])
    cost[i, :] = np.inf
    cost[:, j] = np.inf
    cost = np.where(cost <= eps, cost, eps * 1e3)
    rows, cols = linear_sum_assignment(cost)
    keep = cost[rows, cols] <= eps
    src = np.vstack([points2[j], points2[cols[keep]]])
    dst = np.vstack([points1[i], points1[rows[keep]]])
    return rigid_fit(src, dst)


def inliers(
    points1: np.ndarray, points2: np.ndarray, motion, eps: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(rows, columns, residuals) of the pairs within eps of the one-to-one assignment (Hungarian
    on the residuals) under ``motion``: the hypothesis's support."""
    rotation, translation = motion
    residual = cdist(points1, points2 @ rotation.T + translation)
    rows, cols = linear_sum_assignment(residual)
    inside = residual[rows, cols] <= eps
    return rows[inside], cols[inside], residual[rows, cols][inside]


def support(points1: np.ndarray, points2: np.ndarray, motion, eps: float) -> tuple[int, float]:
    """(pairs within eps of a one-to-one assignment, their summed residual) under ``motion``."""
    rows, _, residual = inliers(points1, points2, motion, eps)
    return len(rows), float(residual.sum())


def agreement_share(
    d1: np.ndarray,
    d2: np.ndarray,
    pairs: tuple[np.ndarray, np.ndarray],
    reference: tuple[np.ndarray, np.ndarray],
    eps: float,
) -> np.ndarray:
    """(len(pairs),) share in [0, 1] of the ``reference`` pairs that agree with each of ``pairs``:
    the mean over the reference pairs (k, l) other than (i, j) itself of w = exp(−2 (Δ / eps)²)
    if Δ = |d1_ik − d2_jl| ≤ eps, else 0; w = 0 for a reference pair sharing exactly one object
    with (i, j) (they contradict each other). 0 where no other reference pair exists."""
    rows, cols = (np.asarray(a, dtype=np.int64) for a in pairs)
    ref_rows, ref_cols = (np.asarray(a, dtype=np.int64) for a in reference)
    delta = np.abs(d1[np.ix_(rows, ref_rows)] - d2[np.ix_(cols, ref_cols)])
    same_row = rows[:, None] == ref_rows[None, :]
    same_col = cols[:, None] == ref_cols[None, :]
    itself = same_row & same_col
    weight = np.where(delta <= eps, np.exp(-2.0 * (np.minimum(delta, eps) / eps) ** 2), 0.0)
    weight[same_row | same_col] = 0.0
    others = len(ref_rows) - itself.sum(axis=1)
    share = weight.sum(axis=1) / np.maximum(others, 1)
    return np.clip(np.where(others > 0, share, 0.0), 0.0, 1.0)


def supported_scores(
    points1: np.ndarray,
    points2: np.ndarray,
    raw: np.ndarray,
    reference: tuple[np.ndarray, np.ndarray],
    eps: float,
) -> np.ndarray:
    """(n, m) scores in [0, 1]: the pairs the shared Hungarian declares on ``raw`` (per-pair
    evidence in [0, 1]) score their :func:`agreement_share` with ``reference`` (a verified set of
    pairs; the declared pairs themselves when it has fewer than 3), at least
    :data:`~matchers.core.discretise.SCORE_GRID`; every other entry 0. The Hungarian on the result
    returns the same pairs as on ``raw`` (each declared score is positive, all others 0). ``raw``
    with no positive entry (no evidence): all 0, and the same (tie-broken) assignment."""
    raw = canonical_scores(np.clip(np.nan_to_num(raw, nan=0.0), 0.0, 1.0))
    scores = np.zeros(raw.shape)
    if not (raw > 0).any():
        return scores
    rows, cols = hungarian(raw)
    if len(reference[0]) < 3:
        reference = (rows, cols)
    p1, p2 = np.asarray(points1, dtype=float), np.asarray(points2, dtype=float)
    share = agreement_share(cdist(p1, p1), cdist(p2, p2), (rows, cols), reference, eps)
    scores[rows, cols] = np.maximum(share, SCORE_GRID)
    return scores


def best_motion(problem: Problem, priority: np.ndarray, eps: float, anchors: int, extra=()):
    """The motion with the most support among the anchors' hypotheses and ``extra`` ones."""
    p1, p2 = np.asarray(problem.points1, float), np.asarray(problem.points2, float)
    d1, d2 = cdist(p1, p1), cdist(p2, p2)
    hypotheses = [anchor_motion(p1, p2, d1, d2, a, eps) for a in top_candidates(priority, anchors)]
    best, best_key = None, None
    for motion in [*extra, *hypotheses]:
        if motion is None:
            continue
        count, residual = support(p1, p2, motion, eps)
        key = (-count, residual)
        if best_key is None or key < best_key:
            best, best_key = motion, key
    return best


def _run(name, problem, threshold, started, eps, neighbours, anchors, likelihood=None, extra=()):
    n, m = problem.n1, problem.n2
    if n == 0 or m == 0:
        return finish(name, np.zeros((n, m)), threshold, started, 0, {"tolerance": eps})
    similarity = context_similarity(problem.points1, problem.points2, neighbours, eps)
    priority = similarity if likelihood is None else similarity * likelihood
    motion = best_motion(problem, priority, eps, anchors, extra)
    p1, p2 = np.asarray(problem.points1, float), np.asarray(problem.points2, float)
    none = np.zeros(0, dtype=np.int64)
    if motion is None:
        raw, reference = priority / max(float(priority.max()), 1e-300), (none, none)
    else:
        raw, reference = alignment_scores(p1, p2, motion, eps), inliers(p1, p2, motion, eps)[:2]
    scores = supported_scores(p1, p2, raw, reference, eps)
    info = {"tolerance": float(eps), "aligned": motion is not None, "inliers": len(reference[0])}
    return finish(name, scores, threshold, started, 0, info)


@budgeted(context_memory, "the number of objects or neighbours")
def cbm(
    problem: Problem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    tolerance_scale: float = 0.1,
    tolerance: float | None = None,
    neighbours: int = NEIGHBOURS,
    anchors: int = 16,
) -> Matching:
    """Context-based matching (module docstring): ``tolerance_scale`` (0.1) × the median
    within-view distance, or ``tolerance`` in metres, is eps; ``neighbours`` (6) per local
    context; ``anchors`` (16) hypotheses. Needs no features and no prior. Deterministic.

    >>> rng = np.random.default_rng(1)
    >>> pts = rng.uniform(0, 30, (7, 3))
    >>> other = np.vstack([pts[:5] @ np.diag([-1.0, -1.0, 1.0]) + 4.0, rng.uniform(0, 30, (2, 3))])
    >>> cbm(Problem(pts, other), threshold=0.5).pairs.tolist()
    [[0, 0], [1, 1], [2, 2], [3, 3], [4, 4]]
    """
    started = time.perf_counter()
    eps = checked_tolerance(
        problem, seed, tolerance_scale, tolerance, neighbours=neighbours, anchors=anchors
    )
    return _run("cbm", problem, threshold, started, eps, neighbours, anchors)


cbm.deterministic = True


@budgeted(context_memory, "the number of objects or neighbours")
def cbm_pose(
    problem: Problem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    tolerance_scale: float = 0.1,
    tolerance: float | None = None,
    neighbours: int = NEIGHBOURS,
    anchors: int = 16,
    spread: float = 3.0,
    gate: float = 8.0,
) -> Matching:
    """:func:`cbm` given the localisation prior: anchors ranked by context similarity times the
    prior likelihood (``spread``, ``gate`` as for :func:`matchers.pose.pose`) and the poses'
    own motion as one more hypothesis. Needs ``problem.world1/world2/world_sigma``."""
    started = time.perf_counter()
    eps = checked_tolerance(
        problem, seed, tolerance_scale, tolerance, neighbours=neighbours, anchors=anchors
    )
    likelihood = prior_weights(problem, "cbm_pose", spread, gate)
    extra = (prior_motion(problem.points1, problem.world1, problem.points2, problem.world2),)
    return _run(
        "cbm_pose", problem, threshold, started, eps, neighbours, anchors, likelihood, extra
    )


cbm_pose.requires = PRIOR_FIELDS
cbm_pose.deterministic = True
