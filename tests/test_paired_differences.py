"""Paired differences: runs averaged per frame pair first, a cluster-robust t-interval over
episodes (never single pairs) whose 95 % interval holds its level at the suite's test-set shape."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from eval.protocol.cluster_interval import t_interval, t_intervals
from eval.protocol.paired_differences import paired_differences


def _per_pair(true_diff: float, episodes: int, per_episode: int, seed: int = 0) -> pd.DataFrame:
    """maximin = mos + true_diff (fraction) + episode effect + pair noise, over 2 runs."""
    rng = np.random.default_rng(seed)
    rows = []
    for e in range(episodes):
        level = rng.uniform(0.3, 0.6)
        effect = rng.normal(scale=0.05)
        for k in range(per_episode):
            pair = e * per_episode + k
            base = level + rng.normal(scale=0.02)
            for run in (0, 1):
                jitter = rng.normal(scale=0.01)
                for matcher, value in (
                    ("mos", base),
                    ("maximin", base + true_diff + effect + jitter),
                ):
                    rows.append(
                        {"dataset": "CAD", "matcher": matcher, "seed": run, "pair": pair}
                        | {"episode": e, "f1": value, "recall": value, "balanced_accuracy": value}
                    )
    return pd.DataFrame(rows)


def test_interval_covers_a_known_difference_and_excludes_zero():
    table = paired_differences(_per_pair(0.05, episodes=40, per_episode=5))
    assert set(table["metric"]) == {"f1", "recall", "balanced_accuracy"}
    row = table[table["metric"] == "f1"].iloc[0]
    assert (row["matcher_a"], row["matcher_b"]) == ("maximin", "mos")
    assert row["ci_low"] < 0.05 < row["ci_high"] and row["ci_low"] > 0  # fractions
    assert row["pairs"] == 200 and row["episodes"] == 40


def test_runs_are_averaged_per_pair_before_the_difference():
    table = _per_pair(0.0, episodes=3, per_episode=2)
    table.loc[(table["matcher"] == "maximin") & (table["seed"] == 0), "f1"] += 0.2
    table.loc[(table["matcher"] == "maximin") & (table["seed"] == 1), "f1"] -= 0.2
    plain = paired_differences(_per_pair(0.0, episodes=3, per_episode=2))
    shifted = paired_differences(table)
    f1 = lambda t: t[t["metric"] == "f1"].iloc[0]  # noqa: E731
    assert f1(shifted)["diff"] == pytest.approx(f1(plain)["diff"])
    assert f1(shifted)["ci_low"] == pytest.approx(f1(plain)["ci_low"])


def _clustered(rng, sims, episodes, per_episode, truth):
    """(sims, episodes * per_episode) differences: truth + episode effect + pair noise, the
    episode effect as large as the pair noise (what CAD's per-pair F1 differences show)."""
    effect = rng.normal(scale=0.08, size=(sims, episodes, 1))
    noise = rng.normal(scale=0.08, size=(sims, episodes, per_episode))
    return (truth + effect + noise).reshape(sims, -1)


@pytest.mark.parametrize("episodes,per_episode", [(10, 5), (5, 10)])
def test_nominal_95_percent_interval_covers_at_the_suite_shape(episodes, per_episode):
    rng = np.random.default_rng(7)
    values = _clustered(rng, 4000, episodes, per_episode, truth=0.05)
    index = np.repeat(np.arange(episodes), per_episode)
    _, low, high = t_intervals(values, index, episodes)
    coverage = np.mean((low <= 0.05) & (0.05 <= high))
    assert coverage >= 0.93, coverage
    # a pair-level interval (ignoring the episodes) would be far too narrow here
    half = 1.96 * values.std(axis=1, ddof=1) / np.sqrt(values.shape[1])
    naive = np.mean(np.abs(values.mean(axis=1) - 0.05) <= half)
    assert naive < 0.85, naive


def test_interval_uses_whole_episodes_not_pairs():
    # One episode: no interval at all, however many pairs it has.
    mean, low, high, groups = t_interval(np.array([0.0, 0.1, 0.2, 0.3]), np.zeros(4, int))
    assert mean == pytest.approx(0.15) and np.isnan(low) and np.isnan(high) and groups == 1
    # Episodes with constant values: the interval is that of the episode means, as wide with 50
    # pairs per episode as with one.
    few = t_interval(np.array([0.0, 0.04, 0.08]), np.array([0, 1, 2]))
    many = t_interval(np.repeat([0.0, 0.04, 0.08], 50), np.repeat([0, 1, 2], 50))
    assert many == pytest.approx(few)
    # ... and equals the textbook t-interval on the episode means (t at 2 degrees of freedom)
    half = 4.302652729749464 * 0.04 / np.sqrt(3)
    assert few[1] == pytest.approx(0.04 - half) and few[2] == pytest.approx(0.04 + half)


def test_interval_rejects_mismatched_input():
    with pytest.raises(ValueError, match="clusters"):
        t_interval(np.zeros(3), np.zeros(2))


def test_an_interval_stays_inside_the_range_of_its_quantity():
    values = np.array([0.0, 0.0, 0.0, 0.02, 0.0, 0.01])  # rates near 0: mean - t * se < 0
    _, low, high, _ = t_interval(values, np.arange(6) // 2)
    assert low < 0
    _, low, high, _ = t_interval(values, np.arange(6) // 2, bounds=(0.0, 1.0))
    assert low == 0.0 and 0 < high <= 1
