"""``sm``: Spectral Matching (Leordeanu & Hebert, ICCV 2005) on the pairwise affinity matrix."""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from matchers.blocks.cue_terms import appearance_weighted_affinity
from matchers.blocks.memory_models import pairwise_matcher
from matchers.blocks.pairwise import NEIGHBOURS, resolve_affinity
from matchers.core.matching import Matching
from matchers.core.memory_budget import budgeted
from matchers.core.options import check_count, check_problem, check_range, rng_from_seed
from matchers.core.problem import Problem
from matchers.core.result import finish, max_normalised


def spectral_vector(
    affinity: np.ndarray, max_iter: int = 200, tol: float = 1e-8
) -> tuple[np.ndarray, int, bool]:
    """Principal eigenvector of a non-negative (N, N) affinity by power iteration.

    x0 uniform, x <- Mx / ||Mx||_2, stop when ||x - x_prev||_2 < tol or after max_iter products
    (pygmtools uses max_iter=50, tol=1e-5; the original code calls eigs — our defaults run the
    power iteration closer to the exact eigenvector). Returns (x >= 0, iterations, converged);
    an all-zero affinity gives x = 0.
    """
    size = affinity.shape[0]
    x = np.full(size, 1.0 / max(size, 1))
    for it in range(1, max_iter + 1):
        y = affinity @ x
        norm = np.linalg.norm(y)
        if not norm > 0:
            return np.zeros(size), it, True
        y /= norm
        if np.linalg.norm(y - x) < tol:
            return np.abs(y), it, True
        x = y
    return np.abs(x), max_iter, False


@budgeted(pairwise_matcher("sm"), "affinity_neighbours")
def sm(
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
    max_iter: int = 200,
    tol: float = 1e-8,
) -> Matching:
    """Spectral Matching: principal eigenvector of the pairwise affinity M, then Hungarian.

    Options: ``affinity`` — a precomputed (nm, nm) matrix in the a = i*m + j convention
    (default: :func:`~matchers.blocks.pairwise.pairwise_affinity` with ``sigma2``, 0.5, in squared
    position units, or ``sigma_scale``, the kernel width sigma as a multiple of the problem's
    median within-view distance; ``pairwise`` "positions" (default) or "image" — edge lengths
    between box centres, pixels1/pixels2); ``max_iter`` (200) and ``tol`` (1e-8) of the power
    iteration; ``affinity_neighbours`` (500): dense while a candidate
    match has at most that many partners, else each match keeps its 500 strongest (a precomputed
    ``affinity`` may be scipy sparse).
    ``appearance`` (False, as published): multiply every affinity entry by the appearance
    similarity of the two candidate matches it joins (the equal-cue protocol;
    :mod:`matchers.blocks.cue_terms`).
    Scores: eigenvector divided by its maximum. Deterministic (uniform start; seed unused).
    """
    started = time.perf_counter()
    check_problem(problem)
    rng_from_seed(seed)
    check_count("max_iter", max_iter)
    check_range("tol", tol, 0.0, np.inf, open_low=True)
    n, m = problem.n1, problem.n2
    affinity = resolve_affinity(
        problem, affinity, sigma2, sigma_scale, pairwise, affinity_neighbours
    )
    if appearance:
        affinity = appearance_weighted_affinity(affinity, problem)
    x, iterations, converged = spectral_vector(affinity, max_iter, tol)
    scores = max_normalised(x, n, m)
    return finish("sm", scores, threshold, started, iterations, {"converged": converged})


sm.deterministic = True  # the result does not depend on `seed`
