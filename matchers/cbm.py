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

Scores: exp(−r² / (2 eps²)) of the residual r under the winning motion (S where no hypothesis
could be fitted); then the shared Hungarian + threshold.

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


def support(points1: np.ndarray, points2: np.ndarray, motion, eps: float) -> tuple[int, float]:
    """(pairs within eps of a one-to-one assignment, their summed residual) under ``motion``."""
    rotation, translation = motion
    residual = cdist(points1, points2 @ rotation.T + translation)
    rows, cols = linear_sum_assignment(residual)
    inside = residual[rows, cols] <= eps
    return int(inside.sum()), float(residual[rows, cols][inside].sum())


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
    if motion is None:
        scores = priority / max(float(priority.max()), 1e-300)
    else:
        scores = alignment_scores(problem.points1, problem.points2, motion, eps)
    info = {"tolerance": float(eps), "aligned": motion is not None}
    return finish(name, np.clip(scores, 0.0, 1.0), threshold, started, 0, info)


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
