"""The V2X study's report: per preset the matcher chosen on validation, the compact table, the
goal lines (:mod:`eval.protocol.goal_verdict`), the best-against-runner-up lines and the README
part. Reads the files :func:`eval.studies.v2x.table.evaluate_v2x` wrote; runs nothing."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from eval.engine.cells import cell, has_interval, ranged
from eval.engine.comparison import INTERVAL_COLUMNS
from eval.engine.goal import Goal
from eval.engine.power import power_line
from eval.engine.result_table import bullets, read_result
from eval.engine.validation_choice import recorded_validation, runnable
from eval.protocol.claims import Claim, difference_verdict, printed
from eval.studies.v2x.markdown import to_markdown
from eval.studies.v2x.realism import realism_claims
from eval.studies.v2x.table import (
    ORACLE_ROW,
    PRESETS,
    REFERENCE_ROWS,
    SUBDIR,
    reads_prior,
)

SOURCE = "table_v2x.csv"  # the file the V2X claims read


def read_intervals(results: Path, name: str) -> pd.DataFrame:
    """``results/table_<name>_intervals.csv`` (empty with its columns when absent)."""
    path = Path(results) / f"table_{name}_intervals.csv"
    return pd.read_csv(path) if path.is_file() else pd.DataFrame(columns=list(INTERVAL_COLUMNS))


TOP = 4


def compact(
    table: pd.DataFrame,
    validation: Mapping[str, Mapping[str, float]] | None = None,
    top: int = TOP,
) -> pd.DataFrame:
    """Per preset: the `top` matchers by validation F1 (test F1 without validation figures)
    among those that can run there, the best one that reads no prior (if not among them) and
    the reference rows, in table order."""
    keep = []
    for preset, group in table.groupby("preset", sort=False):
        rows = group[~group["matcher"].isin(REFERENCE_ROWS)]
        rows = rows[rows["matcher"].isin(runnable(list(rows["matcher"]), preset))]
        val = (validation or {}).get(preset)
        if val:
            ranked = sorted(rows.index, key=lambda i: -val.get(rows.at[i, "matcher"], -np.inf))
        else:
            ranked = list(rows.sort_values("f1_mean", ascending=False, kind="stable").index)
        chosen = ranked[:top]
        free = [i for i in ranked if not reads_prior(rows.at[i, "matcher"])]
        if free and free[0] not in chosen:
            chosen.append(free[0])
        chosen += list(group.index[group["matcher"].isin(REFERENCE_ROWS)])
        keep += chosen
    return table.loc[keep].reset_index(drop=True)


def compact_markdown(results: Path, name: str, label: str) -> str | None:
    """The compact Markdown of the V2X-protocol table ``table_<name>.csv`` under ``results``
    (validation-ranked rows, intervals from ``table_<name>_intervals.csv`` when present), or
    None without ``table_<name>.md``."""
    results = Path(results)
    if not (results / f"table_{name}.md").is_file():
        return None
    table = pd.read_csv(results / f"table_{name}.csv", keep_default_na=False, na_values=[""])
    intervals = read_intervals(results, name)
    return to_markdown(compact(table, recorded_validation(results, name)), intervals, label)


def _family(name: str) -> str:
    if name in REFERENCE_ROWS:
        return "a reference row"
    return "with the prior" if reads_prior(name) else "without a prior"


def chosen_row(
    table: pd.DataFrame, preset: str, validation: Mapping[str, Mapping[str, float]] | None
) -> tuple[str, pd.Series] | None:
    """(name, row) of the matcher of ``preset`` with the highest validation F1 (test F1 without
    validation figures: a table built in memory); None when the preset has no matcher row that
    can run there."""
    rows = table[(table["preset"] == preset) & ~table["matcher"].isin(REFERENCE_ROWS)]
    rows = rows[rows["matcher"].isin(runnable(list(rows["matcher"]), preset))]
    if rows.empty:
        return None
    rows = rows.set_index("matcher")
    val = (validation or {}).get(preset) or {}
    best = max(rows.index, key=lambda m: val.get(m, -np.inf)) if val else rows["f1_mean"].idxmax()
    return best, rows.loc[best]


def chosen_by_preset(
    table: pd.DataFrame, presets, validation: Mapping[str, Mapping[str, float]] | None
) -> dict[str, tuple[str, pd.Series]]:
    """{preset: (name, row)} of :func:`chosen_row` for each of ``presets`` that has a choice."""
    found = {p: chosen_row(table, p, validation) for p in presets}
    return {p: choice for p, choice in found.items() if choice is not None}


def findings(
    table: pd.DataFrame, validation: Mapping[str, Mapping[str, float]] | None = None
) -> list[str]:
    """Plain statements read off the table: per preset the matcher chosen by validation F1, its
    test F1 and success@(1 m, 2°) with their intervals, and the oracle's success."""
    out = []
    for preset in [p for p in PRESETS if p in set(table["preset"])]:
        here = table[table["preset"] == preset].set_index("matcher")
        found = chosen_row(table, preset, validation)
        if found is None:
            continue
        best, b = found
        oracle = here.loc[ORACLE_ROW] if ORACLE_ROW in here.index else None
        ceiling = (
            f"; the oracle's {ranged(oracle.success_1m_2deg, oracle.success_low, oracle.success_high)}"
            if oracle is not None
            else ""
        )
        out.append(
            f"`{preset}`: chosen on validation `{best}` ({_family(best)}): test F1 "
            f"{ranged(b.f1_mean, b.f1_low, b.f1_high)}, success@(1 m, 2°) "
            f"{ranged(b.success_1m_2deg, b.success_low, b.success_high)} "
            f"({cell(b.share_of_oracle, digits=0)} % of the oracle's){ceiling}"
        )
    return out


