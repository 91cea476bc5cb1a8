"""``transitive``: greedy merging of pairwise matches under the cycle constraint."""

from __future__ import annotations

import time

import numpy as np

from matchers.fusion.evidence import PairwiseEvidence
from matchers.fusion.universe import Universe, from_labels


def transitive(evidence: PairwiseEvidence) -> Universe:
    """Greedy transitive closure with the one-detection-per-view constraint, the pairwise
    baseline of the multi-view matching literature (e.g. the "pairwise + transitive" reference
    of Fathian et al., CLEAR, T-RO 2020; also QuickMatch's merge rule, Tron et al., ICCV 2017
    workshops): every declared match, strongest score first (ties by view pair, then rows), joins
    its two detections' objects unless the joined object would hold two detections of one view;
    a match that would is dropped. Consistent by construction; the count is the objects left."""
    started = time.perf_counter()
    a, b, score = evidence.edges()
    view = evidence.view_of()
    n_views = len(evidence.sizes)
    parent = np.arange(evidence.total)
    members = np.zeros((evidence.total, n_views), dtype=bool)  # views held, per root
    members[np.arange(evidence.total), view] = True

    def root(x: int) -> int:
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    for e in np.lexsort((b, a, -score)):  # strongest first, then by rows (a encodes the view)
        ra, rb = root(int(a[e])), root(int(b[e]))
        if ra == rb or (members[ra] & members[rb]).any():
            continue
        keep, gone = (ra, rb) if ra < rb else (rb, ra)
        parent[gone] = keep
        members[keep] |= members[gone]
    while True:  # every row to its root: follow the parents until they stop changing
        grand = parent[parent]
        if np.array_equal(grand, parent):
            break
        parent = grand
    return from_labels(evidence, parent, "transitive", started)


transitive.deterministic = True
transitive.memory_bytes = lambda evidence: (
    8.0 * evidence.total * (len(evidence.sizes) + 8)
    + 32.0 * sum(len(m) for m in evidence.matches.values())
)  # labels, edges and the pairs: bytes
