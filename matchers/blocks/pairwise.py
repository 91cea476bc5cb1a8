"""Second-order affinity for SM / RRWM / MOS: Gaussian of the difference of edge lengths, measured
between 3-D positions (default) or between box centres in the image, with an absolute or a
relative (multiple of the problem's median spacing) kernel width.

Dense up to a few hundred candidate matches (exactly the matrix the paper's baselines use); above
that, sparse: every candidate match keeps only its ``neighbours`` strongest partners, so memory
grows as n*m*neighbours instead of (n*m)^2 (0.8 GB dense at 100 vs 100).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.spatial.distance import cdist

from matchers.core.memory_budget import check_memory
from matchers.core.problem import Problem
from matchers.core.scale import median_spacing
from matchers.hypergraph.tensor_product import index_dtype

PAIRWISE_SPACES = ("positions", "image")
DEFAULT_SIGMA2 = 0.5
NEIGHBOURS = 500
"""Default partners kept per candidate match: at n*m <= 500 a match has fewer, so all are kept."""


def edge_positions(problem: Problem, pairwise: str = "positions") -> tuple[np.ndarray, np.ndarray]:
    """The (n, D) and (m, D) positions whose distances are the edge lengths: ``"positions"`` —
    points1/points2 (metres for CoID data); ``"image"`` — pixels1/pixels2 (box centres, pixels),
    the way the paper's pairwise baselines compared objects. ValueError if pixels are missing."""
    if pairwise not in PAIRWISE_SPACES:
        raise ValueError(f"pairwise: expected one of {PAIRWISE_SPACES}, got {pairwise!r}")
    if pairwise == "positions":
        return problem.points1, problem.points2
    if problem.pixels1 is None:
        raise ValueError(
            "pairwise='image': the problem has no pixels1/pixels2 (box centres in pixels); "
            "give them to Problem or use pairwise='positions'"
        )
    return problem.pixels1, problem.pixels2


def kernel_sigma2(
    problem: Problem,
    sigma2: float | None = None,
    sigma_scale: float | None = None,
    pairwise: str = "positions",
) -> float:
    """The kernel width sigma^2 (squared units of the edge lengths) from one of two options:
    ``sigma2`` — absolute (default 0.5 when neither is given); ``sigma_scale`` — relative, sigma
    = sigma_scale x the median within-view distance of the chosen space pooled over both views
    (:func:`~matchers.core.scale.median_spacing`), so one value suits scenes of any size.

    >>> p = Problem(np.array([[0.0, 0.0], [2.0, 0.0]]), np.array([[0.0, 0.0], [2.0, 0.0]]))
    >>> kernel_sigma2(p, sigma_scale=0.5)  # median spacing 2 -> sigma 1
    1.0
    """
    if sigma2 is not None and sigma_scale is not None:
        raise ValueError("sigma2/sigma_scale: give one kernel width, not both")
    if sigma_scale is None:
        sigma2 = DEFAULT_SIGMA2 if sigma2 is None else sigma2
        if isinstance(sigma2, bool) or not isinstance(sigma2, int | float | np.number):
            raise ValueError(f"sigma2: expected a positive number, got {sigma2!r}")
        if not (np.isfinite(sigma2) and sigma2 > 0):
            raise ValueError(f"sigma2: expected a finite positive number, got {sigma2!r}")
        return float(sigma2)
    if isinstance(sigma_scale, bool) or not isinstance(sigma_scale, int | float | np.number):
        raise ValueError(f"sigma_scale: expected a positive number, got {sigma_scale!r}")
    if not (np.isfinite(sigma_scale) and sigma_scale > 0):
        raise ValueError(f"sigma_scale: expected a finite positive number, got {sigma_scale!r}")
    first, second = edge_positions(problem, pairwise)
    return float((sigma_scale * median_spacing(first, second)) ** 2)


