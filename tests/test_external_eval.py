"""Evaluation side of the external data and the localisation prior: pooled columns, the external
table beside DMGM's figure, the agreement statistic and its bootstrap, the localisation re-draw in
the cache key, and the localisation sweep end to end on a small fake dataset."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pandas as pd
import pytest
from scipy.stats import spearmanr
from test_generate_fakes import FAKE_STAGES, FakeScenario

from eval.commands.sweep_localisation import (
    COLUMNS,
    localisation_of,
    parse_sigmas,
    sweep_localisation,
    write_sweep,
)
from eval.core.cache import ResultCache
from eval.core.executor import SerialExecutor
from eval.core.runner import Runner, requests_for
from eval.core.tasks import MatcherSpec, RunSpec
from eval.engine.splits import open_entry
from eval.protocol.metrics import summarise_pooled
from eval.report.figures import write_fig_localisation
from eval.report.tables import write_table1
from eval.studies.external.agreement import (
    agreement,
    pair_f1,
    paper_f1,
    spearman_rows,
    write_agreement,
)
from eval.studies.external.evaluation import DMGM_PUBLISHED, best_pooled, write_table_external
from matchers import search_space


def _per_pair(rows: list[tuple]) -> pd.DataFrame:
    """Per-pair metric rows from (dataset, matcher, seed, pair, tp, n_pred, n_gt)."""
    out = []
    for dataset, matcher, seed, pair, tp, n_pred, n_gt in rows:
        p = tp / n_pred if n_pred else float(n_gt == 0)
        r = tp / n_gt if n_gt else 1.0
        f1 = 2 * p * r / (p + r) if p + r else 0.0
        out.append(
            {"dataset": dataset, "matcher": matcher, "params": "{}", "seed": seed, "pair": pair}
            | {"episode": 0, "sim_seed": 0, "tau": 0.5, "n1": 9, "n2": 9, "n_gt": n_gt}
            | {"n_pred": n_pred, "tp": tp, "correct": 0, "accuracy": 0.5}
            | {"balanced_accuracy": 0.5, "precision": p, "recall": r, "f1": f1, "time_s": 0.001}
        )
    return pd.DataFrame(out)


def test_pooled_metrics_sum_counts_over_a_runs_pairs():
    per_pair = _per_pair(
        [
            ("X", "a", 0, 0, 1, 1, 1),  # a small pair, perfect
            ("X", "a", 0, 1, 2, 10, 10),  # a large pair, poor
            ("X", "a", 1, 0, 0, 0, 1),
            ("X", "a", 1, 1, 5, 10, 10),
        ]
    )
    pooled = summarise_pooled(per_pair, by=["dataset", "matcher"]).iloc[0]
    run0 = (3 / 11, 3 / 11)
    run1 = (5 / 10, 5 / 11)
    f1 = [2 * p * r / (p + r) for p, r in (run0, run1)]
    assert pooled["precision_pooled_mean"] == pytest.approx((run0[0] + run1[0]) / 2)
    assert pooled["recall_pooled_mean"] == pytest.approx((run0[1] + run1[1]) / 2)
    assert pooled["f1_pooled_mean"] == pytest.approx(np.mean(f1))
    assert pooled["f1_pooled_std"] == pytest.approx(np.std(f1, ddof=1))
    # Per-pair means weigh the small perfect pair as much as the large one; pooling does not.
    assert per_pair[per_pair.seed == 0]["f1"].mean() > pooled["f1_pooled_mean"]
    empty = summarise_pooled(_per_pair([("X", "n", 0, 0, 0, 0, 3)]), by=["matcher"]).iloc[0]
    assert empty["precision_pooled_mean"] == 0 and empty["recall_pooled_mean"] == 0


def _write_eval(folder, per_pair: pd.DataFrame) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    per_pair.to_csv(folder / "metrics_per_pair.csv", index=False)
    taus = per_pair.groupby(["dataset", "matcher"]).size().reset_index()[["dataset", "matcher"]]
    taus.assign(params="{}", tau=0.5, val_f1=0.5, val_frames=1, val_runs=1, val_dir="v").to_csv(
        folder / "thresholds.csv", index=False
    )


def test_table1_and_external_table_carry_pooled_columns(tmp_path):
    rows = [("DMGM", m, 0, k, tp, 4, 4) for k in range(3) for m, tp in (("pose", 4), ("sm", 1))]
    _write_eval(tmp_path / "external", _per_pair(rows))
    table1 = write_table1(tmp_path / "external")
    assert "Pooled P / R / F1" in table1 and "100.0 / 100.0 / 100.0" in table1
    csv = pd.read_csv(tmp_path / "external" / "table1.csv")
    assert {"precision_pooled_mean", "recall_pooled_mean", "f1_pooled_mean"} <= set(csv.columns)
    table = write_table_external(tmp_path)
    ours = table[table["source"] == "ours"].set_index("matcher")
    assert bool(ours.loc["pose", "uses_prior"]) and not bool(ours.loc["sm", "uses_prior"])
    assert ours.loc["sm", "f1_pooled_mean"] == pytest.approx(0.25)
    published = table[table["matcher"] == "dmgm_published"].iloc[0]
    assert published["f1_pooled_mean"] == DMGM_PUBLISHED["f1"] == 0.797
    assert "test set" in published["source"]
    markdown = (tmp_path / "table_external.md").read_text()
    assert "DMGM (published)" in markdown and "not real-world" in markdown
    assert "0.110 (test)" in markdown and "77.6 / 82.0 / 79.7" in markdown
    assert best_pooled(table) == ("Pose prior only", 1.0)


def test_spearman_rows_matches_scipy_with_ties():
    rng = np.random.default_rng(0)
    a = rng.integers(0, 4, (50, 6)).astype(float)
    b = rng.normal(size=(50, 6))
    got = spearman_rows(a, b)
    for k in range(50):
        if np.ptp(a[k]) == 0:
            assert np.isnan(got[k])
        else:
            assert got[k] == pytest.approx(spearmanr(a[k], b[k]).statistic)


def test_agreement_interval_comes_from_both_sides():
    rng = np.random.default_rng(1)
    levels = np.array([0.9, 0.7, 0.5, 0.3, 0.1])
    matchers = ["a", "b", "c", "d", "e"]

    def table(noise: float, flip: bool = False) -> pd.DataFrame:
        means = levels[::-1] if flip else levels
        values = np.clip(means[:, None] + rng.normal(0, noise, (5, 40)), 0, 1)
        return pd.DataFrame(values, index=matchers)

    same = agreement(table(0.02), table(0.02), draws=500)
    assert same["rho"] == pytest.approx(1.0) and same["ci_low"] > 0.8
    assert same["matchers"] == "a;b;c;d;e"
    opposite = agreement(table(0.02), table(0.02, flip=True))
    assert opposite["rho"] == pytest.approx(-1.0) and opposite["ci_high"] < -0.8
    # Noisy pairs on either side widen the interval.
    noisy = agreement(table(0.6), table(0.6))
    assert noisy["ci_high"] - noisy["ci_low"] > same["ci_high"] - same["ci_low"]
    # A fixed side (the paper's column): only the reference is resampled.
    fixed = agreement(None, table(0.02), paper_f1=pd.Series(levels, index=matchers))
    assert fixed["rho"] == pytest.approx(1.0)
    # Fewer than three matchers in common: no ranking to compare.
    assert np.isnan(agreement(table(0.1).iloc[:2], table(0.1))["rho"])
    # Clusters: pairs of one episode share an effect per matcher, so they move together; drawing
    # whole episodes widens the interval that drawing pairs would give.
    episode = np.repeat(np.arange(4), 10)
    shared = rng.normal(0, 0.3, (5, 4))[:, episode]  # matcher x pair, constant within an episode
    clustered = pd.DataFrame(np.clip(levels[:, None] + shared, 0, 1), index=matchers)
    labels = pd.Series(episode, index=clustered.columns)
    by_pair = agreement(clustered, table(0.02))
    by_episode = agreement(clustered, table(0.02), None, labels)
    assert by_episode["rho"] == by_pair["rho"]
    width = lambda r: r["ci_high"] - r["ci_low"]  # noqa: E731
    assert width(by_episode) > width(by_pair)


def test_write_agreement_uses_prior_free_matchers_without_none(tmp_path):
    names = ["sm", "rrwm", "mos", "maximin", "none", "pose"]
    quality = {"sm": 2, "rrwm": 1, "mos": 3, "maximin": 4, "none": 0, "pose": 4}
    rows = []
    for dataset, pairs in (("CAD", 8), ("MRC", 6)):
        rows += [(dataset, m, s, k, quality[m], 4, 4) for m in names for s in (0, 1) for k in range(pairs)]  # fmt: skip
    _per_pair(rows).to_csv(tmp_path / "metrics_per_pair.csv", index=False)
    (tmp_path / "external").mkdir()
    ext = [("DMGM", m, 0, k, quality[m], 4, 4) for m in names for k in range(5)]
    _per_pair(ext).to_csv(tmp_path / "external" / "metrics_per_pair.csv", index=False)
    table = write_agreement(tmp_path)
    assert list(table.columns) == ["dataset", "reference", "matchers", "rho", "ci_low", "ci_high"]
    assert list(table["dataset"]) == ["MRC", "CAD", "paper MRC", "paper CAD"]
    ours = table.iloc[1]
    assert ours["matchers"] == "maximin;mos;rrwm;sm" and ours["rho"] == pytest.approx(1.0)
    assert set(paper_f1()["CAD"].index) >= {"sm", "maximin"}
    assert (tmp_path / "agreement.csv").is_file()
    assert pair_f1(_per_pair(ext)).shape == (6, 5)


def test_localisation_spec_is_part_of_the_cache_key(tmp_path):
    base = RunSpec("c" * 64, MatcherSpec("pose"), 0, None, "v1")
    moved = dataclasses.replace(base, localisation=(2.5, 2.5 * 0.2 / 1.2))
    assert base.key() != moved.key()
    assert moved.key() != dataclasses.replace(base, localisation=(5.0, 5.0 * 0.2 / 1.2)).key()
    assert moved.key() != dataclasses.replace(moved, seed=1).key()
    request = requests_for([("d", "c" * 64)], [MatcherSpec("pose")], [0], localisation=(1, 0))[0]
    assert request.localisation == (1.0, 0.0) and isinstance(request.localisation[0], float)
    assert localisation_of(1.2) == pytest.approx((1.2, 0.2))
    assert parse_sigmas("5,0,1.2,0") == [0.0, 1.2, 5.0]
    with pytest.raises(ValueError, match="--sigmas"):
        parse_sigmas("-1")


@dataclasses.dataclass
class _Scenario(FakeScenario):
    localisation: dict = dataclasses.field(default_factory=dict)


def test_localisation_sweep_end_to_end(tmp_path):
    from cadsim.generation.pipeline import generate_dataset

    for name, seed in (("fake", 11), ("fake-val", 1011)):
        generate_dataset(
            _Scenario(noise={"noise_rate": 0.0}),
            tmp_path / name,
            pairs=3,
            seed=seed,
            workers=1,
            stages=FAKE_STAGES,
            progress=False,
        )
    entry = open_entry(tmp_path / "fake", tmp_path / "fake-val")
    cache = ResultCache(tmp_path / "cache")
    runner = Runner(cache, SerialExecutor(), progress=False)
    matchers = [MatcherSpec("pose"), MatcherSpec("appearance")]
    rows = sweep_localisation(entry, matchers, [0, 1], [0.0, 8.0], runner)
    assert list(rows.columns) == COLUMNS and len(rows) == 4
    f1 = rows.set_index(["position_sigma_m", "matcher"])["f1_mean"]
    assert f1[(0.0, "pose")] == pytest.approx(1.0)  # exact prior, well-separated objects
    assert f1[(8.0, "pose")] < f1[(0.0, "pose")]  # a bad prior hurts the prior matcher
    assert f1[(0.0, "appearance")] == f1[(8.0, "appearance")]  # ... and nothing else
    assert rows.set_index(["position_sigma_m", "matcher"]).loc[(8.0, "pose"), "yaw_sigma_deg"] == (
        pytest.approx(8.0 * 0.2 / 1.2)
    )
    computed = runner.totals.computed
    again = sweep_localisation(entry, matchers, [0, 1], [0.0, 8.0], runner)
    pd.testing.assert_frame_equal(rows, again)
    assert runner.totals.computed == computed  # everything from the cache the second time
    write_sweep(tmp_path / "out", rows)
    assert [p.suffix for p in write_fig_localisation(tmp_path / "out")] == [".png", ".pdf"]
    saved = pd.read_csv(tmp_path / "out" / "localisation_sweep.csv")
    assert list(saved.columns) == COLUMNS and len(saved) == 4
    # appearance ignores the prior and its seed: the same F1 every run, reported as such
    flat = rows[rows["matcher"] == "appearance"]
    assert flat["deterministic"].all() and flat["f1_std"].isna().all()
    assert set(rows["params"]) == {"{}"}  # not tuned: the defaults at every level


def test_localisation_sweep_tunes_every_level_on_validation_at_that_level(tmp_path, monkeypatch):
    from cadsim.generation.pipeline import generate_dataset
    from eval.protocol import tuning

    for name, seed in (("fake", 11), ("fake-val", 1011)):
        generate_dataset(_Scenario(noise={"noise_rate": 0.0}), tmp_path / name, pairs=3,
                         seed=seed, workers=1, stages=FAKE_STAGES, progress=False)  # fmt: skip
    entry = open_entry(tmp_path / "fake", tmp_path / "fake-val")
    runner = Runner(ResultCache(tmp_path / "cache"), SerialExecutor(), progress=False)
    calls, requested, tuning_now = [], [], []
    real_tune, real_run = tuning.tune_entry, runner.run

    def tune_spy(entry, matchers, runner, limit=None, localisation=None):
        calls.append(localisation)
        tuning_now.append(True)
        try:
            return real_tune(entry, matchers, runner, limit, localisation)
        finally:
            tuning_now.pop()

    def run_spy(requests, desc="runs"):
        requested.extend((bool(tuning_now), r) for r in requests)
        return real_run(requests, desc)

    monkeypatch.setattr(tuning, "tune_entry", tune_spy)
    monkeypatch.setattr(runner, "run", run_spy)
    rows = sweep_localisation(entry, [MatcherSpec("pose")], [0], [0.0, 8.0], runner, tune=True)
    assert calls == [(0.0, 0.0), (8.0, pytest.approx(8.0 * 0.2 / 1.2))]  # once per level
    searched = [r for during, r in requested if during]
    assert {r.dataset_dir for r in searched} == {str(entry.val_dir)}  # never the test pairs
    assert {r.localisation[0] for r in searched} == {0.0, 8.0}  # each level at its own error
    assert len({r.matcher for r in searched}) == len(search_space("pose"))
    assert len(rows) == 2 and rows["params"].map(json.loads).map(type).eq(dict).all()
