"""The transfer study (eval/studies/transfer/evaluation.py): the hand-crafted reference is chosen on the
validation split, no model's τ comes from a pair it was trained on, and every goal line carries
the interval of its difference and the verdict of eval.protocol.goal_verdict."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from eval.studies.external.evaluation import CALIBRATION_DIR, TEST_DIR
from eval.studies.transfer import evaluation as transfer
from eval.studies.transfer import report as transfer_report

# --- intervals -------------------------------------------------------------------------------


def _per_pair(rng, pairs=40, episodes=8, seeds=(0,), matcher="m"):
    rows = []
    for seed in seeds:
        for pair in range(pairs):
            n_gt = int(rng.integers(2, 9))
            n_pred = int(rng.integers(1, 9))
            rows.append(
                {
                    "dataset": "D",
                    "matcher": matcher,
                    "seed": seed,
                    "pair": pair,
                    "episode": pair * episodes // pairs,
                    "tp": int(rng.integers(0, min(n_gt, n_pred) + 1)),
                    "n_pred": n_pred,
                    "n_gt": n_gt,
                }
            )
    return pd.DataFrame(rows)


def test_the_terms_average_to_the_tables_pooled_f1_over_runs():
    from eval.protocol.metrics import summarise_pooled

    per_pair = _per_pair(np.random.default_rng(0), seeds=(0, 1, 2))
    terms = transfer.pooled_f1_terms(per_pair)
    pooled = summarise_pooled(per_pair, by=["matcher"])["f1_pooled_mean"].iloc[0]
    assert len(terms) == 40 and terms["value"].mean() == pytest.approx(pooled, abs=1e-12)
    value, low, high, clusters = transfer.paired_interval(terms)
    assert value == pytest.approx(pooled) and low < value < high and clusters == 8


def test_with_equal_pair_sizes_the_interval_is_the_t_interval_of_the_pair_f1s():
    from eval.protocol.cluster_interval import t_interval

    rng = np.random.default_rng(1)
    per_pair = _per_pair(rng)
    per_pair["n_pred"] = per_pair["n_gt"] = 5
    per_pair["tp"] = rng.integers(0, 6, len(per_pair))
    terms = transfer.pooled_f1_terms(per_pair)
    expected = t_interval(2 * per_pair["tp"] / 10.0, per_pair["episode"], bounds=(0, 1))
    assert transfer.paired_interval(terms) == pytest.approx(expected)


def test_a_difference_is_paired_on_the_same_frame_pairs_and_clustered_by_blocks():
    rng = np.random.default_rng(2)
    a = transfer.pooled_f1_terms(_per_pair(rng, pairs=61, episodes=1))
    b = transfer.pooled_f1_terms(_per_pair(rng, pairs=61, episodes=1))
    diff, low, high, clusters = transfer.paired_interval(a, b, block=10)
    assert clusters == 7  # 61 consecutive pairs of one sequence: 6 blocks of 10 and one of 1
    assert diff == pytest.approx(a["value"].mean() - b["value"].mean()) and low < diff < high
    assert math.isnan(transfer.paired_interval(a, b)[1])  # one episode: no interval
    with pytest.raises(ValueError, match="other frame pairs"):
        transfer.paired_interval(a, b[b["pair"] != 3], block=10)


# --- the reference is chosen on validation, reported on test ---------------------------------


def _plant_reference(folder: Path, label: str, val_f1: dict, test_f1: dict, checksum="c" * 64):
    """Main-table files in ``folder``: thresholds.csv with the validation pooled F1 ``val_f1``,
    per-pair test metrics whose pooled F1 is ``test_f1`` (10 pairs, 5 episodes)."""
    folder.mkdir(parents=True, exist_ok=True)
    thresholds = pd.DataFrame(
        {
            "dataset": label,
            "matcher": list(val_f1),
            "params": "{}",
            "tau": 0.5,
            "val_f1": 0.0,  # the per-pair mean: not what the choice reads
            "val_frames": 10,
            "val_runs": 1,
            "val_dir": "val",
            "val_f1_pooled": list(val_f1.values()),
        }
    )
    thresholds.to_csv(folder / "thresholds.csv", index=False)
    rows = []
    for matcher, f1 in test_f1.items():
        tp = round(f1 * 10)  # n_pred = n_gt = 10 per pair: pooled F1 = tp / 10
        for pair in range(10):
            rows.append(
                {"dataset": label, "matcher": matcher, "params": "{}", "seed": 0}
                | {"noise_rate": "", "keep": "", "pair": pair, "episode": pair // 2}
                | {"sim_seed": pair // 2, "tau": 0.5, "n1": 12, "n2": 12, "n_gt": 10}
                | {"n_pred": 10, "tp": tp, "correct": 0, "accuracy": 0.5}
                | {"balanced_accuracy": 0.5, "precision": tp / 10, "recall": tp / 10}
                | {"f1": tp / 10, "time_s": 0.001}
            )
    pd.DataFrame(rows).to_csv(folder / "metrics_per_pair.csv", index=False)
    pd.DataFrame([{"dataset": label, "matcher": m, "seed": 0, "ap": 0.5} for m in test_f1]).to_csv(
        folder / "average_precision.csv", index=False
    )
    record = {
        "datasets": [{"label": label, "test_checksum": checksum, "val_dir": "val"}],
        "seeds": [0],
    }
    (folder / "evaluation.json").write_text(json.dumps(record))


def _test_set(folder: Path, label="DMGM"):
    return transfer.TestSet("T", Path("t"), Path("v"), None, folder, label, 10)


def test_the_reference_is_the_validation_winner_reported_with_its_test_figures(tmp_path):
    val = {"consistency": 0.60, "freealign": 0.70, "pose_refine": 0.90, "maximin_pose": 0.95}
    test = {"consistency": 0.70, "freealign": 0.50, "pose_refine": 1.00, "maximin_pose": 0.80}
    _plant_reference(tmp_path, "DMGM", val | {"none": 0.99}, test | {"none": 0.0})
    reference = transfer.reference_for(_test_set(tmp_path), "c" * 64, runner=None)
    free, prior = reference[False], reference[True]
    assert free["matcher"] == "freealign"  # the test winner is consistency: not chosen
    assert free["val_f1_pooled"] == pytest.approx(0.70)
    assert free["f1_pooled"] == pytest.approx(0.50)  # reported on test
    assert prior["matcher"] == "maximin_pose" and prior["f1_pooled"] == pytest.approx(0.80)


def test_no_reference_without_validation_figures_or_for_another_test_dataset(tmp_path):
    _plant_reference(tmp_path, "DMGM", {"consistency": 0.6}, {"consistency": 0.7})
    assert transfer.reference_for(_test_set(tmp_path), "d" * 64, runner=None) == {}
    thresholds = pd.read_csv(tmp_path / "thresholds.csv").drop(columns="val_f1_pooled")
    thresholds.to_csv(tmp_path / "thresholds.csv", index=False)
    # never falls back to the test figures: without validation runs there is no reference
    assert transfer.reference_for(_test_set(tmp_path), "c" * 64, runner=None) == {}


@pytest.fixture(scope="module")
def runner(tmp_path_factory):
    from eval.core.cache import ResultCache
    from eval.core.executor import make_executor
    from eval.core.runner import Runner

    with make_executor(1) as executor:
        yield Runner(ResultCache(tmp_path_factory.mktemp("cache")), executor, progress=False)


@pytest.fixture(scope="module")
def main_tables(tmp_path_factory, runner) -> Path:
    """The main tables' external evaluation of three cheap hand-crafted matchers."""
    from eval.core.tasks import MatcherSpec
    from eval.engine.protocol_run import evaluate
    from eval.engine.splits import open_entry

    folder = tmp_path_factory.mktemp("results") / "external"
    entry = open_entry(TEST_DIR, CALIBRATION_DIR)
    specs = [MatcherSpec(m) for m in ("appearance", "consistency", "pose")]
    evaluate([entry], specs, [0], runner, folder, untuned=False)
    return folder


