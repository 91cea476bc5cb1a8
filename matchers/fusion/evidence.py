"""What a multi-way fusion reads: every pair of views' two-view matching of one snapshot."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


def _checked_pairs(name: str, pairs, n1: int, n2: int) -> np.ndarray:
    arr = np.asarray(pairs, dtype=np.int64).reshape(-1, 2) if np.size(pairs) else np.empty((0, 2))
    arr = arr.astype(np.int64)
    if arr.size and (arr.min() < 0 or arr[:, 0].max() >= n1 or arr[:, 1].max() >= n2):
        raise ValueError(f"{name}: pairs outside the views' {n1} x {n2} detections")
    if len(np.unique(arr[:, 0])) != len(arr) or len(np.unique(arr[:, 1])) != len(arr):
        raise ValueError(f"{name}: a detection matched twice (not one-to-one)")
    return arr


@dataclass(frozen=True)
class PairwiseEvidence:
    """N views' detections and their pairwise matchings.

    sizes: detections per view (view k holds rows 0..sizes[k]-1; views numbered 0..N-1 here).
    scores: (i, j) with i < j -> (sizes[i], sizes[j]) soft scores in [0, 1] (a two-view
    matcher's). matches: (i, j) -> (K, 2) declared pairs (row of view i, row of view j), one to
    one — the matcher's assignment after its threshold τ. A pair of views missing from both is
    one the caller did not match (no evidence). Validated on construction (ValueError naming the
    pair of views)."""

    sizes: tuple[int, ...]
    scores: dict[tuple[int, int], np.ndarray] = field(default_factory=dict)
    matches: dict[tuple[int, int], np.ndarray] = field(default_factory=dict)

    def __post_init__(self) -> None:
        sizes = tuple(int(s) for s in self.sizes)
        if any(s < 0 for s in sizes):
            raise ValueError(f"sizes: expected non-negative detection counts, got {sizes}")
        object.__setattr__(self, "sizes", sizes)
        scores, matches = {}, {}
        for key in sorted(set(self.scores) | set(self.matches)):
            i, j = (int(key[0]), int(key[1])) if len(key) == 2 else (-1, -1)
            if not 0 <= i < j < len(sizes):
                raise ValueError(f"pair {key}: expected views i < j below {len(sizes)}")
            n1, n2 = sizes[i], sizes[j]
            s = np.asarray(self.scores.get(key, np.zeros((n1, n2))), dtype=float)
            if s.shape != (n1, n2):
                raise ValueError(f"scores {key}: expected shape ({n1}, {n2}), got {s.shape}")
            if s.size and not (np.isfinite(s).all() and s.min() >= 0 and s.max() <= 1):
                raise ValueError(f"scores {key}: expected finite values in [0, 1]")
            scores[(i, j)] = s
            matches[(i, j)] = _checked_pairs(f"matches {key}", self.matches.get(key, ()), n1, n2)
        object.__setattr__(self, "scores", scores)
        object.__setattr__(self, "matches", matches)

    @property
    def offsets(self) -> np.ndarray:
        """First global row of each view (detections numbered view after view), length N + 1."""
        return np.concatenate([[0], np.cumsum(self.sizes)]).astype(np.int64)

    @property
    def total(self) -> int:
        """Detections over all views."""
        return int(sum(self.sizes))

    def view_of(self) -> np.ndarray:
        """The view of every global detection row."""
        return np.repeat(np.arange(len(self.sizes)), self.sizes)

    def edges(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every declared match as global rows (a, b) with a in the lower view, and its score;
        ordered by pair of views, then by the pair's declaration order."""
        off = self.offsets
        parts = [
            (off[i] + m[:, 0], off[j] + m[:, 1], self.scores[(i, j)][m[:, 0], m[:, 1]])
            for (i, j), m in self.matches.items()
        ]
        if not parts:
            return np.empty(0, np.int64), np.empty(0, np.int64), np.empty(0)
        a, b, s = (np.concatenate(p) for p in zip(*parts, strict=True))
        return a.astype(np.int64), b.astype(np.int64), s.astype(float)