F1 = ("f1_mean", "f1_low", "f1_high")
SUCCESS = ("success_1m_2deg", "success_low", "success_high")
GOALS = (
    Goal("gnss-urban", "`gnss-urban` F1 ≥ 90", F1, 0.9),
    Goal("gnss-urban", "`gnss-urban` success@(1 m, 2°) ≥ 90", SUCCESS, 0.9),
    Goal("denied", "`denied` F1 ≥ 80", F1, 0.8),
)
"""The V2X goals: each read off the matcher chosen on validation under its preset."""


def goals(
    table: pd.DataFrame, validation: Mapping[str, Mapping[str, float]] | None = None
) -> list[str]:
    """The statements of :func:`goal_claims`, as the report prints them."""
    return [claim.statement for claim in goal_claims(table, validation)]


def goal_claims(
    table: pd.DataFrame, validation: Mapping[str, Mapping[str, float]] | None = None
) -> list[Claim]:
    """The :data:`GOALS` as claims, each with its interval and a verdict that reads it
    (:mod:`eval.protocol.goal_verdict`); the method is the one chosen on validation."""
    out = []
    chosen = chosen_by_preset(table, {g.condition: None for g in GOALS}, validation)
    for goal in (g for g in GOALS if g.condition in chosen):
        name, row = chosen[goal.condition]
        detail = (
            f"`{name}`; {cell(row.share_of_oracle, digits=0)} % of the oracle's"
            if goal.metric == SUCCESS
            else f"`{name}`, chosen on validation"
        )
        out.append(goal.claim(row, detail, study=SUBDIR, subject=name, source=SOURCE))
    return out