def test_validation_pooled_f1_reads_the_main_tables_validation_runs_from_the_cache(
    main_tables, runner
):
    from eval.protocol.metrics import summarise_pooled

    val = transfer.validation_pooled_f1(main_tables, "DMGM", runner)
    assert runner.stats.computed == 0 and runner.stats.cached == 3  # the calibration's runs
    assert set(val) == {"appearance", "consistency", "pose"}
    assert all(0 <= v <= 1 for v in val.values())
    test = summarise_pooled(pd.read_csv(main_tables / "metrics_per_pair.csv"), by=["matcher"])
    assert val != dict(zip(test["matcher"], test["f1_pooled_mean"], strict=True))


# --- τ never from training pairs -------------------------------------------------------------


def test_the_external_split_is_disjoint_in_frame_order_and_written_once(tmp_path):
    from cadsim.dataset.reader import Dataset

    train, tau = transfer.split_external(CALIBRATION_DIR, tmp_path)
    a, b = Dataset(train, verify=True), Dataset(tau, verify=True)
    assert len(a) == transfer.EXTERNAL_TRAIN_PAIRS and len(a) + len(b) + 10 == 201
    slots_a = [r["slot"] for r in a.manifest["records"]]
    slots_b = [r["slot"] for r in b.manifest["records"]]
    assert slots_a == list(range(100)) and slots_b == list(range(110, 201))
    assert not {p.checksum for p in a} & {p.checksum for p in b}
    assert a.scenario_name == b.scenario_name == Dataset(TEST_DIR).scenario_name
    stamp = (train / "manifest.json").stat().st_mtime_ns
    assert transfer.split_external(CALIBRATION_DIR, tmp_path) == (train, tau)
    assert (train / "manifest.json").stat().st_mtime_ns == stamp
    sets = transfer.train_sets(tmp_path, tmp_path / "cad-train", CALIBRATION_DIR)
    tests = transfer.test_sets(tmp_path, tmp_path / "out", TEST_DIR, CALIBRATION_DIR)
    assert sets[transfer.EXTERNAL_TRAIN] == [train]
    assert tests[-1].label == transfer.EXTERNAL_TEST and tests[-1].val_dir == tau
    assert tests[-1].block == 10 and tests[0].block is None


