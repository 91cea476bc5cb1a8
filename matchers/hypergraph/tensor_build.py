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
    of the interior angles (|sin| in 3-D, see :func:`~matchers.hypergraph.triangles.signed_sines`), Euclidean
    k-NN, value exp(-d / mean(d)) with d the feature distance and the mean over all returned
    neighbours (data-adaptive bandwidth), n*m sampled triangles and n*m neighbours per triangle
    (the BCAGM benchmark's ``createTensor.m``: nNN = nT = n1*n2).

For both: distinct triangles are sampled (without replacement) in the view with fewer objects
(view 1 on a tie) — all C(n, 3) when there are no more than the requested count — and matched
against every ordered triple of distinct objects of the other view (so each vertex correspondence is tried), on descriptors
rounded to 1e-9, by the exact brute-force search of :mod:`matchers.hypergraph.candidate_search`:
each triangle's k nearest, ties broken by candidate index, in index order — so the tensor, entry
order included, depends on the descriptors alone, never on a tree's traversal or the CPU; k is
capped at the number of valid ordered triples. The result is invariant to similarity transforms
of either view; relabelling the objects can change which of several exactly tied candidates are
kept (the lower index wins). Triangles with coincident vertices are skipped. Because the sampled triangles are distinct and the other
view's ordered triples are distinct, no match triple can come up twice, so the builder skips the
de-duplication sort of :meth:`SparseTensor.from_entries` (a test checks that claim).

Bounded size (``max_entries``, default :data:`MAX_ENTRIES` = 1,000,000 = 1000^2): with the defaults
a tensor has (n*m)^2 entries, 10^8 at 100 vs 100. When triangles x neighbours exceeds the cap,
the builder keeps the ``max_entries`` highest-valued entries of the tensor it would otherwise
build — the same sampled triangles and the same per-triangle k-NN lists, ranked globally by
descriptor distance (the value is a decreasing function of it) — without forming that tensor:
a sample of the queries (every triangle in each of its 6 vertex orders) picks a radius that
should hold about 1.25x the cap, and one dual-tree search returns every pair within it
(:func:`_radius_pool`); where the sample cannot vouch for the radius (heavy ties, or dense
neighbourhoods it cannot see the end of), each query is instead asked for about twice its share
of neighbours and only those whose last neighbour is still inside the running global cut are
asked again for more (4x, up to k). Ties at the cut are broken by (query, candidate index), and
the kept entries ordered by (triangle, query, candidate index), so the tree's order never
shows. With the defaults the cap binds exactly when n*m > 1000, so every problem up to 1000 candidate matches gets the paper's tensor unchanged.
The "duchenne" bandwidth is then the mean over the kept entries.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from matchers.core.jit import njit
from matchers.core.memory_budget import check_memory
from matchers.core.portable_exp import decay
from matchers.core.problem import Problem
from matchers.core.row_threads import split_rows
from matchers.hypergraph.candidate_search import nearest
from matchers.hypergraph.sparse_tensor import SparseTensor
from matchers.hypergraph.tensor_sharing import build_or_reuse
from matchers.hypergraph.triangles import (
    PERMUTATIONS,
    all_triangles,
    angle_cosines,
    ordered_descriptors,
    sample_triangles,
    signed_sines,
)

_DECIMALS = 9
MAX_ENTRIES = 1_000_000
"""Default cap on tensor entries: 1000^2, the size of the paper's tensor at n*m = 1000 (a cap of
250,000 cost RRWHM 0.10 and BCAGM 0.07 F1 on 24 dense CoID pairs; this one none, docs/matchers.md)."""
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
    max_entries: int | None = MAX_ENTRIES,
) -> SparseTensor:
    """Third-order tensor of ``problem`` by ``recipe`` ("paper" or "duchenne").

    triangles: number of sampled triangles (default n*m); neighbours: k of the k-NN search per
    triangle (default n*m); sigma: bandwidth override (default: the recipe's); max_entries: cap
    on triangles x neighbours (default 1,000,000; None = no cap), keeping the highest-valued
    entries (module docstring). The tensor's ``info`` records the recipe, counts, bandwidth,
    whether the cap bound and ``build_s`` (seconds). ``rng`` (a numpy Generator or seed) drives
    the triangle sampling. Fewer than 3 objects in a view, or no non-degenerate triangle, gives
    an empty tensor.

    >>> tensor = build_tensor(Problem(points1, points2), "paper", rng=0)
    """
    if recipe not in RECIPES:
        raise ValueError(f"tensor: unknown recipe {recipe!r}; expected one of {sorted(RECIPES)}")
    spec = RECIPES[recipe]
    for label, value in (("triangles", triangles), ("neighbours", neighbours)):
        if value is not None and (not isinstance(value, int | np.integer) or value < 1):
            raise ValueError(f"{label}: expected a positive integer or None, got {value!r}")
    if sigma is not None and not sigma > 0:
        raise ValueError(f"sigma: expected a positive number or None, got {sigma!r}")
    if max_entries is not None and (
        isinstance(max_entries, bool) or not isinstance(max_entries, int | np.integer)
    ):
        raise ValueError(
            f"max_tensor_entries: expected a positive integer or None, got {max_entries!r}"
        )
    if max_entries is not None and max_entries < 1:
        raise ValueError(
            f"max_tensor_entries: expected a positive integer or None, got {max_entries!r}"
        )
    started = time.perf_counter()
    rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    n, m = problem.n1, problem.n2
    found, reused = build_or_reuse(
        problem,
        rng,
        (recipe, triangles, neighbours, max_entries),
        lambda: _candidates(problem, spec, rng, triangles, neighbours, max_entries),
    )
    info = {"recipe": recipe}
    if found.matches is None:
        return SparseTensor.empty(n, m, info | {"entries_raw": 0})
    bandwidth = sigma if sigma is not None else spec.sigma
    if bandwidth is None:
        mean = float(found.dist.mean())
        bandwidth = mean if mean > 0 else 1.0
    values = np.empty(found.dist.size)
    decay(found.dist.reshape(-1), float(bandwidth), values)  # exp(-d / bandwidth), portable
    info |= {
        "triangles": found.triangles,
        "neighbours": found.neighbours,
        "bandwidth": float(bandwidth),
        "entries_raw": int(values.size),
        "capped": found.capped,
        "max_entries": max_entries,
        "build_s": time.perf_counter() - started + (found.search_s if reused else 0.0),
    }
    if (
        reused
    ):  # the search was another matcher's (matchers.hypergraph.tensor_sharing): charge it here
        info |= {"reused": True, "reused_s": found.search_s}
    # distinct sampled triangles x distinct ordered triples => no triple occurs twice
    return SparseTensor.from_entries(
        found.matches.reshape(3, -1).T, values, n, m, info, assume_unique=True
    )


