"""The two protocols and the trivial baselines: ``none`` scores exactly what abstaining earns
(balanced accuracy 50, accuracy = the non-covisible share), under τ and without; the paper
protocol runs SM/RRWM/MOS on image distances, reports full assignments and writes its own table."""

from __future__ import annotations

import pandas as pd
import pytest
from frame_pair_fakes import make_dataset

from eval.core import tasks
from eval.core.cache import ResultCache
from eval.core.executor import SerialExecutor
from eval.core.runner import Runner
from eval.core.tasks import MatcherSpec
from eval.engine.protocol_run import evaluate
from eval.engine.splits import open_entry
from eval.protocol.variants import paper_spec, variant_path
from eval.report.tables import write_tables


@pytest.fixture
def world(monkeypatch):
    datasets = {"data/cad": make_dataset(100, 4), "data/cad-val": make_dataset(900, 3)}
    monkeypatch.setattr(tasks, "open_dataset", lambda path: datasets[path])
    return datasets


def _runner(tmp_path) -> Runner:
    return Runner(ResultCache(tmp_path / "cache"), SerialExecutor(), version="v", progress=False)


def test_paper_spec_sets_image_space_pairwise_terms_only_where_they_exist():
    assert paper_spec(MatcherSpec("sm")) == MatcherSpec.of("sm", pairwise="image")
    assert paper_spec(MatcherSpec.of("mos", sigma=0.2)) == MatcherSpec.of(
        "mos", pairwise="image", sigma=0.2
    )
    assert paper_spec(MatcherSpec("maximin")) == MatcherSpec("maximin")
    assert variant_path("r", "table1", "paper_protocol", ".md").name == "table1_paper_protocol.md"


@pytest.mark.parametrize("protocol", ["calibrated", "paper"])
def test_none_scores_half_balanced_accuracy_and_the_distractor_share_as_accuracy(
    world, tmp_path, protocol
):
    out = tmp_path / "out"
    evaluate(
        [open_entry("data/cad", "data/cad-val")],
        [MatcherSpec("none"), MatcherSpec("appearance")],
        [0],
        _runner(tmp_path),
        out,
        protocol=protocol,
    )
    variant = "" if protocol == "calibrated" else "paper_protocol"
    per_pair = pd.read_csv(variant_path(out, "metrics_per_pair", variant, ".csv"))
    none = per_pair[per_pair["matcher"] == "none"]
    assert (none["n_pred"] == 0).all()
    assert (none["balanced_accuracy"] == 0.5).all()
    share = (none["n1"] + none["n2"] - 2 * none["n_gt"]) / (none["n1"] + none["n2"])
    assert none["accuracy"].to_numpy() == pytest.approx(share.to_numpy())
    appearance = per_pair[per_pair["matcher"] == "appearance"]
    if protocol == "paper":  # full Hungarian: min(n1, n2) pairs, no τ
        assert (appearance["n_pred"] == appearance[["n1", "n2"]].min(axis=1)).all()
        assert appearance["tau"].isna().all()


def test_paper_protocol_runs_image_space_sm_and_writes_its_own_table(world, tmp_path):
    out, runner = tmp_path / "out", _runner(tmp_path)
    entry = open_entry("data/cad", "data/cad-val")
    evaluate([entry], [MatcherSpec("sm"), MatcherSpec("none")], [0], runner, out)
    evaluate([entry], [MatcherSpec("sm"), MatcherSpec("none")], [0], runner, out, protocol="paper")
    calibrated = pd.read_csv(out / "metrics_per_pair.csv")
    paper = pd.read_csv(out / "metrics_per_pair_paper_protocol.csv")
    assert set(paper.loc[paper["matcher"] == "sm", "params"]) == {'{"pairwise":"image"}'}
    assert set(calibrated.loc[calibrated["matcher"] == "sm", "params"]) == {"{}"}
    assert not (out / "thresholds_paper_protocol.csv").exists()

    write_tables(out)
    for name in (
        "table1.md",
        "table1.csv",
        "table1_paper_protocol.md",
        "table1_paper_protocol.csv",
    ):
        assert (out / name).is_file(), name
    table = pd.read_csv(out / "table1_paper_protocol.csv")
    assert table["tau"].isna().all() and table["paper_accuracy_mean"].notna().any()
    assert "balanced_accuracy_mean" in table.columns
    assert "Balanced acc." in (out / "table1.md").read_text()
    assert "pairwise=image" in (out / "table1_paper_protocol.md").read_text()


def test_the_paper_protocol_is_never_tuned(world, tmp_path):
    with pytest.raises(ValueError, match="untuned"):
        evaluate(
            [open_entry("data/cad", "data/cad-val")],
            [MatcherSpec("sm")],
            [0],
            _runner(tmp_path),
            tmp_path,
            tune=True,
            protocol="paper",
        )
