"""Multi-way matching: one consistent assignment of N views' detections to universe objects,
from every pair of views' two-view matching (a registry of its own: :mod:`matchers.fusion.registry`)."""

from matchers.fusion.evidence import PairwiseEvidence
from matchers.fusion.registry import (
    available_fusions,
    checked_fusion,
    get_fusion,
    register_fusion,
    usable_fusions,
)
from matchers.fusion.universe import Universe

__all__ = [
    "PairwiseEvidence",
    "Universe",
    "available_fusions",
    "checked_fusion",
    "get_fusion",
    "register_fusion",
    "usable_fusions",
]
