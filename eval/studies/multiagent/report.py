"""The multi-agent study's report: the table's Markdown, the goals (each "best" chosen on the
validation snapshots, reported on test, read through :mod:`eval.protocol.goal_verdict`), the
cycle-consistency invariant, the timing lines and the README part. Reads the files
:func:`eval.studies.multiagent.evaluation.evaluate_multiagent` wrote; runs nothing."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from eval.engine.result_table import numeric_column
from eval.protocol.claims import measurement_line
from eval.protocol.goal_verdict import NOT_SHOWN, goal_line
from eval.studies.multiagent.evaluation import COUNT_BAR, GAIN_BAR, LABEL, SUBSETS
from eval.studies.multiagent.gains import BASELINE
from eval.studies.multiagent.markdown import gain_family, to_markdown


def best_on_validation(rows: pd.DataFrame, column: str, lowest: bool) -> pd.Series | None:
    """The row of ``rows`` best on the validation figure ``column`` (its lowest or highest
    value; ties: the first row), or None when no row has one (a table without validation
    figures). Every "best" of :func:`goals` is chosen here, then reported on test."""
    known = rows[np.isfinite(numeric_column(rows, column))]
    if known.empty:
        return None
    return known.loc[known[column].idxmin() if lowest else known[column].idxmax()]


def _not_shown(goal: str, why: str) -> str:
    return f"{goal}: {NOT_SHOWN} — {why}"


def invariant_line(table: pd.DataFrame) -> str:
    """The cycle-consistency invariant of every fused output (not a goal: it holds by
    construction, so a violation is a bug), with ``independent``'s rate for contrast."""
    fused = table[table["fusion"] != BASELINE]
    rates = fused["cycle_violation_rate"]
    worst = rates.max() if len(fused) else 0.0
    line = "invariant: fused outputs have no cycle violation — " + (
        "holds" if worst == 0 else "violated"
    )
    if worst != 0:
        row = fused.loc[rates.idxmax()]
        line += (
            f" (rate {100 * worst:.1f} % for {row.matcher} + {row.fusion}, N = {row.n_agents}, "
            f"{row.preset}: a fusion bug)"
        )
    alone = table.loc[table["fusion"] == BASELINE, "cycle_violation_rate"]
    if len(alone):
        line += f"; `independent`'s raw pairs break up to {100 * alone.max():.1f} % of the chains"
    return line


def goals(table: pd.DataFrame, stage_s: float | None = None) -> list[str]:
    """Plain statements of the table's goals, each met, not met or not shown by its interval
    (:mod:`eval.protocol.goal_verdict`), every "best" chosen on the validation snapshots and
    reported on test; first the cycle-consistency invariant."""
    fused = table[table["fusion"] != BASELINE]
    lines = [invariant_line(table)]
    goal = (
        f"fusion raises pooled F1 over `independent` by ≥ {100 * GAIN_BAR:.0f} points at N ≥ 4 "
        "for some matcher"
    )
    wide = fused[fused["n_agents"] >= 4]
    if len(wide):
        best = best_on_validation(wide, "val_f1_gain", lowest=False)
        if best is None:
            lines.append(_not_shown(goal, "no validation figures to choose the method on"))
        else:
            p_holm = best.get("gain_p_holm", np.nan)
            lines.append(
                goal_line(
                    goal,
                    best.f1_gain,
                    best.gain_ci_low,
                    best.gain_ci_high,
                    GAIN_BAR,
                    unit=" points",
                    detail=f"{best.matcher} + {best.fusion}, N = {best.n_agents}, {best.preset}: "
                    f"the largest gain on the validation snapshots ({100 * best.val_f1_gain:+.1f} "
                    "points), scored on test with its 95 % episode-bootstrap interval; Holm-"
                    f"adjusted p over the table's {gain_family(table)} gains {p_holm:.3f}",
                )
            )
    high = table["n_agents"].max()
    goal = f"object-count error ≤ {100 * COUNT_BAR:.0f} % at N = {high} with the best method"
    top = table[table["n_agents"] == high]
    if len(top):
        known = top[numeric_column(top, "val_f1_pooled") > 0]
        best = best_on_validation(known, "val_count_error", lowest=True)
        if best is None:
            lines.append(_not_shown(goal, "no validation figures to choose the method on"))
        else:
            lines.append(
                goal_line(
                    goal,
                    best.count_error,
                    best.get("count_error_ci_low", np.nan),
                    best.get("count_error_ci_high", np.nan),
                    COUNT_BAR,
                    at_least=False,
                    unit=" %",
                    detail=f"{best.matcher} + {best.fusion}, {best.preset}: the lowest on the "
                    f"validation snapshots ({100 * best.val_count_error:.1f} %; methods that "
                    "match something there), scored on test with its 95 % episode-bootstrap "
                    "interval",
                )
            )
    lines += _time_lines(table, stage_s)
    return lines


