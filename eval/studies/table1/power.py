"""Table I's power analysis (:mod:`eval.engine.power_analysis`): at the headline difficulty level
(``table1_levels.json``, chosen on validation), per dataset the MDD of maximin against its best
rival there (``table1_levels_summary.csv``), measured on the variant's per-pair test metrics
joined with ``difficulty_levels.csv``, one pair per episode."""

from __future__ import annotations

import json
from pathlib import Path

from eval.engine.power_analysis import PowerCheck, paired_row, read_csv, run_mean_differences
from eval.protocol.variants import variant_path


def headline_rows(results: Path) -> list[dict]:
    """Per dataset the headline level's maximin − rival row (none without the files)."""
    results = Path(results)
    choice = results / "table1_levels.json"
    summary = read_csv(results / "table1_levels_summary.csv")
    levels = read_csv(results / "difficulty_levels.csv")
    if not choice.is_file() or summary is None or levels is None:
        return []
    headline = json.loads(choice.read_text())
    level = headline["level"]
    per_pair = read_csv(variant_path(results, "metrics_per_pair", headline.get("variant", ""), ".csv"))  # fmt: skip
    if per_pair is None or "rival" not in summary.columns:
        return []
    joined = per_pair.merge(levels[["dataset", "pair", "level"]], on=["dataset", "pair"])
    rows = []
    for entry in summary[summary["level"] == level].itertuples(index=False):
        if not isinstance(entry.rival, str):
            continue
        here = joined[(joined["dataset"] == entry.dataset) & (joined["level"] == level)]
        diff, episodes = run_mean_differences(here, "maximin", entry.rival)
        if len(diff):
            comparison = f"headline level {level}: maximin − {entry.rival}"
            rows.append(paired_row("table1", comparison, str(entry.dataset), diff, episodes, "mdd"))
    return rows


CHECKS = (PowerCheck("headline level: maximin − best rival MDD", headline_rows),)
