"""How hard one frame pair is, from its truth: the difficulty factors every record carries, and the
declared rule that turns them into levels (the way SPair-71k annotates its pairs).

Factors (:func:`difficulty_factors`), computed at generation time from the ground truth and the
observers' true poses, stored in ``record.json``'s ``difficulty`` and never handed to a matcher:

- ``noncovisible_share``: detections without a partner in the other view / all detections (both
  views; 0 … 1) — what a matcher must leave unmatched;
- ``covisible``: the number of true pairs (fewer = less structure to match);
- ``yaw_change_deg``: the angle between the two cameras' horizontal viewing directions (0 … 180°);
- ``baseline_m``: the distance between the two cameras (metres);
- ``position_disagreement_m``: the median, over true pairs, of the distance between the two views'
  positions of one object once both are taken to the world frame with the *true* poses — the
  sensing error a geometric matcher has to absorb (0 without true pairs; None without poses);
- ``look_alike_share``: the share of detections (both views) with another detection of the same
  true class within :data:`LOOK_ALIKE_RADIUS_M` in the same view — the look-alikes appearance
  cannot tell apart.

Imported records without a stored ``difficulty`` get the factors their truth allows at read time
(:meth:`cadsim.dataset.frame_pair.FramePair.difficulty`): without true poses the viewpoint and
disagreement factors are None.

Levels (:class:`LevelRule`, docs/evaluation.md, "Difficulty levels"): a pair's *composite* is the
mean, over the factors it has, of the share of the *reference* pairs (a split's validation pairs)
that the pair is at least as hard as (more non-covisible, fewer covisible, larger viewpoint
change, more disagreement, more look-alikes); the levels are the terciles of the reference pairs'
composites: ``easy``, ``medium``, ``hard``. The rule is fitted on the validation split only, so it is
re-applied whenever the generator changes, and never reads a test result.

Everything that reaches ``record.json`` is computed without BLAS or dispatched transcendental
functions (:mod:`cadsim.portable_math`): the same bytes on every CPU.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from cadsim import portable_math as pm

LOOK_ALIKE_RADIUS_M = 5.0
"""Two detections of one true class closer than this (metres, same view) are look-alikes."""

FACTORS = (
    "noncovisible_share",
    "covisible",
    "yaw_change_deg",
    "baseline_m",
    "position_disagreement_m",
    "look_alike_share",
)
"""The factors, in the order records store them."""

HARDER_WHEN_LOWER = frozenset({"covisible"})
"""Factors where a smaller value makes the pair harder (every other: larger is harder)."""

LEVELS = ("easy", "medium", "hard")
DECIMALS = 6


def _distances(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise Euclidean distance of (k, 3) arrays, coordinate by coordinate (fixed order)."""
    diff = np.asarray(a, float) - np.asarray(b, float)
    squared = np.zeros(len(diff))
    for axis in range(diff.shape[1] if diff.ndim == 2 else 0):
        squared = squared + diff[:, axis] * diff[:, axis]
    return np.sqrt(squared)


def _look_alikes(positions: np.ndarray, classes: Sequence[str]) -> int:
    """How many detections of one view have another of the same true class within the radius."""
    positions = np.asarray(positions, float).reshape(-1, 3)
    k = len(positions)
    if k < 2:
        return 0
    first, second = np.triu_indices(k, 1)
    close = _distances(positions[first], positions[second]) < LOOK_ALIKE_RADIUS_M
    labels = np.asarray(list(classes), dtype=object)
    same = labels[first] == labels[second]
    hit = np.zeros(k, dtype=bool)
    hit[first[close & same]] = True
    hit[second[close & same]] = True
    return int(hit.sum())


def _heading(to_world: np.ndarray) -> float:
    """Compass-free heading (radians, world x-y plane) of a camera's optical axis (OpenCV z)."""
    axis = np.asarray(to_world, float)[:3, 2]
    return pm.arctan2(float(axis[1]), float(axis[0]))


