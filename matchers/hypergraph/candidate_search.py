"""Exact k-nearest-neighbour search among triangle descriptors, with canonical ties.

For each query row (a sampled triangle's descriptor) the ``k`` nearest rows of ``candidates`` (the
other view's ordered triples) by L1 or Euclidean distance, ties broken by candidate index, and
each list in candidate-index order. No tree promises that choice — which of several exactly
tied candidates a k-d tree keeps depends on its traversal — so the search is brute force: every
distance of a query is computed (the compiled path histograms their float64 bit patterns in the
same pass, 64 bins per octave), the k-th smallest is found by a selection inside the one bin
that holds it, and one more pass keeps everything strictly closer and then the lowest-indexed
candidates at exactly the k-th distance, in index order.

At every size the uncapped tensor meets (queries x k <= 10^6 entries) brute force is also the
fastest exact search, measured on two cores against a k-d tree made canonical (asked for a few
more than k, re-ranked): 20 v 20 (400 queries x 6,840 candidates, k = 400) 4.7 vs 60 ms,
25 v 40 (1,000 x 59,280, k = 1,000) 69 vs 440 ms, 10 v 100 (120 x 970,200, k = 1,000) 150 vs
210 ms — and 3.5 ms against 9 ms for the plain threaded cKDTree query it replaces at 20 v 20.
Two paths give the same result bit for bit: a compiled loop per query (numba,
:mod:`matchers.core.jit`; split over threads by :func:`matchers.core.row_threads.split_rows` —
rows are independent, so the split never changes a bit) and a numpy one over blocks of queries (:data:`BLOCK_CELLS` distances
at a time); both compute each distance with the same operations in the same order
(``(|d0| + |d1|) + |d2|`` or ``sqrt((d0*d0 + d1*d1) + d2*d2)``), and sqrt is correctly rounded
everywhere. ``tests/test_candidate_search.py`` compares them with a full lexicographic sort on
problems full of exact ties.
"""

from __future__ import annotations

import numpy as np

from matchers.core.jit import njit
from matchers.core.row_threads import split_rows

BLOCK_CELLS = 1 << 21
"""Distances the numpy path holds at once (16 MB of float64 per array)."""


def nearest(
    queries: np.ndarray, candidates: np.ndarray, k: int, p: int
) -> tuple[np.ndarray, np.ndarray]:
    """(distances (Q, k), candidate indices (Q, k)) of each query's k nearest candidates by the
    Minkowski ``p`` distance (1 or 2), ties broken by candidate index, each list in
    candidate-index order; descriptors are (Q, 3) and (F, 3) float64, 1 <= k <= F."""
    queries = np.ascontiguousarray(queries, dtype=np.float64)
    candidates = np.ascontiguousarray(candidates, dtype=np.float64)
    if p not in (1, 2):
        raise ValueError(f"p: expected 1 or 2, got {p!r}")
    if not 1 <= k <= len(candidates):
        raise ValueError(f"k: expected 1..{len(candidates)}, got {k!r}")
    if _nearest_jit is None:
        return nearest_numpy(queries, candidates, k, p)
    dist = np.empty((len(queries), k))
    idx = np.empty((len(queries), k), dtype=np.int64)

    def job(lo: int, hi: int) -> None:
        _nearest_jit(queries[lo:hi], candidates, k, p, dist[lo:hi], idx[lo:hi])

    split_rows(job, len(queries), len(queries) * len(candidates))
    return dist, idx


