"""Dataset-level spread: the same scenario generated again with other scenario seeds, evaluated
with the matchers' parameters and τ from the main evaluation (same scenario, so the same
calibration), so the reader sees how much Table I's numbers move from one generated dataset to the
next — a spread no run seed shows.

``dataset_spread.csv``: one row per (generated dataset, matcher) — ``dataset`` (the table's
label), ``generated`` (the dataset's directory name), ``scenario_seed``, ``pairs``, ``runs``,
``matcher``, ``f1``, ``balanced_accuracy`` (mean over runs of the per-run mean over frame pairs,
at τ, as fractions).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import pandas as pd

from eval.core.runner import Runner
from eval.engine.named_runs import run_named, score_runs
from eval.engine.splits import Named

COLUMNS = (
    "dataset",
    "generated",
    "scenario_seed",
    "pairs",
    "runs",
    "matcher",
    "f1",
    "balanced_accuracy",
)


def spread_rows(
    label: str,
    generated: Sequence[tuple[str, str, int]],
    named: Named,
    taus: Mapping[str, float | None],
    seeds: Sequence[int],
    runner: Runner,
) -> pd.DataFrame:
    """Rows for the datasets `generated` ((directory, checksum, scenario seed) each) of scenario
    `label`, every matcher of `named` at its τ."""
    rows = []
    for directory, checksum, scenario_seed in generated:
        runs = run_named(runner, (directory, checksum), named, seeds, f"{label} spread")
        per_pair = score_runs(runs, taus)
        per_run = per_pair.groupby(["matcher", "seed"], sort=False)[
            ["f1", "balanced_accuracy"]
        ].mean()
        means = per_run.groupby(level=0, sort=False).mean()
        for matcher, r in means.iterrows():
            rows.append(
                {
                    "dataset": label,
                    "generated": Path(directory).name,
                    "scenario_seed": scenario_seed,
                    "pairs": per_pair["pair"].nunique(),
                    "runs": len(seeds),
                    "matcher": matcher,
                    "f1": r["f1"],
                    "balanced_accuracy": r["balanced_accuracy"],
                }
            )
    return pd.DataFrame(rows, columns=list(COLUMNS))


def spread_ranges(path: str | Path) -> pd.DataFrame:
    """Per (dataset, matcher): min and max F1 over the generated datasets and how many there
    are (percent)."""
    table = pd.read_csv(path, keep_default_na=False, na_values=[""])
    grouped = table.groupby(["dataset", "matcher"], sort=False)["f1"]
    return pd.DataFrame(
        {"f1_min": 100 * grouped.min(), "f1_max": 100 * grouped.max(), "datasets": grouped.size()}
    ).reset_index()
