"""Bootstrap over episodes and draws, for curves measured on thinned (or otherwise re-drawn) data.

A regime-sweep value is a mean over frame pairs (grouped in simulation episodes, which are
correlated inside) and over runs (each run its own thinning draw and matcher seed). One resample
draws the episodes with replacement *and* the runs with replacement — both are sources of
variation a reader would see with other traffic or other draws (``../shared/DESIGN.md`` §3, §10) —
and recomputes every pooled mean with the same weights at every level of the curve, so the
resampled curves stay curves (the same episodes and draws at every level).

Arrays: per level k, a sum S[k, e, d] over the frame pairs of episode e in run d (a metric, or a
count for a pooled share) and the pair count n[e]; a resample r has episode weights W[r, e] and
run weights U[r, d] (multinomial counts) and gives Σ_e Σ_d W·S·U / (Σ_e W·n · Σ_d U).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import pandas as pd

RESAMPLES = 2000
LEVEL = 0.95
SEED = 0


class Weights(NamedTuple):
    """Multinomial resampling counts: ``episodes`` (R, E) and ``draws`` (R, D)."""

    episodes: np.ndarray
    draws: np.ndarray


def resampling_weights(
    n_episodes: int, n_draws: int, resamples: int = RESAMPLES, seed: int = SEED
) -> Weights:
    """Seeded counts of how often each episode and each draw enters each of `resamples`
    resamples (the same inputs give the same weights)."""
    if n_episodes < 1 or n_draws < 1 or resamples < 1:
        raise ValueError(
            f"episodes/draws/resamples: expected >= 1, got {n_episodes}, {n_draws}, {resamples}"
        )
    rng = np.random.default_rng(seed)
    w = rng.multinomial(n_episodes, np.full(n_episodes, 1 / n_episodes), size=resamples)
    u = rng.multinomial(n_draws, np.full(n_draws, 1 / n_draws), size=resamples)
    return Weights(w.astype(float), u.astype(float))


def pooled(sums: np.ndarray, weights: Weights) -> np.ndarray:
    """Σ_e Σ_d W[r, e] · sums[..., e, d] · U[r, d] for every resample r: shape (R, ...)."""
    return np.einsum("re,...ed,rd->r...", weights.episodes, sums, weights.draws)


class Table(NamedTuple):
    """Per-level sums of one quantity, laid out for :func:`pooled`: ``sums`` (K, E, D), the
    ``levels`` (K,), ``episodes`` (E,) and ``draws`` (D,) they refer to."""

    sums: np.ndarray
    levels: np.ndarray
    episodes: np.ndarray
    draws: np.ndarray


def table(
    frame: pd.DataFrame,
    value: str,
    level: str = "keep",
    episode: str = "episode",
    draw: str = "seed",
    axes: tuple[np.ndarray, np.ndarray] | None = None,
) -> Table:
    """Sums of column `value` of `frame` (one row per level, frame pair and run) per (level,
    episode, draw); missing combinations count 0. `axes`: the (episodes, draws) to lay the sums
    out on (default: those of `frame`), so tables of several matchers share one layout."""
    grouped = frame.groupby([level, episode, draw], sort=True)[value].sum()
    levels = np.sort(frame[level].unique())
    episodes, draws = axes or (np.sort(frame[episode].unique()), np.sort(frame[draw].unique()))
    index = pd.MultiIndex.from_product([levels, episodes, draws])
    sums = grouped.reindex(index, fill_value=0.0).to_numpy(dtype=float)
    return Table(sums.reshape(len(levels), len(episodes), len(draws)), levels, episodes, draws)


def axes_of(frame: pd.DataFrame, episode: str = "episode", draw: str = "seed") -> tuple:
    """The sorted episodes and draws of `frame` (a shared layout for :func:`table`)."""
    return np.sort(frame[episode].unique()), np.sort(frame[draw].unique())


def weights_for(frame: pd.DataFrame, seed: int = SEED) -> Weights:
    """Resampling weights over the episodes and draws of `frame`."""
    episodes, draws = axes_of(frame)
    return resampling_weights(len(episodes), len(draws), seed=seed)


def means(
    frame: pd.DataFrame, value: str, weights: Weights, axes: tuple
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(levels, point mean per level (K,), resampled means (R, K)) of column `value` over the
    rows of `frame` (frame pairs × draws), laid out on `axes`."""
    values = table(frame, value, axes=axes)
    counts = table(frame.assign(_one=1.0), "_one", axes=axes).sums
    point = values.sums.sum(axis=(1, 2)) / counts.sum(axis=(1, 2))
    with np.errstate(invalid="ignore"):
        resampled = pooled(values.sums, weights) / pooled(counts, weights)
    return values.levels, point, resampled


def interval(values: np.ndarray, level: float = LEVEL) -> tuple[float, float]:
    """The percentile interval of resampled `values` along axis 0 (inf and nan included: an
    interval reaching them is open on that side)."""
    tail = 100 * (1 - level) / 2
    low, high = np.percentile(values, [tail, 100 - tail], axis=0, method="inverted_cdf")
    return low, high
