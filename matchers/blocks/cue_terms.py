"""The cues a matcher may be handed, folded into second- and third-order terms (the equal-cue
protocol's extension of the published matchers; docs/matchers.md, "Equal cues").

Two cues are added to the families that were published without them:

* **Metric distances** for the third-order (hypergraph) matchers, whose tensor compares only
  scale-free triangle angles (Eq. (1)). Every stored tensor entry T[a, b, c] over the candidate
  matches a = (i, i'), b = (j, j'), c = (k, k') is multiplied by the pairwise affinity of its three
  edges — the very kernel SM and RRWM use:

      T'[a, b, c] = T[a, b, c] · M[a, b] · M[b, c] · M[a, c],
      M[a, b]     = exp(-(‖p_i − p_j‖ − ‖q_i' − q_j'‖)² / σ_d²),   σ_d = distance_scale · s,

  with p, q the two views' positions (metres) and s the problem's median within-view distance
  (:func:`~matchers.core.scale.median_spacing`), so one ``distance_scale`` suits every scene.
* **Appearance** for the matchers published without a first-order term (SM, RRWM, TM, HGM,
  BCAGM, RRWHM): each entry of the affinity or tensor is multiplied by the appearance similarity
  b (cosine, [0, 1]) of every candidate match it joins — M'[a, b] = M[a, b] · b_a · b_b,
  T'[a, b, c] = T[a, b, c] · b_a · b_b · b_c — so evidence multiplies as independent likelihoods
  do. Without features b = 1 and nothing changes.

Both keep the tensor's sparsity pattern (an entry can only shrink), so the candidate search in
angle space is unchanged. Exponentials go through :mod:`matchers.core.portable_exp` (same bits on
every CPU). Imports nothing from ``cadsim`` or ``eval``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from matchers.blocks.appearance_similarity import appearance_similarity
from matchers.core.portable_exp import exp_nonpositive
from matchers.core.problem import Problem
from matchers.core.scale import median_spacing
from matchers.hypergraph.sparse_tensor import SparseTensor


def check_distance_scale(distance_scale: float | None) -> float | None:
    """``distance_scale``: None (no metric term) or a finite positive number; else ValueError."""
    if distance_scale is None:
        return None
    if isinstance(distance_scale, bool) or not isinstance(distance_scale, int | float | np.number):
        raise ValueError(
            f"distance_scale: expected a positive number or None, got {distance_scale!r}"
        )
    if not (np.isfinite(distance_scale) and distance_scale > 0):
        raise ValueError(
            f"distance_scale: expected a finite positive number, got {distance_scale!r}"
        )
    return float(distance_scale)


def _distances(points: np.ndarray) -> np.ndarray:
    """(n, n) ‖p_i − p_j‖ of one view's positions, summed coordinate by coordinate (one fixed
    order of IEEE operations: the same bits on every CPU)."""
    points = np.asarray(points, dtype=float)
    diff = points[:, None, :] - points[None, :, :]
    squared = np.zeros(diff.shape[:2])
    for axis in range(diff.shape[2]):
        squared = squared + diff[..., axis] * diff[..., axis]
    return np.sqrt(squared)


def _squared_gaps(
    d1: np.ndarray,
    d2: np.ndarray,
    first: tuple[np.ndarray, np.ndarray],
    second: tuple[np.ndarray, np.ndarray],
) -> np.ndarray:
    """(‖p_i − p_j‖ − ‖q_i' − q_j'‖)² per edge between candidate matches ``first`` = (i, i')
    and ``second`` = (j, j') (index arrays), from the two views' distance matrices."""
    gap = d1[first[0], second[0]] - d2[first[1], second[1]]
    return gap * gap


def metric_factor(
    problem: Problem, first: np.ndarray, second: np.ndarray, distance_scale: float
) -> np.ndarray:
    """M[a, b] of the module docstring for candidate-match index arrays ``first``, ``second``
    (a = i*m + i'): exp(-(d1 − d2)² / σ_d²), σ_d = distance_scale × median spacing."""
    m = problem.n2
    width = distance_scale * median_spacing(problem.points1, problem.points2)
    d1, d2 = _distances(problem.points1), _distances(problem.points2)
    squared = _squared_gaps(d1, d2, np.divmod(first, m), np.divmod(second, m))
    return exp_nonpositive(-squared / (width * width))


_GAP_TABLE_LIMIT = 1 << 22
"""Candidate-match counts nm with nm² ≤ this get their squared gaps tabulated once (≤ 32 MiB)."""


def _edge_sums(problem: Problem, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """g_ab² + g_bc² + g_ac² per tensor entry (a, b, c), g the edge-length gap of
    :func:`_squared_gaps`: read from an (nm, nm) table of every candidate pair's squared gap when
    it is small enough, else computed per entry."""
    n, m = problem.n1, problem.n2
    d1, d2 = _distances(problem.points1), _distances(problem.points2)
    if (n * m) ** 2 <= _GAP_TABLE_LIMIT:
        own, other = np.divmod(np.arange(n * m), m)
        gap = d1[np.ix_(own, own)] - d2[np.ix_(other, other)]
        table = (gap * gap).reshape(-1)
        nm = n * m
        return table[a * nm + b] + table[b * nm + c] + table[a * nm + c]
    ends = [np.divmod(slot, m) for slot in (a, b, c)]
    squared = _squared_gaps(d1, d2, ends[0], ends[1])
    squared += _squared_gaps(d1, d2, ends[1], ends[2])
    return squared + _squared_gaps(d1, d2, ends[0], ends[2])


def weighted_tensor(
    tensor: SparseTensor,
    problem: Problem,
    distance_scale: float | None = None,
    appearance: bool = False,
) -> SparseTensor:
    """``tensor`` with the metric term (``distance_scale`` not None) and/or the appearance
    factor (``appearance``) of the module docstring; the same tensor when neither is asked for
    or it is empty. The info dict records both.

    The three edge factors of an entry are taken as one exponential of their summed exponents,
    exp(−(g_ab² + g_bc² + g_ac²) / σ_d²) — the same product, one third of the exponentials; the
    edge lengths are read from each view's distance matrix rather than recomputed per entry."""
    distance_scale = check_distance_scale(distance_scale)
    if not tensor.nnz or (distance_scale is None and not appearance):
        return tensor
    a, b, c = (tensor.indices[:, slot] for slot in range(3))
    values = tensor.values.copy()
    if distance_scale is not None:
        width = distance_scale * median_spacing(problem.points1, problem.points2)
        squared = _edge_sums(problem, a, b, c)
        values *= exp_nonpositive(-squared / (width * width))
    if appearance:
        similarity = appearance_similarity(problem).reshape(-1)
        values *= similarity[a] * similarity[b] * similarity[c]
    info = dict(tensor.info or {}) | {"distance_scale": distance_scale, "appearance": appearance}
    return SparseTensor(tensor.indices, values, tensor.n, tensor.m, info, tensor._plan)


def appearance_weighted_affinity(
    affinity: np.ndarray | sp.spmatrix, problem: Problem
) -> np.ndarray | sp.csr_matrix:
    """M'[a, b] = M[a, b] · b_a · b_b (module docstring) for a dense or sparse (nm, nm) affinity."""
    similarity = appearance_similarity(problem).reshape(-1)
    if sp.issparse(affinity):
        weighted = sp.csr_matrix(affinity, dtype=float, copy=True)
        rows = np.repeat(np.arange(weighted.shape[0]), np.diff(weighted.indptr))
        weighted.data = weighted.data * similarity[rows] * similarity[weighted.indices]
        return weighted
    return np.asarray(affinity, dtype=float) * similarity[:, None] * similarity[None, :]
