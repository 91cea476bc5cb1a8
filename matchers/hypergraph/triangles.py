"""Triangles (hyperedges) of a view and their descriptors.

A triangle is an ordered triple (t0, t1, t2) of distinct object indices. Descriptors have one
component per vertex, in the triangle's vertex order, so that matching triangle (i, j, k) of view 1
to (i', j', k') of view 2 compares vertex i with i', j with j' and k with k'.
A triangle with two coincident vertices (edge shorter than 1e-9 of the view's extent) has no
defined angles: the descriptor functions flag it invalid and the tensor builder skips it.
"""

from __future__ import annotations

import math

import numpy as np

_COINCIDENT = 1e-9  # relative to the view's extent


PERMUTATIONS = np.array([[0, 1, 2], [1, 2, 0], [2, 0, 1], [0, 2, 1], [2, 1, 0], [1, 0, 2]])
"""The 6 vertex orders; the first three keep a triangle's orientation, the last three reverse it."""


def sample_triangles(n: int, count: int, rng: np.random.Generator) -> np.ndarray:
    """(k, 3) distinct unordered triangles of n objects (vertices increasing).

    All C(n, 3) of them if that is <= count, else ``count`` of them drawn uniformly without
    replacement. Distinct triangles guarantee that the tensor builder never produces the same
    match triple twice. Empty (0, 3) when n < 3 or count < 1."""
    if n < 3 or count < 1:
        return np.zeros((0, 3), dtype=np.int64)
    total = math.comb(n, 3)
    if total <= count:
        return all_triangles(n)
    chosen = np.sort(rng.choice(total, size=count, replace=False))
    return all_triangles(n)[chosen]


def all_triangles(n: int) -> np.ndarray:
    """(C(n, 3), 3) all unordered triangles, vertices increasing, in lexicographic order."""
    if n < 3:
        return np.zeros((0, 3), dtype=np.int64)
    i, j = np.triu_indices(n, 1)
    counts = n - 1 - j  # choices of k > j
    total = int(counts.sum())
    first = np.repeat(np.cumsum(counts) - counts, counts)
    k = np.repeat(j, counts) + 1 + (np.arange(total) - first)
    return np.stack([np.repeat(i, counts), np.repeat(j, counts), k], axis=1).astype(np.int64)


def ordered_triples(n: int) -> np.ndarray:
    """(n(n-1)(n-2), 3) every ordered triple of distinct vertices: each unordered triangle of
    :func:`all_triangles` in the 6 orders of :data:`PERMUTATIONS` (blocks of C(n, 3) rows)."""
    base = all_triangles(n)
    return np.concatenate([base[:, p] for p in PERMUTATIONS]) if len(base) else base


def _edges(points: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit vectors from each vertex to the next and to the previous one, and a validity mask."""
    corners = points[triangles]  # (k, 3, D)
    forward = np.roll(corners, -1, axis=1) - corners  # vertex f -> f+1
    length = np.linalg.norm(forward, axis=2)  # (k, 3): edge f -> f+1
    extent = float(np.ptp(points, axis=0).max()) if len(points) else 0.0
    valid = np.all(length > _COINCIDENT * extent, axis=1)
    safe = np.where(length > 0, length, 1.0)[..., None]
    to_next = forward / safe
    to_prev = -np.roll(to_next, 1, axis=1)  # vertex f -> f-1
    return to_next, to_prev, valid


def angle_cosines(points: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cosines of the interior angles at the three vertices (the paper's hyperedge, Eq. 1).

    Works in 2-D and 3-D (3-D angles: invariant to rotation, translation, scale and reflection).
    Returns ((k, 3) descriptors, (k,) bool valid)."""
    to_next, to_prev, valid = _edges(points, triangles)
    cosines = np.clip(np.einsum("kfd,kfd->kf", to_next, to_prev), -1.0, 1.0)
    return np.where(valid[:, None], cosines, 0.0), valid


def ordered_descriptors(
    points: np.ndarray, descriptor, oriented: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Descriptors of every ordered triple of ``points`` (the order of :func:`ordered_triples`),
    computed once per unordered triangle and permuted: a per-vertex descriptor follows its vertex;
    an ``oriented`` one (2-D signed sines) also changes sign when the order reverses the triangle.
    Returns (triples, descriptors, valid)."""
    base = all_triangles(len(points))
    desc, valid = descriptor(points, base)
    signs = (1, 1, 1, -1, -1, -1) if oriented else (1,) * 6
    triples = np.concatenate([base[:, p] for p in PERMUTATIONS]) if len(base) else base
    descs = np.concatenate([desc[:, p] * sg for p, sg in zip(PERMUTATIONS, signs, strict=True)])
    return triples, descs, np.tile(valid, 6)


def signed_sines(points: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Duchenne's descriptor: sine of the interior angle at each vertex.

    2-D: signed by the triangle's orientation (cross product of the unit edge vectors; all three
    positive for a counter-clockwise triple, negative for clockwise) — invariant to rotation,
    translation and scale, not to reflection, exactly as the published benchmarks.
    3-D: a triangle in space has no orientation without a reference normal (a rotation can turn it
    over), so the rigid-invariant analogue is the norm of the cross product, |sin| per vertex.
    Returns ((k, 3) descriptors, (k,) bool valid)."""
    to_next, to_prev, valid = _edges(points, triangles)
    if points.shape[1] == 2:
        sines = to_next[..., 0] * to_prev[..., 1] - to_next[..., 1] * to_prev[..., 0]
    else:
        sines = np.linalg.norm(np.cross(to_next, to_prev), axis=2)
    return np.where(valid[:, None], sines, 0.0), valid
