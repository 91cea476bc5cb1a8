"""The README's results section is written from a results directory, between its markers only."""

import json

from eval.readme_results import BEGIN, END, update_readme


def test_results_section_replaces_only_the_marked_part(tmp_path):
    results = tmp_path / "results"
    results.mkdir()
    (results / "table1.md").write_text(
        "| Method | Accuracy |\n|---|---|\n| Maximin | 61.2 ± 0.3 |\n"
    )
    (results / "run_record.json").write_text(
        json.dumps(
            {
                "command": "python -m eval.reproduce",
                "created": "2026-01-01T00:00:00+00:00",
                "git": {"commit": "abcdef1234567890", "dirty": False},
                "wall_s": {"generate": 10.0, "evaluate": 20.0, "total": 30.0},
                "noise_sweep": {"rates": [0.0, 0.01], "seeds": [0, 1], "pairs": 5},
            }
        )
    )
    readme = tmp_path / "README.md"
    readme.write_text(f"# title\n\nbefore\n{BEGIN}\nold numbers 99.9\n{END}\nafter\n")
    assert update_readme(readme, results)
    text = readme.read_text()
    assert text.startswith("# title\n\nbefore\n") and text.endswith(f"{END}\nafter\n")
    assert "old numbers" not in text
    assert "| Maximin | 61.2 ± 0.3 |" in text and "abcdef1234" in text
    assert "](results/fig4.png)" in text and "0, 0.01" in text and "wall time 30 s" in text


def test_readme_without_markers_is_left_alone(tmp_path):
    readme = tmp_path / "README.md"
    readme.write_text("# no markers\n")
    assert not update_readme(readme, tmp_path)
    assert readme.read_text() == "# no markers\n"


def _table_row(dataset, matcher, f1, accuracy, balanced):
    return {"dataset": dataset, "matcher": matcher, "method": matcher, "f1_mean": f1} | {
        "accuracy_mean": accuracy,
        "balanced_accuracy_mean": balanced,
        "params": "{}",
    }


def test_agreement_is_written_from_the_tables(tmp_path):
    import pandas as pd

    results = tmp_path / "results"
    results.mkdir()
    (results / "table1.md").write_text("| Method | F1 |\n|---|---|\n| Maximin | 40.0 |\n")
    (results / "run_record.json").write_text(json.dumps({"tuning": {"CAD": {}}}))
    pd.DataFrame(
        [
            _table_row("CAD", "maximin", 0.40, 0.30, 0.60),  # fractions, as every CSV
            _table_row("CAD", "mos", 0.45, 0.65, 0.62),
            _table_row("CAD", "sm", 0.10, 0.70, 0.45),
            _table_row("CAD", "none", 0.0, 0.71, 0.50),
        ]
    ).to_csv(results / "table1.csv", index=False)
    pd.DataFrame(
        [
            {"dataset": "CAD", "matcher_a": "maximin", "matcher_b": "mos", "metric": m}
            | {"diff": -0.05, "ci_low": -0.095, "ci_high": 0.0125, "pairs": 50, "episodes": 5}
            for m in ("f1", "balanced_accuracy", "recall")
        ]
    ).to_csv(results / "paired_differences.csv", index=False)
    pd.DataFrame(
        [
            {"dataset": "CAD", "objects_per_view": 17.0, "covisible": 4.8}
            | {"noncovisible_share": 0.71, "covisible_share_of_smaller": 0.33}
            | {"appearance_auc": 0.88, "position_error_median_m": 0.4}
        ]
    ).to_csv(results / "regime.csv", index=False)
    sweep = [
        {"dataset": "CAD", "keep": k, "share": s, "matcher": m, "f1_mean": f}
        for k, s, fa, fb in ((1.0, 0.7, 0.40, 0.45), (0.0, 0.0, 0.9, 0.8))
        for m, f in (("maximin", fa), ("mos", fb))
    ]
    pd.DataFrame(sweep).to_csv(results / "regime_sweep.csv", index=False)
    crossing = {"dataset": "CAD", "matcher_a": "maximin", "metric": "f1", "direction": "a_loses"}
    pd.DataFrame(
        [
            crossing
            | {"matcher_b": "mos", "crossing_share": 0.35, "share_ci_low": 0.3}
            | {"share_ci_high": 0.41, "significant": True},
            crossing  # a crossing within the noise: never stated as one
            | {"matcher_b": "rrwhm", "crossing_share": 0.2, "share_ci_low": 0.1}
            | {"share_ci_high": None, "significant": False},
        ]
    ).to_csv(results / "crossovers.csv", index=False)
    readme = tmp_path / "README.md"
    readme.write_text(f"{BEGIN}\n{END}\n")
    assert update_readme(readme, results)
    text = readme.read_text()
    assert "### Regime of each dataset" in text and "| CAD | 17.0 | 4.8 | 71 % | 33 % |" in text
    assert "| CAD | MOS | -5.0 [-9.5, +1.2] |" in text  # the paired-differences table
    assert "maximin ranks 2 of 3 of the paper's methods by F1" in text
    assert "71 % non-covisible, appearance AUC 0.88" in text
    assert "an interval that includes 0" in text and "unlike the paper" in text
    assert "accuracy 71.0 (above 3 of 3 methods), balanced accuracy 50.0, 1 method below 50" in text
    assert "maximin leads MOS below 35 % non-covisible (95 % interval 30–41 %) and trails" in text
    assert "no crossover with RRWHM that its interval supports" in text
    assert "RRWHM below" not in text


def test_a_warm_run_keeps_the_last_cold_runs_stage_times(tmp_path):
    from eval.report.run_record import cold_record, keep_cold_record

    cold = {"cold_start": {"cold": True}, "wall_s": {"generate": 120.0, "total": 400.0}}
    cold |= {"git": {"commit": "abc"}, "runs": {}}
    assert keep_cold_record(tmp_path, cold) is not None
    warm = {"cold_start": {"cold": False}, "wall_s": {"generate": 1.0, "total": 60.0}}
    assert keep_cold_record(tmp_path, warm) is None
    assert cold_record(tmp_path)["wall_s"]["generate"] == 120.0
