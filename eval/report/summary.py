"""The headline results as one compact Markdown table per study, for the README's first page
(the full tables are in the report, ``results/README.md``). Every function reads the study's CSV
from a results directory and returns the table's lines, or ``[]`` when the file is missing or
lacks what the table needs: a results folder written by another version of the code shortens
the page, it never stops it being written.

Every builder takes the folder and its claims (``claims.csv``, :mod:`eval.protocol.claims`):
a comparative cell (a rank, a rival, a leader) is a claim's statement, chosen on validation; the
V2X, multi-agent and transfer tables show fixed columns (matchers, fusions, models), and the
report's own verdict lines stay in the report.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from eval.core.abstention import NO_NUMBER, cannot_run
from eval.report.markdown_cell import cell as label_cell
from eval.report.markdown_cell import row
from eval.report.tables import PAPER_NAMES, dataset_order, method_name

# The V2X matchers shown (those present in the table): the paper's method and the strongest
# families without and with the localisation prior.
V2X_MATCHERS = ("maximin", "mos", "freealign", "maximin_pose", "pose_refine")
NOISE_MATCHERS = ("maximin", "mos", "rrwhm")


def read_csv(path: Path) -> pd.DataFrame | None:
    """The CSV at ``path`` (empty strings as missing), or None when it is absent or unreadable."""
    if not path.is_file():
        return None
    from eval.core.spreadsheet_safe import restore

    try:
        return restore(pd.read_csv(path, keep_default_na=False, na_values=[""]))
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError):
        return None


def _has(table: pd.DataFrame | None, *columns: str) -> bool:
    return table is not None and len(table) > 0 and set(columns) <= set(table.columns)


def pct(value: object, digits: int = 1) -> str:
    """A fraction in percent; "–" when missing."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        return "–"
    return "–" if pd.isna(number) else f"{100 * number:.{digits}f}"


def _ordinal(rank: int) -> str:
    return f"{rank}{'th' if 10 <= rank % 100 <= 20 else {1: 'st', 2: 'nd', 3: 'rd'}.get(rank % 10, 'th')}"


def _row(cells: list[str]) -> str:
    return row(cells)


def _claims_of(claims: pd.DataFrame | None, study: str) -> pd.DataFrame:
    if claims is None or not len(claims):
        return pd.DataFrame(columns=["study", "subject", "comparison", "metric", "statement"])
    return claims[claims["study"] == study]


def table1(results: Path, claims: pd.DataFrame | None = None) -> list[str]:
    """Per dataset: maximin's F1 and its rank among the paper's methods with the rank's episode
    interval (the paper's own rank of it by accuracy beside), the other paper method of highest
    *validation* F1 and maximin − it on test with its interval, and the matcher of highest
    validation F1 of all — each comparative cell a claim's statement (``claims``, study
    "table1") — under the equal-cue protocol (``table1_equal_cues.csv``) when the folder has it,
    else as published (``table1.csv``)."""
    results = Path(results)
    suffix = "_equal_cues" if (results / "table1_equal_cues.csv").is_file() else ""
    protocol = "equal cues" if suffix else "as published"
    table = read_csv(results / f"table1{suffix}.csv")
    if not _has(table, "dataset", "matcher", "f1_mean"):
        return []
    said = _claims_of(claims, "table1")
    lines = [
        "| Dataset | Maximin F1 | its rank of the paper's 8 [95 % CI] (paper's) | other paper "
        "method of highest validation F1 | Maximin − it, F1 [95 % CI] (MDD: smallest detectable "
        "at 80 % power) | highest validation F1 "
        "of all matchers |",
        "|:---|---:|---:|:---|---:|:---|",
    ]
    for dataset in sorted(table["dataset"].unique(), key=dataset_order):
        rows = table[table["dataset"] == dataset].set_index("matcher")
        paper = rows[rows.index.isin(list(PAPER_NAMES))]
        if "maximin" not in paper.index:
            continue
        mine = said[said["subject"] == f"maximin on {dataset} ({protocol})"]
        rank = mine[mine["metric"] == "rank_f1"]
        cell = str(rank["statement"].iloc[0]) if len(rank) else "–"
        if "paper_accuracy_mean" in paper.columns and paper["paper_accuracy_mean"].notna().any():
            by_paper = paper["paper_accuracy_mean"].dropna().sort_values(ascending=False)
            if "maximin" in by_paper.index:
                cell += f" ({list(by_paper.index).index('maximin') + 1})"
        rival = mine[mine["metric"] == "f1"]
        rival_cell, interval = "–", "–"
        if len(rival):
            name = str(rival["comparison"].iloc[0])
            rival_cell = f"{method_name(name)} {pct(rows.loc[name, 'f1_mean'])}"
            interval = str(rival["statement"].iloc[0]) + _mdd(results, suffix, dataset, name)
        best = said[said["subject"] == f"{dataset} ({protocol})"]
        lines.append(
            _row(
                [
                    label_cell(dataset),
                    pct(paper.loc["maximin", "f1_mean"]),
                    cell,
                    rival_cell,
                    interval,
                    str(best["statement"].iloc[0]) if len(best) else "–",
                ]
            )
        )
    return lines if len(lines) > 2 else []


