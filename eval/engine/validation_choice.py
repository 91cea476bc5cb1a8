"""Choices made on validation: a study's validation F1 per method (as its evaluation recorded it)
and the ranking every "chosen on validation" statement reads. Test figures never choose, except
in a table built in memory without validation figures (then no verdict is stated). Imports
``eval/core/`` only."""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from eval.core.abstention import cannot_run
from eval.core.tasks import MatcherSpec
from eval.engine.named_runs import as_named
from eval.engine.splits import Named


def runnable(names: Sequence[str], condition: str) -> list[str]:
    """``names`` less the matchers that cannot run under localisation ``condition`` (a prior
    reader under ``denied``, :func:`eval.core.abstention.cannot_run`), in order."""
    return [m for m in names if not cannot_run(m, condition)]


def validation_f1(thresholds: Path, label: str) -> dict[str, float]:
    """{matcher: mean per-pair validation F1 at its calibrated τ} from a ``thresholds.csv``."""
    if not Path(thresholds).is_file():
        return {}
    table = pd.read_csv(thresholds, keep_default_na=False, na_values=[""])
    table = table[table["dataset"] == label]
    return {
        str(r.matcher): float(r.val_f1) for r in table.itertuples(index=False) if pd.notna(r.val_f1)
    }


def recorded_validation(results: Path, name: str) -> dict[str, dict[str, float]]:
    """{preset: {matcher: validation F1}} as ``results/<name>/validation_f1.csv`` records it,
    matchers that cannot run under the preset left out."""
    path = Path(results) / name / "validation_f1.csv"
    if not path.is_file():
        return {}
    table = pd.read_csv(path)
    return {
        p: {m: f for m, f in zip(g["matcher"], g["val_f1"], strict=True) if not cannot_run(m, p)}
        for p, g in table.groupby("preset", sort=False)
    }


def ranked_on_validation(group: pd.DataFrame, validation: Mapping[str, float] | None) -> list[str]:
    """The matchers of one condition's per-pair rows, best first by validation F1
    (``validation``: {matcher: val F1}; a matcher without one ranks last). Without validation
    figures (a table built in memory) the ranking is by test F1 — callers that state a verdict
    pass them. A matcher that cannot run under the condition (``preset``) is not ranked."""
    presets = set(group["preset"]) if "preset" in group.columns else set()
    names = list(dict.fromkeys(group["matcher"]))
    for preset in presets:
        names = runnable(names, preset)
    group = group[group["matcher"].isin(names)]
    if validation:
        return sorted(names, key=lambda m: -validation.get(m, -np.inf))
    test = group.groupby("matcher", sort=False)["f1"].mean()
    return list(test.sort_values(ascending=False, kind="stable").index)


def chosen_specs(
    out_dir: str | Path, label: str, matchers: Sequence[MatcherSpec]
) -> tuple[Named, dict[str, float | None]]:
    """The spec (tuned parameters included) and τ of each matcher on dataset `label`, as the
    main variant's ``thresholds.csv`` in `out_dir` records them; a matcher it lacks runs as
    requested with no τ (None)."""
    named, taus = as_named(matchers), {}
    path = Path(out_dir) / "thresholds.csv"
    if not path.is_file():
        return named, {m: None for m in named}
    table = pd.read_csv(path, keep_default_na=False, na_values=[""])
    table = table[table["dataset"] == label]
    for row in table.itertuples(index=False):
        if row.matcher not in named:
            continue
        params = json.loads(row.params) if "params" in table.columns and row.params else {}
        named[row.matcher] = MatcherSpec.of(named[row.matcher].name, **params)
        taus[row.matcher] = None if pd.isna(row.tau) else float(row.tau)
    return named, {m: taus.get(m) for m in named}