def _time_lines(table: pd.DataFrame, stage_s: float | None) -> list[str]:
    """The time goals: N = max against N = min per snapshot, and the stage's wall time."""
    lines = []
    pairs = len(SUBSETS[max(SUBSETS)]) * (len(SUBSETS[max(SUBSETS)]) - 1) // 2
    low, high = table["n_agents"].min(), table["n_agents"].max()
    rows = table[table["n_agents"] == high]
    if numeric_column(rows, "val_f1_pooled").notna().any():
        rows = rows[numeric_column(rows, "val_f1_pooled") > 0]  # methods matching something on val
    rows = rows[np.isfinite(numeric_column(rows, "time_ratio"))]
    if len(rows) and low != high:
        fusion_ms = table.loc[table["n_agents"] == high, "fusion_ms_per_snapshot"].max()
        lines.append(
            goal_line(
                f"time per snapshot at N = {high} ≤ {pairs} × the two-view time (N = {low}) for "
                "every matcher and fusion",
                rows["time_ratio"].max(),
                rows["time_ratio_ci_low"].max(),
                rows["time_ratio_ci_high"].max(),
                pairs,
                at_least=False,
                scale=1.0,
                unit="×",
                detail=f"the largest ratio over the matchers and fusions, its interval the "
                "largest ends of their 95 % episode-bootstrap intervals; the smallest ratio "
                f"{rows['time_ratio'].min():.1f}×; the fusions themselves take at most "
                f"{fusion_ms:.1f} ms per snapshot, the rest is the {pairs} pairs' matching, "
                "whose views beyond the first two hold more detections (a roadside unit sees "
                "more)",
            )
        )
    if stage_s is not None:  # given only from a cold run (eval.readme_results)
        lines.append(
            measurement_line(
                "this table's stages (generation and runs)",
                stage_s,
                120.0,
                "last cold run, results/cold_run.json",
            )
        )
    return lines


def readme_part(results: Path, rel: str, stage_s: float | None = None) -> list[str]:
    """README lines for the multi-agent table (none without ``table_multiagent.csv``)."""
    path = Path(results) / "table_multiagent.csv"
    if not path.is_file():
        return []
    table = pd.read_csv(path)
    if table.empty:
        return []
    high = table["n_agents"].max()
    shown = table[(table["n_agents"] == high) & (table["preset"] == "gnss-urban")]
    if shown.empty:
        shown = table[table["n_agents"] == high]
    return [
        "### Multi-agent matching",
        "",
        f"![Pooled pairwise F1 and cycle violations against the number of agents]({rel}/fig_multiagent.png)",
        "",
        "`scenarios/cad-multi.toml`: the CAD junction seen per snapshot by 4 vehicles and 2 "
        "roadside units. Every two-view matcher (CAD's tuned parameters, τ per preset on the "
        "validation snapshots) on every pair of views; for N agents the pairwise matchings are "
        "fused into one assignment of every detection to an object (docs/multi-agent.md). "
        f"N = {high} under `gnss-urban` below; every N and preset: "
        f"[{rel}/table_multiagent.md]({rel}/table_multiagent.md).",
        "",
        to_markdown(shown, LABEL),
        "",
        *[f"- {line}." for line in goals(table, stage_s)],
        "",
    ]


__all__ = ["best_on_validation", "goals", "invariant_line", "readme_part", "to_markdown"]