@pytest.fixture(scope="module")
def dmgm_model(tmp_path_factory) -> tuple[Path, Path]:
    """(a small model trained as the study trains its DMGM model, its τ split)."""
    from cadsim.commands.train import train_datasets

    folder = tmp_path_factory.mktemp("transfer")
    train, tau = transfer.split_external(CALIBRATION_DIR, folder)
    path = folder / "dmgm.json"
    train_datasets([str(train)], path, variants="learned", rounds=5)
    return path, tau


def test_no_model_has_its_tau_from_a_pair_it_was_trained_on(dmgm_model):
    from cadsim.dataset.training_set import dataset_records
    from matchers.learned.model import load_model

    path, tau = dmgm_model
    trained = load_model(path).training_records()
    assert len(trained) == 100 and not trained & dataset_records(tau)
    transfer.check_tau_split(path, tau)  # disjoint: accepted
    with pytest.raises(ValueError, match="τ would be calibrated on"):
        transfer.check_tau_split(path, CALIBRATION_DIR)  # the old scheme: all of 070


def test_the_study_refuses_a_tau_split_the_model_was_trained_on_before_running(
    dmgm_model, tmp_path
):
    path, _ = dmgm_model
    test = transfer.TestSet("T", TEST_DIR, CALIBRATION_DIR, None, tmp_path, "DMGM", 10)
    with pytest.raises(ValueError, match="trained on 100 record"):
        transfer.evaluate_transfer({"m": (path, 0.0)}, [test], None, tmp_path)
    assert not (tmp_path / transfer.SUBDIR).exists()
    test = transfer.TestSet("T", CALIBRATION_DIR, TEST_DIR, None, tmp_path, "DMGM", 10)
    with pytest.raises(ValueError, match="which it would score"):  # the test set, as before
        transfer.evaluate_transfer({"m": (path, 0.0)}, [test], None, tmp_path)


