"""The multi-agent study's power analysis (:mod:`eval.engine.power_analysis`): the MDD of its
gain goal — the fusion with the largest validation gain over ``independent`` at N ≥ 4, scored on
test in pooled F1 — from ``table_multiagent.csv``'s episode-bootstrap interval, the clusters the
test episodes of ``multiagent/per_snapshot.csv`` (one snapshot per episode: no ICC to measure)."""

from __future__ import annotations

from pathlib import Path

from eval.engine.power_analysis import PowerCheck, interval_row, read_csv
from eval.studies.multiagent.gains import BASELINE
from eval.studies.multiagent.report import best_on_validation


def gain_rows(results: Path) -> list[dict]:
    """The gain goal's row (none without the table or its validation figures)."""
    table = read_csv(Path(results) / "table_multiagent.csv")
    if table is None or "val_f1_gain" not in table.columns:
        return []
    wide = table[(table["fusion"] != BASELINE) & (table["n_agents"] >= 4)]
    best = best_on_validation(wide, "val_f1_gain", lowest=False) if len(wide) else None
    if best is None:
        return []
    snapshots = read_csv(Path(results) / "multiagent" / "per_snapshot.csv")
    items = None
    if snapshots is not None and {"episode", "snapshot"} <= set(snapshots.columns):
        test = snapshots[snapshots["split"] == "test"]
        clusters, items = int(test["episode"].nunique()), int(test["snapshot"].nunique())
    else:
        clusters = int(best.snapshots)
    comparison = f"pooled F1, fused − {BASELINE}: {best.matcher} + {best.fusion}, N = {best.n_agents}"  # fmt: skip
    return [
        interval_row(
            "multiagent",
            comparison,
            str(best.preset),
            best.gain_ci_low,
            best.gain_ci_high,
            clusters,
            "mdd",
            items=items,
        )
    ]


CHECKS = (PowerCheck("fusion gain at N ≥ 4 (chosen on validation): MDD", gain_rows),)
