"""``maximin``: maximin hypergraph matching (Gao et al.), Algorithm 1 of the paper, Eqs. (5)-(8).

Variant ``maximin_pose`` (below): maximin given what a connected vehicle knows — the
localisation prior's likelihood L folded into the first-order term, b'_ij = b_ij * L_ij, which
replaces b in the worst-case tensor of Eqs. (5)-(6) and in the jump of Eq. (7); everything else
is :func:`maximin` unchanged.
"""

from __future__ import annotations

import time

import numpy as np

from matchers.blocks.appearance_similarity import appearance_similarity
from matchers.blocks.cue_terms import weighted_tensor
from matchers.blocks.memory_models import prior_evidence_memory, tensor_matcher
from matchers.blocks.prior import PRIOR_FIELDS
from matchers.blocks.sinkhorn import sinkhorn
from matchers.core.matching import Matching
from matchers.core.memory_budget import budgeted
from matchers.core.options import check_count, check_problem, check_range, rng_from_seed
from matchers.core.problem import Problem
from matchers.core.result import finish, max_normalised
from matchers.hypergraph.sparse_tensor import SparseTensor
from matchers.hypergraph.tensor_build import MAX_ENTRIES, resolve_tensor
from matchers.pose_refine import pose_likelihood

INITS = ("uniform", "appearance", "random")
NORMALISATIONS = ("sum", "none")


def worst_case_tensor(tensor: SparseTensor, b: np.ndarray) -> SparseTensor:
    """Eqs. (5)-(6): T' = T * min(b_a, b_b, b_c) per entry, then P = T' / max_a sum_{b,c} T'[a,b,c]
    (the mode-1 row sums of the full super-symmetric tensor). All-zero T' gives an empty P."""
    b = np.asarray(b, dtype=float).reshape(-1)
    if not tensor.nnz:
        return tensor
    worst = tensor.min_weighted(b)
    t_prime = tensor.with_values(worst)
    row_max = (2.0 * t_prime.degrees()).max()
    if not row_max > 0:
        return SparseTensor.empty(tensor.n, tensor.m, tensor.info)
    return t_prime.with_values(worst / row_max)


def appearance_jump(x: np.ndarray, b: np.ndarray, n: int, m: int, beta: float, sinkhorn_iter: int):
    """Eq. (7) and step 5: z = exp(beta * (x o b) / max(x o b)), bistochastically normalised
    (Sinkhorn with slack for n != m). beta = 1 is the paper's Eq. (7); x o b = 0 gives z = 1."""
    xb = x * b
    top = xb.max()
    z = np.exp(beta * xb / top) if top > 0 else np.ones_like(xb)
    z, _ = sinkhorn(z.reshape(n, m), sinkhorn_iter)
    return z.reshape(-1)


def maximin_iterate(
    p: SparseTensor,
    b: np.ndarray,
    x0: np.ndarray,
    alpha: float = 0.3,
    beta: float = 1.0,
    max_iter: int = 100,
    tol: float = 1e-4,
    normalise: str = "sum",
    sinkhorn_iter: int = 100,
) -> tuple[np.ndarray, int, bool]:
    """Steps 3-7 of Algorithm 1 on the normalised worst-case tensor P (see :func:`worst_case_tensor`).

        repeat:  z = bistochastic(exp(beta x o b / max(x o b)))                      Eq. (7)
                 x' = alpha * P x_2 x x_3 x + (1 - alpha) * z                         Eq. (8)
                 stop when ||x' - x||_1 < tol * ||x'||_1 or after max_iter

    normalise="sum" (default): both terms of Eq. (8) are scaled to sum 1 before mixing and x
    sums to 1 — RRWHM's convention, which the paper builds on. Literally, P x x is tiny next to
    the bistochastic z (P is divided by the largest full row sum, and x covers few of a row's
    entries), so without it the spatial term carries ~1 % of x and maximin degenerates to
    appearance-only matching. normalise="none" is the literal Eq. (8), x unscaled.
    Returns (x, iterations, converged).
    """
    n, m = p.n, p.m
    x = np.asarray(x0, dtype=float).copy()
    for it in range(1, max_iter + 1):
        z = appearance_jump(x, b, n, m, beta, sinkhorn_iter)
        walk = p.product(x) if p.nnz else np.zeros_like(x)
        if normalise == "sum":
            walk_total, z_total = walk.sum(), z.sum()
            walk = walk / walk_total if walk_total > 0 else walk
            z = z / z_total if z_total > 0 else z
        x_new = alpha * walk + (1.0 - alpha) * z
        if normalise == "sum":
            x_new /= x_new.sum()
        change = np.abs(x_new - x).sum()
        x = x_new
        if change < tol * np.abs(x).sum():
            return x, it, True
    return x, max_iter, False