def _mdd(results: Path, suffix: str, dataset: str, rival: str) -> str:
    """' (MDD 6.6)': the minimum detectable ΔF1 of maximin − ``rival`` on ``dataset`` (pp, from
    ``paired_differences{suffix}.csv``); empty where the file has none (older files)."""
    paired = read_csv(results / f"paired_differences{suffix}.csv")
    if paired is None or "mdd" not in paired.columns:
        return ""
    row = paired[(paired["dataset"] == dataset) & (paired["matcher_b"] == rival) & (paired["metric"] == "f1")]  # fmt: skip
    mdd = float(row["mdd"].iloc[0]) if len(row) else float("nan")
    return f" (MDD {100 * mdd:.1f})" if np.isfinite(mdd) else ""


def noise(results: Path, claims: pd.DataFrame | None = None) -> list[str]:
    """Per swept dataset: F1 of maximin and its two rivals at the lowest and the highest noise
    rate, and the F1 leader at each end — a labelled point value (the "fig4" claims)."""
    runs = read_csv(Path(results) / "noise_runs.csv")
    if not _has(runs, "dataset", "matcher", "noise_rate", "f1"):
        return []
    rates = sorted(runs["noise_rate"].unique())
    if len(rates) < 2:
        return []
    lo, hi = rates[0], rates[-1]
    shown = [m for m in NOISE_MATCHERS if m in set(runs["matcher"])]
    said = _claims_of(claims, "fig4")
    lines = [
        "| Dataset | "
        + " | ".join(f"{method_name(m)} F1, {lo:g} → {hi:g}" for m in shown)
        + f" | F1 leader at {lo:g} on test (point value) | at {hi:g} on test (point value) |",
        "|:---|" + "---:|" * len(shown) + ":---|:---|",
    ]
    for dataset, rows in runs.groupby("dataset", sort=False):
        means = rows[rows["matcher"] != "none"].groupby(["noise_rate", "matcher"])["f1"].mean()
        cells = [f"{pct(means.get((lo, m)))} → {pct(means.get((hi, m)))}" for m in shown]
        mine = said[said["subject"].str.endswith(f" on {dataset}")]
        leaders = []
        for rate in (lo, hi):
            hit = mine[mine["comparison"] == f"F1 leader at noise rate {rate:g}"]
            leaders.append(
                f"{method_name(str(hit['subject'].iloc[0]).rsplit(' on ', 1)[0])} "
                f"{pct(hit['value'].iloc[0])}"
                if len(hit)
                else "–"
            )
        lines.append(_row([label_cell(dataset), *cells, *leaders]))
    return lines


