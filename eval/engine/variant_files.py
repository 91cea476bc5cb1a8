"""The files of one protocol variant (:func:`eval.protocol.variants.variant_path`): thresholds,
per-pair metrics, average precision, ``evaluation.json``; for the main variant also the PR curves
and the qualitative-figure input. Imports ``eval/core/``, ``eval/protocol/``, this folder."""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path

import pandas as pd

from eval.core.result_files import recorded_path, write_csv, write_text
from eval.core.runner import Runner
from eval.engine.splits import DatasetEntry, Named
from eval.protocol import calibration, tuning
from eval.protocol.variants import MAIN, PAPER, variant_path


@dataclass
class EntryResult:
    """One dataset evaluated under one variant: τ and options per row label and the tables."""

    entry: DatasetEntry
    named: Named
    taus: dict[str, float | None]
    fits: dict[str, calibration.Calibration]
    per_pair: pd.DataFrame
    ap_rows: list[dict]
    pr: pd.DataFrame
    qualitative: dict = field(default_factory=dict)
    val_per_pair: pd.DataFrame | None = None
    """The validation runs scored at the same τ (``split`` "validation"): what a choice made on
    validation (the headline's difficulty level) reads; never a test number."""


THRESHOLD_COLUMNS = (
    "dataset",
    "matcher",
    "params",
    "tau",
    "val_f1",
    "val_frames",
    "val_runs",
    "val_dir",
)


def write_variant(
    out_dir: Path,
    variant: str,
    results: Sequence[EntryResult],
    seeds: Sequence[int],
    runner: Runner,
    settings: dict,
) -> None:
    """The files of one variant (:func:`eval.protocol.variants.variant_path`); the PR curves and the
    qualitative-figure input only for the main variant."""
    tau_rows = [
        {
            "dataset": r.entry.label,
            "matcher": label,
            "params": tuning.params_json(dict(r.named[label].options)),
            "tau": fit.tau,
            "val_f1": fit.val_f1,
            "val_frames": fit.frames,
            "val_runs": fit.runs,
            "val_dir": recorded_path(r.entry.val_dir),
        }
        for r in results
        for label, fit in r.fits.items()
    ]
    if variant != PAPER:
        write_csv(
            pd.DataFrame(tau_rows, columns=list(THRESHOLD_COLUMNS)),
            variant_path(out_dir, "thresholds", variant, ".csv"),
        )
    write_csv(
        pd.concat([r.per_pair for r in results], ignore_index=True),
        variant_path(out_dir, "metrics_per_pair", variant, ".csv"),
    )
    validation = [r.val_per_pair for r in results if r.val_per_pair is not None]
    if validation:
        write_csv(
            pd.concat(validation, ignore_index=True),
            variant_path(out_dir, "metrics_per_pair_validation", variant, ".csv"),
        )
    write_csv(
        pd.DataFrame([a for r in results for a in r.ap_rows]),
        variant_path(out_dir, "average_precision", variant, ".csv"),
    )
    if variant == MAIN:
        write_csv(
            pd.concat([r.pr for r in results], ignore_index=True).round(6),
            out_dir / "pr_curves.csv",
        )
        qualitative = {r.entry.label: r.qualitative for r in results if r.qualitative}
        write_text(out_dir / "qualitative.json", json.dumps(qualitative, indent=1))
    record = {
        "datasets": [
            asdict(r.entry)
            | {
                "test_dir": recorded_path(r.entry.test_dir),
                "val_dir": recorded_path(r.entry.val_dir),
            }
            for r in results
        ],
        "matchers": list(results[0].named) if results else [],
        "seeds": list(seeds),
        **settings,
        "thresholds": {r.entry.label: r.taus for r in results},
        "params": {
            r.entry.label: {label: dict(spec.options) for label, spec in r.named.items()}
            for r in results
        },
        "code_version": runner.version,
        "cache": str(runner.cache.root),
    }
    write_text(variant_path(out_dir, "evaluation", variant, ".json"), json.dumps(record, indent=1))
