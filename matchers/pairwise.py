"""Second-order affinity matrix for SM / RRWM / MOS: Gaussian of the difference of edge lengths."""

from __future__ import annotations

import numpy as np
from scipy.spatial.distance import cdist

from .problem import Problem


def pairwise_affinity(problem: Problem, sigma2: float = 0.5) -> np.ndarray:
    """Dense (nm, nm) affinity M[a, b] between candidate matches a = (i, j) and b = (k, l).

    M[a, b] = exp(-(d1[i, k] - d2[j, l])**2 / sigma2) for i != k and j != l, where d1, d2 are the
    Euclidean distances inside each view (same units as the positions; 2-D or 3-D). Entries of
    matches that share a node (i == k or j == l, the diagonal included) are 0. sigma2 = 0.5 is the
    setting of the published synthetic benchmarks (``makeMatchingProblem_2nd.m``); it is in squared
    position units, so scale it with your data. Rigid-invariant, not scale-invariant.
    Memory: (nm)^2 doubles (40 vs 40 points: 20 MB).
    """
    if not sigma2 > 0:
        raise ValueError(f"sigma2: expected a positive number, got {sigma2!r}")
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


def resolve_affinity(problem: Problem, affinity: np.ndarray | None, sigma2: float) -> np.ndarray:
    """The ``affinity=`` option of SM/RRWM/MOS: a precomputed (nm, nm) non-negative matrix in the
    a = i*m + j convention, checked, or (None) :func:`pairwise_affinity` with ``sigma2``."""
    size = problem.n1 * problem.n2
    if affinity is None:
        return pairwise_affinity(problem, sigma2)
    affinity = np.asarray(affinity, dtype=float)
    if affinity.shape != (size, size):
        raise ValueError(f"affinity: expected shape ({size}, {size}), got {affinity.shape}")
    if not np.all(np.isfinite(affinity)) or (affinity.size and affinity.min() < 0):
        raise ValueError("affinity: entries must be finite and non-negative")
    return affinity
