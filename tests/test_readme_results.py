"""The report (``results/README.md``, ``index.html``) and the README's results section are
written from a results directory — the README between its markers only — and a folder with
missing or unreadable files still gets both."""

import json

import pandas as pd

from eval.readme_results import (
    BEGIN,
    END,
    main,
    report_markdown,
    summary_section,
    update_readme,
    write_report,
)


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
    assert (
        "abcdef1234" in text and "](results/README.md)" in text and "](results/index.html)" in text
    )
    assert "| Maximin | 61.2 ± 0.3 |" not in text  # the full tables are the report's

    report, site = write_report(results)
    assert report == results / "README.md" and site == results / "index.html"
    full = report.read_text()
    assert "| Maximin | 61.2 ± 0.3 |" in full and "abcdef1234" in full
    assert "](./fig4.png)" in full and "0, 0.01" in full and "wall time 30 s" in full
    assert "### Stage times" in full and "| evaluate | 20 | | |" in full.replace("  ", " ")
    assert "<td>Maximin</td>" in site.read_text() and "61.2 ± 0.3" in site.read_text()


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
    pd.DataFrame(  # sm: the highest validation F1 of the paper's rivals, not the best on test
        [
            {"dataset": "CAD", "matcher": "sm", "metric": "f1", "diff": 0.30, "ci_low": 0.20}
            | {"ci_high": 0.40, "matcher_a": "maximin", "pairs": 8, "episodes": 4}
        ]
    ).to_csv(results / "paired_differences.csv", mode="a", header=False, index=False,
             columns=["dataset", "matcher_a", "matcher", "metric", "diff", "ci_low", "ci_high",
                      "pairs", "episodes"])  # fmt: skip
    pd.DataFrame(
        [
            {"dataset": "CAD", "matcher": m, "val_f1": v}
            for m, v in (("maximin", 0.5), ("mos", 0.6), ("sm", 0.9), ("none", 0.0))
        ]
    ).to_csv(results / "thresholds.csv", index=False)
    pd.DataFrame(  # 4 episodes of 2 test pairs: maximin 0.40, MOS 0.45, SM 0.10 in each
        [
            {"dataset": "CAD", "split": "test", "matcher": m, "seed": 0}
            | {"episode": k // 2, "pair": k, "f1": f[k % 2]}
            for m, f in (("maximin", (0.3, 0.5)), ("mos", (0.5, 0.4)), ("sm", (0.1, 0.1)))
            for k in range(8)
        ]
    ).to_csv(results / "metrics_per_pair.csv", index=False)
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
    text = report_markdown(results)
    assert "### Regime of each dataset" in text and "| CAD | 17.0 | 4.8 | 71 % | 33 % |" in text
    assert "| CAD | MOS | -5.0 [-9.5, +1.2] |" in text  # the paired-differences table
    assert "maximin ranks 2 of 3 of the paper's methods by test F1 (40.0; 95 % interval" in text
    assert "ranks 2–2); first, as on CAD in the paper: not met" in text
    assert "71 % non-covisible, appearance AUC 0.88" in text
    # the rival is the other paper method of highest validation F1 (SM), not MOS (best on test)
    assert (
        "maximin − SM (the other paper method of highest validation F1; 10.0 on test) = "
        "+30.0 [+20.0, +40.0] pp F1: maximin ahead, an interval that excludes 0" in text
    )
    assert "accuracy 71.0 (above 3 of 3 methods), balanced accuracy 50.0, 1 method below 50" in text
    assert "maximin leads MOS below 35 % non-covisible (95 % interval 30–41 %) and trails" in text
    assert "no crossover with RRWHM that its interval supports" in text
    assert "RRWHM below" not in text

    readme = tmp_path / "README.md"
    readme.write_text(f"{BEGIN}\n{END}\n")
    assert update_readme(readme, results)
    compact = readme.read_text()
    # Table I in one row per dataset: maximin, its rank and its interval, the rival and the best of
    # all chosen on validation, and the difference
    assert "| CAD | 40.0 | 2 of 3 [2–2] | SM 10.0 | +30.0 [+20.0, +40.0] | SM 10.0 |" in compact
    assert "(results/README.md#table-i)" in compact
    assert "maximin ranks" not in compact


def test_a_part_whose_files_cannot_be_read_is_replaced_not_fatal(tmp_path):
    """A study file in another format: its part says so and shows the run's own table; the rest
    of the report and the README's other tables are written."""
    results = tmp_path / "results"
    results.mkdir()
    (results / "table1.md").write_text("| Method | F1 |\n|---|---|\n| Maximin | 40.0 |\n")
    (results / "table_v2x.md").write_text("| Preset | Matcher |\n|---|---|\n| exact | sm |\n")
    pd.DataFrame([{"matcher": "sm", "preset": "exact"}]).to_csv(
        results / "table_v2x.csv", index=False
    )  # no metric columns at all
    (results / "run_record.json").write_text("{not json")
    text = report_markdown(results)
    assert "### The V2X task" in text and "could not be summarised" in text
    assert "| exact | sm |" in text and "| Maximin | 40.0 |" in text
    assert "wall time" not in text  # no readable run record: no run part
    readme = tmp_path / "README.md"
    readme.write_text(f"{BEGIN}\n{END}\n")
    assert update_readme(readme, results)
    assert "V2X" not in readme.read_text()  # no compact table without F1


def test_an_empty_results_folder_gets_a_report(tmp_path):
    tmp_path = tmp_path / "results"
    tmp_path.mkdir()
    report, site = write_report(tmp_path)
    assert report.read_text().startswith("# cadsim results")
    assert site.read_text().startswith("<!DOCTYPE html>")
    assert "results/README.md" in summary_section(tmp_path, tmp_path.parent)


def test_the_command_rewrites_report_and_readme_from_the_files(tmp_path, capsys):
    results = tmp_path / "results"
    results.mkdir()
    (results / "table1.md").write_text("| Method | F1 |\n|---|---|\n| Maximin | 40.0 |\n")
    readme = tmp_path / "README.md"
    readme.write_text(f"# x\n{BEGIN}\n{END}\n")
    assert main(["--results", str(results), "--readme", str(readme)]) == 0
    assert (results / "README.md").is_file() and (results / "index.html").is_file()
    assert "(results/README.md)" in readme.read_text()
    assert "rewrote the results section" in capsys.readouterr().out


def test_a_warm_run_keeps_the_last_cold_runs_stage_times(tmp_path):
    from eval.report.run_record import cold_record, keep_cold_record

    cold = {"cold_start": {"cold": True}, "wall_s": {"generate": 120.0, "total": 400.0}}
    cold |= {"git": {"commit": "abc"}, "runs": {}}
    assert keep_cold_record(tmp_path, cold) is not None
    warm = {"cold_start": {"cold": False}, "wall_s": {"generate": 1.0, "total": 60.0}}
    assert keep_cold_record(tmp_path, warm) is None
    assert cold_record(tmp_path)["wall_s"]["generate"] == 120.0