@dataclass(frozen=True)
class Candidates:
    """The k-NN search's result, before values: ``matches`` (3, ...) match indices of slot 0, 1,
    2 (None: no tensor), ``dist`` the descriptor distances (same shape), the counts, and
    ``search_s`` the seconds it took. It does not depend on the bandwidth, so matchers that
    differ only in ``sigma`` can share it."""

    matches: np.ndarray | None
    dist: np.ndarray | None
    triangles: int = 0
    neighbours: int = 0
    capped: bool = False
    search_s: float = 0.0


def _candidates(
    problem: Problem,
    spec: TensorRecipe,
    rng: np.random.Generator,
    triangles: int | None,
    neighbours: int | None,
    max_entries: int | None,
) -> Candidates:
    """Sample the triangles (``rng``'s only draw) and find their k-NN candidate triples."""
    started = time.perf_counter()
    n, m = problem.n1, problem.n2
    none = Candidates(None, None)
    if n < 3 or m < 3:
        return none
    swap = m < n  # sample in the smaller view
    sampled_pts, full_pts = (
        (problem.points2, problem.points1) if swap else (problem.points1, problem.points2)
    )
    n_tri = triangles if triangles is not None else n * m
    k = neighbours if neighbours is not None else n * m
    _check_tensor_memory(n, m, len(sampled_pts), len(full_pts), n_tri, k, max_entries)

    tri_s = sample_triangles(len(sampled_pts), n_tri, rng)
    desc_s, valid_s = spec.descriptor(sampled_pts, tri_s)
    tri_s, desc_s = tri_s[valid_s], desc_s[valid_s]
    oriented = spec.signed_in_2d and problem.dim == 2
    if not len(tri_s):
        return none
    ordered = 6 * math.comb(len(full_pts), 3)
    capped = max_entries is not None and len(tri_s) * min(k, ordered) > max_entries
    if capped:  # the count of valid ordered triples decides
        base = all_triangles(len(full_pts))
        base_desc, base_valid = spec.descriptor(full_pts, base)
        base, base_desc = base[base_valid], base_desc[base_valid]
        capped = len(tri_s) * min(k, 6 * len(base)) > max_entries

    matches = None
    if not capped:  # the paper's tensor, exactly
        tri_f, desc_f, valid_f = ordered_descriptors(full_pts, spec.descriptor, oriented)
        tri_f, desc_f = tri_f[valid_f], desc_f[valid_f]
        k = min(k, len(tri_f))
        if k == 0:
            return none
        # Rounded to 1e-9, far below any meaningful difference: a rotation/translation/scaling
        # of a view perturbs descriptors by ~1e-16, and rounding makes them bit-identical, so
        # the k-NN choice — including which of several exactly tied candidates (common under
        # the L1 metric, where swapping two vertices often leaves the distance unchanged) fill
        # the last places — does not change under those transforms.
        desc_s, desc_f = np.round(desc_s, _DECIMALS), np.round(desc_f, _DECIMALS)
        dist, idx = nearest(desc_s, desc_f, k, spec.minkowski_p)
        if _match_indices_jit is not None:
            matches = np.empty((3, *idx.shape), dtype=np.int64)

            def job(lo: int, hi: int) -> None:
                _match_indices_jit(tri_s[lo:hi], tri_f, idx[lo:hi], m, swap, matches[:, lo:hi])

            split_rows(job, len(idx), idx.size * 8)
        else:
            mine = tri_s[:, :, None]  # (T, 3, 1)
            theirs = [np.take(np.ascontiguousarray(tri_f[:, f]), idx) for f in range(3)]  # (T, k)
    else:
        k = min(k, 6 * len(base))
        rows, dist, theirs = _capped_candidates(
            base, base_desc, desc_s, k, max_entries, spec.minkowski_p, oriented
        )
        mine = tri_s[rows]  # (E, 3)
    if matches is None:  # slot-major (3, ...): the tensor's column-major indices need no copy
        matches = np.empty((3, *dist.shape), dtype=np.intp)
        for f in range(3):
            mine_f = mine[:, f]  # (T, 1) or (E,)
            if swap:
                np.add(theirs[f] * m, mine_f, out=matches[f])
            else:
                np.add(mine_f * m, theirs[f], out=matches[f])
    return Candidates(
        matches, dist, int(len(tri_s)), int(k), bool(capped), time.perf_counter() - started
    )


