"""``rrwm``: Reweighted Random Walks for graph matching (Cho, Lee & Lee, ECCV 2010)."""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from matchers.blocks.cue_terms import appearance_weighted_affinity
from matchers.blocks.memory_models import pairwise_matcher
from matchers.blocks.pairwise import NEIGHBOURS, resolve_affinity
from matchers.blocks.sinkhorn import sinkhorn
from matchers.core.indexing import conflict_mask
from matchers.core.matching import Matching
from matchers.core.memory_budget import budgeted
from matchers.core.options import check_count, check_problem, check_range, rng_from_seed
from matchers.core.problem import Problem
from matchers.core.result import finish, max_normalised


def reweighted_walk(
    affinity: np.ndarray | sp.spmatrix,
    n: int,
    m: int,
    jump: float = 0.8,
    beta: float = 30.0,
    max_iter: int = 300,
    tol: float = 1e-25,
    zero_conflicts: bool = True,
    sinkhorn_iter: int = 100,
    sinkhorn_tol: float = 1e-3,
) -> tuple[np.ndarray, int, bool]:
    """The original RRWM iteration (author code v1.22) on an (nm, nm) affinity.

        M <- M with entries of conflicting matches (sharing a node) zeroed  [zero_conflicts]
        Mo = M / max column sum;  x = y = uniform
        repeat:  x' = Mo ((1 - jump) x + jump y);  x' /= sum x'
                 y = Sinkhorn(exp(beta x' / max x')) (slack rows for n != m);  y /= sum y
                 stop if min(||x' - x||^2, ||x' - x_prev||^2) < tol   (2-step check vs oscillation)

    Sinkhorn stops at ``sinkhorn_tol`` 1e-3 (the original's) or ``sinkhorn_iter`` 100 sweeps (the
    original allows 1000; peaked y without total support converges slowly, and 100 sweeps
    already fix the ordering that the walk and the final Hungarian depend on).
    ``jump`` is the weight of the reweighted jump: 0.8 in the original (c = 0.2 on the walk);
    pygmtools' ``alpha`` = 0.2 is the same knob with the other value. Returns (x summing to 1 —
    or all-zero when M is all-zero —, iterations, converged).
    """
    size = n * m
    if sp.issparse(affinity):
        mat = sp.csr_matrix(affinity, dtype=float, copy=True)
        if zero_conflicts and mat.nnz:
            a, b = np.repeat(np.arange(size), np.diff(mat.indptr)), mat.indices
            mat.data[(a // m == b // m) | (a % m == b % m)] = 0.0
        col_max = np.asarray(mat.sum(axis=0)).max() if size else 0.0
    else:
        mat = np.array(affinity, dtype=float)
        if zero_conflicts and size:
            mat[conflict_mask(n, m)] = 0.0
        col_max = mat.sum(axis=0).max() if size else 0.0
    if not col_max > 0:
        return np.zeros(size), 0, True
    if sp.issparse(mat):
        mat.data /= col_max
    else:
        mat /= col_max
    x = np.full(size, 1.0 / size)
    y = x.copy()
    previous = x.copy()
    for it in range(1, max_iter + 1):
        x_new = mat @ ((1.0 - jump) * x + jump * y)
        total = x_new.sum()
        if not total > 0:
            return np.zeros(size), it, True
        x_new /= total
        y, _ = sinkhorn(
            np.exp(beta * x_new / x_new.max()).reshape(n, m), sinkhorn_iter, sinkhorn_tol
        )
        y = y.reshape(-1) / y.sum()
        change = min(np.sum((x_new - x) ** 2), np.sum((x_new - previous) ** 2))
        previous, x = x, x_new
        if change < tol:
            return x, it, True
    return x, max_iter, False


@budgeted(pairwise_matcher("rrwm"), "affinity_neighbours")
def rrwm(
    problem: Problem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    affinity: np.ndarray | sp.spmatrix | None = None,
    sigma2: float | None = None,
    sigma_scale: float | None = None,
    pairwise: str = "positions",
    affinity_neighbours: int | None = NEIGHBOURS,
    appearance: bool = False,
    jump: float = 0.8,
    beta: float = 30.0,
    max_iter: int = 300,
    tol: float = 1e-25,
    zero_conflicts: bool = True,
    sinkhorn_iter: int = 100,
) -> Matching:
    """RRWM on the pairwise affinity (:func:`~matchers.blocks.pairwise.resolve_affinity`: ``sigma2``
    0.5 or relative ``sigma_scale``, ``pairwise`` "positions" | "image", as for
    :func:`matchers.sm.sm`; dense up to ``affinity_neighbours`` (500) partners per candidate match,
    sparse beyond; or a precomputed dense or scipy-sparse ``affinity`` in the a = i*m + j
    convention), then
    Hungarian.

    Defaults are the original code's: ``jump`` 0.8 (weight on the reweighted jump), ``beta`` 30,
    ``max_iter`` 300, ``tol`` 1e-25, conflicting entries zeroed; ``sinkhorn_iter`` 100 (ours;
    the original's cap is 1000). See :func:`reweighted_walk`.
    ``appearance`` (False, as published): multiply every affinity entry by the appearance
    similarity of the two candidate matches it joins (the equal-cue protocol;
    :mod:`matchers.blocks.cue_terms`).
    Scores: the walk's distribution divided by its maximum. Deterministic (seed unused).
    """
    started = time.perf_counter()
    check_problem(problem)
    rng_from_seed(seed)
    check_range("jump", jump, 0.0, 1.0)
    check_range("beta", beta, 0.0, np.inf, open_low=True)
    check_count("max_iter", max_iter)
    check_range("tol", tol, 0.0, np.inf)
    check_count("sinkhorn_iter", sinkhorn_iter)
    n, m = problem.n1, problem.n2
    affinity = resolve_affinity(
        problem, affinity, sigma2, sigma_scale, pairwise, affinity_neighbours
    )
    if appearance:
        affinity = appearance_weighted_affinity(affinity, problem)
    x, iterations, converged = reweighted_walk(
        affinity, n, m, jump, beta, max_iter, tol, bool(zero_conflicts), sinkhorn_iter
    )
    scores = max_normalised(x, n, m)
    return finish("rrwm", scores, threshold, started, iterations, {"converged": converged})


rrwm.deterministic = True  # the result does not depend on `seed`
