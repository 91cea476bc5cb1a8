"""``hgm``: probabilistic hypergraph matching (Zass & Shashua, CVPR 2008)."""

from __future__ import annotations

import time

import numpy as np

from matchers.blocks.cue_terms import weighted_tensor
from matchers.blocks.memory_models import tensor_matcher
from matchers.core.matching import Matching
from matchers.core.memory_budget import budgeted
from matchers.core.options import check_count, check_problem, check_range, rng_from_seed
from matchers.core.problem import Problem
from matchers.core.result import finish, max_normalised
from matchers.hypergraph.sparse_tensor import SparseTensor
from matchers.hypergraph.tensor_build import MAX_ENTRIES, resolve_tensor


def nearest_substochastic_kl(
    y: np.ndarray, total: float, max_iter: int = 1000, tol: float = 1e-3
) -> tuple[np.ndarray, int, bool]:
    """Nearest matrix to the non-negative (n, m) ``y`` in relative entropy (KL(Z || Y)) with row
    sums <= 1, column sums <= 1 and total sum = ``total``.

    Dykstra's algorithm for Bregman (KL) projections, cycling over the three constraint sets;
    each projection is closed form — scale the rows (columns) whose sum exceeds 1 down to 1;
    scale everything to the total — and each set keeps a multiplicative correction, which makes
    the cycle converge to the projection onto the intersection rather than to some point in it.
    Stops when, right after the total-sum projection, no row or column sum exceeds 1 + tol, or
    after max_iter cycles (infeasible supports — fewer positive cells than needed — never
    converge). Zero cells stay zero. Returns (Z, cycles, converged).
    """
    z = np.asarray(y, dtype=float).copy()
    if not z.sum() > 0:
        return np.zeros_like(z), 0, True
    corrections = [np.ones_like(z) for _ in range(3)]
    for it in range(1, max_iter + 1):
        for k, project in enumerate((_rows_at_most_one, _cols_at_most_one, _total(total))):
            w = z * corrections[k]
            projected = project(w)
            corrections[k] = np.divide(w, projected, out=np.ones_like(w), where=projected > 0)
            z = projected
        if z.sum(axis=1).max() <= 1 + tol and z.sum(axis=0).max() <= 1 + tol:
            return z, it, True
    return z, max_iter, False


def _rows_at_most_one(w: np.ndarray) -> np.ndarray:
    rows = w.sum(axis=1, keepdims=True)
    return w / np.maximum(rows, 1.0)


def _cols_at_most_one(w: np.ndarray) -> np.ndarray:
    cols = w.sum(axis=0, keepdims=True)
    return w / np.maximum(cols, 1.0)


def _total(total: float):
    def project(w: np.ndarray) -> np.ndarray:
        s = w.sum()
        return w * (total / s) if s > 0 else w

    return project


def hgm_solve(
    tensor: SparseTensor, max_iter: int = 1000, tol: float = 1e-3
) -> tuple[np.ndarray, int, bool]:
    """HGM: marginalise the hyperedge-correspondence tensor to Y[a] = sum of h over stored
    triples containing a (each triple adds its value to each of its three matches), then the
    KL projection onto {row sums <= 1, column sums <= 1, total = min(n, m)}
    (:func:`nearest_substochastic_kl`). Returns (Z as a length-nm vector, cycles, converged)."""
    n, m = tensor.n, tensor.m
    marginal = tensor.degrees().reshape(n, m)
    z, cycles, converged = nearest_substochastic_kl(marginal, float(min(n, m)), max_iter, tol)
    return z.reshape(-1), cycles, converged


@budgeted(tensor_matcher("hgm"), "max_tensor_entries, triangles or neighbours")
def hgm(
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
    max_iter: int = 1000,
    tol: float = 1e-3,
) -> Matching:
    """HGM (:func:`hgm_solve`), then Hungarian on Z — the BCAGM benchmark's re-discretisation;
    the original's greedy soft2hard is not used, discretisation is shared by all matchers.

    Tensor options as for every hypergraph matcher (see :func:`matchers.rrwhm.rrwhm`).
    ``max_iter`` 1000 and ``tol`` 1e-3 for the projection (reference: 1000 loops, precision
    0.01). Scores: Z divided by its maximum; all zero for an empty tensor.
    ``distance_scale`` (None, as published): multiply every tensor entry by the metric
    affinity of its three edges, width ``distance_scale`` x the median within-view
    distance (the equal-cue protocol; :mod:`matchers.blocks.cue_terms`).
    ``appearance`` (False, as published): multiply every entry by the appearance
    similarity of its three candidate matches.
    """
    started = time.perf_counter()
    check_problem(problem)
    rng = rng_from_seed(seed)
    check_count("max_iter", max_iter)
    check_range("tol", tol, 0.0, np.inf, open_low=True)
    built = weighted_tensor(
        resolve_tensor(problem, tensor, rng, triangles, neighbours, sigma, max_tensor_entries),
        problem,
        distance_scale,
        appearance,
    )
    z, cycles, converged = hgm_solve(built, max_iter, tol)
    scores = max_normalised(z, problem.n1, problem.n2)
    info = {"converged": converged, "tensor_entries": built.nnz, "tensor": built.info}
    return finish("hgm", scores, threshold, started, cycles, info)
