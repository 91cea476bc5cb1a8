"""``mos``: multi-order similarity matching — RRWHM over first-, second- and third-order terms.

The paper's baseline [38] has no public code; the paper describes it as "based on RRWHM but
considering multi-order similarity". We implement exactly that: one RRWHM walk
(:func:`matchers.rrwhm.jump_walk`, same jump, beta, stopping rule) whose walk operator is a
weighted sum of three orders, each scaled to a distribution before mixing so the weights mean
shares of the step rather than being at the mercy of each order's magnitude:

    step(x) = w1 * (b o x) / sum(b o x)        first order: appearance similarity b (cosine)
            + w2 * (M x) / sum(M x)            second order: pairwise affinity M (edge lengths)
            + w3 * (T x x) / sum(T x x)        third order: triangle tensor T

Default weights (w1, w2, w3) = (1/3, 1/3, 1/3). A term that is all zero (no triangles -> T = 0)
drops out of that step. Without features b = 1 and the first-order term just keeps x (damping).

As published, appearance reaches the walk only through the additive first-order share w1. The
equal-cue protocol (``appearance=True``, ``distance_scale``; :mod:`matchers.blocks.cue_terms`)
hands MOS its cues in the form every other matcher gets them — multiplied into each higher-order
entry — while the additive mix stays:

    M'[a, b]    = M[a, b] · b_a · b_b
    T'[a, b, c] = T[a, b, c] · K[a, b] · K[b, c] · K[a, c] · b_a · b_b · b_c

with K the metric edge kernel of width ``distance_scale`` × the median within-view distance (the
hypergraph matchers' metric term; M already compares metric edge lengths).
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from matchers.blocks.appearance_similarity import appearance_similarity
from matchers.blocks.cue_terms import appearance_weighted_affinity, weighted_tensor
from matchers.blocks.memory_models import mos_memory
from matchers.blocks.pairwise import NEIGHBOURS, resolve_affinity
from matchers.core.matching import Matching
from matchers.core.memory_budget import budgeted
from matchers.core.options import check_count, check_problem, check_range, rng_from_seed
from matchers.core.problem import Problem
from matchers.core.result import finish, max_normalised
from matchers.hypergraph.sparse_tensor import SparseTensor
from matchers.hypergraph.tensor_build import MAX_ENTRIES, resolve_tensor
from matchers.rrwhm import jump_walk


def multi_order_step(b: np.ndarray, affinity: np.ndarray, tensor: SparseTensor, weights):
    """The walk operator x -> weighted mix of the three normalised order terms."""
    w1, w2, w3 = weights

    def step(x: np.ndarray) -> np.ndarray:
        terms = []
        if w1 > 0:
            terms.append((w1, b * x))
        if w2 > 0:
            terms.append((w2, affinity @ x))
        if w3 > 0 and tensor.nnz:
            terms.append((w3, tensor.slot_sums(x)))
        out = np.zeros_like(x)
        for weight, term in terms:
            total = term.sum()
            if total > 0:
                out += weight * term / total
        return out

    return step


@budgeted(mos_memory, "affinity_neighbours, max_tensor_entries, triangles or neighbours")
def mos(
    problem: Problem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    tensor: str | SparseTensor = "paper",
    triangles: int | None = None,
    neighbours: int | None = None,
    sigma: float | None = None,
    max_tensor_entries: int | None = MAX_ENTRIES,
    affinity: np.ndarray | sp.spmatrix | None = None,
    sigma2: float | None = None,
    sigma_scale: float | None = None,
    pairwise: str = "positions",
    affinity_neighbours: int | None = NEIGHBOURS,
    weights: tuple[float, float, float] = (1 / 3, 1 / 3, 1 / 3),
    jump: float = 0.8,
    beta: float = 30.0,
    max_iter: int = 300,
    tol: float = 1e-6,
    sinkhorn_iter: int = 100,
    appearance: bool = False,
    distance_scale: float | None = None,
) -> Matching:
    """MOS (see the module docstring), then Hungarian.

    ``weights`` (first, second, third order; non-negative, not all zero; default equal thirds),
    pairwise options ``affinity`` / ``sigma2`` / ``sigma_scale`` / ``pairwise`` /
    ``affinity_neighbours`` as for :func:`matchers.sm.sm` (the second-order term), tensor
    options as for every hypergraph matcher, walk options as for :func:`matchers.rrwhm.rrwhm`.
    ``appearance`` (False, as published) and ``distance_scale`` (None, as published): the
    equal-cue terms of the module docstring. Scores: the final distribution divided by its
    maximum.

    >>> import numpy as np
    >>> from matchers.core.problem import Problem
    >>> p = np.random.default_rng(0).normal(size=(6, 3)) * 10
    >>> mos(Problem(p, p), appearance=True, distance_scale=0.1).pairs.shape[1]
    2
    """
    started = time.perf_counter()
    check_problem(problem)
    rng = rng_from_seed(seed)
    try:
        weights = tuple(float(w) for w in weights)
    except (TypeError, ValueError):
        raise ValueError(f"weights: expected three non-negative numbers, got {weights!r}") from None
    if (
        len(weights) != 3
        or min(weights) < 0
        or not sum(weights) > 0
        or not np.all(np.isfinite(weights))
    ):
        raise ValueError(
            f"weights: expected three non-negative numbers, not all 0, got {weights!r}"
        )
    check_range("jump", jump, 0.0, 1.0)
    check_range("beta", beta, 0.0, np.inf, open_low=True)
    check_count("max_iter", max_iter)
    check_range("tol", tol, 0.0, np.inf)
    check_count("sinkhorn_iter", sinkhorn_iter)
    n, m = problem.n1, problem.n2
    built = resolve_tensor(problem, tensor, rng, triangles, neighbours, sigma, max_tensor_entries)
    pairwise = resolve_affinity(
        problem, affinity, sigma2, sigma_scale, pairwise, affinity_neighbours
    )
    if appearance:
        pairwise = appearance_weighted_affinity(pairwise, problem)
    built = weighted_tensor(built, problem, distance_scale, appearance)
    b = appearance_similarity(problem).reshape(-1)
    step = multi_order_step(b, pairwise, built, weights)
    x, iterations, converged = jump_walk(step, n, m, jump, beta, max_iter, tol, sinkhorn_iter)
    scores = max_normalised(x, n, m)
    info = {
        "converged": converged,
        "tensor_entries": built.nnz,
        "tensor": built.info,
        "weights": weights,
    }
    return finish("mos", scores, threshold, started, iterations, info)
