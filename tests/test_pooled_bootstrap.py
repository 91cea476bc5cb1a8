"""The episode-level bootstrap of pooled figures (eval.protocol.pooled_bootstrap): a hand-made
table's pooled F1 difference, its interval and p, the seed, the einsum against a loop, and the
unit of resampling being the episode."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from eval.protocol.multiway_metrics import MultiwayCounts, summarise_counts
from eval.protocol.pooled_bootstrap import (
    F1_COUNTS,
    f1_difference,
    f1_of,
    group_sums,
    interval,
    mean_of,
    pooled_f1,
    two_sided_p,
    weights_for,
)


def frame(tp: list[int], episodes: list[int], declared: int = 10, true_pairs: int = 10):
    """One row per snapshot (run 0): its counts and episode."""
    return pd.DataFrame(
        {
            "group": "g",
            "episode": episodes,
            "seed": 0,
            "true_positives": tp,
            "declared": declared,
            "true_pairs": true_pairs,
        }
    )


EPISODES = [0, 0, 1, 1, 2, 2, 3, 3]
MINE = frame([6, 7, 8, 7, 5, 6, 7, 8], EPISODES)  # 54 of 80 declared, 80 true: F1 108 / 160
BASE = frame([5] * 8, EPISODES)  # 40 of 80 and 80: F1 0.5


def sums(table: pd.DataFrame):
    return group_sums(table, ["group"], F1_COUNTS)


def test_the_pooled_f1_difference_of_a_hand_made_table_and_its_interval():
    result = f1_difference(sums(MINE), sums(BASE), resamples=4000, seed=3)
    assert result.point[0] == pytest.approx(108 / 160 - 0.5)  # pooled, not a mean of ratios
    assert result.low[0] <= 0.175 <= result.high[0]
    assert result.low[0] > 0  # every episode gains: the interval sits above 0 ...
    assert result.p[0] == pytest.approx(2 / 4001)  # ... and no resample is on the other side


def test_the_bootstrap_is_reproducible_with_its_seed():
    first = f1_difference(sums(MINE), sums(BASE), resamples=500, seed=7)
    again = f1_difference(sums(MINE), sums(BASE), resamples=500, seed=7)
    for a, b in zip(first, again, strict=True):
        assert np.array_equal(a, b)
    s = sums(MINE)
    same = f1_of(s, weights_for(s, 500, seed=7)), f1_of(s, weights_for(s, 500, seed=7))
    other = f1_of(s, weights_for(s, 500, seed=8))
    assert np.array_equal(*same) and not np.array_equal(same[0], other)


def test_resamples_are_the_einsum_of_episode_and_run_weights():
    rng = np.random.default_rng(0)
    n = 30
    table = pd.DataFrame(
        {
            "group": rng.choice(["a", "b"], n),
            "episode": rng.integers(0, 5, n),
            "seed": rng.integers(0, 3, n),
            "true_positives": rng.integers(0, 5, n),
            "declared": rng.integers(5, 10, n),
            "true_pairs": rng.integers(5, 10, n),
        }
    )
    s = sums(table)
    weights = weights_for(s, resamples=20, seed=1)
    fast = f1_of(s, weights)
    for r in range(20):  # a resample: each episode and run as often as its weight says
        w = weights.episodes[r][:, None] * weights.draws[r][None, :]
        tp, dec, true = (np.einsum("ked,ed->k", s.of(v), w) for v in F1_COUNTS)
        np.testing.assert_allclose(fast[r], 2 * tp / (dec + true))
    # the point estimate is the table's pooled F1 of every row
    for k, name in enumerate(s.groups["group"]):
        rows = table[table["group"] == name]
        assert f1_of(s)[k] == pytest.approx(
            2 * rows["true_positives"].sum() / (rows["declared"].sum() + rows["true_pairs"].sum())
        )


def test_episodes_are_resampled_not_snapshots():
    # 6 episodes of 5 snapshots; inside an episode every snapshot gains the same, the episodes
    # differ: the episode is the unit of variation and the interval must be as wide as that
    gains = [4, -2, 3, 0, 5, -1]
    episodes = np.repeat(np.arange(6), 5)
    mine = frame(list(np.repeat(np.array(gains) + 5, 5)), list(episodes))
    base = frame([5] * 30, list(episodes))
    clustered = f1_difference(sums(mine), sums(base), resamples=4000, seed=0)
    alone = f1_difference(
        sums(mine.assign(episode=np.arange(30))), sums(base.assign(episode=np.arange(30)))
    )
    width = clustered.high[0] - clustered.low[0]
    assert clustered.point[0] == pytest.approx(alone.point[0])
    assert width > 1.8 * (alone.high[0] - alone.low[0])  # about sqrt(5) wider


def test_runs_are_resampled_with_the_episodes():
    # one episode, two runs that disagree: only resampling the runs gives the interval width
    table = pd.concat([frame([9, 9], [0, 0]), frame([1, 1], [0, 0]).assign(seed=1)])
    s = sums(table)
    low, high = interval(f1_of(s, weights_for(s, resamples=2000, seed=0)))
    assert low[0] == pytest.approx(0.1) and high[0] == pytest.approx(0.9)


def test_two_sided_p_counts_both_sides_with_the_plus_one():
    assert two_sided_p(np.array([-1.0, 1.0, 2.0, 3.0])) == pytest.approx(2 * 2 / 5)
    assert two_sided_p(np.zeros(99)) == 1.0  # no difference anywhere
    assert two_sided_p(np.full(99, 0.2)) == pytest.approx(2 / 100)
    np.testing.assert_allclose(two_sided_p(np.array([[1.0, -1.0], [2.0, -2.0]])), [2 / 3, 2 / 3])


def test_pooled_f1_follows_the_metric_conventions():
    rng = np.random.default_rng(2)
    for _ in range(50):
        tp = int(rng.integers(0, 4))
        declared, true = tp + int(rng.integers(0, 3)), tp + int(rng.integers(0, 3))
        counts = MultiwayCounts(tp, declared, true, 0, 0, 1, 1, 0, 0, 0)
        assert pooled_f1(tp, declared, true) == pytest.approx(
            summarise_counts([counts])["f1_pooled"]
        )


def test_a_mean_per_snapshot_is_resampled_by_episode():
    table = pd.DataFrame(
        {"group": "g", "episode": [0, 0, 1], "seed": 0, "error": [0.1, 0.3, 0.5], "n": 1.0}
    )
    s = group_sums(table, ["group"], ["error", "n"])
    assert mean_of(s, "error", "n")[0] == pytest.approx(0.3)
    low, high = interval(mean_of(s, "error", "n", weights_for(s, 2000, 0)))
    assert low[0] == pytest.approx(0.2) and high[0] == pytest.approx(0.5)  # episode means


def test_one_episode_has_no_interval_and_no_p():
    one = f1_difference(sums(frame([7, 8], [0, 0])), sums(frame([5, 5], [0, 0])), resamples=100)
    assert one.point[0] == pytest.approx(0.25)
    assert np.isnan(one.low[0]) and np.isnan(one.high[0]) and np.isnan(one.p[0])