def _match_indices(
    tri_s: np.ndarray, tri_f: np.ndarray, idx: np.ndarray, m: int, swap: bool, out: np.ndarray
) -> None:
    # into out (3, T, k): match indices a = i*m + j of sampled triangle t's vertex f paired with
    # vertex f of its neighbour idx[t, q] (view 1 index first: swapped when view 2 was sampled)
    count, k = idx.shape
    for t in range(count):
        for q in range(k):
            other = idx[t, q]
            for f in range(3):
                if swap:
                    out[f, t, q] = tri_f[other, f] * m + tri_s[t, f]
                else:
                    out[f, t, q] = tri_s[t, f] * m + tri_f[other, f]


_match_indices_jit = njit(_match_indices)


# Working bytes per stored entry (distances, neighbour indices, the three match indices, the value
# and the sparse tensor's sort/dedup copies) and per ordered triple of the searched view
# (vertex triple, descriptor, k-d tree); measured peaks stay below these.
_BYTES_PER_ENTRY = 160
_BYTES_PER_TRIPLE = 96


def planned_entries(
    sampled: int, full: int, triangles: int, k: int, max_entries: int | None
) -> tuple[int, int, bool]:
    """(entries, triangles searched, capped) of a build that samples `triangles` triangles among
    `sampled` objects and searches k candidates among the triangles of `full` objects: the
    uncapped search reads every ordered triple, the capped one the unordered base."""
    ordered = 6 * math.comb(full, 3)
    entries = min(triangles, math.comb(sampled, 3)) * min(k, ordered)
    if max_entries is not None and entries > max_entries:
        return max_entries, math.comb(full, 3), True
    return entries, ordered, False


