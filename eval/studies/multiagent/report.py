"""The multi-agent study's report: the table's Markdown, the goals (each "best" chosen on the
validation snapshots, reported on test, read through :mod:`eval.protocol.goal_verdict`), the
cycle-consistency invariant, the timing lines and the README part. Reads the files
:func:`eval.studies.multiagent.evaluation.evaluate_multiagent` wrote; runs nothing."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from eval.engine.goal import Goal
from eval.engine.result_table import numeric_column
from eval.protocol.claims import Claim, claims_in, lines_of, measurement_claim
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
    """The lines of :func:`goal_items`, as the report prints them."""
    return lines_of(goal_items(table, stage_s))


def claims(results: Path, stage_s: float | None = None) -> list[Claim]:
    """The claims of the multi-agent part (none without ``table_multiagent.csv``)."""
    path = Path(results) / SOURCE
    table = pd.read_csv(path) if path.is_file() else None
    return [] if table is None or table.empty else claims_in(goal_items(table, stage_s))


def goal_items(table: pd.DataFrame, stage_s: float | None = None) -> list[Claim | str]:
    """The table's goals, each a claim met, not met or not shown by its interval
    (:mod:`eval.protocol.goal_verdict`), every "best" chosen on the validation snapshots and
    reported on test; first the cycle-consistency invariant (a plain line: it holds by
    construction). A goal without validation figures to choose on is a plain "not shown"
    line."""
    fused = table[table["fusion"] != BASELINE]
    lines: list[Claim | str] = [invariant_line(table)]
    gain_goal = Goal(
        "N ≥ 4",
        f"fusion raises pooled F1 over `independent` by ≥ {100 * GAIN_BAR:.0f} points at N ≥ 4 "
        "for some matcher",
        ("f1_gain", "gain_ci_low", "gain_ci_high"),
        GAIN_BAR,
        unit=" points",
    )
    goal = gain_goal.text
    wide = fused[fused["n_agents"] >= 4]
    if len(wide):
        best = best_on_validation(wide, "val_f1_gain", lowest=False)
        if best is None:
            why = "no validation figures to choose the method on"
            lines.append(gain_goal.not_shown(why, study="multiagent", subject=goal, source=SOURCE))
        else:
            p_holm = best.get("gain_p_holm", np.nan)
            mdd = float(best.get("gain_mdd", np.nan))
            mdd_text = f"; MDD {100 * mdd:.1f} points" if np.isfinite(mdd) else ""
            lines.append(
                gain_goal.claim(
                    best,
                    study="multiagent",
                    subject=f"{best.matcher} + {best.fusion}",
                    source=SOURCE,
                    detail=f"{best.matcher} + {best.fusion}, N = {best.n_agents}, {best.preset}: "
                    f"the largest gain on the validation snapshots ({100 * best.val_f1_gain:+.1f} "
                    "points), scored on test with its 95 % episode-bootstrap interval; Holm-"
                    f"adjusted p over the table's {gain_family(table)} gains {p_holm:.3f}"
                    + mdd_text,
                )
            )
    high = table["n_agents"].max()
    count_goal = Goal(
        f"N = {high}",
        f"object-count error ≤ {100 * COUNT_BAR:.0f} % at N = {high} with the best method",
        ("count_error", "count_error_ci_low", "count_error_ci_high"),
        COUNT_BAR,
        at_least=False,
        unit=" %",
    )
    goal = count_goal.text
    top = table[table["n_agents"] == high]
    if len(top):
        known = top[numeric_column(top, "val_f1_pooled") > 0]
        best = best_on_validation(known, "val_count_error", lowest=True)
        if best is None:
            why = "no validation figures to choose the method on"
            lines.append(count_goal.not_shown(why, study="multiagent", subject=goal, source=SOURCE))
        else:
            lines.append(
                count_goal.claim_of(
                    best.count_error,
                    best.get("count_error_ci_low", np.nan),
                    best.get("count_error_ci_high", np.nan),
                    study="multiagent",
                    subject=f"{best.matcher} + {best.fusion}",
                    source=SOURCE,
                    detail=f"{best.matcher} + {best.fusion}, {best.preset}: the lowest on the "
                    f"validation snapshots ({100 * best.val_count_error:.1f} %; methods that "
                    "match something there), scored on test with its 95 % episode-bootstrap "
                    "interval",
                )
            )
    lines += _time_lines(table, stage_s)
    return lines


def _time_lines(table: pd.DataFrame, stage_s: float | None) -> list[Claim]:
    """The time goals: N = max against N = min per snapshot (the largest ratio over every
    matcher and fusion: no choice, ``fixed``), and the stage's wall time."""
    lines = []
    pairs = len(SUBSETS[max(SUBSETS)]) * (len(SUBSETS[max(SUBSETS)]) - 1) // 2
    low, high = table["n_agents"].min(), table["n_agents"].max()
    rows = table[table["n_agents"] == high]
    if numeric_column(rows, "val_f1_pooled").notna().any():
        rows = rows[numeric_column(rows, "val_f1_pooled") > 0]  # methods matching something on val
    rows = rows[np.isfinite(numeric_column(rows, "time_ratio"))]
    if len(rows) and low != high:
        fusion_ms = table.loc[table["n_agents"] == high, "fusion_ms_per_snapshot"].max()
        worst = rows.loc[rows["time_ratio"].idxmax()]
        text = (
            f"time per snapshot at N = {high} ≤ {pairs} × the two-view time (N = {low}) for "
            "every matcher and fusion"
        )
        ratio = Goal(
            f"N = {high}",
            text,
            ("time_ratio", "time_ratio_ci_low", "time_ratio_ci_high"),
            pairs,
            at_least=False,
            chosen_on="fixed",
            scale=1.0,
            unit="×",
        )
        lines.append(
            ratio.claim_of(
                rows["time_ratio"].max(),
                rows["time_ratio_ci_low"].max(),
                rows["time_ratio_ci_high"].max(),
                study="multiagent",
                subject=text.split(" (")[0],
                source=SOURCE,
                detail=f"the largest ratio over the matchers and fusions, its interval the "
                "largest ends of their 95 % episode-bootstrap intervals; the smallest ratio "
                f"{rows['time_ratio'].min():.1f}×; the fusions themselves take at most "
                f"{fusion_ms:.1f} ms per snapshot, the rest is the {pairs} pairs' matching, "
                "whose views beyond the first two hold more detections (a roadside unit sees "
                "more)" + _per_pair(table, worst, low, pairs),
            )
        )
    if stage_s is not None:  # given only from a cold run (eval.readme_results)
        lines.append(
            measurement_claim(
                "multiagent",
                "this table's stages (generation and runs)",
                stage_s,
                120.0,
                "last cold run, results/cold_run.json",
            )
        )
    return lines


