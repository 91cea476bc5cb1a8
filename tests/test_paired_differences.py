"""Paired differences: runs averaged per frame pair first, a seeded bootstrap over episodes (never
single pairs) whose 95 % interval covers a known difference."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from eval.protocol.paired_differences import episode_bootstrap, paired_differences


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


def test_bootstrap_is_seeded():
    rng = np.random.default_rng(1)
    values, episodes = rng.normal(size=60), np.repeat(np.arange(12), 5)
    assert episode_bootstrap(values, episodes, seed=3) == episode_bootstrap(
        values, episodes, seed=3
    )
    assert episode_bootstrap(values, episodes, seed=3) != episode_bootstrap(
        values, episodes, seed=4
    )


def test_bootstrap_resamples_whole_episodes_not_pairs():
    # One episode: every resample draws it whole, so the interval is the mean itself, however
    # much its pairs differ (a pair bootstrap would spread).
    values = np.array([0.0, 10.0, 20.0, 30.0])
    mean, low, high = episode_bootstrap(values, np.zeros(4, int))
    assert mean == low == high == 15.0
    # Episodes with constant values: every resampled mean is a mixture of the episode means, and
    # the interval is as wide as with one pair per episode, not narrower with more pairs each.
    few = episode_bootstrap(np.array([0.0, 4.0, 8.0]), np.array([0, 1, 2]))
    many = episode_bootstrap(np.repeat([0.0, 4.0, 8.0], 50), np.repeat([0, 1, 2], 50))
    assert many == pytest.approx(few)
    assert 0.0 <= many[1] <= many[2] <= 8.0


def test_bootstrap_rejects_mismatched_input():
    with pytest.raises(ValueError, match="episodes"):
        episode_bootstrap(np.zeros(3), np.zeros(2))
