"""``consistency``: robust data association without any prior — the largest set of candidate
matches whose within-view distances all agree (the maximum-clique / CLIPPER family).

Two candidate matches a = (i, j) and b = (k, l), i != k and j != l, are *consistent* when the
3-D distance between objects i and k in view 1 and between j and l in view 2 differ by at most
a tolerance eps: a rigid motion preserves distances, so the true matches are all mutually
consistent, while a wrong match agrees with the others only by chance. Edge weights

    W[a, b] = exp(-2 (d1_ik - d2_jl)^2 / eps^2)  if |d1_ik - d2_jl| <= eps,  else 0

(0 between matches sharing an object). The densest consistent set is sought as CLIPPER does —
a leading-eigenvector relaxation, then a consistent set extracted from it — vectorised:

1. u = principal eigenvector of W (power iteration, as Spectral Matching);
2. from each of the ``starts`` candidates with the largest u, grow a clique greedily: add the
   candidate of largest u that is consistent with every member so far (all starts at once,
   as boolean masks);
3. keep the largest clique S (ties: the largest total weight W inside it).

Every decision compares canonical values (:func:`~matchers.core.discretise.canonical_scores`,
a 2^-40 grid): the weights W themselves (so that W stays exactly symmetric whatever the CPU's
``exp``), the eigenvector u that orders the starts and the growth, and the clique weights of the
last step; ties then go to the lower index. Mirror-symmetric candidates (two objects of one
view equally far from a third) give exactly tied cliques, which raw last bits would otherwise
decide differently on another CPU (``../shared/DESIGN.md`` §10).

Scores: s_a = sum_{b in S, b != a} W[a, b] / (|S| - 1) in [0, 1] — the share of the consistent
set that agrees with candidate a (members close to 1; 0 everywhere when no two candidates are
consistent); then the shared Hungarian + threshold.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp
from scipy.spatial.distance import cdist

from matchers.blocks.memory_models import consistency_memory
from matchers.core.discretise import canonical_scores
from matchers.core.matching import Matching
from matchers.core.memory_budget import budgeted
from matchers.core.options import check_count, check_problem, check_range, rng_from_seed
from matchers.core.problem import Problem
from matchers.core.result import finish
from matchers.core.scale import median_spacing
from matchers.sm import spectral_vector


def consistency_weights(problem: Problem, tolerance: float) -> np.ndarray:
    """Dense (nm, nm) consistency weights W (module docstring) in the a = i*m + j convention,
    for a distance ``tolerance`` eps in the units of the positions."""
    n, m = problem.n1, problem.n2
    if n == 0 or m == 0:
        return np.zeros((n * m, n * m))
    d1 = cdist(problem.points1, problem.points1)
    d2 = cdist(problem.points2, problem.points2)
    diff = np.abs(d1[:, None, :, None] - d2[None, :, None, :])  # [i, j, k, l]
    weights = np.where(diff <= tolerance, np.exp(-2.0 * (diff / tolerance) ** 2), 0.0)
    weights = canonical_scores(weights)  # the same bits on every CPU: W exactly symmetric
    same_i = np.eye(n, dtype=bool)[:, None, :, None]
    same_j = np.eye(m, dtype=bool)[None, :, None, :]
    weights[np.broadcast_to(same_i | same_j, weights.shape)] = 0.0
    return weights.reshape(n * m, n * m)


def greedy_cliques(adjacent: np.ndarray, priority: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """(len(starts), N) bool membership of one clique grown from each start: repeatedly add the
    vertex of highest ``priority`` adjacent to every member, until none is left."""
    count, size = len(starts), adjacent.shape[0]
    members = np.zeros((count, size), dtype=bool)
    rows = np.arange(count)
    members[rows, starts] = True
    allowed = adjacent[starts].copy()
    while allowed.any():
        ranked = np.where(allowed, priority[None, :], -np.inf)
        best = ranked.argmax(axis=1)
        growing = allowed[rows, best]
        members[rows[growing], best[growing]] = True
        allowed[growing] &= adjacent[best[growing]]
        allowed[rows, best] = False
    return members


def _weight_inside(cliques: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """(k,) total weight Σ_{a, b ∈ clique} W[a, b] of each clique ((k, N) bool membership), read
    from each clique's own (s, s) block of W. Exact: W holds multiples of the score grid
    (2⁻⁴⁰) in [0, 1], and the sum of at most N² of them needs fewer than 53 bits, so no
    summation order changes a bit."""
    width = max(int(cliques.sum(axis=1).max()), 1)
    order = np.argsort(~cliques, axis=1, kind="stable")[:, :width]  # members first
    inside = np.take_along_axis(cliques, order, axis=1)
    block = weights[order[:, :, None], order[:, None, :]]
    return np.where(inside[:, :, None] & inside[:, None, :], block, 0.0).sum(axis=(1, 2))


def consistent_set(weights: np.ndarray, starts: int = 64) -> np.ndarray:
    """Bool mask of the densest consistent set found (steps 1-3 of the module docstring)."""
    size = weights.shape[0]
    adjacent = weights > 0
    if not adjacent.any():
        return np.zeros(size, dtype=bool)
    # the power iteration on the sparse W (most candidate pairs are inconsistent): each product
    # sums a row's nonzeros in index order, the same bits on every CPU
    u, _, _ = spectral_vector(sp.csr_matrix(weights))
    u = canonical_scores(u)  # orders starts and growth: equal u tie by index on every CPU
    has_edge = adjacent.any(axis=1)
    order = np.argsort(-np.where(has_edge, u, -1.0), kind="stable")
    first = order[: min(starts, int(has_edge.sum()))]
    cliques = greedy_cliques(adjacent, u, first)
    sizes = cliques.sum(axis=1)
    inside = _weight_inside(cliques, weights)  # exactly tied (mirror) cliques: first start wins
    best = np.lexsort((-inside, -sizes))[0]
    return cliques[best]


@budgeted(consistency_memory, "the number of objects (a dense (nm)^2 consistency matrix)")
def consistency(
    problem: Problem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    tolerance_scale: float = 0.1,
    tolerance: float | None = None,
    starts: int = 64,
) -> Matching:
    """Largest mutually consistent set of candidate matches, then Hungarian (module docstring).

    Options: ``tolerance_scale`` (0.1) — eps as a multiple of the problem's median within-view
    distance (:func:`~matchers.core.scale.median_spacing`); or ``tolerance`` — eps in position units
    (metres), which replaces it; ``starts`` (64) — clique growths from the candidates of largest
    eigenvector weight. Needs no features and no prior (ignores both). Deterministic; ``seed``
    unused. Memory (nm)^2 like the pairwise matchers.

    >>> rng = np.random.default_rng(1)
    >>> pts = rng.uniform(0, 30, (6, 3))
    >>> other = np.vstack([pts[:4][::-1] + 5.0, rng.uniform(0, 30, (3, 3))])
    >>> consistency(Problem(pts, other), threshold=0.5).pairs.tolist()
    [[0, 3], [1, 2], [2, 1], [3, 0]]
    """
    started = time.perf_counter()
    check_problem(problem)
    rng_from_seed(seed)
    check_count("starts", starts)
    if tolerance is None:
        scale = check_range("tolerance_scale", tolerance_scale, 0.0, np.inf, open_low=True)
        eps = scale * median_spacing(problem.points1, problem.points2)
    else:
        eps = check_range("tolerance", tolerance, 0.0, np.inf, open_low=True)
    n, m = problem.n1, problem.n2
    weights = consistency_weights(problem, eps)
    members = consistent_set(weights, starts)
    size = int(members.sum())
    if size >= 2:
        support = weights[:, members].sum(axis=1) / (size - 1)
        scores = np.clip(support, 0.0, 1.0).reshape(n, m)
    else:
        scores = np.zeros((n, m))
    info = {"tolerance": float(eps), "clique": size}
    return finish("consistency", scores, threshold, started, 0, info)


consistency.deterministic = True  # the result does not depend on `seed`
