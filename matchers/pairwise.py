"""Second-order affinity for SM / RRWM / MOS: Gaussian of the difference of edge lengths.

Dense up to a few hundred candidate matches (exactly the matrix the paper's baselines use); above
that, sparse: every candidate match keeps only its ``neighbours`` strongest partners, so memory
grows as n*m*neighbours instead of (n*m)^2 (0.8 GB dense at 100 vs 100).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.spatial.distance import cdist

from .problem import Problem
from .tensor_product import index_dtype

NEIGHBOURS = 500
"""Default partners kept per candidate match: at n*m <= 500 a match has fewer, so all are kept."""


def pairwise_affinity(problem: Problem, sigma2: float = 0.5) -> np.ndarray:
    """Dense (nm, nm) affinity M[a, b] between candidate matches a = (i, j) and b = (k, l).

    M[a, b] = exp(-(d1[i, k] - d2[j, l])**2 / sigma2) for i != k and j != l, where d1, d2 are the
    Euclidean distances inside each view (same units as the positions; 2-D or 3-D). Entries of
    matches that share a node (i == k or j == l, the diagonal included) are 0. sigma2 = 0.5 is the
    setting of the published synthetic benchmarks (``makeMatchingProblem_2nd.m``); it is in squared
    position units, so scale it with your data. Rigid-invariant, not scale-invariant.
    Memory: (nm)^2 doubles (40 vs 40 points: 20 MB).
    """
    _check_sigma2(sigma2)
    n, m = problem.n1, problem.n2
    if n == 0 or m == 0:
        return np.zeros((n * m, n * m))
    d1 = cdist(problem.points1, problem.points1)
    d2 = cdist(problem.points2, problem.points2)
    diff = d1[:, None, :, None] - d2[None, :, None, :]  # (n, m, n, m) = [i, j, k, l]
    affinity = np.exp(-(diff**2) / sigma2)
    same_i = np.eye(n, dtype=bool)[:, None, :, None]
    same_j = np.eye(m, dtype=bool)[None, :, None, :]
    affinity[np.broadcast_to(same_i | same_j, affinity.shape)] = 0.0
    return affinity.reshape(n * m, n * m)


def sparse_pairwise_affinity(
    problem: Problem, sigma2: float = 0.5, neighbours: int = NEIGHBOURS
) -> sp.csr_matrix:
    """The entries of :func:`pairwise_affinity` that matter, as an (nm, nm) CSR matrix.

    Every candidate match a = (i, j) keeps its ``neighbours`` strongest partners b = (k, l) —
    the smallest |d1[i, k] - d2[j, l]|, matches sharing a node excluded — and M[a, b] is stored
    when a keeps b or b keeps a, so the matrix stays symmetric. Stored values are bit-identical
    to the dense matrix's; with ``neighbours`` >= (n-1)(m-1) nothing is dropped. Memory: at most
    2 * n*m*neighbours entries (100 vs 100, 500 neighbours: 120 MB), built one object of view 1
    at a time ((n*m)*m numbers of scratch).

    >>> affinity = sparse_pairwise_affinity(problem, sigma2=0.5, neighbours=200)
    """
    _check_sigma2(sigma2)
    if isinstance(neighbours, bool) or not isinstance(neighbours, int | np.integer):
        raise ValueError(f"affinity_neighbours: expected a positive integer, got {neighbours!r}")
    if neighbours < 1:
        raise ValueError(f"affinity_neighbours: expected a positive integer, got {neighbours!r}")
    n, m = problem.n1, problem.n2
    size = n * m
    keep = min(int(neighbours), max((n - 1) * (m - 1), 0))
    if keep == 0:
        return sp.csr_matrix((size, size))
    d1 = cdist(problem.points1, problem.points1)
    d2 = cdist(problem.points2, problem.points2)
    dtype = index_dtype(max(size, 2))
    rows = np.empty((n, m, keep), dtype=dtype)
    cols = np.empty((n, m, keep), dtype=dtype)
    values = np.empty((n, m, keep))
    same_j = np.eye(m, dtype=bool)[:, None, :]  # [j, ., l]
    for i in range(n):  # one view-1 object's m candidate matches at a time: (m, n, m) scratch
        diff = d1[i][None, :, None] - d2[:, None, :]  # [j, k, l] = d1[i, k] - d2[j, l]
        gap = np.abs(diff)
        gap[:, i, :] = np.inf  # k == i
        gap[np.broadcast_to(same_j, gap.shape)] = np.inf  # l == j
        gap, diff = gap.reshape(m, size), diff.reshape(m, size)
        chosen = np.argpartition(gap, keep - 1, axis=1)[:, :keep]  # (m, keep) partners b
        picked = np.take_along_axis(diff, chosen, axis=1)
        values[i] = np.exp(-(picked**2) / sigma2)
        rows[i] = (i * m + np.arange(m))[:, None]
        cols[i] = chosen
    kept = sp.csr_matrix(
        (values.reshape(-1), (rows.reshape(-1), cols.reshape(-1))), shape=(size, size)
    )
    del rows, cols, values
    return kept.maximum(kept.T).tocsr()


def resolve_affinity(
    problem: Problem,
    affinity: np.ndarray | sp.spmatrix | None,
    sigma2: float,
    neighbours: int | None = NEIGHBOURS,
) -> np.ndarray | sp.csr_matrix:
    """The ``affinity=`` option of SM/RRWM/MOS: a precomputed (nm, nm) non-negative matrix in the
    a = i*m + j convention (dense or scipy sparse), checked; or (None) the affinity with
    ``sigma2``: dense (:func:`pairwise_affinity`) while a candidate match has at most
    ``neighbours`` partners ((n-1)(m-1) <= neighbours; always with ``neighbours=None``), else
    sparse (:func:`sparse_pairwise_affinity`)."""
    size = problem.n1 * problem.n2
    if affinity is None:
        if neighbours is None or (problem.n1 - 1) * (problem.n2 - 1) <= neighbours:
            return pairwise_affinity(problem, sigma2)
        return sparse_pairwise_affinity(problem, sigma2, neighbours)
    if sp.issparse(affinity):
        affinity = sp.csr_matrix(affinity, dtype=float)
        stored = affinity.data
    else:
        affinity = np.asarray(affinity, dtype=float)
        stored = affinity
    if affinity.shape != (size, size):
        raise ValueError(f"affinity: expected shape ({size}, {size}), got {affinity.shape}")
    if not np.all(np.isfinite(stored)) or (stored.size and stored.min() < 0):
        raise ValueError("affinity: entries must be finite and non-negative")
    return affinity


def _check_sigma2(sigma2: float) -> None:
    if not sigma2 > 0:
        raise ValueError(f"sigma2: expected a positive number, got {sigma2!r}")