def nearest_numpy(
    queries: np.ndarray, candidates: np.ndarray, k: int, p: int
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`nearest` by numpy over blocks of queries (the path without numba)."""
    count, total = len(queries), len(candidates)
    dist_out = np.empty((count, k))
    idx_out = np.empty((count, k), dtype=np.int64)
    step = max(1, BLOCK_CELLS // total)
    for start in range(0, count, step):
        block = queries[start : start + step]
        dist = _distances(block, candidates, p)
        kth = np.partition(dist, k - 1, axis=1)[:, k - 1 : k]
        closer = dist < kth
        tied = dist == kth
        room = k - closer.sum(axis=1, keepdims=True)  # places left for the tied, lowest index first
        keep = closer | (tied & (np.cumsum(tied, axis=1) <= room))
        idx = np.nonzero(keep)[1].reshape(len(block), k)  # row-major: ascending index per row
        dist_out[start : start + step] = np.take_along_axis(dist, idx, axis=1)
        idx_out[start : start + step] = idx
    return dist_out, idx_out


def _distances(block: np.ndarray, candidates: np.ndarray, p: int) -> np.ndarray:
    # (B, F) distances
    return _combine([block[:, f, None] - candidates[None, :, f] for f in range(3)], p)


def _combine(parts: list[np.ndarray], p: int) -> np.ndarray:
    # the distance from its three coordinate differences, with the compiled kernel's operations
    # in its order
    if p == 1:
        return (np.abs(parts[0]) + np.abs(parts[1])) + np.abs(parts[2])
    return np.sqrt((parts[0] * parts[0] + parts[1] * parts[1]) + parts[2] * parts[2])


def _kth_smallest(buf: np.ndarray, size: int, kth: int) -> float:
    # the kth smallest (0-based) of buf[:size], by quickselect in place (median-of-three pivot)
    lo, hi = 0, size - 1
    while lo < hi:
        mid = (lo + hi) // 2
        a, b, c = buf[lo], buf[mid], buf[hi]
        pivot = max(min(a, b), min(max(a, b), c))
        i, j = lo, hi
        while i <= j:
            while buf[i] < pivot:
                i += 1
            while buf[j] > pivot:
                j -= 1
            if i <= j:
                buf[i], buf[j] = buf[j], buf[i]
                i += 1
                j -= 1
        if kth <= j:
            hi = j
        elif kth >= i:
            lo = i
        else:
            return buf[kth]
    return buf[kth]


_kth = njit(_kth_smallest) or _kth_smallest  # called by the compiled kernel


_LOW_EXPONENT = 1013  # float64 exponent field of 2**-10: smaller distances share the first bin
_BIN_SHIFT = 46  # 11 exponent + 6 mantissa bits: 64 bins per octave
_BINS = 14 * 64  # 2**-10 .. 2**4 (distances of unit-scale descriptors), larger in the last bin


def _nearest_kernel(
    queries: np.ndarray,
    candidates: np.ndarray,
    k: int,
    p: int,
    dist_out: np.ndarray,
    idx_out: np.ndarray,
):
    # per query: distances and a histogram over their float64 bit patterns (order-preserving for
    # non-negative numbers) in one pass; the bin holding the k-th smallest is then the only one
    # that needs a selection; one more pass keeps the candidates below it in index order
    count, total = queries.shape[0], candidates.shape[0]
    dist = np.empty(total)
    bits = dist.view(np.int64)
    bins = np.empty(total, dtype=np.int32)
    buf = np.empty(total + 1)
    pool = np.empty(total + 1, dtype=np.int64)
    hist = np.empty((4, _BINS), dtype=np.int32)  # 4 interleaved: no chain of increments
    low = np.int64(_LOW_EXPONENT) << np.int64(52 - _BIN_SHIFT)
    for q in range(count):
        a0, a1, a2 = queries[q, 0], queries[q, 1], queries[q, 2]
        hist[:] = 0
        for j in range(total):
            d0 = a0 - candidates[j, 0]
            d1 = a1 - candidates[j, 1]
            d2 = a2 - candidates[j, 2]
            if p == 1:
                d = (abs(d0) + abs(d1)) + abs(d2)
            else:
                d = np.sqrt((d0 * d0 + d1 * d1) + d2 * d2)
            dist[j] = d
            b = (bits[j] >> _BIN_SHIFT) - low
            b = min(max(b, 0), _BINS - 1)
            bins[j] = b
            hist[j & 3, b] += 1
        below = 0
        edge = 0
        while True:
            here = hist[0, edge] + hist[1, edge] + hist[2, edge] + hist[3, edge]
            if below + here >= k:
                break
            below += here
            edge += 1
        size = 0  # distances in the edge bin
        kept = 0  # candidates in bins up to the edge, in index order
        for j in range(total):  # branch-free: write always, advance when kept
            b = bins[j]
            pool[kept] = j
            kept += b <= edge
            buf[size] = dist[j]
            size += b == edge
        kth = _kth(buf, size, k - 1 - below)
        room = k - below  # places left for candidates at exactly the k-th distance
        for s in range(size):
            if buf[s] < kth:
                room -= 1
        filled = 0
        for s in range(kept):
            j = pool[s]
            d = dist[j]
            if d < kth or (d == kth and room > 0):
                if d == kth:
                    room -= 1
                dist_out[q, filled] = d
                idx_out[q, filled] = j
                filled += 1


_nearest_jit = njit(_nearest_kernel)