def _check_tensor_memory(
    n: int, m: int, sampled: int, full: int, triangles: int, k: int, max_entries: int | None
) -> None:
    """Refuse (``ProblemTooLarge``) a tensor whose build would exceed the memory budget."""
    entries, triples, _ = planned_entries(sampled, full, triangles, k, max_entries)
    check_memory(
        f"third-order tensor ({n} x {m} objects: {entries:,} entries, {triples:,} triangles "
        "searched)",
        entries * _BYTES_PER_ENTRY + triples * _BYTES_PER_TRIPLE,
        "max_tensor_entries, triangles or neighbours",
    )


def _capped_candidates(
    base: np.ndarray,
    base_desc: np.ndarray,
    desc_s: np.ndarray,
    k: int,
    cap: int,
    p: int,
    oriented: bool,
) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """The capped k-NN lists: (triangle row, distance, [vertex f of the matched ordered triple
    of the other view for f = 0, 1, 2]) of the ``cap`` best (triangle, ordered triple) pairs.

    The other view's ordered triples are its valid triangles ``base`` in the 6 vertex orders of
    :data:`PERMUTATIONS`; instead of a tree over all 6 (6x the points to index), the tree holds
    ``base`` once and each sampled triangle asks it 6 times, its descriptor permuted back:
    |a - s c[P]| summed over vertices equals |s a[P^-1] - c| (s = -1 for a 2-D signed
    descriptor in a reversing order); a triangle keeps at most k pairs, as uncapped."""
    count = len(desc_s)
    signs = (1, 1, 1, -1, -1, -1) if oriented else (1,) * 6
    queries = np.concatenate(
        [desc_s[:, np.argsort(perm)] * sign for perm, sign in zip(PERMUTATIONS, signs, strict=True)]
    )
    tree = cKDTree(np.round(base_desc, _DECIMALS), balanced_tree=False, compact_nodes=False)
    groups = np.tile(np.arange(count), 6)
    query, dist, idx = capped_neighbours(
        tree, np.round(queries, _DECIMALS), groups, k, min(k, len(base)), cap, p
    )
    order, rows = np.divmod(query, count)
    flat, at = base.reshape(-1), idx * 3  # base[idx, PERMUTATIONS[order, f]], one 1-D gather
    theirs = [np.take(flat, at + np.take(PERMUTATIONS[:, f], order)) for f in range(3)]
    return rows, dist, theirs