def test_the_matrix_on_dmgm_end_to_end(dmgm_model, main_tables, runner, monkeypatch):
    from learned_fixture import model_path

    monkeypatch.setattr(transfer, "LEARNED", ("learned",))
    path, tau = dmgm_model
    out = main_tables.parent
    test = transfer.TestSet(transfer.EXTERNAL_TEST, TEST_DIR, tau, None, main_tables, "DMGM", 10)
    models = {transfer.SIM_ONLY: (Path(model_path()), 0.0), transfer.EXTERNAL_TRAIN: (path, 0.0)}
    table = transfer.evaluate_transfer(models, [test], runner, out)
    assert list(table.columns) == transfer.COLUMNS and len(table) == 2
    assert (table["tau_split"] == tau.name).all() and (table["frames"] == 109).all()
    assert (table["cluster_unit"] == "block of 10 pairs").all() and (table["clusters"] == 12).all()
    val = transfer.validation_pooled_f1(main_tables, "DMGM", runner)
    free = [m for m in val if m != "pose"]
    assert (table["handcrafted_matcher"] == max(free, key=val.get)).all()
    row = table.set_index("train").loc[transfer.EXTERNAL_TRAIN]
    assert row["diff_handcrafted"] == pytest.approx(
        row["f1_pooled"] - row["handcrafted_f1_pooled"], abs=1e-9
    )
    assert row["diff_handcrafted_low"] < row["diff_handcrafted"] < row["diff_handcrafted_high"]
    sim = table.set_index("train").loc[transfer.SIM_ONLY]
    assert row["diff_sim_only"] == pytest.approx(row["f1_pooled"] - sim["f1_pooled"], abs=1e-9)
    assert math.isnan(sim["diff_sim_only"])
    written = pd.read_csv(out / "table_transfer.csv")
    assert len(written) == 2 and "Δ F1 [95 % CI]" in (out / "table_transfer.md").read_text()
    lines = transfer_report.goals(written)
    assert lines[0].startswith("trained on cadsim only, no prior") and " [" in lines[0]


# --- goal lines ------------------------------------------------------------------------------


def _goal_table(diff, low, high, gap=(0.01, -0.02, 0.04), pose=(0.98, 0.975, 0.99)):
    base = {c: np.nan for c in transfer.COLUMNS} | {"test": transfer.EXTERNAL_TEST}
    base |= {"clusters": 12, "cluster_unit": "block of 10 pairs", "handcrafted": "Freealign"}
    base |= {"frames": 109}
    rows = []
    for train in (transfer.SIM_ONLY, transfer.EXTERNAL_TRAIN):
        for matcher in ("learned", "learned_pose"):
            row = base | {"train": train, "matcher": matcher}
            row |= {"f1_pooled": 0.612, "handcrafted_f1_pooled": 0.607}
            row |= {"handcrafted_val_f1_pooled": 0.70}
            row |= {"diff_handcrafted": diff, "diff_handcrafted_low": low}
            row |= {"diff_handcrafted_high": high}
            if matcher == "learned_pose":
                row |= dict(
                    zip(("f1_pooled", "f1_pooled_low", "f1_pooled_high"), pose, strict=True)
                )
            if train == transfer.EXTERNAL_TRAIN:
                row |= dict(zip(transfer.GAP_COLUMNS, gap, strict=True))
            rows.append(row)
    return pd.DataFrame(rows, columns=transfer.COLUMNS)


