"""The one evaluation every study runs: per dataset, the equal tuning budget on validation
(:mod:`eval.protocol.tuning`), τ on validation, the test runs through the executor scored at τ,
and the files of each protocol variant (calibrated, untuned, paper, equal cues). Imports
``eval/core/``, ``eval/protocol/``, this folder."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import pandas as pd

from eval.core.result_files import write_csv
from eval.core.runner import Runner
from eval.core.tasks import MatcherSpec
from eval.engine.named_runs import as_named, calibrate_entry, run_named, score_runs
from eval.engine.ranking_quality import qualitative_entry, ranking_quality
from eval.engine.splits import DatasetEntry, Named
from eval.engine.variant_files import EntryResult, write_variant
from eval.protocol import calibration, tuning
from eval.protocol.cues import equal_cue_spec
from eval.protocol.variants import (
    EQUAL,
    MAIN,
    PAPER,
    UNTUNED,
    check_protocol,
    paper_spec,
    variant_path,
)


def evaluate_entry(
    entry: DatasetEntry,
    named: Named,
    seeds: Sequence[int],
    runner: Runner,
    calibrate: bool,
    score_validation: bool = False,
) -> EntryResult:
    """Validation runs and τ (when `calibrate`), then the test runs scored at τ;
    ``score_validation``: the validation runs scored at τ too (``EntryResult.val_per_pair``: the
    equal-cue variant's, which the headline's difficulty level is chosen on)."""
    val_runs, fits = calibrate_entry(entry, named, seeds, runner) if calibrate else ({}, {})
    test_runs = run_named(
        runner,
        (entry.test_dir, entry.test_checksum),
        named,
        seeds,
        f"{entry.label} test",
        localisation=entry.localisation,
        sensor=entry.sensor,
    )
    if val_runs:
        calibration.check_disjoint(
            [r for runs in val_runs.values() for r in runs],
            [r for runs in test_runs.values() for r in runs],
        )
    taus = {label: (fits[label].tau if label in fits else None) for label in named}
    ap_rows, pr = ranking_quality(entry.label, test_runs)
    return EntryResult(
        entry=entry,
        named=named,
        taus=taus,
        fits=fits,
        per_pair=score_runs(test_runs, taus, dataset=entry.label, split="test"),
        ap_rows=ap_rows,
        pr=pr,
        qualitative=qualitative_entry(entry, test_runs, taus),
        val_per_pair=(
            score_runs(val_runs, taus, dataset=entry.label, split="validation")
            if val_runs and score_validation
            else None
        ),
    )


def evaluate(
    entries: Sequence[DatasetEntry],
    matchers: Sequence[MatcherSpec],
    seeds: Sequence[int],
    runner: Runner,
    out_dir: str | Path,
    calibrate: bool = True,
    tune: bool = False,
    protocol: str = "calibrated",
    tune_limit: int | None = None,
    untuned: bool = True,
) -> dict:
    """The whole evaluation of one protocol; writes into `out_dir` the variant files of
    :mod:`eval.protocol.variants` (thresholds, metrics_per_pair, average_precision, evaluation.json; the
    main variant also pr_curves.csv and qualitative.json; with `tune` also ``tuning.csv`` and the
    untuned variant, unless `untuned` is False; `tune_limit`: tune on the first N validation
    pairs only). Returns the τ table of the main (or paper) variant as
    {dataset label: {matcher label: τ or None}}."""
    protocol = check_protocol(protocol)
    if protocol == "paper" and tune:
        raise ValueError("--tune: the paper protocol runs every matcher untuned")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    labels = [e.label for e in entries]
    if len(set(labels)) != len(labels):
        raise ValueError(f"datasets: two test datasets of the same scenario kind {labels}")
    base = as_named(matchers)
    main_variant = MAIN
    if protocol == "equal_cues":
        base = {label: equal_cue_spec(spec) for label, spec in base.items()}
        main_variant, untuned, protocol = EQUAL, False, "calibrated"
    calibrate = calibrate and protocol == "calibrated"
    results: dict[str, list[EntryResult]] = {}
    choices: list[tuning.TuningChoice] = []
    for entry in entries:
        if (calibrate or tune) and entry.val_dir is None:
            raise ValueError(
                f"{entry.test_dir}: no validation dataset (give --val DIR or create "
                f"{entry.test_dir}-val), or pass --no-calibration"
            )
        if protocol == "paper":
            named = {label: paper_spec(spec) for label, spec in base.items()}
            results.setdefault(PAPER, []).append(
                evaluate_entry(entry, named, seeds, runner, calibrate=False)
            )
            continue
        if tune:
            chosen = tuning.tune_entry(entry, base, runner, tune_limit, entry.localisation)
            choices += chosen.values()
            named = {label: chosen[label].spec for label in base}
            if untuned:
                results.setdefault(UNTUNED, []).append(
                    evaluate_entry(entry, base, seeds, runner, calibrate)
                )
            results.setdefault(main_variant, []).append(
                evaluate_entry(entry, named, seeds, runner, calibrate, main_variant == EQUAL)
            )
        else:
            results.setdefault(main_variant, []).append(
                evaluate_entry(entry, base, seeds, runner, calibrate, main_variant == EQUAL)
            )
    for variant, variant_results in results.items():
        settings = {
            "protocol": protocol,
            "calibrated": calibrate,
            "tuned": tune and variant == main_variant,
        }
        if variant == EQUAL:
            settings["protocol"] = "equal_cues"
        write_variant(out_dir, variant, variant_results, seeds, runner, settings)
    if tune:
        write_csv(
            pd.DataFrame(tuning.tuning_rows(choices)),
            variant_path(out_dir, "tuning", main_variant, ".csv"),
        )
    main = results.get(PAPER if protocol == "paper" else main_variant, [])
    return {r.entry.label: r.taus for r in main}
