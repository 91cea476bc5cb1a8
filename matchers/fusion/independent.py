"""``independent``: no fusion — every pair of views keeps its own two-view matching."""

from __future__ import annotations

import time

from matchers.fusion.evidence import PairwiseEvidence
from matchers.fusion.transitive import transitive
from matchers.fusion.universe import Universe


def independent(evidence: PairwiseEvidence) -> Universe:
    """The baseline: the pairs are the input's declared matches, unchanged (so they may
    contradict each other around a cycle: A-B, B-C but not A-C) — what its pairwise precision,
    recall and cycle violations are scored on. Its objects (count and universe clustering) come
    from the clustering rule the fusions count objects with, not from the connected components
    of the match graph: the greedy transitive closure of :mod:`matchers.fusion.transitive`
    (strongest match first, never two detections of one view in an object). Connected
    components would chain a cycle's contradictions into one object holding several detections
    of a view — an object count no fusion would give, so a strawman for the count error."""
    started = time.perf_counter()
    clustered = transitive(evidence)
    pairs = {key: m.copy() for key, m in evidence.matches.items()}
    return Universe(
        clustered.labels,
        clustered.count,
        pairs,
        False,
        "independent",
        time.perf_counter() - started,
    )


independent.deterministic = True
independent.memory_bytes = lambda evidence: (
    transitive.memory_bytes(evidence) + 32.0 * sum(len(m) for m in evidence.matches.values())
)  # the clustering's labels and edges, and the pairs kept: bytes
