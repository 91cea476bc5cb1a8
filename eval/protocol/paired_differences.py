"""Paired differences between matchers with episode-bootstrap confidence intervals.

For a dataset and two matchers a, b, each frame pair's metric is first averaged over the runs
(seeds), then d = a − b per frame pair, in percentage points; ``diff`` is the mean of d over the
frame pairs. Frame pairs drawn from one simulation episode are correlated (same traffic, nearby
times), so the bootstrap resamples whole *episodes* with replacement — never single pairs — and
recomputes the pair-weighted mean of d (Σ d over the drawn episodes' pairs / their count). The
interval is the percentile interval of the resampled means (95 %: the 2.5 and 97.5 percentiles),
from a seeded generator, so the same inputs give the same interval. With few episodes (CAD has 5
of 10 pairs each) the interval is wide and itself uncertain; it is what the data support.

Output: ``paired_differences.csv`` (:data:`COLUMNS`), maximin against every other matcher.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from eval.core.result_files import write_csv

COLUMNS = (
    "dataset",
    "matcher_a",
    "matcher_b",
    "metric",
    "diff",
    "ci_low",
    "ci_high",
    "pairs",
    "episodes",
)
DIFF_METRICS = ("f1", "balanced_accuracy", "recall")
REFERENCE = "maximin"
RESAMPLES = 2000
LEVEL = 0.95
SEED = 0


def episode_bootstrap(
    values: np.ndarray,
    episodes: np.ndarray,
    resamples: int = RESAMPLES,
    seed: int = SEED,
    level: float = LEVEL,
) -> tuple[float, float, float]:
    """(mean, low, high) of per-frame-pair `values` (1-D), the interval from resampling the
    `episodes` (same length; one label per frame pair) with replacement `resamples` times."""
    values = np.asarray(values, dtype=float).reshape(-1)
    labels, index = np.unique(np.asarray(episodes).reshape(-1), return_inverse=True)
    if len(values) != len(index):
        raise ValueError(f"episodes: {len(index)} labels for {len(values)} values")
    if not len(values):
        raise ValueError("values: nothing to resample")
    if resamples < 1 or not 0 < level < 1:
        raise ValueError(f"resamples/level: expected ≥ 1 and (0, 1), got {resamples}, {level}")
    sums = np.bincount(index, weights=values, minlength=len(labels))
    counts = np.bincount(index, minlength=len(labels)).astype(float)
    rng = np.random.default_rng(seed)
    # How often each episode is drawn in each resample: (resamples, episodes).
    draws = rng.multinomial(len(labels), np.full(len(labels), 1 / len(labels)), size=resamples)
    means = (draws @ sums) / (draws @ counts)
    tail = 100 * (1 - level) / 2
    low, high = np.percentile(means, [tail, 100 - tail])
    return float(values.mean()), float(low), float(high)


def per_pair_means(per_pair: pd.DataFrame, metrics: Sequence[str]) -> pd.DataFrame:
    """Each (dataset, matcher, frame pair)'s metrics averaged over its runs, with its episode."""
    return (
        per_pair.groupby(["dataset", "matcher", "pair"], sort=False)
        .agg(episode=("episode", "first"), **{m: (m, "mean") for m in metrics})
        .reset_index()
    )


def paired_differences(
    per_pair: pd.DataFrame,
    reference: str = REFERENCE,
    metrics: Sequence[str] = DIFF_METRICS,
    resamples: int = RESAMPLES,
    seed: int = SEED,
) -> pd.DataFrame:
    """``reference`` − every other matcher, per dataset and metric (a difference of fractions;
    printed as percentage points), with episode-bootstrap intervals; empty when `reference` is
    absent."""
    metrics = [m for m in metrics if m in per_pair.columns]
    means = per_pair_means(per_pair, metrics)
    rows = []
    for dataset, group in means.groupby("dataset", sort=False):
        ref = group[group["matcher"] == reference]
        if ref.empty:
            continue
        for other, rest in group[group["matcher"] != reference].groupby("matcher", sort=False):
            joined = ref.merge(rest, on="pair", suffixes=("", "_b"))
            for metric in metrics:
                d = (joined[metric] - joined[f"{metric}_b"]).to_numpy()
                diff, low, high = episode_bootstrap(
                    d, joined["episode"].to_numpy(), resamples, seed
                )
                rows.append(
                    {
                        "dataset": dataset,
                        "matcher_a": reference,
                        "matcher_b": other,
                        "metric": metric,
                        "diff": diff,
                        "ci_low": low,
                        "ci_high": high,
                        "pairs": len(joined),
                        "episodes": joined["episode"].nunique(),
                    }
                )
    return pd.DataFrame(rows, columns=list(COLUMNS))


def write_paired_differences(out_dir: str | Path) -> Path | None:
    """``paired_differences.csv`` from the main ``metrics_per_pair.csv`` of `out_dir` (None when
    that file is missing)."""
    out_dir = Path(out_dir)
    source = out_dir / "metrics_per_pair.csv"
    if not source.is_file():
        return None
    per_pair = pd.read_csv(source, keep_default_na=False, na_values=[""])
    path = out_dir / "paired_differences.csv"
    write_csv(paired_differences(per_pair).round(6), path)
    return path
