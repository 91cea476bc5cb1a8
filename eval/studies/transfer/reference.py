"""The transfer study's hand-crafted reference: per test set and kind (with or without the
prior), the main tables' matcher of largest pooled F1 on the *validation* split, with its test
figures. Reads the main tables' files (and their cached validation runs); chooses on validation
only."""

from __future__ import annotations

import json
import logging
import math
from collections.abc import Mapping
from pathlib import Path

import pandas as pd

from eval.core.runner import Runner
from eval.core.tasks import MatcherSpec
from eval.engine.named_runs import run_named, score_runs
from eval.engine.validation_choice import chosen_specs
from eval.protocol.metrics import summarise_pooled
from eval.protocol.variants import MAIN, variant_path
from eval.report.tables import build_table
from eval.studies.transfer.sets import TestSet

log = logging.getLogger("eval.studies.transfer.evaluation")

LEARNED = ("learned", "learned_pose", "maximin_learned", "rrwm_learned")
EXCLUDED = {"none", "dmgm_published", *LEARNED}


def validation_pooled_f1(
    reference_dir: str | Path, label: str, runner: Runner | None = None
) -> dict[str, float]:
    """{matcher: pooled F1 on the validation split at its own τ} of the hand-crafted matchers the
    main tables in ``reference_dir`` calibrated on dataset ``label``: the ``val_f1_pooled``
    column of ``thresholds.csv`` where it has one; else the main tables' own validation runs
    (the specs and τ of ``thresholds.csv``, the split, seeds and prior preset of
    ``evaluation.json``) read through ``runner`` — the result cache holds them from the
    calibration — and scored at τ. Empty without the files (or without ``runner``)."""
    reference_dir = Path(reference_dir)
    path = variant_path(reference_dir, "thresholds", MAIN, ".csv")
    if not path.is_file():
        return {}
    thresholds = pd.read_csv(path, keep_default_na=False, na_values=[""])
    thresholds = thresholds[
        (thresholds["dataset"] == label) & ~thresholds["matcher"].isin(EXCLUDED)
    ]
    if thresholds.empty:
        return {}
    if "val_f1_pooled" in thresholds.columns and thresholds["val_f1_pooled"].notna().all():
        values = thresholds["val_f1_pooled"].astype(float)
        return dict(zip(thresholds["matcher"], values, strict=True))
    record = _evaluation_record(reference_dir, label)
    if runner is None or record is None or not record[0].get("val_dir"):
        return {}
    entry, seeds = record
    specs = [MatcherSpec(m) for m in thresholds["matcher"]]
    named, taus = chosen_specs(reference_dir, label, specs)
    runs = run_named(
        runner,
        (entry["val_dir"], entry["val_checksum"]),
        named,
        seeds,
        f"{label} validation (hand-crafted reference)",
        localisation=entry.get("localisation"),
    )
    scored = score_runs(runs, taus, dataset=label, split="val")
    pooled = summarise_pooled(scored, by=["matcher"])
    return dict(zip(pooled["matcher"], pooled["f1_pooled_mean"].astype(float), strict=True))


def _evaluation_record(reference_dir: Path, label: str) -> tuple[dict, list[int]] | None:
    """(the dataset entry of ``label``, the seeds) of ``reference_dir``'s main evaluation.json."""
    path = variant_path(reference_dir, "evaluation", MAIN, ".json")
    if not path.is_file():
        return None
    record = json.loads(path.read_text(encoding="utf-8"))
    entry = next((d for d in record.get("datasets", []) if d.get("label") == label), None)
    return None if entry is None else (entry, list(record.get("seeds", [])))


def choose_reference(
    val_f1: Mapping[str, float], test_table: pd.DataFrame, priors: set[str]
) -> dict[bool, dict]:
    """{uses prior: {matcher, method, val_f1_pooled, f1_pooled, ap}}: of the hand-crafted
    matchers with a validation pooled F1 (``val_f1``) and a row in ``test_table`` (build_table
    rows of one dataset), per kind (in ``priors`` or not) the one with the largest *validation*
    pooled F1 (ties: the first in ``val_f1``'s order), with its *test* pooled F1 and AP."""
    tested = test_table.set_index("matcher")
    out = {}
    for prior in (False, True):
        kind = [
            m
            for m, f1 in val_f1.items()
            if (m in priors) == prior and m not in EXCLUDED and m in tested.index
            if math.isfinite(f1)
        ]
        if not kind:
            continue
        best = max(kind, key=lambda m: val_f1[m])  # max keeps the first of equal values
        row = tested.loc[best]
        out[prior] = {
            "matcher": best,
            "method": str(row["method"]),
            "val_f1_pooled": float(val_f1[best]),
            "f1_pooled": float(row["f1_pooled_mean"]),
            "ap": float(row["ap_mean"]) if "ap_mean" in row.index else math.nan,
        }
    return out


def reference_for(test: TestSet, test_checksum: str, runner: Runner | None) -> dict[bool, dict]:
    """:func:`choose_reference` on ``test``'s main tables; empty where they have not run, or
    ran on another test dataset than the one at ``test_checksum``."""
    from eval.engine.matcher_list import prior_matchers

    record = _evaluation_record(Path(test.reference_dir), test.reference_label)
    if record is None:
        return {}
    if record[0].get("test_checksum") != test_checksum:
        log.warning(
            "[transfer] %s: the main tables in %s scored another dataset; no hand-crafted "
            "reference",
            test.label,
            test.reference_dir,
        )
        return {}
    try:
        table = build_table(test.reference_dir)
    except FileNotFoundError:
        return {}
    table = table[table["dataset"] == test.reference_label].dropna(subset=["f1_pooled_mean"])
    val_f1 = validation_pooled_f1(test.reference_dir, test.reference_label, runner)
    return choose_reference(val_f1, table, set(prior_matchers()))


__all__ = ["EXCLUDED", "LEARNED", "choose_reference", "reference_for", "validation_pooled_f1"]
