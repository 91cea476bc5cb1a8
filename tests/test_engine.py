"""The study engine's shared steps (eval/engine/): cells, episode intervals, choices on
validation, best against runner-up, result files read back."""

from __future__ import annotations

import numpy as np
import pandas as pd

from eval.engine.cells import cell, ranged, signed_interval
from eval.engine.comparison import INTERVAL_COLUMNS, best_against_runner_up
from eval.engine.episode_interval import column_interval, pair_means
from eval.engine.result_table import numeric_column, read_result
from eval.engine.validation_choice import ranked_on_validation, recorded_validation


def _per_pair(levels: dict[str, float], episodes: int = 4, pairs: int = 3, runs: int = 2):
    rng = np.random.default_rng(0)
    rows = []
    for matcher, level in levels.items():
        for e in range(episodes):
            for p in range(pairs):
                for seed in range(runs):
                    f1 = float(np.clip(level + rng.normal(0, 0.02), 0, 1))
                    rows.append(
                        {"matcher": matcher, "preset": "exact", "pair": e * pairs + p}
                        | {"episode": e, "seed": seed, "f1": f1}
                    )
    return pd.DataFrame(rows)


def test_cells_show_percent_intervals_and_a_dash_for_missing_values():
    assert cell(0.8123) == "81.2"
    assert cell(2.5, percent=False, digits=2) == "2.50"
    assert cell(float("nan")) == cell(None) == "–"
    assert ranged(0.5, 0.4, 0.6) == "50.0 [40.0, 60.0]"
    assert ranged(0.5, np.nan, 0.6) == "50.0"
    assert signed_interval(-0.012, 0.034) == "[-1.2, +3.4]"


def test_runs_are_averaged_per_pair_before_the_episode_interval():
    per_pair = _per_pair({"a": 0.7})
    means = pair_means(per_pair, ["f1"])
    assert len(means) == 12 and set(means["episode"]) == {0, 1, 2, 3}
    mean, low, high = column_interval(per_pair, "f1")
    assert low < mean < high
    assert np.isclose(mean, means["f1"].mean())


def test_the_validation_ranking_decides_even_against_test_figures():
    per_pair = _per_pair({"good_on_test": 0.9, "good_on_val": 0.5, "third": 0.3})
    validation = {"good_on_val": 0.8, "good_on_test": 0.6, "third": 0.1}
    assert ranked_on_validation(per_pair, validation) == ["good_on_val", "good_on_test", "third"]
    assert ranked_on_validation(per_pair, None)[0] == "good_on_test"  # in memory: test F1
    rows = best_against_runner_up(per_pair, {"exact": validation})
    assert list(rows.columns) == list(INTERVAL_COLUMNS)
    row = rows.iloc[0]
    assert (row.best, row.runner_up) == ("good_on_val", "good_on_test")
    assert row.f1_diff < 0 and row.ci_high < 0  # chosen on validation, behind on test
    assert row.episodes == 4 and row.pairs == 12


def test_a_prior_reader_under_denied_is_not_ranked():
    per_pair = _per_pair({"pose": 0.9, "sm": 0.4}).assign(preset="denied")
    assert ranked_on_validation(per_pair, {"pose": 0.9, "sm": 0.4}) == ["sm"]


def test_result_files_read_back(tmp_path):
    assert read_result(tmp_path, "table.csv") is None
    (tmp_path / "table.csv").write_text("a,b\n")
    assert read_result(tmp_path, "table.csv") is None
    assert read_result(tmp_path, "table.csv", allow_empty=True).empty
    (tmp_path / "table.csv").write_text("a,b\n1,\n")
    table = read_result(tmp_path, "table.csv")
    assert np.isnan(table["b"].iloc[0])
    assert numeric_column(table, "missing").isna().all()
    (tmp_path / "v2x").mkdir()
    (tmp_path / "v2x" / "validation_f1.csv").write_text(
        "preset,matcher,val_f1\ndenied,pose,0.9\ndenied,sm,0.5\nexact,pose,0.8\n"
    )
    assert recorded_validation(tmp_path, "v2x") == {"denied": {"sm": 0.5}, "exact": {"pose": 0.8}}


def test_a_declared_goal_is_met_only_when_its_interval_clears_the_bar():
    from eval.engine.goal import Goal

    goal = Goal("gnss-urban", "F1 ≥ 90", ("f1_mean", "f1_low", "f1_high"), 0.9)
    row = pd.Series({"f1_mean": 0.95, "f1_low": 0.92, "f1_high": 0.97})
    assert goal.line(row, "`x`").startswith("F1 ≥ 90: met — 95.0 [92.0, 97.0]")
    crossing = row.copy()
    crossing["f1_low"] = 0.88
    assert "not shown" in goal.line(crossing, "`x`")
    at_most = Goal("denied", "error ≤ 10", ("f1_mean", "f1_low", "f1_high"), 0.99, at_least=False)
    assert ": met" in at_most.line(row, "`x`")
