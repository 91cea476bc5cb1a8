"""Paired differences between matchers with cluster-robust t-intervals over episodes.

For a dataset and two matchers a, b, each frame pair's metric is first averaged over the runs
(seeds), then d = a − b per frame pair (a difference of fractions; printed in percentage
points); ``diff`` is the mean of d over the frame pairs. Frame pairs drawn from one simulation
episode are correlated (same traffic, nearby times), so the interval treats the *episode* as the
unit: the cluster-robust t-interval of :func:`eval.protocol.cluster_interval.t_interval` (with
equal episode sizes, the t-interval on the episode means of d, G − 1 degrees of freedom). It
replaces a percentile bootstrap over episodes whose 95 % interval covered the truth 83 % of the
time at 5 episodes. ``episodes`` says how many there were: with few, the interval is wide; with
one there is none. ``mdd`` is the minimum detectable difference at 95 % confidence and 80 % power
from the same per-cluster differences (:mod:`eval.protocol.detectable_difference`), ``clusters``
the number of independent clusters it counts.

Output: ``paired_differences.csv`` (:data:`COLUMNS`), the reference (maximin unless
``cadsim evaluate --reference NAME`` names another) against every other matcher.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import pandas as pd

from eval.core.result_files import write_csv
from eval.protocol.cluster_interval import t_interval
from eval.protocol.detectable_difference import minimum_detectable_difference

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
    "mdd",
    "clusters",
)
DIFF_METRICS = ("f1", "balanced_accuracy", "recall")
REFERENCE = "maximin"
LEVEL = 0.95


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
    level: float = LEVEL,
) -> pd.DataFrame:
    """``reference`` − every other matcher, per dataset and metric (a difference of fractions;
    printed as percentage points), with cluster-robust t-intervals over episodes; empty when
    `reference` is absent."""
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
                episodes = joined["episode"].to_numpy()
                diff, low, high, _ = t_interval(d, episodes, level, bounds=(-1.0, 1.0))
                mdd, clusters = minimum_detectable_difference(d, episodes, level)
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
                        "mdd": mdd,
                        "clusters": clusters,
                    }
                )
    return pd.DataFrame(rows, columns=list(COLUMNS))


def write_paired_differences(
    out_dir: str | Path, variant: str = "", reference: str = REFERENCE
) -> Path | None:
    """``paired_differences[_variant].csv`` (`reference` − every other matcher) from that
    variant's ``metrics_per_pair`` file in `out_dir` (None when it is missing; variant "" is the
    main one)."""
    from eval.protocol.variants import variant_path

    out_dir = Path(out_dir)
    source = variant_path(out_dir, "metrics_per_pair", variant, ".csv")
    if not source.is_file():
        return None
    per_pair = pd.read_csv(source, keep_default_na=False, na_values=[""])
    path = variant_path(out_dir, "paired_differences", variant, ".csv")
    write_csv(paired_differences(per_pair, reference=reference).round(6), path)
    return path
