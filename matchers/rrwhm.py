"""``rrwhm``: Reweighted Random Walks for Hyper-graph Matching (Lee, Cho & Lee, CVPR 2011)."""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from matchers.blocks.cue_terms import weighted_tensor
from matchers.blocks.memory_models import tensor_matcher
from matchers.blocks.sinkhorn import sinkhorn
from matchers.core.matching import Matching
from matchers.core.memory_budget import budgeted
from matchers.core.options import check_count, check_problem, check_range, rng_from_seed
from matchers.core.problem import Problem
from matchers.core.result import finish, max_normalised
from matchers.hypergraph.sparse_tensor import SparseTensor
from matchers.hypergraph.tensor_build import MAX_ENTRIES, resolve_tensor


def reweighted_jump(x: np.ndarray, n: int, m: int, beta: float, sinkhorn_iter: int) -> np.ndarray:
    """y = Sinkhorn(exp(beta * x / max x)) with slack for n != m, normalised to sum 1."""
    top = x.max()
    y = np.exp(beta * x / top) if top > 0 else np.ones_like(x)
    y, _ = sinkhorn(y.reshape(n, m), sinkhorn_iter)
    y = y.reshape(-1)
    return y / y.sum()


def jump_walk(
    step: Callable[[np.ndarray], np.ndarray],
    n: int,
    m: int,
    jump: float = 0.8,
    beta: float = 30.0,
    max_iter: int = 300,
    tol: float = 1e-6,
    sinkhorn_iter: int = 100,
) -> tuple[np.ndarray, int, bool]:
    """The RRWHM loop around a walk operator ``step`` (x -> non-negative vector of length nm):

        x = uniform
        repeat:  x~ = step(x);  x~ /= sum x~
                 y = Sinkhorn(exp(beta x~ / max x~)) (slack rows for n != m, <= sinkhorn_iter
                     sweeps — the reference code has neither);  y /= sum y
                 x' = (1 - jump) x~ + jump y;  x' /= sum x'
                 stop if ||x' - x||^2 < tol (reference: 1e-6) or after max_iter (300)

    Returns (x summing to 1, or all-zero when step(uniform) is all-zero; iterations; converged).
    """
    size = n * m
    x = np.full(size, 1.0 / max(size, 1))
    for it in range(1, max_iter + 1):
        walk = step(x)
        total = walk.sum()
        if not total > 0:
            return (x if it > 1 else np.zeros(size)), it, True
        walk = walk / total
        y = reweighted_jump(walk, n, m, beta, sinkhorn_iter)
        x_new = (1.0 - jump) * walk + jump * y
        x_new /= x_new.sum()
        change = np.sum((x_new - x) ** 2)
        x = x_new
        if change < tol:
            return x, it, True
    return x, max_iter, False


def hypergraph_walk(
    tensor: SparseTensor,
    jump: float = 0.8,
    beta: float = 30.0,
    max_iter: int = 300,
    tol: float = 1e-6,
    sinkhorn_iter: int = 100,
) -> tuple[np.ndarray, int, bool]:
    """RRWHM on a sparse super-symmetric tensor: :func:`jump_walk` with step(x) = T x x, after
    the reference normalisation h <- h / max_a d_a (d = stored-entry degree; it does not change
    the walk, which is L1-normalised every step). An empty tensor gives x = 0."""
    if not tensor.nnz:
        return np.zeros(tensor.size), 0, True
    tensor = tensor.with_values(tensor.values / tensor.degrees().max())
    return jump_walk(tensor.slot_sums, tensor.n, tensor.m, jump, beta, max_iter, tol, sinkhorn_iter)


@budgeted(tensor_matcher("rrwhm"), "max_tensor_entries, triangles or neighbours")
def rrwhm(
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
    appearance: bool = False,
    jump: float = 0.8,
    beta: float = 30.0,
    max_iter: int = 300,
    tol: float = 1e-6,
    sinkhorn_iter: int = 100,
) -> Matching:
    """RRWHM on the third-order tensor, then Hungarian.

    Tensor options (every hypergraph matcher): ``tensor`` "paper" | "duchenne" | a prebuilt
    :class:`~matchers.hypergraph.sparse_tensor.SparseTensor`; ``triangles``, ``neighbours``, ``sigma``
    override the recipe's sampled-triangle count, k-NN count and bandwidth;
    ``max_tensor_entries`` (10^6; None = no cap) bounds triangles x neighbours, keeping the
    best-ranked entries — it binds only above n*m = 1000 with the defaults
    (:func:`~matchers.hypergraph.tensor_build.build_tensor`); ``seed`` drives the triangle sampling.
    Walk options (reference defaults): ``jump`` 0.8 (c = 0.2 on the walk), ``beta`` 30,
    ``max_iter`` 300, ``tol`` 1e-6 (squared L2 change), ``sinkhorn_iter`` 100 (our cap).
    Scores: the final distribution divided by its maximum; all zero for an empty tensor.
    ``distance_scale`` (None, as published): multiply every tensor entry by the metric
    affinity of its three edges, width ``distance_scale`` x the median within-view
    distance (the equal-cue protocol; :mod:`matchers.blocks.cue_terms`).
    ``appearance`` (False, as published): multiply every entry by the appearance
    similarity of its three candidate matches.
    """
    started = time.perf_counter()
    check_problem(problem)
    rng = rng_from_seed(seed)
    check_range("jump", jump, 0.0, 1.0)
    check_range("beta", beta, 0.0, np.inf, open_low=True)
    check_count("max_iter", max_iter)
    check_range("tol", tol, 0.0, np.inf)
    check_count("sinkhorn_iter", sinkhorn_iter)
    built = weighted_tensor(
        resolve_tensor(problem, tensor, rng, triangles, neighbours, sigma, max_tensor_entries),
        problem,
        distance_scale,
        appearance,
    )
    x, iterations, converged = hypergraph_walk(built, jump, beta, max_iter, tol, sinkhorn_iter)
    scores = max_normalised(x, problem.n1, problem.n2)
    info = {"converged": converged, "tensor_entries": built.nnz, "tensor": built.info}
    return finish("rrwhm", scores, threshold, started, iterations, info)
