"""Maximin's rank among the paper's methods with its episode-bootstrap interval
(eval/protocol/rank_interval.py), as Table I states it."""

import pandas as pd

from eval.protocol.rank_interval import rank_interval


def _pairs(f1: dict[str, list[float]], per_episode: int = 2) -> pd.DataFrame:
    return pd.DataFrame(
        [
            {"matcher": m, "episode": k // per_episode, "pair": k, "seed": 0, "f1": v}
            for m, values in f1.items()
            for k, v in enumerate(values)
        ]
    )


def test_a_rank_that_holds_in_every_episode_has_a_one_point_interval():
    per_pair = _pairs({"maximin": [0.9] * 8, "mos": [0.5] * 8, "sm": [0.2] * 8})
    assert rank_interval(per_pair, "maximin", ["maximin", "mos", "sm"]) == (1, 1, 1, 4)
    assert rank_interval(per_pair, "sm", ["maximin", "mos", "sm"])[:3] == (3, 3, 3)


def test_a_rank_that_episodes_disagree_on_has_a_wide_interval():
    # maximin first in half the episodes, second in the others (first overall, 0.5 against
    # 0.45): the interval spans both ranks
    maximin = [0.9, 0.9, 0.1, 0.1] * 5
    mos = [0.45] * 20
    rank, low, high, episodes = rank_interval(_pairs({"maximin": maximin, "mos": mos}), "maximin",
                                              ["maximin", "mos"])  # fmt: skip
    assert (rank, low, high, episodes) == (1, 1, 2, 10)
