"""Building the third-order tensor of a problem: triangles, k-NN candidate search, values.

Two recipes (``tensor=`` on every hypergraph matcher):

``"paper"`` (default) — the maximin paper, Eq. (1): descriptor = cosines of the three interior
    angles (3-D angles in 3-D), value exp(-(1/sigma) * sum_p |cos(theta_p) - cos(theta_p')|) with
    sigma = 0.5, where the sum runs over the three corresponding vertex pairs (p, p') — the pairing
    the tensor index (ii', jj', kk') encodes. Candidate triangle pairs by k-NN in descriptor space
    with the same L1 distance; k = n*m neighbours per triangle (the paper's "k = n^2" with n^2 read
    as n*n', the number of candidate matches) and n*m sampled triangles, so the tensor holds
    O((nm)^2) = O(n^4) entries before de-duplication, as the paper's complexity paragraph states.
``"duchenne"`` — the recipe of the published TM/RRWHM/BCAGM benchmarks: descriptor = signed sines
    of the interior angles (|sin| in 3-D, see :func:`~matchers.triangles.signed_sines`), Euclidean
    k-NN, value exp(-d / mean(d)) with d the feature distance and the mean over all returned
    neighbours (data-adaptive bandwidth), n*m sampled triangles and n*m neighbours per triangle
    (the BCAGM benchmark's ``createTensor.m``: nNN = nT = n1*n2).

For both: distinct triangles are sampled (without replacement) in the view with fewer objects
(view 1 on a tie) — all C(n, 3) when there are no more than the requested count — and matched against every ordered triple of
distinct objects of the other view (so each vertex correspondence is tried), with scipy's
cKDTree (exact search, both cores) on descriptors rounded to 1e-9. k is capped at the number of
valid ordered triples. Candidates tied with the k-th distance are chosen by the tree's internal
order: the result is invariant to similarity transforms of either view, but relabelling the
objects can swap which of several equal-valued tied candidates are kept. Triangles
with coincident vertices are skipped. Because the sampled triangles are distinct and the other
view's ordered triples are distinct, no match triple can come up twice, so the builder skips the
de-duplication sort of :meth:`SparseTensor.from_entries` (a test checks that claim).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from .problem import Problem
from .sparse_tensor import SparseTensor
from .triangles import angle_cosines, ordered_descriptors, sample_triangles, signed_sines

_DECIMALS = 9
Descriptor = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class TensorRecipe:
    """How to turn triangle descriptors into tensor entries."""

    name: str
    descriptor: Descriptor
    minkowski_p: int  # 1: L1 (paper, Eq. 1); 2: Euclidean (Duchenne)
    sigma: float | None  # fixed bandwidth, or None for mean neighbour distance
    signed_in_2d: bool  # descriptor changes sign when a 2-D triangle's orientation reverses


RECIPES: dict[str, TensorRecipe] = {
    "paper": TensorRecipe("paper", angle_cosines, 1, 0.5, False),
    "duchenne": TensorRecipe("duchenne", signed_sines, 2, None, True),
}


def build_tensor(
    problem: Problem,
    recipe: str = "paper",
    rng: np.random.Generator | int | None = 0,
    triangles: int | None = None,
    neighbours: int | None = None,
    sigma: float | None = None,
) -> SparseTensor:
    """Third-order tensor of ``problem`` by ``recipe`` ("paper" or "duchenne").

    triangles: number of sampled triangles (default n*m); neighbours: k of the k-NN search per
    triangle (default n*m); sigma: bandwidth override (default: the recipe's). The tensor's
    ``info`` records the recipe, counts, bandwidth and ``build_s`` (seconds). ``rng`` (a numpy
    Generator or seed) drives the triangle sampling. Fewer than 3 objects in a view, or no
    non-degenerate triangle, gives an empty tensor.
    """
    if recipe not in RECIPES:
        raise ValueError(f"tensor: unknown recipe {recipe!r}; expected one of {sorted(RECIPES)}")
    spec = RECIPES[recipe]
    for label, value in (("triangles", triangles), ("neighbours", neighbours)):
        if value is not None and (not isinstance(value, int | np.integer) or value < 1):
            raise ValueError(f"{label}: expected a positive integer or None, got {value!r}")
    if sigma is not None and not sigma > 0:
        raise ValueError(f"sigma: expected a positive number or None, got {sigma!r}")
    started = time.perf_counter()
    rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    n, m = problem.n1, problem.n2
    info = {"recipe": recipe}
    if n < 3 or m < 3:
        return SparseTensor.empty(n, m, info | {"entries_raw": 0})
    swap = m < n  # sample in the smaller view
    sampled_pts, full_pts = (
        (problem.points2, problem.points1) if swap else (problem.points1, problem.points2)
    )
    n_tri = triangles if triangles is not None else n * m
    k = neighbours if neighbours is not None else n * m

    tri_s = sample_triangles(len(sampled_pts), n_tri, rng)
    desc_s, valid_s = spec.descriptor(sampled_pts, tri_s)
    tri_s, desc_s = tri_s[valid_s], desc_s[valid_s]
    oriented = spec.signed_in_2d and problem.dim == 2
    tri_f, desc_f, valid_f = ordered_descriptors(full_pts, spec.descriptor, oriented)
    tri_f, desc_f = tri_f[valid_f], desc_f[valid_f]
    k = min(k, len(tri_f))
    if not len(tri_s) or k == 0:
        return SparseTensor.empty(n, m, info | {"entries_raw": 0})

    # Rounded to 1e-9, far below any meaningful difference: a rotation/translation/scaling of a
    # view perturbs descriptors by ~1e-16, and rounding makes them bit-identical, so the k-NN
    # choice — including which of several exactly tied candidates (common under the L1 metric,
    # where swapping two vertices often leaves the distance unchanged) fill the last places —
    # does not change under those transforms.
    desc_s, desc_f = np.round(desc_s, _DECIMALS), np.round(desc_f, _DECIMALS)
    tree = cKDTree(desc_f, balanced_tree=False, compact_nodes=False)
    dist, idx = tree.query(desc_s, k=k, p=spec.minkowski_p, workers=-1)
    dist, idx = dist.reshape(len(tri_s), k), idx.reshape(len(tri_s), k)
    bandwidth = sigma if sigma is not None else spec.sigma
    if bandwidth is None:
        mean = float(dist.mean())
        bandwidth = mean if mean > 0 else 1.0
    values = np.exp(-dist / bandwidth).reshape(-1)

    matches = np.empty((3, len(tri_s), k), dtype=np.int64)  # slot-major: no copy downstream
    for f in range(3):
        mine = tri_s[:, f][:, None]  # (T, 1)
        theirs = np.take(np.ascontiguousarray(tri_f[:, f]), idx)  # (T, k)
        if swap:
            np.add(theirs * m, mine, out=matches[f])
        else:
            np.add(mine * m, theirs, out=matches[f])
    info |= {
        "triangles": int(len(tri_s)),
        "neighbours": int(k),
        "bandwidth": float(bandwidth),
        "entries_raw": int(values.size),
        "build_s": time.perf_counter() - started,
    }
    # distinct sampled triangles x distinct ordered triples => no triple occurs twice
    return SparseTensor.from_entries(
        matches.reshape(3, -1).T, values, n, m, info, assume_unique=True
    )


def resolve_tensor(
    problem: Problem,
    tensor: str | SparseTensor,
    rng: np.random.Generator,
    triangles: int | None,
    neighbours: int | None,
    sigma: float | None,
) -> SparseTensor:
    """The ``tensor=`` option of the hypergraph matchers: a recipe name, or a prebuilt tensor
    (so that several matchers can be run on exactly the same tensor)."""
    if isinstance(tensor, SparseTensor):
        if (tensor.n, tensor.m) != (problem.n1, problem.n2):
            raise ValueError(
                f"tensor: built for {tensor.n} x {tensor.m} objects, problem has "
                f"{problem.n1} x {problem.n2}"
            )
        return tensor
    if not isinstance(tensor, str):
        raise ValueError(f"tensor: expected a recipe name or a SparseTensor, got {tensor!r}")
    return build_tensor(problem, tensor, rng, triangles, neighbours, sigma)
