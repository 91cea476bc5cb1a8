"""``independent``: no fusion — every pair of views keeps its own two-view matching."""

from __future__ import annotations

import time

from matchers.fusion.evidence import PairwiseEvidence
from matchers.fusion.universe import Universe, canonical_labels, components


def independent(evidence: PairwiseEvidence) -> Universe:
    """The baseline: the pairs are the input's declared matches, unchanged (so they may
    contradict each other around a cycle: A-B, B-C but not A-C). Its objects are the connected
    components of the match graph (what chaining the pairwise matches would merge), which is
    what its count and universe clustering are scored on."""
    started = time.perf_counter()
    flat = canonical_labels(components(evidence))
    off = evidence.offsets
    labels = tuple(flat[off[k] : off[k + 1]] for k in range(len(evidence.sizes)))
    count = int(flat.max()) + 1 if flat.size else 0
    pairs = {key: m.copy() for key, m in evidence.matches.items()}
    return Universe(labels, count, pairs, False, "independent", time.perf_counter() - started)


independent.deterministic = True
independent.memory_bytes = lambda evidence: (
    48.0 * evidence.total + 32.0 * sum(len(m) for m in evidence.matches.values())
)  # labels, edges and the pairs: bytes
