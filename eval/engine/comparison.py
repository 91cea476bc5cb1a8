"""A study's headline comparison: per condition, the method of highest validation F1 against
the runner-up, the paired per-pair *test* F1 difference with its episode-level cluster
t-interval and the minimum detectable difference (:mod:`eval.protocol.detectable_difference`).
Imports ``eval/protocol/`` and this folder."""

from __future__ import annotations

from collections.abc import Mapping

import pandas as pd

from eval.engine.validation_choice import ranked_on_validation
from eval.protocol.cluster_interval import t_interval
from eval.protocol.detectable_difference import minimum_detectable_difference

INTERVAL_COLUMNS = (
    "preset",
    "best",
    "runner_up",
    "f1_diff",
    "ci_low",
    "ci_high",
    "pairs",
    "episodes",
    "mdd",
    "clusters",
)


def best_against_runner_up(
    per_pair: pd.DataFrame,
    validation: Mapping[str, Mapping[str, float]] | None = None,
    level: float = 0.95,
) -> pd.DataFrame:
    """Per preset: the matcher of highest validation F1 (``validation``: {preset: {matcher: val
    F1}}) against the second, the mean per-pair *test* F1 difference (runs averaged first) and
    its cluster t-interval over episodes, with the minimum detectable difference (``mdd``, 95 %
    confidence, 80 % power) over its ``clusters``. Matchers that cannot run under the preset are
    in no comparison (:func:`eval.engine.validation_choice.ranked_on_validation`)."""
    rows = []
    for preset, group in per_pair.groupby("preset", sort=False):
        ranking = ranked_on_validation(group, (validation or {}).get(preset))
        if len(ranking) < 2:
            continue
        best, second = ranking[:2]
        means = (
            group.groupby(["matcher", "pair"], sort=False)
            .agg(f1=("f1", "mean"), episode=("episode", "first"))
            .reset_index()
        )
        joined = means[means["matcher"] == best].merge(
            means[means["matcher"] == second], on="pair", suffixes=("", "_b")
        )
        d = (joined["f1"] - joined["f1_b"]).to_numpy()
        episodes = joined["episode"].to_numpy()
        diff, low, high, _ = t_interval(d, episodes, level, bounds=(-1.0, 1.0))
        mdd, clusters = minimum_detectable_difference(d, episodes, level)
        rows.append(
            {"preset": preset, "best": best, "runner_up": second, "f1_diff": diff}
            | {"ci_low": low, "ci_high": high, "pairs": len(joined)}
            | {"episodes": joined["episode"].nunique(), "mdd": mdd, "clusters": clusters}
        )
    return pd.DataFrame(rows, columns=list(INTERVAL_COLUMNS))