def external(results: Path, claims: pd.DataFrame | None = None, top: int = 2) -> list[str]:
    """The external DMGM pairs: the strongest matchers without and with the prior (pooled F1,
    as the full table sorts them), maximin's rows and the published DMGM figure."""
    table = read_csv(Path(results) / "table_external.csv")
    if not _has(table, "matcher", "method", "uses_prior", "f1_pooled_mean"):
        return []
    table = table.assign(prior=table["uses_prior"].astype(str).str.lower() == "true")
    source = table["source"].astype(str) if "source" in table.columns else None
    ours = table if source is None else table[source == "ours"]
    ours = ours[ours["matcher"] != "none"]
    picked = []
    for prior in (False, True):
        rows = ours[ours["prior"] == prior].sort_values("f1_pooled_mean", ascending=False)
        names = list(rows["matcher"][:top])
        names += [m for m in ("maximin", "maximin_pose") if m in set(rows["matcher"])]
        picked += [rows[rows["matcher"] == m].iloc[0] for m in dict.fromkeys(names)]
    lines = ["| Method | prior | pooled F1 | F1 per pair |", "|:---|:---|---:|---:|"]
    lines += [
        _row(
            [
                method_name(str(r["matcher"])),
                "yes" if r["prior"] else "no",
                pct(r["f1_pooled_mean"]),
                pct(r.get("f1_mean")),
            ]
        )
        for r in picked
    ]
    if source is not None:
        for _, r in table[source.str.startswith("published")].iterrows():
            note = str(r["source"]).removeprefix("published").strip(" ()")
            name = f"{r['method']}" + (f", {note}" if note else "")
            lines.append(_row([name, "yes", pct(r["f1_pooled_mean"]), "–"]))
    return lines if len(lines) > 2 else []


def v2x(results: Path, claims: pd.DataFrame | None = None) -> list[str]:
    """CAD-V2X: F1 per localisation preset of a fixed set of matchers."""
    table = read_csv(Path(results) / "table_v2x.csv")
    if not _has(table, "matcher", "preset", "f1_mean"):
        return []
    shown = [m for m in V2X_MATCHERS if m in set(table["matcher"])]
    if not shown:
        return []
    f1 = table.drop_duplicates(["preset", "matcher"]).set_index(["preset", "matcher"])["f1_mean"]
    boxes = _boxes_best(results)
    extra = ["boxes only: chosen on validation"] if boxes else []
    lines = [
        "| Preset | " + " | ".join([*(method_name(m) for m in shown), *extra]) + " |",
        "|:---|" + "---:|" * (len(shown) + len(extra)),
    ]
    for preset in dict.fromkeys(table["preset"]):
        cells = [
            NO_NUMBER if cannot_run(m, str(preset)) else pct(f1.get((preset, m))) for m in shown
        ]
        if boxes:
            cells.append(boxes.get(preset, "–"))
        lines.append(_row([str(preset), *cells]))
    return lines


def _boxes_best(results: Path) -> dict[str, str]:
    """Per preset of the box-only V2X table (``table_v2x_boxes.csv``): "F1 (matcher)" of the
    matcher with the highest validation F1 (``v2x_boxes/validation_f1.csv``); {} without them."""
    table = read_csv(Path(results) / "table_v2x_boxes.csv")
    validation = read_csv(Path(results) / "v2x_boxes" / "validation_f1.csv")
    if not (_has(table, "matcher", "preset", "f1_mean") and _has(validation, "preset", "val_f1")):
        return {}
    out = {}
    for preset, rows in table.groupby("preset", sort=False):
        rows = rows[~rows["matcher"].isin(("oracle", "prior"))]
        rows = rows[[not cannot_run(m, str(preset)) for m in rows["matcher"]]]
        val = validation[validation["preset"] == preset].set_index("matcher")["val_f1"]
        if rows.empty or val.empty:
            continue
        best = max(rows.itertuples(index=False), key=lambda r: val.get(r.matcher, float("-inf")))
        out[preset] = f"{pct(best.f1_mean)} ({method_name(best.matcher)})"
    return out


TEMPORAL_METHODS = ("windowed:consistency", "trajectory_pose", "temporal_pose")


