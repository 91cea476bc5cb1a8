"""A multi-way fusion's result: every detection assigned to a universe object."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from matchers.fusion.evidence import PairwiseEvidence


@dataclass(frozen=True)
class Universe:
    """labels: per view, the universe object of each detection (0..count-1); count: distinct
    objects; pairs: (i, j) -> (K, 2) the matches it implies between views i < j (for a fused
    result: same label; for ``independent``: the input's matches, possibly inconsistent);
    fused: whether pairs follow from the labels (cycle-consistent by construction); method and
    time_s (seconds) as the fusion reports."""

    labels: tuple[np.ndarray, ...]
    count: int
    pairs: dict[tuple[int, int], np.ndarray]
    fused: bool
    method: str
    time_s: float = 0.0


def canonical_labels(flat: np.ndarray) -> np.ndarray:
    """Labels renumbered 0, 1, ... in order of first appearance (global row order)."""
    _, first, inverse = np.unique(flat, return_index=True, return_inverse=True)
    rank = np.empty(len(first), dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(len(first))
    return rank[inverse.reshape(-1)]


def from_labels(
    evidence: PairwiseEvidence, flat: np.ndarray, method: str, started: float
) -> Universe:
    """The fused :class:`Universe` of global-row labels ``flat``: pairs between every two views
    are the detections sharing a label (a view may hold a label at most once)."""
    import time

    flat = canonical_labels(np.asarray(flat, dtype=np.int64))
    off = evidence.offsets
    labels = tuple(flat[off[k] : off[k + 1]] for k in range(len(evidence.sizes)))
    if any(len(np.unique(view)) != len(view) for view in labels):
        raise ValueError(f"{method}: a universe object holds two detections of one view")
    count = int(flat.max()) + 1 if flat.size else 0
    pairs = {}
    for i in range(len(labels)):
        for j in range(i + 1, len(labels)):
            slot_j = np.full(count, -1, dtype=np.int64)
            slot_j[labels[j]] = np.arange(len(labels[j]))
            rows = np.flatnonzero(slot_j[labels[i]] >= 0)
            pairs[(i, j)] = np.stack([rows, slot_j[labels[i][rows]]], axis=1).astype(np.int64)
    return Universe(labels, count, pairs, True, method, time.perf_counter() - started)


def components(evidence: PairwiseEvidence) -> np.ndarray:
    """Global-row labels of the connected components of the declared-match graph."""
    a, b, _ = evidence.edges()
    n = evidence.total
    graph = coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n))
    return connected_components(graph, directed=False)[1] if n else np.empty(0, np.int64)
