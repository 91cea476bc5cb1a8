"""``freealign``: FreeAlign (Lei et al., collaborative perception without external localisation
and clock devices, ICRA 2024), implemented from the paper's description: the largest common
subgraph of the two views' object graphs, found by anchor-based greedy search, pose-free.

Each view is a complete graph: nodes are objects, edge weights the distances between them (a
rigid motion keeps them; the paper also compares relative headings, which our problems do not
carry — positions only). From each of the ``anchors`` node pairs of most similar local context
(:func:`~matchers.blocks.local_context.context_similarity`), a common subgraph is grown greedily:
a candidate pair (k, l) may join while every edge it closes agrees with its counterpart within
eps (|d1_kp − d2_lq| ≤ eps for every member (p, q)); among those, the one of most similar local
context joins (ties: index order), and the members' rows and columns leave the candidates. The
largest subgraph wins (ties: the smaller mean edge disagreement). The relative pose is fitted to
it (Kabsch), as FreeAlign then does.

Declared pairs: the shared Hungarian on exp(−r² / (2 eps²)) of the residual r under that pose
(on 1 for the members of a subgraph of fewer than 3 pairs, 0 elsewhere).

Scores (:func:`~matchers.cbm.supported_scores`): a declared pair's score is the share of the
winning subgraph's members that agree with it — for each other member (k, l),
w = exp(−2 (Δ / eps)²) if Δ = |d1_ik − d2_jl| ≤ eps, else 0 (0 for a member sharing exactly one
object with it), averaged over the members other than the pair itself. A member agrees with every
other member within eps by construction (each weight ≥ e⁻² ≈ 0.14; near 1 for precise positions);
a pair of objects seen in one view only agrees with them only by chance, so a threshold abstains. A
subgraph of fewer than 3 members: the other declared pairs are the reference instead. Every other
entry scores 0, and a declared pair with no support scores
:data:`~matchers.core.discretise.SCORE_GRID` (2⁻⁴⁰), so the Hungarian on the scores returns the
same pairs; no subgraph at all: all 0.

Variant ``freealign_pose``: anchors and growth ranked by context similarity times the prior
likelihood, so the search starts where the vehicles' poses say the common objects are.
"""

from __future__ import annotations

import time

import numpy as np
from scipy.spatial.distance import cdist

from matchers.blocks.local_context import (
    NEIGHBOURS,
    alignment_scores,
    checked_tolerance,
    context_similarity,
    prior_weights,
    rigid_fit,
    top_candidates,
)
from matchers.blocks.memory_models import context_memory
from matchers.blocks.prior import PRIOR_FIELDS
from matchers.cbm import supported_scores
from matchers.core.matching import Matching
from matchers.core.memory_budget import budgeted
from matchers.core.problem import Problem
from matchers.core.result import finish


def grow_subgraph(
    d1: np.ndarray, d2: np.ndarray, priority: np.ndarray, anchor: tuple[int, int], eps: float
) -> tuple[list[tuple[int, int]], float]:
    """(member pairs, mean edge disagreement) of the common subgraph grown from ``anchor``."""
    a, b = anchor
    members = [(a, b)]
    disagreement = np.abs(d1[:, a][:, None] - d2[:, b][None, :])
    allowed = disagreement <= eps
    total = disagreement.copy()
    allowed[a, :] = False
    allowed[:, b] = False
    edges, error = 0, 0.0
    while True:
        ranked = np.where(allowed, priority, -np.inf)
        best = int(np.argmax(ranked))
        if not np.isfinite(ranked.flat[best]):
            break
        row, col = divmod(best, priority.shape[1])
        edges += len(members)
        error += float(total[row, col])
        members.append((row, col))
        step = np.abs(d1[:, row][:, None] - d2[:, col][None, :])
        allowed &= step <= eps
        total += step
        allowed[row, :] = False
        allowed[:, col] = False
    return members, (error / edges if edges else 0.0)


def _run(name, problem, threshold, started, eps, neighbours, anchors, likelihood=None) -> Matching:
    n, m = problem.n1, problem.n2
    if n == 0 or m == 0:
        return finish(name, np.zeros((n, m)), threshold, started, 0, {"tolerance": eps})
    p1, p2 = np.asarray(problem.points1, float), np.asarray(problem.points2, float)
    similarity = context_similarity(p1, p2, neighbours, eps)
    priority = similarity if likelihood is None else similarity * likelihood
    d1, d2 = cdist(p1, p1), cdist(p2, p2)
    best, best_key = [], None
    for anchor in top_candidates(priority, anchors):
        members, error = grow_subgraph(d1, d2, priority, anchor, eps)
        key = (-len(members), error)
        if best_key is None or key < best_key:
            best, best_key = members, key
    motion = None
    if len(best) >= 3:
        rows, cols = np.array(best).T
        motion = rigid_fit(p2[cols], p1[rows])
    members = np.array(best, dtype=np.int64).reshape(-1, 2).T
    if motion is not None:
        raw = alignment_scores(p1, p2, motion, eps)
    else:
        raw = np.zeros((n, m))
        raw[members[0], members[1]] = 1.0
    scores = supported_scores(p1, p2, raw, (members[0], members[1]), eps)
    info = {"tolerance": float(eps), "subgraph": len(best)}
    return finish(name, scores, threshold, started, len(best), info)


@budgeted(context_memory, "the number of objects or neighbours")
def freealign(
    problem: Problem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    tolerance_scale: float = 0.1,
    tolerance: float | None = None,
    neighbours: int = NEIGHBOURS,
    anchors: int = 16,
) -> Matching:
    """FreeAlign's anchor-based common-subgraph search (module docstring): eps from
    ``tolerance_scale`` (0.1 × the median within-view distance) or ``tolerance`` (metres);
    ``neighbours`` (6) per local context; ``anchors`` (16) growths. Needs no features and no
    prior. Deterministic.

    >>> rng = np.random.default_rng(1)
    >>> pts = rng.uniform(0, 30, (7, 3))
    >>> other = np.vstack([pts[:5] @ np.diag([-1.0, -1.0, 1.0]) + 4.0, rng.uniform(0, 30, (2, 3))])
    >>> freealign(Problem(pts, other), threshold=0.5).pairs.tolist()
    [[0, 0], [1, 1], [2, 2], [3, 3], [4, 4]]
    """
    started = time.perf_counter()
    eps = checked_tolerance(
        problem, seed, tolerance_scale, tolerance, neighbours=neighbours, anchors=anchors
    )
    return _run("freealign", problem, threshold, started, eps, neighbours, anchors)


freealign.deterministic = True


@budgeted(context_memory, "the number of objects or neighbours")
def freealign_pose(
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
    """:func:`freealign` with anchors and growth ranked by context similarity times the prior
    likelihood (``spread``, ``gate`` as for :func:`matchers.pose.pose`). Needs
    ``problem.world1/world2/world_sigma``."""
    started = time.perf_counter()
    eps = checked_tolerance(
        problem, seed, tolerance_scale, tolerance, neighbours=neighbours, anchors=anchors
    )
    likelihood = prior_weights(problem, "freealign_pose", spread, gate)
    return _run("freealign_pose", problem, threshold, started, eps, neighbours, anchors, likelihood)


freealign_pose.requires = PRIOR_FIELDS
freealign_pose.deterministic = True
