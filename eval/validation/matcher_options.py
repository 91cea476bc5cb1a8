"""Which options the validation harnesses pass to a matcher: the tensor recipe, for the matchers
that build a third-order tensor. Shared by the published-protocol and CoID benchmarks."""

from __future__ import annotations

HYPERGRAPH_MATCHERS = frozenset({"tm", "hgm", "bcagm", "rrwhm", "mos", "maximin"})


def matcher_options(name: str, tensor: str | None) -> dict:
    """Options our harness passes to matcher ``name``: only the tensor recipe, for hypergraph ones."""
    return {"tensor": tensor} if tensor and name in HYPERGRAPH_MATCHERS else {}
