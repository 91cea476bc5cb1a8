"""The regime sweep: thinning levels on validation and test alike, τ recalibrated per level, the
achieved share falls to 0; crossovers between two matchers' curves; regime cards as a table."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from frame_pair_fakes import make_dataset

from eval.commands.sweep_regime import SweepResult, parse_keep, sweep_regime, write_sweep
from eval.core import tasks
from eval.core.cache import ResultCache
from eval.core.executor import SerialExecutor
from eval.core.runner import Runner
from eval.core.tasks import MatcherSpec
from eval.engine.splits import open_entry
from eval.protocol import calibration
from eval.protocol.crossovers import crossings, find_crossovers
from eval.studies.table1 import regime_cards


@pytest.fixture
def world(monkeypatch):
    datasets = {
        "data/cad": make_dataset(100, 4, only1=8, only2=7),
        "data/cad-val": make_dataset(900, 3, only1=8, only2=7),
    }
    monkeypatch.setattr(tasks, "open_dataset", lambda path: datasets[path])
    return datasets


def test_sweep_thins_validation_and_test_and_the_share_falls_to_zero(world, tmp_path, monkeypatch):
    calibrated = []
    real = calibration.calibrate

    def spy(runs):
        calibrated.append(runs)
        return real(runs)

    monkeypatch.setattr(calibration, "calibrate", spy)
    runner = Runner(ResultCache(tmp_path / "cache"), SerialExecutor(), version="v", progress=False)
    entry = open_entry("data/cad", "data/cad-val")
    named = {"appearance": MatcherSpec("appearance"), "none": MatcherSpec("none")}
    result = sweep_regime(entry, named, [0, 1], [1.0, 0.5, 0.0], runner, limit=3)
    rows = result.rows

    shares = rows.drop_duplicates("keep").set_index("keep")["share"]
    pairs = world["data/cad"][:3]
    total = sum(len(p.view1) + len(p.view2) for p in pairs)
    expected = sum(len(p.view1) + len(p.view2) - 2 * len(p.gt_pairs) for p in pairs) / total
    assert shares[1.0] == pytest.approx(expected)
    assert shares[1.0] > shares[0.5] > shares[0.0] == 0.0
    assert (rows["pairs"] == 3).all() and set(rows["matcher"]) == {"appearance", "none"}
    # τ is refitted per level on validation runs thinned the same way (keep in each run's spec).
    keeps = [{r.spec.keep for r in runs} for runs in calibrated]
    assert keeps == [{None}, {None}, {0.5}, {0.5}, {0.0}, {0.0}]
    # Two runs = two thinning draws per level; each level's mean F1 has an interval around it.
    assert (rows["runs"] == 2).all()
    assert (rows["f1_ci_low"] <= rows["f1_mean"] + 1e-9).all()
    assert (rows["f1_mean"] <= rows["f1_ci_high"] + 1e-9).all()
    assert all(r.dataset_dir == "data/cad-val" for runs in calibrated for r in runs)
    none = rows[rows["matcher"] == "none"].set_index("keep")
    assert none.loc[1.0, "balanced_accuracy_mean"] == 0.5 and none.loc[0.0, "f1_mean"] == 0.0

    written = write_sweep(tmp_path / "out", result)
    assert [p.name for p in written[:2]] == ["regime_sweep.csv", "crossovers.csv"]
    assert (tmp_path / "out" / "fig_regime.png").is_file()
    # Another dataset's rows are kept when one dataset is swept again.
    other = SweepResult(rows.assign(dataset="MRC"), result.crossovers.assign(dataset="MRC"))
    write_sweep(tmp_path / "out", other)
    write_sweep(tmp_path / "out", result)
    table = pd.read_csv(tmp_path / "out" / "regime_sweep.csv")
    assert sorted(table["dataset"].unique()) == ["CAD", "MRC"] and len(table) == 2 * len(rows)


def test_parse_keep():
    assert parse_keep("1,0.5,0,0.5") == [1.0, 0.5, 0.0]
    with pytest.raises(ValueError, match="--keep"):
        parse_keep("1,2")


def test_crossings_are_interpolated_and_directed():
    share = np.array([0.0, 0.2, 0.4, 0.6])
    assert crossings(share, np.array([-2.0, -1.0, 1.0, 3.0])) == [(pytest.approx(0.3), "a_gains")]
    assert crossings(share, np.array([1.0, 0.0, -1.0, -1.0])) == [(0.2, "a_loses")]
    assert crossings(share, np.array([1.0, 2.0, 3.0, 1.0])) == []


def _sweep_per_pair(curves, noise=0.0, episodes=5, pairs_per_episode=4, draws=5, seed=0):
    """Per-(level, matcher, pair, run) rows of a fake regime sweep: matcher `m`'s F1 at keep k is
    ``curves[m](share)`` plus Gaussian noise of sd `noise`; 4 covisible objects and round(12 k)
    non-covisible ones a pair."""
    rng = np.random.default_rng(seed)
    rows = []
    for keep in (1.0, 0.75, 0.5, 0.25, 0.0):
        non = round(keep * 12)
        share = non / (8 + non)
        for matcher, curve in curves.items():
            for pair in range(episodes * pairs_per_episode):
                for run in range(draws):
                    f1 = curve(share) + noise * rng.normal()
                    rows.append(
                        {"dataset": "CAD", "keep": keep, "matcher": matcher, "pair": pair}
                        | {"episode": pair // pairs_per_episode, "seed": run}
                        | {"n1": 4 + non // 2, "n2": 4 + non - non // 2, "n_gt": 4}
                        | {"f1": f1, "balanced_accuracy": f1}
                    )
    return pd.DataFrame(rows)


def test_a_clear_crossover_is_significant_with_an_interval_around_it():
    per_pair = _sweep_per_pair(
        {"maximin": lambda s: 0.5 + s, "mos": lambda s: 0.8, "rrwhm": lambda s: 0.1}, noise=0.02
    )
    table = find_crossovers(per_pair)
    mos = table[(table["matcher_b"] == "mos") & (table["metric"] == "f1")].iloc[0]
    assert mos["crossing_share"] == pytest.approx(0.3, abs=0.02) and mos["direction"] == "a_gains"
    assert mos["share_ci_low"] <= mos["crossing_share"] <= mos["share_ci_high"]
    assert mos["share_ci_high"] - mos["share_ci_low"] < 0.1
    assert mos["significant"] and mos["resamples_crossing"] == 1.0
    # No crossing: one row per metric, empty share, not significant.
    rrwhm = table[table["matcher_b"] == "rrwhm"]
    assert len(rrwhm) == 2 and rrwhm["crossing_share"].isna().all()
    assert not rrwhm["significant"].any()


def test_a_crossover_within_the_noise_is_not_significant():
    # maximin and MOS differ by < 0.01, the runs by 0.3: the noisy curves cross (here several
    # times, and in most resamples too), but they never swap order beyond their noise.
    per_pair = _sweep_per_pair(
        {"maximin": lambda s: 0.8 + 0.02 * (s - 0.3), "mos": lambda s: 0.8}, noise=0.3, seed=3
    )
    table = find_crossovers(per_pair)
    assert table["crossing_share"].notna().all() and len(table) > 2
    assert (table["resamples_crossing"] > 0.5).all()
    assert not table["significant"].any()


def test_crossover_intervals_resample_draws_not_only_episodes():
    # One episode: an episode-only bootstrap would have nothing to resample; the draws still vary.
    per_pair = _sweep_per_pair(
        {"maximin": lambda s: 0.5 + s, "mos": lambda s: 0.8}, noise=0.05, episodes=1
    )
    row = find_crossovers(per_pair).query("metric == 'f1'").iloc[0]
    assert row["share_ci_high"] > row["share_ci_low"]


def test_regime_cards_are_written_per_dataset_and_shown_as_markdown(tmp_path, monkeypatch):
    fields = {
        "objects_per_view": 9.5,
        "covisible": 5.25,
        "noncovisible_share": 0.42,
        "covisible_share_of_smaller": 0.66,
        "appearance_auc": 0.913,
        "position_error_median_m": None,
    }
    monkeypatch.setattr(regime_cards, "regime_of", lambda path: fields | {"extra": 1})
    bounds = {"appearance_auc": 0.913, "appearance_auc_low": 0.9, "appearance_auc_high": 0.93}
    monkeypatch.setattr(regime_cards, "auc_intervals_of", lambda path: bounds | {"episodes": 10})
    path = regime_cards.write_regime(tmp_path, {"CAD": "data/cad", "MRC": "data/mrc"})
    intervals = pd.read_csv(tmp_path / regime_cards.AUC_FILE)
    assert list(intervals.columns) == list(regime_cards.AUC_COLUMNS)
    assert intervals["dataset"].tolist() == ["CAD", "MRC"]
    assert intervals["appearance_auc_low"].tolist() == [0.9, 0.9]
    table = pd.read_csv(path)
    assert list(table.columns) == list(regime_cards.COLUMNS)
    assert table["dataset"].tolist() == ["CAD", "MRC"]
    assert table["position_error_median_m"].isna().all()
    markdown = regime_cards.regime_markdown(path)
    assert "| MRC | 9.5 | 5.2 | 42 % | 66 % | 0.91 | – |" in markdown
    assert markdown.index("| MRC") < markdown.index("| CAD")  # the paper's column order
