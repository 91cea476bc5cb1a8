"""A method's rank among others with an episode-bootstrap interval.

Per frame pair the metric is averaged over the runs (seeds); each bootstrap resample draws the
test *episodes* with replacement (frame pairs of one episode are correlated, so the episode is
the unit), recomputes every method's mean over the drawn frame pairs and ranks the target
(1 = highest; a tie counts in the target's favour). The interval is the 2.5 and 97.5
percentiles of the resampled ranks; the point rank is that of the full test set.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd


def rank_interval(
    per_pair: pd.DataFrame,
    target: str,
    methods: Sequence[str],
    metric: str = "f1",
    resamples: int = 2000,
    seed: int = 0,
    level: float = 0.95,
) -> tuple[int, int, int, int]:
    """(rank, low, high, episodes) of ``target`` among ``methods`` by mean ``metric`` over the
    frame pairs of ``per_pair`` (columns ``matcher``, ``episode``, ``pair``, ``metric``; one
    dataset's test rows)."""
    rows = per_pair[per_pair["matcher"].isin(list(methods))]
    pairs = rows.groupby(["matcher", "episode", "pair"], sort=True)[metric].mean()
    wide = pairs.unstack("matcher").dropna()  # frame pairs every method scored
    if target not in wide.columns or wide.empty:
        raise ValueError(f"rank_interval: no frame pairs scored by {target!r} and every method")
    episodes = wide.index.get_level_values("episode").to_numpy()
    labels, codes = np.unique(episodes, return_inverse=True)
    sums = np.zeros((len(labels), wide.shape[1]))
    np.add.at(sums, codes, wide.to_numpy())
    counts = np.bincount(codes, minlength=len(labels)).astype(float)
    column = list(wide.columns).index(target)

    def rank_of(means: np.ndarray) -> np.ndarray:
        return 1 + (means > means[..., [column]]).sum(axis=-1)

    point = int(rank_of(sums.sum(0) / counts.sum())[()])
    draw = np.random.default_rng(seed).integers(0, len(labels), size=(resamples, len(labels)))
    means = sums[draw].sum(1) / counts[draw].sum(1)[:, None]
    ranks = rank_of(means)
    tail = 100 * (1 - level) / 2
    low, high = np.percentile(ranks, [tail, 100 - tail], method="nearest")
    return point, int(low), int(high), len(labels)