def initial_x(init: str, b: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Step 1: "uniform" (default; 1/nm everywhere), "appearance" (b / sum b) or "random"
    (uniform(0, 1) draws from the seeded generator), each summing to 1."""
    size = b.size
    if init == "uniform" or size == 0:
        x = np.ones(size)
    elif init == "appearance":
        x = b.copy() if b.sum() > 0 else np.ones(size)
    else:
        x = rng.random(size) + 1e-12
    return x / max(x.sum(), 1e-300)


@budgeted(tensor_matcher("maximin"), "max_tensor_entries, triangles or neighbours")
def maximin(
    problem: Problem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    tensor: str | SparseTensor = "paper",
    triangles: int | None = None,
    neighbours: int | None = None,
    sigma: float | None = None,
    max_tensor_entries: int | None = MAX_ENTRIES,
    distance_scale: float | None = None,
    alpha: float = 0.3,
    beta: float = 1.0,
    max_iter: int = 100,
    tol: float = 1e-4,
    init: str = "uniform",
    normalise: str = "sum",
    sinkhorn_iter: int = 100,
    first_order: np.ndarray | None = None,
) -> Matching:
    """Maximin hypergraph matching, Algorithm 1 (Gao et al., §III-B/C).

    1. x0 by ``init`` ("uniform" default; "appearance"; "random" from ``seed``).
    2. b = appearance similarity (cosine, [0, 1]); P by Eqs. (5)-(6) (:func:`worst_case_tensor`).
    3-7. Iterate Eqs. (7)-(8) (:func:`maximin_iterate`) with ``alpha`` = 0.3 (weight of the walk
       term), ``beta`` = 1 (Eq. 7 has no amplification; RRWHM's is 30), ``normalise`` "sum";
       the paper leaves the convergence test open: we stop when the L1 change of x falls below
       ``tol`` (1e-4) of its L1 norm, or after ``max_iter`` (100) iterations.
    8. Hungarian on the scores (x divided by its maximum); ``threshold`` drops weak pairs.

    Tensor options as for every hypergraph matcher (``tensor`` "paper" default | "duchenne" |
    a SparseTensor; ``triangles``, ``neighbours``, ``sigma``, ``max_tensor_entries``; ``seed``
    drives triangle sampling and the random init). With no tensor entries (fewer than 3 objects in a view) the walk term
    is zero and the result rests on appearance alone.

    ``first_order``: an (n, m) array in [0, 1] used as b instead of the features' cosine
    similarity (e.g. appearance times a localisation prior, :mod:`matchers.maximin`);
    default None.
    ``distance_scale`` (None, as published): multiply every tensor entry by the metric
    affinity of its three edges, width ``distance_scale`` x the median within-view
    distance (the equal-cue protocol; :mod:`matchers.blocks.cue_terms`).
    """
    started = time.perf_counter()
    check_problem(problem)
    rng = rng_from_seed(seed)
    check_range("alpha", alpha, 0.0, 1.0)
    check_range("beta", beta, 0.0, np.inf, open_low=True)
    check_count("max_iter", max_iter)
    check_range("tol", tol, 0.0, np.inf)
    check_count("sinkhorn_iter", sinkhorn_iter)
    if init not in INITS:
        raise ValueError(f"init: expected one of {INITS}, got {init!r}")
    if normalise not in NORMALISATIONS:
        raise ValueError(f"normalise: expected one of {NORMALISATIONS}, got {normalise!r}")
    n, m = problem.n1, problem.n2
    if n == 0 or m == 0:
        return finish("maximin", np.zeros((n, m)), threshold, started, 0, {"converged": True})
    built = weighted_tensor(
        resolve_tensor(problem, tensor, rng, triangles, neighbours, sigma, max_tensor_entries),
        problem,
        distance_scale,
        False,
    )
    b = (
        appearance_similarity(problem).reshape(-1)
        if first_order is None
        else checked_first_order(first_order, n, m)
    )
    p = worst_case_tensor(built, b)
    x0 = initial_x(init, b, rng)
    x, iterations, converged = maximin_iterate(
        p, b, x0, alpha, beta, max_iter, tol, normalise, sinkhorn_iter
    )
    scores = max_normalised(x, n, m)
    info = {"converged": converged, "tensor_entries": built.nnz, "tensor": built.info}
    return finish("maximin", scores, threshold, started, iterations, info)


def checked_first_order(first_order: np.ndarray, n: int, m: int) -> np.ndarray:
    """The ``first_order`` option of :func:`maximin` as a flat vector in the a = i*m + j order:
    an (n, m) array, finite, in [0, 1]; else ValueError naming it."""
    b = np.asarray(first_order, dtype=float)
    if b.shape != (n, m):
        raise ValueError(f"first_order: expected shape ({n}, {m}), got {b.shape}")
    if not np.all(np.isfinite(b)) or (b.size and (b.min() < 0 or b.max() > 1)):
        raise ValueError("first_order: entries must be finite and in [0, 1]")
    return b.reshape(-1)


@budgeted(
    prior_evidence_memory(2.0, 12.0, True, tensor_matcher("maximin")),
    "max_tensor_entries, triangles or neighbours",
)
def maximin_pose(
    problem: Problem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    spread: float = 2.0,
    gate: float = 12.0,
    refine: bool = True,
    **options,
) -> Matching:
    """Maximin with b' = b * L (module docstring). ``spread`` (2) and ``gate`` (12) shape the
    prior likelihood L as for :func:`matchers.pose.pose` (multiples of world_sigma; ground
    plane x, y, z up); ``refine`` (True) first corrects the prior's relative rigid error as
    :func:`matchers.pose_refine.pose_refine` does; every other option is :func:`~matchers.maximin.maximin`'s (tensor,
    alpha, beta, init, ...), except ``first_order``, which this matcher sets. Scores as
    maximin's (x / max). Needs ``problem.world1/world2/world_sigma``.

    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> xyz = rng.uniform(-20, 20, (6, 3)) * [1, 1, 0]
    >>> p = Problem(xyz, xyz[::-1], world1=xyz, world2=xyz[::-1] + 0.5, world_sigma=1.0)
    >>> maximin_pose(p, threshold=0.5).pairs[:, 1].tolist()
    [5, 4, 3, 2, 1, 0]
    """
    started = time.perf_counter()
    check_problem(problem)
    if "first_order" in options:
        raise TypeError("maximin_pose() sets first_order itself; pass spread/gate instead")
    likelihood, info = pose_likelihood(problem, "maximin_pose", spread, gate, bool(refine))
    b = appearance_similarity(problem) * likelihood
    matching = maximin(problem, seed, threshold, first_order=b, **options)
    matching.name = "maximin_pose"
    matching.info |= info
    matching.time_s = time.perf_counter() - started
    return matching


maximin_pose.requires = PRIOR_FIELDS
