"""Episode-level intervals of per-pair values: runs are averaged per frame pair first, then the
pairs' values get a cluster t-interval over their episodes (:mod:`eval.protocol.cluster_interval`).
Imports ``eval/protocol/`` only."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from eval.protocol.cluster_interval import t_interval


def pair_means(group: pd.DataFrame, columns: Sequence[str]) -> pd.DataFrame:
    """Per frame pair (``pair``): the mean over runs of ``columns``, with the pair's ``episode``."""
    agg = {c: (c, "mean") for c in columns} | {"episode": ("episode", "first")}
    return group.groupby("pair", sort=True).agg(**agg).reset_index()


def rate_interval(values: np.ndarray, episodes: np.ndarray) -> tuple[float, float, float]:
    """(mean, low, high) of per-pair rates in [0, 1] with their 95 % episode-level cluster
    t-interval; NaNs without values."""
    if not len(values):
        return (float("nan"),) * 3
    mean, low, high, _ = t_interval(values, episodes, bounds=(0.0, 1.0))
    return mean, low, high


def column_interval(group: pd.DataFrame, column: str) -> tuple[float, float, float]:
    """:func:`rate_interval` of ``column`` of per-run, per-pair rows (runs averaged per pair)."""
    means = pair_means(group, [column])
    return rate_interval(means[column].to_numpy(), means["episode"].to_numpy())