def pairwise_affinity(
    problem: Problem, sigma2: float = DEFAULT_SIGMA2, pairwise: str = "positions"
) -> np.ndarray:
    """Dense (nm, nm) affinity M[a, b] between candidate matches a = (i, j) and b = (k, l).

    M[a, b] = exp(-(d1[i, k] - d2[j, l])**2 / sigma2) for i != k and j != l, where d1, d2 are the
    Euclidean distances inside each view between the positions (``pairwise="positions"``,
    default: points1/points2, 2-D or 3-D, their units) or between the box centres in the image
    (``pairwise="image"``: pixels1/pixels2, pixels). Entries of
    matches that share a node (i == k or j == l, the diagonal included) are 0. sigma2 = 0.5 is the
    setting of the published synthetic benchmarks (``makeMatchingProblem_2nd.m``); it is in squared
    position units, so scale it with your data (or use ``sigma_scale``, :func:`kernel_sigma2`).
    Rigid-invariant, not scale-invariant. Memory: (nm)^2 doubles (40 vs 40 points: 20 MB).
    """
    if not sigma2 > 0:
        raise ValueError(f"sigma2: expected a positive number, got {sigma2!r}")
    first, second = edge_positions(problem, pairwise)
    n, m = problem.n1, problem.n2
    if n == 0 or m == 0:
        return np.zeros((n * m, n * m))
    check_memory(  # the (nm)^2 differences, their Gaussian and the shared-node mask
        f"dense pairwise affinity ({n} x {m} objects: {(n * m) ** 2:,} entries)",
        3 * 8 * float(n * m) ** 2,
        "affinity_neighbours (None means dense)",
    )
    d1 = cdist(first, first)
    d2 = cdist(second, second)
    diff = d1[:, None, :, None] - d2[None, :, None, :]  # (n, m, n, m) = [i, j, k, l]
    affinity = np.exp(-(diff**2) / sigma2)
    same_i = np.eye(n, dtype=bool)[:, None, :, None]
    same_j = np.eye(m, dtype=bool)[None, :, None, :]
    affinity[np.broadcast_to(same_i | same_j, affinity.shape)] = 0.0
    return affinity.reshape(n * m, n * m)


def sparse_pairwise_affinity(
    problem: Problem,
    sigma2: float = DEFAULT_SIGMA2,
    neighbours: int = NEIGHBOURS,
    pairwise: str = "positions",
) -> sp.csr_matrix:
    """The entries of :func:`pairwise_affinity` that matter, as an (nm, nm) CSR matrix.

    Every candidate match a = (i, j) keeps its ``neighbours`` strongest partners b = (k, l) —
    the smallest |d1[i, k] - d2[j, l]|, matches sharing a node excluded — and M[a, b] is stored
    when a keeps b or b keeps a, so the matrix stays symmetric. Stored values are bit-identical
    to the dense matrix's; with ``neighbours`` >= (n-1)(m-1) nothing is dropped. Memory: at most
    2 * n*m*neighbours entries (100 vs 100, 500 neighbours: 120 MB), built one object of view 1
    at a time ((n*m)*m numbers of scratch). ``pairwise``: as in :func:`pairwise_affinity`.

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
    check_memory(  # kept entries (values + two indices), doubled by symmetrising; per-row scratch
        f"sparse pairwise affinity ({n} x {m} objects, {keep} partners per candidate match)",
        2 * 2 * 24 * float(size) * keep + 3 * 8 * float(m) * size,
        "affinity_neighbours",
    )
    first, second = edge_positions(problem, pairwise)
    d1 = cdist(first, first)
    d2 = cdist(second, second)
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
    sigma2: float | None,
    sigma_scale: float | None = None,
    pairwise: str = "positions",
    neighbours: int | None = NEIGHBOURS,
) -> np.ndarray | sp.csr_matrix:
    """The pairwise options of SM/RRWM/MOS: ``affinity`` — a precomputed (nm, nm) non-negative
    matrix (dense or scipy sparse) in the a = i*m + j convention, checked (``sigma2`` is then
    unused, as it always was; ``sigma_scale`` or ``pairwise="image"`` with it is an error) — or
    (None) the affinity in space ``pairwise`` with the width of :func:`kernel_sigma2` (``sigma2``
    absolute, default 0.5, or ``sigma_scale`` relative): dense (:func:`pairwise_affinity`) while a
    candidate match has at most ``neighbours`` partners ((n-1)(m-1) <= neighbours; always with
    ``neighbours=None``), else sparse (:func:`sparse_pairwise_affinity`)."""
    size = problem.n1 * problem.n2
    if affinity is None:
        width = kernel_sigma2(problem, sigma2, sigma_scale, pairwise)
        if neighbours is None or (problem.n1 - 1) * (problem.n2 - 1) <= neighbours:
            return pairwise_affinity(problem, width, pairwise)
        return sparse_pairwise_affinity(problem, width, neighbours, pairwise)
    if sigma_scale is not None or pairwise != "positions":
        raise ValueError("affinity: a precomputed affinity takes no sigma_scale or pairwise option")
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
