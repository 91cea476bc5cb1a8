"""Table I and the V2X tables by difficulty level (:mod:`eval.engine.difficulty_levels`): the
README's headline on the level chosen on validation, and the report's per-level tables.

A dataset whose top method is perfect on more than :data:`CEILING_SHARE` of the headline level's
test pairs is at the ceiling there: the headline says so in one line and leaves it out, rather
than the data being made artificially hard."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

from cadsim.dataset.difficulty import LEVELS
from eval.report.markdown_cell import cell
from eval.report.tables import method_name as display_name

CEILING_SHARE = 0.5
V2X_STEMS = (
    ("table_v2x", "V2X, camera"),
    ("table_v2x_boxes", "V2X, boxes only"),
    ("table_v2x_lidar", "V2X, LiDAR boxes"),
)


def _read(path: Path) -> pd.DataFrame | None:
    if not path.is_file():
        return None
    return pd.read_csv(path, keep_default_na=False, na_values=[""])


def _pct(value: object) -> str:
    try:
        number = float(value)
    except (TypeError, ValueError):
        return "–"
    return "–" if number != number else f"{100 * number:.1f}"


def _signed(value: object) -> str:
    text = _pct(value)
    return text if text == "–" or text.startswith("-") else f"+{text}"


def _interval(low: object, high: object, signed: bool = True) -> str:
    show = _signed if signed else _pct
    return f"[{show(low)}, {show(high)}]"


def headline(results: Path) -> dict | None:
    """The headline choice (``table1_levels.json``), None before an equal-cue run wrote it."""
    path = results / "table1_levels.json"
    return json.loads(path.read_text()) if path.is_file() else None


def _name(matcher: object) -> str:
    return cell(display_name(str(matcher)))


def table1(results: Path, claims: pd.DataFrame | None = None) -> list[str]:
    """The README's compact table on the headline level (one row per dataset not at the
    ceiling there), then a line per dataset left out."""
    choice = headline(results)
    summary = _read(results / "table1_levels_summary.csv")
    rows = _read(results / "table1_levels.csv")
    if choice is None or summary is None or rows is None:
        return []
    level = choice["level"]
    at = summary[summary["level"] == level]
    out = [
        "| Dataset | pairs on the level | top method, F1 [95 % CI] | pairs it scores perfectly "
        "| top − runner-up [95 % CI] | Maximin F1 | Maximin − best rival [95 % CI] (MDD; "
        "clusters for MDD 5) |",
        "|:---|---:|:---|---:|:---|---:|:---|",
    ]
    left_out = []
    for _, r in at.iterrows():
        dataset = cell(str(r["dataset"]))
        if float(r["top_perfect_share"]) > CEILING_SHARE:
            left_out.append(
                f"{dataset} ({_name(r['top'])} perfect on {_pct(r['top_perfect_share'])} % of "
                f"{int(r['pairs'])} pairs)"
            )
            continue
        mine = rows[(rows["dataset"] == r["dataset"]) & (rows["level"] == level)]
        top = mine[mine["matcher"] == r["top"]].iloc[0]
        maximin = mine[mine["matcher"] == "maximin"]
        maximin_f1 = _pct(maximin.iloc[0]["f1"]) if len(maximin) else "–"
        separated = "separated" if bool(r.get("separated")) else "not separated"
        runner = (
            f"{_name(r['runner_up'])}: {_signed(r['top_minus_runner_up'])} "
            f"{_interval(r['top_low'], r['top_high'])}, {separated}"
            if isinstance(r.get("runner_up"), str)
            else "–"
        )
        rival = "–"
        if isinstance(r.get("rival"), str):
            needed = r.get("clusters_for_mdd_5")
            needed = "–" if needed != needed or needed is None else f"{int(needed)}"
            rival = (
                f"{_name(r['rival'])}: {_signed(r['maximin_minus_rival'])} "
                f"{_interval(r['rival_low'], r['rival_high'])} (MDD {_pct(r['mdd'])}; {needed})"
            )
        out.append(
            f"| {dataset} | {int(r['pairs'])} | {_name(r['top'])} {_pct(top['f1'])} "
            f"{_interval(top['low'], top['high'], signed=False)} | "
            f"{_pct(r['top_perfect_share'])} % | {runner} | {maximin_f1} | {rival} |"
        )
    if len(out) == 2:
        out = []
    note = f"Level **{level}**, chosen on validation ({choice['criterion']})"
    if left_out:
        note += (
            "; at the ceiling on it, so left out of the headline (rows in the report): "
            + ", ".join(left_out)
        )
    return [*out, *([""] if out else []), note + "."]


def _level_markdown(rows: pd.DataFrame, summary: pd.DataFrame, by: list[str]) -> list[str]:
    """One Markdown table: a row per group × level, a column per matcher (F1 [CI])."""
    matchers = list(dict.fromkeys(rows["matcher"]))
    rank = {level: i for i, level in enumerate(LEVELS)}
    rows = rows.sort_values(
        [*by, "level"], key=lambda c: c.map(rank) if c.name == "level" else c, kind="stable"
    )
    head = [*by, "level", "pairs", *(display_name(m) for m in matchers), "top perfect"]
    out = [
        "| " + " | ".join(cell(h) for h in head) + " |",
        "|" + "|".join(":---" for _ in head) + "|",
    ]
    for key, group in rows.groupby([*by, "level"], sort=False):
        key = key if isinstance(key, tuple) else (key,)
        by_matcher = {r["matcher"]: r for _, r in group.iterrows()}
        match = summary
        for column, value in zip([*by, "level"], key, strict=True):
            match = match[match[column] == value]
        perfect = _pct(match.iloc[0]["top_perfect_share"]) + " %" if len(match) else "–"
        cells = [cell(str(k)) for k in key] + [str(int(group["pairs"].iloc[0]))]
        for m in matchers:
            r = by_matcher.get(m)
            cells.append(
                "–" if r is None else f"{_pct(r['f1'])} {_interval(r['low'], r['high'], False)}"
            )
        out.append("| " + " | ".join([*cells, perfect]) + " |")
    return out


def report_part(results: Path, rel: str) -> list[str]:
    """The report's section: the level rule, Table I and each V2X table per level."""
    choice = headline(results)
    rows = _read(results / "table1_levels.csv")
    summary = _read(results / "table1_levels_summary.csv")
    if choice is None or rows is None or summary is None:
        return []
    counts = "; ".join(
        f"{cell(d)}: " + ", ".join(f"{lv} {n}" for lv, n in c.items())
        for d, c in choice.get("level_counts", {}).items()
    )
    spread = ", ".join(f"{lv} {_pct(v)}" for lv, v in choice["spread"].items())
    out = [
        "### Difficulty levels",
        "",
        "Every frame pair carries difficulty factors computed from its truth (non-covisible "
        "share, covisible objects, the observers' yaw change and baseline, the covisible objects' "
        "position disagreement, look-alikes); a pair's level is the tercile of a rank composite "
        "of them fitted on the *validation* split ([docs/evaluation.md](../docs/evaluation.md#"
        f"difficulty-levels)). Test pairs per level: {counts}. The headline level is "
        f"**{choice['level']}**, chosen on validation ({choice['criterion']}: {spread}). F1 in "
        "percent with 95 % episode intervals; *top perfect*: the share of the level's pairs on "
        f"which its top method scores F1 = 1 (all rows: [{rel}/table1_levels.csv]"
        f"({rel}/table1_levels.csv), [{rel}/table1_levels_summary.csv]"
        f"({rel}/table1_levels_summary.csv)).",
        "",
        *_level_markdown(rows, summary, ["dataset"]),
        "",
    ]
    for stem, title in V2X_STEMS:
        v_rows = _read(results / f"{stem}_levels.csv")
        v_summary = _read(results / f"{stem}_levels_summary.csv")
        if v_rows is None or v_summary is None or v_rows.empty:
            continue
        out += [f"**{title}** by level ([{rel}/{stem}_levels.csv]({rel}/{stem}_levels.csv)):", ""]
        out += _level_markdown(v_rows, v_summary, ["preset"]) + [""]
    return out
