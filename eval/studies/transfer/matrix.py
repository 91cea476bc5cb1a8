"""The transfer matrix's columns and Markdown: one block per test set, a row per (training set,
learned matcher), the hand-crafted matcher chosen on validation beside it, the difference with
its interval. Rendering only."""

from __future__ import annotations

import math

import pandas as pd

COLUMNS = [
    "train",
    "test",
    "matcher",
    "uses_prior",
    "f1_pooled",
    "f1_pooled_low",
    "f1_pooled_high",
    "ap",
    "tau",
    "tau_split",
    "frames",
    "handcrafted",
    "handcrafted_matcher",
    "handcrafted_val_f1_pooled",
    "handcrafted_f1_pooled",
    "handcrafted_ap",
    "diff_handcrafted",
    "diff_handcrafted_low",
    "diff_handcrafted_high",
    "diff_sim_only",
    "diff_sim_only_low",
    "diff_sim_only_high",
    "clusters",
    "cluster_unit",
    "model_sha256",
]
GAP_COLUMNS = ("diff_sim_only", "diff_sim_only_low", "diff_sim_only_high")


def pct(value: float) -> str:
    return "–" if pd.isna(value) else f"{100 * value:.1f}"


def points(value: float, low: float, high: float) -> str:
    """``+1.2 [−3.4, 5.6]`` (percentage points), ``–`` without a value."""
    if pd.isna(value):
        return "–"
    shown = f"{100 * value:+.1f}"
    if pd.isna(low) or pd.isna(high):
        return shown + " (no interval)"
    return shown + f" [{100 * low:+.1f}, {100 * high:+.1f}]"


def value_of(row: pd.Series | None, column: str) -> float:
    if row is None or column not in row.index:
        return math.nan
    try:
        return float(row[column])
    except (TypeError, ValueError):
        return math.nan


def clusters_text(row: pd.Series | None, lead: str = "95 % cluster t-interval over") -> str:
    """``95 % cluster t-interval over 12 blocks of 10 pairs`` (``lead`` first)."""
    count = value_of(row, "clusters")
    unit = row.get("cluster_unit") if row is not None else None
    if not math.isfinite(count) or not isinstance(unit, str):
        return "95 % cluster t-interval"
    plural = unit.replace("block", "blocks", 1) if unit.startswith("block") else unit + "s"
    text = f"{lead} {int(count)} {plural if int(count) != 1 else unit}"
    if unit.startswith("block") and lead != "in":  # DMGM's test pairs: two sequences
        text += " from 2 sequences (blocks of one sequence are not independent clusters)"
    return text


def to_markdown(table: pd.DataFrame) -> str:
    """The transfer matrix: one block per test set, a row per (training set, learned matcher),
    the hand-crafted matcher of the same kind chosen on validation beside it (percent), and the
    difference with its interval (percentage points)."""
    from eval.report.markdown_cell import cell as md_cell

    lines = [
        "Transfer of the learned matchers (pooled F1 and AP, percent). τ of every learned row "
        "from pairs its model was not trained on: each cadsim test set's validation split; on "
        "DMGM pairs 111–201 of sequence 070 (pairs 1–100 train the DMGM model). Beside each "
        "row, the hand-crafted matcher of the same kind (with or without the prior) with the "
        "best pooled F1 on the *validation* split, and its *test* figures. Δ: learned − "
        "hand-crafted pooled F1 on the same test pairs, percentage points, with its 95 % "
        "cluster t-interval (episodes; on DMGM blocks of 10 consecutive pairs).",
        "",
    ]
    header = ["Trained on", "Matcher", "Pooled F1", "AP", "Hand-crafted (chosen on val.)"]
    header += ["its F1", "its AP", "Δ F1 [95 % CI]"]
    table = table.reindex(columns=list(dict.fromkeys([*COLUMNS, *table.columns])))
    for test, rows in table.groupby("test", sort=False):
        frames = rows["frames"].max()
        shown = [] if pd.isna(frames) else [f"{int(frames)} frame pairs"]
        shown += [clusters_text(rows.iloc[0], "in")] if pd.notna(rows["clusters"].max()) else []
        lines += [f"**Tested on {md_cell(test)}**" + (f" ({' '.join(shown)})" if shown else ""), ""]
        lines += ["| " + " | ".join(header) + " |", "|:---|:---|---:|---:|:---|---:|---:|---:|"]
        for r in rows.itertuples(index=False):
            cells = [
                md_cell(r.train),
                md_cell(r.matcher),
                pct(r.f1_pooled),
                pct(r.ap),
                r.handcrafted if isinstance(r.handcrafted, str) and r.handcrafted else "–",
                pct(r.handcrafted_f1_pooled),
                pct(r.handcrafted_ap),
                points(r.diff_handcrafted, r.diff_handcrafted_low, r.diff_handcrafted_high),
            ]
            lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines)


__all__ = ["COLUMNS", "GAP_COLUMNS", "to_markdown"]