def _per_pair(table: pd.DataFrame, row: pd.Series, low: int, pairs: int) -> str:
    """For the method of ``row`` (at the largest N, ``pairs`` view pairs): its matching time per
    view pair beyond the first against the first pair's (the N = ``low`` run of the same matcher,
    fusion and preset; each without its fusion's time), or "" without that run."""
    same = table[
        (table["n_agents"] == low)
        & (table["matcher"] == row.matcher)
        & (table["fusion"] == row.fusion)
        & (table["preset"] == row.preset)
    ]
    if same.empty or pairs < 2:
        return ""
    first = float(same["ms_per_snapshot"].iloc[0] - same["fusion_ms_per_snapshot"].iloc[0])
    rest = (row.ms_per_snapshot - row.fusion_ms_per_snapshot - first) / (pairs - 1)
    if not (np.isfinite(first) and np.isfinite(rest)):
        return ""
    return (
        f"; for {row.matcher} + {row.fusion} ({row.preset}) each of the {pairs - 1} pairs beyond "
        f"views 1-2 takes {rest:.2f} ms to match against {first:.2f} ms for views 1-2"
    )


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


SOURCE = "table_multiagent.csv"  # the file the multi-agent claims read

__all__ = [
    "best_on_validation",
    "claims",
    "goal_items",
    "goals",
    "invariant_line",
    "readme_part",
    "to_markdown",
]