def capped_neighbours(
    tree: cKDTree,
    queries: np.ndarray,
    groups: np.ndarray,
    k: int,
    per_query: int,
    cap: int,
    p: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The ``cap`` best pairs of the uncapped k-NN lists, without forming those lists.

    Query q belongs to group ``groups[q]`` (a sampled triangle; its 6 vertex orders are 6
    queries); a group's uncapped list is the k nearest over its queries' neighbours, each query
    contributing at most ``per_query``. Every query starts with about twice its share of ``cap``
    neighbours; one whose farthest neighbour is still within both the running cut (the cap-th
    smallest distance of the pool) and its group's k-th smallest is asked again for 4x as many.
    A query not asked again holds every neighbour that could still be kept, so the result is
    the uncapped lists' ``cap`` smallest distances (ties: lowest (query, index) first). The pool
    comes from one radius search instead when a sample vouches for the radius
    (:func:`_radius_pool`); it then holds every pair within the radius, which is beyond the cut.
    Returns (query, distance, neighbour index) of the kept pairs, grouped by group.
    """
    count = len(queries)
    first = min(per_query, max(1, -(-2 * cap // count)))
    pool = _radius_pool(tree, queries, groups, k, per_query, cap, p, first)
    if pool is not None:
        pool_query, pool_dist, pool_idx = pool
        cut = np.partition(pool_dist, cap - 1)[cap - 1] if pool_dist.size > cap else np.inf
    else:
        pool_query, pool_dist, pool_idx, cut = _grown_pool(
            tree, queries, groups, k, per_query, cap, p, first
        )
    if pool_dist.size > cap:
        inside = pool_dist < cut
        tied = np.flatnonzero(pool_dist == cut)
        tied = tied[np.lexsort((pool_idx[tied], pool_query[tied]))]  # canonical: (query, index)
        inside[tied[: cap - int(inside.sum())]] = True
        pool_query, pool_dist, pool_idx = pool_query[inside], pool_dist[inside], pool_idx[inside]
    order = np.lexsort((pool_idx, pool_query, groups[pool_query]))  # search order never shows
    return pool_query[order], pool_dist[order], pool_idx[order]


_SAMPLED_QUERIES = 2000  # queries asked first to choose the radius


def _radius_pool(tree, queries, groups, k, per_query, cap, p, first):
    """Every pair within a radius r chosen to hold about 1.25 * cap of them (from 4 * ``first``
    neighbours of every (count / 2000)-th query), limited to ``per_query`` per query and k per
    group, by one dual-tree search (``sparse_distance_matrix``: 2-4x cheaper than asking every
    query for its neighbours); None when the sample cannot vouch for r (ties at r, or over 10 %
    of the sampled queries with all their neighbours within r — the density is then unknown and
    the search could return far more pairs than the memory budget allows) or the pool falls
    short of cap."""
    count = len(queries)
    step = max(1, count // _SAMPLED_QUERIES)
    deep = min(per_query, 4 * first)  # the sample looks 4x deeper than a query's share
    sampled, _ = tree.query(queries[::step], k=deep, p=p, workers=-1)
    sampled = sampled.reshape(-1, deep)
    want = -(-5 * cap * len(sampled) // (4 * count))  # sampled pairs within r
    ranked = np.sort(sampled.reshape(-1))
    if want >= ranked.size:
        return None
    radius = ranked[want - 1]
    if (
        np.mean(sampled[:, -1] <= radius) > 0.1
        or np.searchsorted(ranked, radius, "right") > 2 * want
    ):
        return None
    found = cKDTree(queries, balanced_tree=False, compact_nodes=False).sparse_distance_matrix(
        tree, radius, p=p, output_type="ndarray"
    )
    pool_query, pool_idx, pool_dist = found["i"], found["j"], found["v"]
    for label, limit in ((pool_query, per_query), (groups[pool_query], k)):
        keep, _ = _group_best(label, pool_dist, pool_query, pool_idx, limit)
        if keep is not None:
            pool_query, pool_dist, pool_idx = pool_query[keep], pool_dist[keep], pool_idx[keep]
    if pool_dist.size < cap:
        return None
    return pool_query, pool_dist, pool_idx


def _grown_pool(tree, queries, groups, k, per_query, cap, p, first):
    """The pool of :func:`capped_neighbours` grown query by query (the fallback of
    :func:`_radius_pool`): every query asks for ``first`` neighbours, and one whose farthest is
    still within both the running cut and its group's k-th smallest asks again for 4x as many.
    Returns (query, distance, index, cut)."""
    count = len(queries)
    dist, idx = tree.query(queries, k=first, p=p, workers=-1)
    pool_query = np.repeat(np.arange(count), first)
    pool_dist, pool_idx = dist.reshape(-1), idx.reshape(-1)
    asked = np.full(count, first)
    farthest = dist.reshape(count, first)[:, -1].copy()
    while True:
        keep, group_kth = _group_best(
            groups[pool_query], pool_dist, pool_query, pool_idx, k, int(groups.max()) + 1
        )
        if keep is not None:
            pool_query, pool_dist, pool_idx = pool_query[keep], pool_dist[keep], pool_idx[keep]
        cut = np.partition(pool_dist, cap - 1)[cap - 1] if pool_dist.size > cap else np.inf
        again = np.flatnonzero(
            (asked < per_query) & (farthest <= np.minimum(cut, group_kth[groups]))
        )
        if not again.size:
            break
        more = min(per_query, 4 * int(asked[again].max()))
        dist, idx = tree.query(queries[again], k=more, p=p, workers=-1)
        stale = np.zeros(count, dtype=bool)
        stale[again] = True
        fresh = ~stale[pool_query]
        pool_query = np.concatenate([pool_query[fresh], np.repeat(again, more)])
        pool_dist = np.concatenate([pool_dist[fresh], dist.reshape(-1)])
        pool_idx = np.concatenate([pool_idx[fresh], idx.reshape(-1)])
        asked[again], farthest[again] = more, dist.reshape(len(again), more)[:, -1]
    return pool_query, pool_dist, pool_idx, cut


def _group_best(
    group: np.ndarray,
    dist: np.ndarray,
    query: np.ndarray,
    idx: np.ndarray,
    k: int,
    groups: int | None = None,
):
    """(mask of the pool entries among their group's k smallest distances — ties: lowest
    (query, index) first — or None when that is all of them, each group's k-th smallest
    distance or inf if it has fewer than k)."""
    groups = int(group.max(initial=0)) + 1 if groups is None else groups
    size = np.bincount(group, minlength=groups)
    kth = np.full(groups, np.inf)
    if size.max(initial=0) <= k:
        return None, kth
    ranked = np.lexsort((idx, query, dist, group))
    rank = np.empty(len(dist), dtype=np.int64)
    rank[ranked] = np.arange(len(dist)) - np.repeat(np.cumsum(size) - size, size)
    full = rank == k - 1
    kth[group[full]] = dist[full]
    return rank < k, kth


def resolve_tensor(
    problem: Problem,
    tensor: str | SparseTensor,
    rng: np.random.Generator,
    triangles: int | None,
    neighbours: int | None,
    sigma: float | None,
    max_entries: int | None = MAX_ENTRIES,
) -> SparseTensor:
    """The ``tensor=`` option of the hypergraph matchers: a recipe name, or a prebuilt tensor
    (so that several matchers can be run on exactly the same tensor). A recipe's k-NN search is
    reused inside :func:`matchers.shared_tensors`."""
    if isinstance(tensor, SparseTensor):
        if (tensor.n, tensor.m) != (problem.n1, problem.n2):
            raise ValueError(
                f"tensor: built for {tensor.n} x {tensor.m} objects, problem has "
                f"{problem.n1} x {problem.n2}"
            )
        return tensor
    if not isinstance(tensor, str):
        raise ValueError(f"tensor: expected a recipe name or a SparseTensor, got {tensor!r}")
    return build_tensor(problem, tensor, rng, triangles, neighbours, sigma, max_entries)
