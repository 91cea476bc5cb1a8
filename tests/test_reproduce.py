"""A tiny end-to-end ``make reproduce`` on the real pipeline (simulation, rendering, detection,
matchers): 2 pairs per dataset, 2 matchers and the `none` baseline, 2 noise rates, 2 keep levels.
Every output file appears, and a second run generates and computes nothing."""

from __future__ import annotations

import json
import logging

import pandas as pd
import pytest

from cadsim import cli
from eval import reproduce
from matchers import deterministic

OUTPUTS = (
    "table1.md",
    "table1.csv",
    "table1.tex",
    "fig4.png",
    "fig4.pdf",
    "pr_curves.png",
    "qualitative.png",
    "qualitative.pdf",
    "run_record.json",
    "thresholds.csv",
    "metrics_per_pair.csv",
    "average_precision.csv",
    "pr_curves.csv",
    "noise_runs.csv",
    "qualitative.json",
    "evaluation.json",
    "tuning.csv",
    "table1_untuned.md",
    "table1_untuned.csv",
    "table1_paper_protocol.md",
    "table1_paper_protocol.csv",
    "paired_differences.csv",
    "regime_sweep.csv",
    "crossovers.csv",
    "fig_regime.png",
    "fig_regime.pdf",
    "dataset_spread.csv",
    "localisation_sweep.csv",
    "fig_localisation.png",
    "fig_localisation.pdf",
    "table_external.md",
    "table_external.csv",
    "agreement.csv",
    "table_multiagent.md",
    "table_multiagent.csv",
    "fig_multiagent.png",
    "table_transfer.md",
    "table_transfer.csv",
    "README.md",  # the report, and the same page in HTML
    "index.html",
)
MATCHERS = ["maximin", "none", "sm"]


