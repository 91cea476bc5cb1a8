"""Episode-level bootstrap of pooled figures: pooled F1 and its differences, means per snapshot
and ratios of means, with percentile intervals and two-sided p-values.

A pooled figure sums counts over every item (a snapshot's view pairs, a frame pair) of every
episode and run before it divides; the snapshots of one simulation episode share traffic and
are correlated, so the unit of resampling is the episode, and the runs (matcher seeds) are
resampled too (:mod:`eval.protocol.episode_draw_bootstrap`, whose seeded multinomial weights
this module uses). Arrays: per group k and quantity v, the sum S[k, v, e, d] over the items of
episode e in run d; resample r, with episode weights W[r, e] and run weights U[r, d], has the
totals Σ_e Σ_d W[r, e] · S[k, v, e, d] · U[r, d] — one einsum, no loop over resamples. The point
estimate is the same expression with every weight 1: exactly the figure the table shows.

Two-sided p-value of a difference from the same resamples: twice the smaller share of
resamples on either side of 0 (a resample at 0 counts for both sides), with the +1 of a
bootstrap p (a p of 0 is never reported), capped at 1. A difference that is 0 in every episode
has p = 1. With a single episode there is nothing to resample between clusters: no interval and
no p (NaN), so a goal read off them is "not shown" (:mod:`eval.protocol.goal_verdict`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
import pandas as pd

from eval.protocol.episode_draw_bootstrap import Weights, pooled, resampling_weights

RESAMPLES = 10_000
"""Enough for a Holm family of ~100 comparisons: the smallest p, 2 / (R + 1), times 100 is 0.02."""
LEVEL = 0.95
SEED = 0


class Sums(NamedTuple):
    """Sums laid out for the bootstrap: ``sums`` (K, V, E, D) of the ``values`` columns per
    group (``groups``, K rows of the key columns), episode (``episodes``, E) and run
    (``draws``, D); missing combinations are 0."""

    sums: np.ndarray
    groups: pd.DataFrame
    values: tuple[str, ...]
    episodes: np.ndarray
    draws: np.ndarray

    def of(self, value: str) -> np.ndarray:
        """(K, E, D): the sums of one value column."""
        return self.sums[:, self.values.index(value)]


def group_sums(
    frame: pd.DataFrame,
    keys: Sequence[str],
    values: Sequence[str],
    episode: str = "episode",
    draw: str = "seed",
) -> Sums:
    """Column sums of ``values`` per group of ``keys`` (in order of first appearance), episode
    and run of ``frame`` (one row per item, group and run)."""
    keys, values = list(keys), list(values)
    groups = frame[keys].drop_duplicates().reset_index(drop=True)
    episodes = np.sort(frame[episode].unique())
    draws = np.sort(frame[draw].unique())
    grouped = frame.groupby([*keys, episode, draw], sort=False)[values].sum()
    index = pd.MultiIndex.from_tuples(
        [(*g, e, d) for g in groups.itertuples(index=False) for e in episodes for d in draws],
        names=[*keys, episode, draw],
    )
    table = grouped.reindex(index, fill_value=0).to_numpy(dtype=float)
    sums = table.reshape(len(groups), len(episodes), len(draws), len(values)).transpose(0, 3, 1, 2)
    return Sums(sums, groups, tuple(values), episodes, draws)


def resamplable(sums: Sums) -> bool:
    """Whether ``sums`` has the two episodes or more that an episode bootstrap needs."""
    return len(sums.episodes) >= 2


def weights_for(sums: Sums, resamples: int = RESAMPLES, seed: int = SEED) -> Weights:
    """Seeded multinomial weights over the episodes and runs of ``sums``."""
    return resampling_weights(len(sums.episodes), len(sums.draws), resamples, seed)


def totals(sums: np.ndarray, weights: Weights | None) -> np.ndarray:
    """Totals of (..., E, D) ``sums``: (...) with every weight 1 (``weights`` None, the point
    estimate), else (R, ...) per resample."""
    if weights is None:
        return sums.sum(axis=(-2, -1))
    return pooled(sums, weights)


def pooled_f1(true_positives, declared, true_pairs) -> np.ndarray:
    """F1 of pooled counts, elementwise, with the conventions of
    :func:`eval.protocol.multiway_metrics.summarise_counts`: precision 1 when nothing is
    declared, recall 1 when there is nothing to find, F1 0 when both are 0."""
    tp, dec, true = (np.asarray(x, dtype=float) for x in (true_positives, declared, true_pairs))
    with np.errstate(invalid="ignore", divide="ignore"):
        precision = np.where(dec > 0, tp / np.where(dec > 0, dec, 1), 1.0)
        recall = np.where(true > 0, tp / np.where(true > 0, true, 1), 1.0)
        total = precision + recall
        return np.where(total > 0, 2 * precision * recall / np.where(total > 0, total, 1), 0.0)


F1_COUNTS = ("true_positives", "declared", "true_pairs")


def f1_of(sums: Sums, weights: Weights | None = None) -> np.ndarray:
    """Pooled F1 per group, (K,) (point) or (R, K) (resampled), from sums holding
    :data:`F1_COUNTS`."""
    return pooled_f1(*(totals(sums.of(v), weights) for v in F1_COUNTS))


def mean_of(sums: Sums, value: str, count: str, weights: Weights | None = None, empty=0.0):
    """Σ value / Σ count per group (a mean per item): (K,) or (R, K); ``empty`` where no item
    counts."""
    num, den = totals(sums.of(value), weights), totals(sums.of(count), weights)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, num / np.where(den > 0, den, 1), empty)


def interval(resampled: np.ndarray, level: float = LEVEL) -> tuple[np.ndarray, np.ndarray]:
    """Percentile interval of (R, ...) resampled values along axis 0: (low, high)."""
    if not 0 < level < 1:
        raise ValueError(f"level: expected a number in (0, 1), got {level}")
    tail = 100 * (1 - level) / 2
    low, high = np.percentile(resampled, [tail, 100 - tail], axis=0, method="inverted_cdf")
    return low, high


def two_sided_p(resampled: np.ndarray, null: float = 0.0) -> np.ndarray:
    """Bootstrap p-value of each column of (R, ...) resampled differences against ``null``
    (module docstring)."""
    resampled = np.asarray(resampled, dtype=float)
    count = resampled.shape[0]
    below = (np.count_nonzero(resampled <= null, axis=0) + 1) / (count + 1)
    above = (np.count_nonzero(resampled >= null, axis=0) + 1) / (count + 1)
    return np.minimum(1.0, 2 * np.minimum(below, above))


class Difference(NamedTuple):
    """A bootstrapped difference per group: ``point`` (K,), ``low`` / ``high`` (K,) percentile
    interval, ``p`` (K,) two-sided p-value against 0."""

    point: np.ndarray
    low: np.ndarray
    high: np.ndarray
    p: np.ndarray


def summarise(
    point: np.ndarray, resampled: np.ndarray, level: float = LEVEL, episodes: int = 2
) -> Difference:
    """Point, percentile interval and two-sided p of a bootstrapped difference; NaN interval and
    p when fewer than 2 ``episodes`` were resampled."""
    point = np.asarray(point, float)
    if episodes < 2:
        nan = np.full(point.shape, np.nan)
        return Difference(point, nan, nan.copy(), nan.copy())
    low, high = interval(resampled, level)
    return Difference(point, low, high, two_sided_p(resampled))


def f1_difference(
    mine: Sums,
    base: Sums,
    resamples: int = RESAMPLES,
    seed: int = SEED,
    level: float = LEVEL,
) -> Difference:
    """Pooled F1 of each group of ``mine`` minus that of the same row of ``base`` (same groups'
    order, episodes and runs), resampling the episodes and runs of both together."""
    if mine.sums.shape[2:] != base.sums.shape[2:] or len(mine.groups) != len(base.groups):
        raise ValueError("mine and base: expected the same groups, episodes and runs")
    if not (
        np.array_equal(mine.episodes, base.episodes) and np.array_equal(mine.draws, base.draws)
    ):
        raise ValueError("mine and base: expected the same episodes and runs")
    weights = weights_for(mine, resamples, seed)
    point = f1_of(mine) - f1_of(base)
    resampled = f1_of(mine, weights) - f1_of(base, weights)
    return summarise(point, resampled, level, len(mine.episodes))
