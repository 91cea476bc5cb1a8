"""The multi-agent table's Markdown (``table_multiagent.md``): one row per (preset, N, matcher,
fusion), pooled F1, the gain over ``independent`` with its Holm-adjusted p and its minimum
detectable difference, the count error with its interval. Rendering only; imports no study module but the study's own statistics."""

from __future__ import annotations

import numpy as np
import pandas as pd

from eval.core.abstention import NO_NUMBER, cannot_run
from eval.engine.cells import cell
from eval.engine.result_table import numeric_column
from eval.studies.multiagent.gains import BASELINE


def gain_family(table: pd.DataFrame) -> int:
    family = numeric_column(table, "gain_family")
    return int(family.max()) if family.notna().any() else 0


def to_markdown(table: pd.DataFrame, label: str) -> str:
    """The table as Markdown, percent for fractions, one block per preset."""
    m = gain_family(table)
    lines = [
        f"**{label}** — two-view matcher × fusion × number of agents, test snapshots; pooled "
        "pairwise F1, object-count error (with its 95 % episode-bootstrap interval) and "
        "clustering in percent; F1 gain: pooled F1 minus `independent`'s (same matcher, preset "
        "and N), in points, with its two-sided episode-bootstrap p Holm-adjusted over the "
        f"table's {m} gains (family-wise: a gain is shown at the 5 % level when its adjusted p "
        "≤ 0.05); MDD: the minimum detectable difference from `independent` in points, the "
        "smallest true difference a two-sided 5 % test detects with 80 % power, from the "
        "cluster-robust standard error over episodes; cycle violations: an invariant, 0 for every fused output by construction — "
        "only `independent`'s raw pairs have any; time in ms per snapshot",
        "",
        f"| Preset | N | Matcher | Fusion | F1 pooled | F1 gain (Holm-adjusted p, m = {m}) "
        "| MDD | cycle violations | count error [95 % CI] | cluster P / R | ms / snapshot |",
        "|:---|---:|:---|:---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    ordered = table.sort_values(["preset", "n_agents", "matcher"], kind="stable")
    for row in ordered.itertuples(index=False):
        if cannot_run(row.matcher, row.preset):
            lines.append(
                f"| {row.preset} | {row.n_agents} | {row.matcher} | {row.fusion} | {NO_NUMBER} "
                "| n/a | n/a | n/a | n/a | n/a | n/a |"
            )
            continue
        p_holm = getattr(row, "gain_p_holm", np.nan)
        gain = (
            "–"
            if row.fusion == BASELINE or not np.isfinite(row.f1_gain)
            else f"{100 * row.f1_gain:+.1f}" + (f" (p {p_holm:.3f})" if np.isfinite(p_holm) else "")
        )
        mdd = getattr(row, "gain_mdd", np.nan)  # absent from files written before it
        mdd_cell = "–" if row.fusion == BASELINE else cell(mdd)
        low = getattr(row, "count_error_ci_low", np.nan)
        high = getattr(row, "count_error_ci_high", np.nan)
        count = cell(row.count_error) + (
            f" [{cell(low)}, {cell(high)}]" if np.isfinite(low) and np.isfinite(high) else ""
        )
        lines.append(
            f"| {row.preset} | {row.n_agents} | {row.matcher} | {row.fusion} "
            f"| {cell(row.f1_pooled)} | {gain} | {mdd_cell} | {cell(row.cycle_violation_rate)} "
            f"| {count} | {cell(row.cluster_precision)} / "
            f"{cell(row.cluster_recall)} | {row.ms_per_snapshot:.1f} |"
        )
    return "\n".join(lines)


__all__ = ["gain_family", "to_markdown"]