def runner_up_claims(intervals: pd.DataFrame) -> list[Claim]:
    """Per preset of ``table_v2x_intervals.csv``: the matcher chosen on validation against the
    runner-up, test F1 difference with its episode interval — ahead / behind only where the
    interval excludes 0 (:func:`eval.protocol.claims.difference_verdict`)."""
    out = []
    for row in intervals.itertuples(index=False):
        interval = (
            f"{100 * row.f1_diff:+.1f} [{100 * row.ci_low:+.1f}, {100 * row.ci_high:+.1f}]"
            if has_interval(row.ci_low, row.ci_high)
            else f"{100 * row.f1_diff:+.1f} (no interval)"
        )
        statement = (
            f"`{row.preset}`: `{row.best}` (chosen on validation) − the runner-up `{row.runner_up}`,"
            f" test F1 {interval} points over {int(row.episodes)} episodes — "
            f"{difference_verdict(row.ci_low, row.ci_high)}"
        )
        out.append(
            Claim(
                SUBDIR,
                row.preset,
                "difference",
                "f1 points",
                printed(row.f1_diff),
                printed(row.ci_low),
                printed(row.ci_high),
                0.0,
                "diff",
                difference_verdict(row.ci_low, row.ci_high),
                "validation",
                "simulation episodes",
                SOURCE,
                statement,
            )  # fmt: skip
        )
    return out


def runner_up_lines(intervals: pd.DataFrame) -> list[str]:
    """The statements of :func:`runner_up_claims`, as the report prints them."""
    return [claim.statement for claim in runner_up_claims(intervals)]


def claims(results: Path) -> list[Claim]:
    """The claims of the V2X part (its goals, best against runner-up, appearance realism), in
    the order the report states them; none without ``table_v2x.md``."""
    results = Path(results)
    table = read_result(results, "table_v2x.csv", allow_empty=True)
    if table is None or not (results / "table_v2x.md").is_file():
        return []
    validation = recorded_validation(results, SUBDIR)
    return [
        *goal_claims(table, validation),
        *runner_up_claims(read_intervals(results, SUBDIR)),
        *realism_claims(results),
    ]


def readme_part(results: Path, rel: str) -> list[str]:
    """README lines for the V2X task (none without ``table_v2x.md``)."""
    results = Path(results)
    table = read_result(results, "table_v2x.csv", allow_empty=True)
    if table is None or not (results / "table_v2x.md").is_file():
        return []
    validation = recorded_validation(results, SUBDIR)
    intervals = read_intervals(results, SUBDIR)
    said = (*goal_claims(table, validation), *runner_up_claims(intervals))
    lines = [c.statement for c in said]
    lines += [line for line in (power_line(results, SUBDIR),) if line]
    lines += [c.statement for c in realism_claims(results)]
    episodes = int(intervals["episodes"].max()) if len(intervals) else 0
    return [
        "### The V2X task",
        "",
        "`scenarios/cad-v2x.toml`: CAD with GNSS-like localisation error and 100 ms message "
        "latency, detector misses, clutter and jitter, and varied light and exposure "
        "(docs/localisation.md, docs/detection.md). Every matcher under every localisation "
        "preset, tuned (equal budget) under `gnss-urban` and, if it reads the prior, again under "
        "each preset on that preset's validation draw; τ per preset; pose metrics from the "
        "robust planar fit of the declared matches against the true relative pose "
        "(latency included); `oracle` is the same fit of the true matches (the ceiling), "
        f"`prior` the vehicles' broadcast poses alone; {episodes} test episodes. Per preset "
        f"the {TOP} best by validation F1, the best without a prior and the reference rows; "
        f"every matcher: [{rel}/table_v2x.md]({rel}/table_v2x.md).",
        "",
        to_markdown(compact(table, validation), intervals, "CAD-V2X"),
        "",
        *bullets(findings(table, validation) + lines),
        "",
        f"(`{rel}/table_v2x.csv`, `{rel}/table_v2x_intervals.csv`, `{rel}/v2x/`: per-preset "
        "evaluation files.)",
        "",
    ]


__all__ = [
    "TOP",
    "chosen_row",
    "compact",
    "compact_markdown",
    "findings",
    "goal_claims",
    "goals",
    "read_intervals",
    "readme_part",
    "runner_up_claims",
    "runner_up_lines",
    "claims",
]