def difficulty_factors(
    positions1: np.ndarray,
    positions2: np.ndarray,
    classes1: Sequence[str],
    classes2: Sequence[str],
    gt_pairs: np.ndarray,
    to_world: tuple[np.ndarray, np.ndarray] | None,
) -> dict[str, float | int | None]:
    """The factors of the module docstring for one pair of views.

    positions1/2: (n, 3), (m, 3) metres in each view's own camera frame; classes1/2: the true
    classes; gt_pairs: (k, 2) true pairs; to_world: per view the 4×4 camera (OpenCV) → world
    transform with the true pose, or None (the viewpoint and disagreement factors are then None).

    >>> import numpy as np
    >>> p = np.array([[0.0, 0.0, 5.0], [1.0, 0.0, 5.0], [9.0, 0.0, 5.0]])
    >>> f = difficulty_factors(p, p[:2], ["car"] * 3, ["car"] * 2, np.array([[0, 0], [1, 1]]), None)
    >>> f["noncovisible_share"], f["covisible"], f["look_alike_share"]
    (0.2, 2, 0.8)
    """
    p1 = np.asarray(positions1, float).reshape(-1, 3)
    p2 = np.asarray(positions2, float).reshape(-1, 3)
    gt = np.asarray(gt_pairs, dtype=np.int64).reshape(-1, 2)
    total = len(p1) + len(p2)
    factors: dict[str, float | int | None] = {
        "noncovisible_share": 1.0 - 2.0 * len(gt) / total if total else 0.0,
        "covisible": len(gt),
        "yaw_change_deg": None,
        "baseline_m": None,
        "position_disagreement_m": None,
        "look_alike_share": (
            (_look_alikes(p1, classes1) + _look_alikes(p2, classes2)) / total if total else 0.0
        ),
    }
    if to_world is not None:
        t1, t2 = (np.asarray(t, float) for t in to_world)
        change = abs(_heading(t1) - _heading(t2)) % (2 * math.pi)
        factors["yaw_change_deg"] = math.degrees(min(change, 2 * math.pi - change))
        factors["baseline_m"] = float(_distances(t1[None, :3, 3], t2[None, :3, 3])[0])
        if len(gt):
            w1 = pm.matmul(p1[gt[:, 0]], t1[:3, :3].T) + t1[:3, 3]
            w2 = pm.matmul(p2[gt[:, 1]], t2[:3, :3].T) + t2[:3, 3]
            factors["position_disagreement_m"] = float(np.median(_distances(w1, w2)))
        else:
            factors["position_disagreement_m"] = 0.0
    return {
        key: (round(float(v), DECIMALS) if isinstance(v, float) else v)
        for key, v in factors.items()
    }


def _hardness(values: np.ndarray, key: str) -> np.ndarray:
    """The factor oriented so that larger is harder."""
    return -values if key in HARDER_WHEN_LOWER else values


def _column(rows: Sequence[Mapping], key: str) -> np.ndarray:
    return np.array([np.nan if r.get(key) is None else float(r[key]) for r in rows], dtype=float)


def _composite(reference: Mapping[str, np.ndarray], factors: Sequence[Mapping]) -> np.ndarray:
    """:meth:`LevelRule.composite` against the sorted ``reference`` values of each factor."""
    shares = []
    for key, values_sorted in reference.items():
        values = _hardness(_column(factors, key), key)
        share = np.searchsorted(values_sorted, values, side="right") / values_sorted.size
        shares.append(np.where(np.isfinite(values), share, np.nan))
    if not shares:
        return np.full(len(factors), np.nan)
    stacked = np.vstack(shares)
    known = np.isfinite(stacked).sum(axis=0)
    total = np.nansum(stacked, axis=0)
    return np.divide(total, known, out=np.full(len(factors), np.nan), where=known > 0)


@dataclass(frozen=True)
class LevelRule:
    """The declared level rule fitted on reference pairs (module docstring): per factor the
    reference values (oriented, larger = harder; sorted), and the two tercile cut points of the
    reference composites."""

    reference: Mapping[str, np.ndarray]
    cuts: tuple[float, float]
    pairs: int

    @classmethod
    def fit(cls, factors: Sequence[Mapping]) -> LevelRule:
        """The rule of ``factors`` (the reference pairs' factor dicts, e.g. a validation split);
        ValueError for no pairs."""
        if not len(factors):
            raise ValueError("difficulty levels: the reference split has no pairs")
        reference = {}
        for key in FACTORS:
            values = _hardness(_column(factors, key), key)
            values = np.sort(values[np.isfinite(values)])
            if values.size:
                reference[key] = values
        low, high = np.quantile(_composite(reference, factors), [1 / 3, 2 / 3])
        return cls(reference, (float(low), float(high)), len(factors))

    def composite(self, factors: Sequence[Mapping]) -> np.ndarray:
        """Per pair, the mean over its known factors of the share of reference pairs it is at
        least as hard as (0 … 1; nan for a pair without any known factor)."""
        return _composite(self.reference, factors)

    def levels(self, factors: Sequence[Mapping]) -> list[str]:
        """Per pair its level: ``easy`` up to the first cut, ``hard`` above the second."""
        composite = self.composite(factors)
        index = np.searchsorted(np.asarray(self.cuts), composite, side="left")
        return [
            LEVELS[int(i)] if np.isfinite(c) else "n/a"
            for i, c in zip(index, composite, strict=True)
        ]

    def as_record(self) -> dict:
        """JSON-ready summary: the cut points and how many reference pairs set them."""
        return {"cuts": [round(c, DECIMALS) for c in self.cuts], "reference_pairs": self.pairs}


def level_counts(levels: Sequence[str]) -> dict[str, int]:
    """How many pairs each level has (every level listed, 0 included)."""
    counts = {level: 0 for level in LEVELS}
    for level in levels:
        counts[level] = counts.get(level, 0) + 1
    return counts
