"""The transfer study's own metric: the pooled F1 linearised per frame pair (delta method), so
that a pooled F1, or the difference of two on the same frame pairs, gets a cluster t-interval
(:mod:`eval.protocol.cluster_interval`) over episodes or blocks of consecutive pairs."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from eval.protocol.cluster_interval import t_interval
from eval.studies.external.agreement import pair_clusters


def pooled_f1_terms(per_pair: pd.DataFrame) -> pd.DataFrame:
    """(pair, episode, value) per frame pair of one matcher's per-pair rows (columns pair,
    episode, seed, tp, n_pred, n_gt): in each run, the pooled F1 F = 2ΣTP / (Σ|M| + Σ|G|) plus
    the pair's linearised share, N · (2 tp − F (|M| + |G|)) / (Σ|M| + Σ|G|) (delta method; its
    mean over the pairs is 0), averaged over the runs. The mean of ``value`` is the mean over
    runs of the pooled F1 (the table's ``f1_pooled``); its cluster-robust variance is the
    delta-method variance. NaN values where a run has no match and no ground truth at all."""
    missing = [c for c in ("pair", "episode", "seed", "tp", "n_pred", "n_gt") if c not in per_pair]
    if missing:
        raise ValueError(f"per_pair: missing columns {missing}")
    if per_pair.empty:
        raise ValueError("per_pair: no rows")
    pairs = np.sort(per_pair["pair"].unique())
    values = []
    for seed, run in per_pair.groupby("seed", sort=True):
        run = run.sort_values("pair")
        if not np.array_equal(run["pair"].to_numpy(), pairs):
            raise ValueError(f"per_pair: run {seed} does not hold each frame pair once")
        tp = run["tp"].to_numpy(float)
        size = run["n_pred"].to_numpy(float) + run["n_gt"].to_numpy(float)
        total = size.sum()
        if total <= 0:
            values.append(np.full(len(pairs), np.nan))
            continue
        f1 = 2 * tp.sum() / total
        values.append(f1 + len(pairs) * (2 * tp - f1 * size) / total)
    episodes = per_pair.groupby("pair")["episode"].first().reindex(pairs).to_numpy()
    return pd.DataFrame({"pair": pairs, "episode": episodes, "value": np.mean(values, axis=0)})


def paired_interval(
    a: pd.DataFrame, b: pd.DataFrame | None = None, block: int | None = None
) -> tuple[float, float, float, int]:
    """(value, low, high, clusters): the pooled F1 of ``a`` (or the difference a − b on the same
    frame pairs) with its 95 % cluster t-interval; clusters are episodes, or with ``block``
    blocks of ``block`` consecutive pairs of one episode. ``a``, ``b``: :func:`pooled_f1_terms`.
    ValueError when ``b`` holds other frame pairs; NaN interval with one cluster."""
    terms = a[["pair", "episode", "value"]]
    bounds = (0.0, 1.0)
    if b is not None:
        merged = a.merge(b, on="pair", how="outer", suffixes=("_a", "_b"), indicator=True)
        same = (merged["_merge"] == "both").all()
        if not same or not (merged["episode_a"] == merged["episode_b"]).all():
            raise ValueError("paired_interval: the two matchers were scored on other frame pairs")
        terms = pd.DataFrame(
            {
                "pair": merged["pair"],
                "episode": merged["episode_a"],
                "value": merged["value_a"] - merged["value_b"],
            }
        )
        bounds = (-1.0, 1.0)
    if terms["value"].isna().any():
        return math.nan, math.nan, math.nan, 0
    clusters = pair_clusters(terms, block).reindex(terms["pair"]).to_numpy()
    return t_interval(terms["value"].to_numpy(), clusters, bounds=bounds)


__all__ = ["paired_interval", "pooled_f1_terms"]
