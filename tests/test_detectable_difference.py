"""The minimum detectable difference: the t-based formula on the cluster means, its promised
power at a planted difference of known variance, and its columns in the interval files."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy.stats import t as student_t

from eval.protocol.cluster_interval import t_interval
from eval.protocol.detectable_difference import (
    cluster_standard_error,
    mdd_factor,
    minimum_detectable_difference,
)
from eval.protocol.paired_differences import COLUMNS, paired_differences
from eval.studies.v2x.table import INTERVAL_COLUMNS, best_against_runner_up


def test_equal_clusters_give_the_textbook_formula():
    rng = np.random.default_rng(3)
    clusters, per = 30, 4
    values = rng.normal(0.02, 0.1, size=clusters * per)
    labels = np.repeat(np.arange(clusters), per)
    mdd, g = minimum_detectable_difference(values, labels)
    means = values.reshape(clusters, per).mean(axis=1)
    factor = student_t.ppf(0.975, clusters - 1) + student_t.ppf(0.8, clusters - 1)
    assert g == clusters
    assert mdd == pytest.approx(factor * means.std(ddof=1) / np.sqrt(clusters), rel=1e-12)


def test_planted_known_variance():
    """Cluster means with sample sd exactly 0.1 over 25 clusters: MDD = (t + t) · 0.1 / 5."""
    raw = np.random.default_rng(0).normal(size=25)
    means = 0.03 + 0.1 * (raw - raw.mean()) / raw.std(ddof=1)
    mdd, g = minimum_detectable_difference(means, np.arange(25))
    assert g == 25
    assert mdd == pytest.approx((2.063899 + 0.856855) * 0.1 / 5, abs=1e-6)
    assert mdd_factor(100_000) == pytest.approx(1.959964 + 0.841621, abs=1e-3)  # normal limit


def test_a_difference_of_one_mdd_is_detected_with_the_stated_power():
    """Simulate: true mean difference = the MDD of the true sd; the interval excludes 0 in
    ≈ 80 % of data sets (noncentral-t power of the (t + t) rule at G = 20: 0.80 ± 0.01)."""
    rng = np.random.default_rng(11)
    clusters, sd, sims = 20, 0.08, 4000
    true = mdd_factor(clusters) * sd / np.sqrt(clusters)
    draws = rng.normal(true, sd, size=(sims, clusters))
    se = draws.std(axis=1, ddof=1) / np.sqrt(clusters)
    rejected = np.abs(draws.mean(axis=1) / se) > student_t.ppf(0.975, clusters - 1)
    assert rejected.mean() == pytest.approx(0.80, abs=0.025)
    # and half the MDD is detected far less often: an overlap there is no evidence of equality
    half = rng.normal(true / 2, sd, size=(sims, clusters))
    se = half.std(axis=1, ddof=1) / np.sqrt(clusters)
    assert (np.abs(half.mean(axis=1) / se) > student_t.ppf(0.975, clusters - 1)).mean() < 0.4


def test_mdd_and_interval_share_one_standard_error():
    rng = np.random.default_rng(5)
    labels = rng.integers(0, 12, size=60)  # unequal cluster sizes
    values = rng.normal(size=60)
    mean, low, high, g = t_interval(values, labels)
    se, g2 = cluster_standard_error(values, labels)
    assert g == g2
    assert (high - low) / 2 == pytest.approx(student_t.ppf(0.975, g - 1) * se, rel=1e-10)


def test_one_cluster_has_no_mdd():
    mdd, g = minimum_detectable_difference(np.array([0.1, 0.2]), np.array([7, 7]))
    assert g == 1 and np.isnan(mdd)
    with pytest.raises(ValueError, match="clusters"):
        minimum_detectable_difference(np.zeros(3), np.zeros(2))


def _per_pair(episodes: int = 8, per: int = 3) -> pd.DataFrame:
    rng = np.random.default_rng(2)
    rows = []
    for e in range(episodes):
        for k in range(per):
            base = rng.uniform(0.3, 0.7)
            for matcher, f1 in (("mos", base), ("maximin", base + 0.05 + rng.normal(0, 0.05))):
                rows.append(
                    {"dataset": "CAD", "preset": "rtk", "matcher": matcher, "seed": 0}
                    | {"pair": e * per + k, "episode": e, "f1": f1, "recall": f1}
                    | {"balanced_accuracy": f1}
                )
    return pd.DataFrame(rows)


def test_paired_differences_and_intervals_files_carry_mdd_and_clusters():
    per_pair = _per_pair()
    assert {"mdd", "clusters"} <= set(COLUMNS) and {"mdd", "clusters"} <= set(INTERVAL_COLUMNS)
    table = paired_differences(per_pair)
    row = table[table["metric"] == "f1"].iloc[0]
    means = per_pair.groupby(["matcher", "pair"]).agg(f1=("f1", "mean"), e=("episode", "first"))
    d = means.loc["maximin", "f1"] - means.loc["mos", "f1"]
    expected, _ = minimum_detectable_difference(d.to_numpy(), means.loc["maximin", "e"].to_numpy())
    assert row["clusters"] == 8 and row["mdd"] == pytest.approx(expected)
    intervals = best_against_runner_up(per_pair, {"rtk": {"maximin": 0.9, "mos": 0.8}})
    assert intervals.iloc[0]["clusters"] == 8
    assert intervals.iloc[0]["mdd"] == pytest.approx(expected)


def test_the_mdd_of_a_bootstrap_interval_is_its_normal_standard_error_times_2_80():
    from eval.studies.temporal.gain import bootstrap_mdd

    # a 95 % interval of half-width 1.96 is a standard error of 1: MDD = 1.960 + 0.842
    assert bootstrap_mdd(-1.96, 1.96) == pytest.approx(2.8016, abs=1e-4)
    assert bootstrap_mdd(0.10, 0.10 + 2 * 1.96 * 0.05) == pytest.approx(0.05 * 2.8016, abs=1e-5)
    assert np.isnan(bootstrap_mdd(float("nan"), 0.1))