def test_a_goal_is_met_only_when_its_whole_interval_clears_the_bar(tmp_path):
    lines = transfer_report.goals(_goal_table(0.005, -0.05, 0.06))  # 61.2 against 60.7, ± 5.5
    assert lines[0].startswith("trained on cadsim only, no prior, beats")
    assert ": not shown — 0.5 points [-5.0, 6.0]" in lines[0]
    assert "Freealign chosen on the validation split (its pooled F1 there 70.0)" in lines[0]
    assert "12 blocks" in lines[0]
    assert ": met — 98.0 [97.5, 99.0]" in lines[1] and "learned − Freealign" in lines[1]
    assert ": met — 1.0 points [-2.0, 4.0]" in lines[2]  # gap ≤ 5: the whole interval below
    assert transfer_report.goals(_goal_table(0.05, 0.01, 0.09))[0].split(" — ")[0].endswith(": met")
    assert ": not met —" in transfer_report.goals(_goal_table(-0.08, -0.12, -0.03))[0]
    crossing = transfer_report.goals(
        _goal_table(0, 0, 0, gap=(0.04, 0.01, 0.07), pose=(0.98, 0.96, 1))
    )
    assert ": not shown —" in crossing[1] and ": not shown —" in crossing[2]
    no_interval = transfer_report.goals(_goal_table(0.1, np.nan, np.nan))
    assert ": not shown — 10.0 points (no interval)" in no_interval[0]
    # a measured time has no sampling interval: a point measurement, never "met" / "not met"
    for seconds in (90, 130):
        timed = transfer_report.goals(_goal_table(0, 0, 0), stage_s=seconds, computed=3)[-1]
        assert f": {seconds} s (" in timed and timed.endswith("no interval, so no verdict)")
        assert " met" not in timed


def test_the_readme_part_reads_the_goals_from_the_csv(tmp_path):
    _goal_table(0.005, -0.05, 0.06).to_csv(tmp_path / "table_transfer.csv", index=False)
    text = "\n".join(transfer_report.readme_part(tmp_path, "results"))
    assert "### Does simulation transfer?" in text and "not shown — 0.5 points" in text
    assert "Δ F1 [95 % CI]" in text and "+0.5 [-5.0, +6.0]" in text


def test_the_blocks_are_named_in_the_table_and_the_goal_lines(tmp_path):
    table = _goal_table(0.005, -0.05, 0.06)
    assert "(109 frame pairs in 12 blocks of 10 pairs)" in transfer.to_markdown(table)
    assert "t-interval over 12 blocks of 10 pairs" in transfer_report.goals(table)[0]


def test_a_table_written_before_the_intervals_reads_as_not_shown(tmp_path):
    old = ["train", "test", "matcher", "uses_prior", "f1_pooled", "ap", "tau", "frames"]
    old += ["handcrafted", "handcrafted_f1_pooled", "handcrafted_ap", "model_sha256"]
    table = _goal_table(0.005, -0.05, 0.06)[old]
    table.to_csv(tmp_path / "table_transfer.csv", index=False)
    lines = transfer_report.readme_part(tmp_path, "results")
    goals = [line for line in lines if line.startswith("- ")]
    assert len(goals) == 4 and all(": not shown —" in line for line in goals)
    assert "Freealign not chosen on validation" in goals[0]  # an older table says so


def test_the_overlap_from_manifests_is_the_overlap_from_records(tmp_path):
    from test_generate_fakes import FAKE_STAGES, FakeScenario

    from cadsim.dataset import Dataset, training_set
    from cadsim.generation.pipeline import generate_dataset
    from eval.protocol import model_options

    folder = tmp_path / "d"
    generate_dataset(FakeScenario(), folder, pairs=3, workers=1, stages=FAKE_STAGES, progress=False)
    records = [pair.checksum for pair in Dataset(folder)]
    for trained in (set(), {records[0]}, set(records[1:]) | {"elsewhere"}):
        assert model_options.overlapping_records(trained, [folder]) == (
            training_set.overlapping_records(trained, [folder])
        )
    assert model_options.overlapping_records({records[2]}, [folder]) == {str(folder): 1}