def temporal(results: Path, claims: pd.DataFrame | None = None) -> list[str]:
    """CAD-V2X sequences: pooled F1 at W = 1 and W = 10 of a fixed pair of methods, per preset
    (:data:`~eval.core.abstention.NO_NUMBER` where a method cannot run)."""
    table = read_csv(Path(results) / "table_temporal.csv")
    if not _has(table, "method", "window", "preset", "f1_pooled"):
        return []
    shown = [m for m in TEMPORAL_METHODS if m in set(table["method"])]
    if not shown:
        return []
    f1 = table.set_index(["preset", "method", "window"])["f1_pooled"]
    header = [f"{m}, W = {w}" for m in shown for w in (1, 10)]
    lines = ["| Preset | " + " | ".join(header) + " |", "|:---|" + "---:|" * len(header)]
    for preset in dict.fromkeys(table["preset"]):
        cells = [
            NO_NUMBER if cannot_run(m, str(preset), temporal=True) else pct(f1.get((preset, m, w)))
            for m in shown
            for w in (1, 10)
        ]
        lines.append(_row([str(preset), *cells]))
    return lines


def multiagent(
    results: Path, claims: pd.DataFrame | None = None, preset: str = "gnss-urban"
) -> list[str]:
    """CAD-multi at the largest number of agents (under ``preset`` when it was run): pooled
    pairwise F1 of every two-view matcher under every fusion."""
    table = read_csv(Path(results) / "table_multiagent.csv")
    if not _has(table, "n_agents", "matcher", "fusion", "preset", "f1_pooled"):
        return []
    high = table["n_agents"].max()
    rows = table[table["n_agents"] == high]
    if preset in set(rows["preset"]):
        rows = rows[rows["preset"] == preset]
    else:
        rows = rows[rows["preset"] == rows["preset"].iloc[0]]
    fusions = list(dict.fromkeys(sorted(rows["fusion"], key=lambda f: (f != "independent", f))))
    f1 = rows.drop_duplicates(["matcher", "fusion"]).set_index(["matcher", "fusion"])["f1_pooled"]
    lines = [
        f"| Matcher (N = {high}, {rows['preset'].iloc[0]}) | " + " | ".join(fusions) + " |",
        "|:---|" + "---:|" * len(fusions),
    ]
    for matcher in dict.fromkeys(rows["matcher"]):
        lines.append(
            _row([method_name(str(matcher)), *(pct(f1.get((matcher, f))) for f in fusions)])
        )
    return lines


def transfer(results: Path, claims: pd.DataFrame | None = None) -> list[str]:
    """Learned matchers on the external test set (DMGM's when present): pooled F1 per training
    set and matcher, the hand-crafted reference the study compares each matcher with below."""
    table = read_csv(Path(results) / "table_transfer.csv")
    if not _has(table, "train", "test", "matcher", "f1_pooled"):
        return []
    tests = list(dict.fromkeys(table["test"]))
    test = next((t for t in tests if str(t).startswith("DMGM")), tests[0])
    rows = table[table["test"] == test]
    matchers = list(dict.fromkeys(rows["matcher"]))
    f1 = rows.drop_duplicates(["train", "matcher"]).set_index(["train", "matcher"])["f1_pooled"]
    lines = [
        f"| Trained on (tested on {label_cell(test)}) | "
        + " | ".join(label_cell(m) for m in matchers)
        + " |",
        "|:---|" + "---:|" * len(matchers),
    ]
    for train in dict.fromkeys(rows["train"]):
        lines.append(_row([label_cell(train), *(pct(f1.get((train, m))) for m in matchers)]))
    if _has(rows, "handcrafted", "handcrafted_f1_pooled"):
        cells = []
        for m in matchers:
            ref = rows[(rows["matcher"] == m) & rows["handcrafted"].notna()]
            cells.append(
                f"{ref['handcrafted'].iloc[0]} {pct(ref['handcrafted_f1_pooled'].iloc[0])}"
                if len(ref)
                else "–"
            )
        lines.append(_row(["*hand-crafted reference*", *cells]))
    return lines
