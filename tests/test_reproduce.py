"""A tiny end-to-end ``make reproduce`` on the real pipeline (simulation, rendering, detection,
matchers): 2 pairs per dataset, 2 matchers, 2 noise rates. Every output file appears, and a second
run generates and computes nothing."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from cadsim import cli
from eval import reproduce

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
)


@pytest.mark.slow
@pytest.mark.render
def test_tiny_reproduce_writes_every_output_and_reruns_from_cache(tmp_path, capsys):
    out, data, cache = tmp_path / "results", tmp_path / "data", tmp_path / "cache"
    argv = ["--pairs", "2", "--val-pairs", "2", "--matchers", "sm,maximin", "--rates", "0,0.01"]
    argv += ["--runs", "2", "--out", str(out), "--data", str(data), "--cache", str(cache)]
    argv += ["--sweep-runs", "2", "--workers", "2", "--quiet"]
    assert reproduce.main(argv) == 0
    printed = capsys.readouterr().out
    assert "Table I" in printed and "Maximin" in printed

    for name in OUTPUTS:
        assert (out / name).is_file() and (out / name).stat().st_size > 0, name
    labels = [d["label"] for d in json.loads((out / "run_record.json").read_text())["datasets"]]
    expected = [
        s
        for s in ("CAD", "MRC")
        if any(s.lower() in f for f in reproduce.SCENARIOS if (reproduce.ROOT / f).is_file())
    ]
    assert labels == expected

    table = pd.read_csv(out / "table1.csv")
    assert sorted(table["matcher"].unique()) == ["maximin", "sm"]
    assert set(table["dataset"]) == set(labels)
    assert (table["frames"] == 2).all() and (table["runs"] == 2).all()
    assert table["paper_accuracy_mean"].notna().all()  # the paper's numbers are beside ours
    per_pair = pd.read_csv(out / "metrics_per_pair.csv")
    assert len(per_pair) == len(labels) * 2 * 2 * 2  # datasets × matchers × runs × pairs
    assert per_pair[["accuracy", "precision", "recall", "f1"]].stack().between(0, 1).all()
    noise = pd.read_csv(out / "noise_runs.csv")
    assert sorted(noise["noise_rate"].unique()) == [0.0, 0.01]
    assert len(noise) == 2 * 2 * 2  # matchers × runs × rates

    record = json.loads((out / "run_record.json").read_text())
    assert set(record["thresholds"]) == set(labels)
    for taus in record["thresholds"].values():
        assert set(taus) == {"sm", "maximin"} and all(t is not None for t in taus.values())
    assert record["seeds"] == [0, 1] and record["noise_sweep"]["rates"] == [0.0, 0.01]
    assert {"generate", "evaluate", "noise_sweep", "tables_figures", "total"} <= set(
        record["wall_s"]
    )
    assert record["packages"]["numpy"] and "commit" in record["git"]
    for d in record["datasets"]:
        assert d["test_seed"] != d["val_seed"] and d["scenario"]["text"]
    assert record["runs"]["evaluate"]["computed"] == len(labels) * 2 * 2 * 2  # val + test

    # Everything cached: nothing generated, nothing computed, same table.
    before = (out / "table1.csv").read_text()
    assert reproduce.main(argv) == 0
    again = json.loads((out / "run_record.json").read_text())
    assert all(d["new_records"] == 0 for d in again["datasets"])
    assert again["runs"]["evaluate"]["computed"] == 0
    assert again["runs"]["noise_sweep"]["computed"] == 0
    assert (out / "table1.csv").read_text() == before

    # `cadsim table` re-renders tables and figures from the CSVs alone.
    for name in ("table1.md", "table1.tex", "fig4.png", "qualitative.png", "pr_curves.png"):
        (out / name).unlink()
    assert cli.main(["table", str(out)]) == 0
    assert all(
        (out / n).is_file() for n in ("table1.md", "table1.tex", "fig4.png", "qualitative.png")
    )
    assert (out / "table1.csv").read_text() == before

    # The standalone commands reuse the same cache: nothing is computed again.
    datasets = [str(data / d["label"].lower()) for d in record["datasets"]]
    other = tmp_path / "other"
    common = ["--matchers", "sm,maximin", "--runs", "2", "--cache", str(cache), "--workers", "1"]
    assert cli.main(["evaluate", *datasets, "--out", str(other), *common]) == 0
    assert (other / "table1.csv").read_text() == before
    if "CAD" in labels:
        cad = str(data / "cad")
        assert (
            cli.main(["sweep-noise", cad, "--rates", "0,0.01", "--out", str(other), *common]) == 0
        )
        swept = pd.read_csv(other / "noise_runs.csv")
        assert len(swept) == 2 * 2 * 2 and (other / "fig4.pdf").is_file()