@pytest.mark.slow
@pytest.mark.render
@pytest.mark.timeout(900)  # 84 s on 2 quiet cores, 272 s at load 10: room for a busy machine
def test_tiny_reproduce_writes_every_output_and_reruns_from_cache(tmp_path, capsys, caplog):
    out, data, cache = tmp_path / "results", tmp_path / "data", tmp_path / "cache"
    argv = ["--pairs", "2", "--val-pairs", "2", "--matchers", "sm,maximin,none"]
    argv += ["--rates", "0,0.01", "--keep", "1,0", "--regime-runs", "1", "--spread-runs", "1"]
    argv += ["--runs", "2", "--out", str(out), "--data", str(data), "--cache", str(cache)]
    argv += ["--sweep-runs", "2", "--workers", "2", "--no-progress"]
    argv += ["--localisation-sigmas", "0,2", "--localisation-runs", "1"]
    argv += ["--external-runs", "1", "--external-tune-pairs", "3"]
    argv += ["--no-temporal"]  # the temporal table: tests/test_temporal_study.py (fake sequences)
    assert reproduce.main(argv) == 0
    printed = capsys.readouterr().out
    assert "Table I" in printed and "Maximin" in printed

    for name in OUTPUTS:
        assert (out / name).is_file() and (out / name).stat().st_size > 0, name
    assert "could not be summarised" not in (out / "README.md").read_text()  # every part read
    assert not (out / "table_temporal.csv").exists()  # --no-temporal
    labels = [d["label"] for d in json.loads((out / "run_record.json").read_text())["datasets"]]
    expected = [
        label
        for path, label in zip(reproduce.SCENARIOS, ("CAD", "MRC", "CAD-dense"), strict=True)
        if (reproduce.ROOT / path).is_file()
    ]
    assert labels == expected

    table = pd.read_csv(out / "table1.csv")
    assert sorted(table["matcher"].unique()) == MATCHERS
    assert set(table["dataset"]) == set(labels)
    assert (table["frames"] == 2).all() and (table["runs"] == 2).all()
    paper_rows = table[table["matcher"] != "none"]
    assert paper_rows["paper_accuracy_mean"].notna().all()  # the paper's numbers are beside ours
    assert (table.loc[table["matcher"] == "none", "balanced_accuracy_mean"] == 0.5).all()
    per_pair = pd.read_csv(out / "metrics_per_pair.csv")
    assert len(per_pair) == len(labels) * 3 * 2 * 2  # datasets × matchers × runs × pairs
    metrics = ["accuracy", "balanced_accuracy", "precision", "recall", "f1"]
    assert per_pair[metrics].stack().between(0, 1).all()
    noise = pd.read_csv(out / "noise_runs.csv")
    assert sorted(noise["noise_rate"].unique()) == [0.0, 0.01]
    swept = [d for d in labels if d in ("CAD", "MRC")]  # the datasets Fig. 4 sweeps
    assert sorted(noise["dataset"].unique()) == sorted(swept)
    assert len(noise) == len(swept) * 3 * 2 * 2  # datasets × matchers × runs × rates
    regime = pd.read_csv(out / "regime_sweep.csv")
    assert set(regime["dataset"]) == set(labels) and sorted(regime["keep"].unique()) == [0.0, 1.0]
    assert (regime.loc[regime["keep"] == 0, "share"] == 0).all()
    assert len(pd.read_csv(out / "table1_paper_protocol.csv")) == len(labels) * 3
    external = pd.read_csv(out / "table_external.csv")
    assert sorted(external.loc[external["source"] == "ours", "matcher"]) == MATCHERS
    assert (external.loc[external["source"] == "ours", "frames"] == 109).all()
    assert external["f1_pooled_mean"].between(0, 1).all() and "dmgm_published" in set(
        external["matcher"]
    )
    agreement = pd.read_csv(out / "agreement.csv")
    assert list(agreement.columns) == [
        "dataset",
        "reference",
        "matchers",
        "rho",
        "ci_low",
        "ci_high",
    ]
    if "CAD" in labels:
        loc = pd.read_csv(out / "localisation_sweep.csv")
        assert sorted(loc["position_sigma_m"].unique()) == [0.0, 2.0]
        assert {"pose", "pose_refine", "maximin"} <= set(loc["matcher"])
    multi = pd.read_csv(out / "table_multiagent.csv")
    assert sorted(multi["n_agents"].unique()) == [2, 3, 4, 6]
    assert set(multi["preset"]) == {"denied", "gnss-urban"}
    abstained = (multi["matcher"] == "pose_refine") & (multi["preset"] == "denied")
    assert multi.loc[abstained, "f1_pooled"].isna().all()  # needs the prior: no number
    assert (multi.loc[~abstained, "snapshots"] == 2).all()
    assert set(multi["fusion"]) >= {"independent", "spectral", "clear", "transitive"}
    fused = multi[(multi["fusion"] != "independent") & ~abstained]
    assert (fused["cycle_violation_rate"] == 0).all()
    assert multi.loc[abstained, "cycle_violation_rate"].isna().all()
    fractions = ["f1_pooled", "cycle_violation_rate", "precision_pooled", "recall_pooled"]
    assert multi.loc[~abstained, fractions].stack().between(0, 1).all()
    assert set(json.loads((out / "run_record.json").read_text())["multiagent"]["test"]) >= {
        "dir",
        "seed",
        "snapshots",
    }
    transfer = pd.read_csv(out / "table_transfer.csv")
    assert set(transfer["train"].str.split().str[0]) == {"cadsim", "DMGM"}
    assert set(transfer["matcher"]) == {
        "learned",
        "learned_pose",
        "maximin_learned",
        "rrwm_learned",
    }
    assert transfer["test"].nunique() == 3 and len(transfer) == 4 * 3 * 4
    assert transfer[["f1_pooled", "ap"]].stack().between(0, 1).all()
    assert transfer["model_sha256"].nunique() == 4  # one model per training set
    assert len(list((data / "models").glob("*.json"))) == 4
    tuning = pd.read_csv(out / "tuning.csv")
    assert set(tuning["dataset"]) == set(labels)
    assert (tuning.groupby(["dataset", "matcher"])["chosen"].sum() == 1).all()

    record = json.loads((out / "run_record.json").read_text())
    assert set(record["thresholds"]) == set(labels)
    for taus in record["thresholds"].values():
        assert set(taus) == set(MATCHERS) and all(t is not None for t in taus.values())
    assert set(record["tuning"]) == set(labels)
    assert record["seeds"] == [0, 1] and record["noise_sweep"]["rates"] == [0.0, 0.01]
    stages = {"generate", "evaluate", "paper_protocol", "noise_sweep", "regime_sweep"}
    assert stages | {"dataset_spread", "tables_figures", "total"} <= set(record["wall_s"])
    assert record["packages"]["numpy"] and "commit" in record["git"]
    for d in record["datasets"]:
        assert d["test_seed"] != d["val_seed"] and d["scenario"]["text"]
    # Tuning: each grid configuration once on validation seed 0; then the untuned runs (the
    # defaults' seed-0 validation run is shared), then the chosen configuration's other runs.
    # A seed-free matcher (matchers.deterministic) runs seed 0 only: its test run is new, its
    # validation run is the tuning run.
    per_dataset = 0
    for (_, matcher), rows in tuning.groupby(["dataset", "matcher"]):
        default_chosen = json.loads(rows.loc[rows["chosen"], "params"].item()) == {}
        later = 1 if deterministic(matcher) else 1 + 2
        per_dataset += len(rows) + later + (0 if default_chosen else later)
    for name in set(MATCHERS) - set(tuning["matcher"]):  # untunable: not in tuning.csv
        later = 1 if deterministic(name) else 1 + 2
        per_dataset += len(set(tuning["dataset"])) * (1 + later)  # its one grid point too
    assert record["runs"]["evaluate"]["computed"] == per_dataset

    # Everything cached: nothing generated, nothing computed, same table.
    before = (out / "table1.csv").read_text()
    fused = (out / "multiagent" / "per_snapshot.csv").read_bytes()
    assert len(list((cache / "multiagent").glob("*.json"))) == 1  # the fused rows, stored
    with caplog.at_level(logging.INFO, logger="eval.reproduce"):
        assert reproduce.main(argv) == 0
    assert "CAD-multi: fused rows read from the result cache" in caplog.text
    assert (out / "multiagent" / "per_snapshot.csv").read_bytes() == fused  # times included
    again = json.loads((out / "run_record.json").read_text())
    assert all(d["new_records"] == 0 for d in again["datasets"])
    assert all(r["computed"] == 0 for r in again["runs"].values())
    assert (out / "table1.csv").read_text() == before

    # `cadsim table` re-renders tables and figures from the CSVs alone.
    rendered = ("table1.md", "table1.tex", "table1_paper_protocol.md", "fig4.png")
    rendered += ("qualitative.png", "pr_curves.png", "fig_regime.png")  # crossovers: the sweep
    for name in rendered:
        (out / name).unlink()
    assert cli.main(["table", str(out)]) == 0
    assert all((out / n).is_file() for n in rendered)
    assert (out / "table1.csv").read_text() == before

    # The standalone commands reuse the same cache: nothing is computed again.
    datasets = [str(data / d["label"].lower()) for d in record["datasets"]]
    other = tmp_path / "other"
    common = ["--matchers", ",".join(MATCHERS), "--runs", "2", "--cache", str(cache)]
    common += ["--workers", "1"]
    assert cli.main(["evaluate", *datasets, "--tune", "--out", str(other), *common]) == 0
    assert (other / "table1.csv").read_text() == before
    paper = ["evaluate", *datasets, "--protocol", "paper", "--out", str(other), *common]
    assert cli.main(paper) == 0
    assert (other / "table1_paper_protocol.csv").read_text() == (
        out / "table1_paper_protocol.csv"
    ).read_text()
    if "CAD" in labels:
        cad = str(data / "cad")
        assert (
            cli.main(["sweep-noise", cad, "--rates", "0,0.01", "--out", str(other), *common]) == 0
        )
        swept = pd.read_csv(other / "noise_runs.csv")
        assert len(swept) == 3 * 2 * 2 and (other / "fig4.pdf").is_file()
        regime = ["sweep-regime", cad, "--keep", "1,0", "--val-runs", "1", "--out", str(other)]
        assert cli.main([*regime, *common[:2], "--runs", "1", *common[4:]]) == 0
        order = ["keep", "matcher"]
        mine = pd.read_csv(other / "regime_sweep.csv").sort_values(order, ignore_index=True)
        theirs = pd.read_csv(out / "regime_sweep.csv")
        theirs = theirs[theirs["dataset"] == "CAD"].sort_values(order, ignore_index=True)
        pd.testing.assert_frame_equal(mine, theirs)
