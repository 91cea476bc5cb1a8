"""The result every matcher returns."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class Matching:
    """A matcher's output.

    pairs: (k, 2) int array of matched (i, j) indices, i into view 1, j into view 2; a partial
    one-to-one matching (no index repeats). scores: (n, m) soft score matrix before
    discretisation (finite, non-negative unless the matcher documents otherwise).
    name: matcher name; iterations: iterations run; time_s: wall time of the call in seconds.
    """

    pairs: np.ndarray
    scores: np.ndarray
    name: str
    iterations: int = 0
    time_s: float = 0.0
    info: dict = field(default_factory=dict)

    def as_dict(self) -> dict[int, int]:
        """Mapping i -> j of the matched pairs."""
        return {int(i): int(j) for i, j in self.pairs}
