"""Writes the results report and the README's results section from a results directory, so that
every number either shows comes from a run of ``make reproduce`` (called at its end). Run alone,
``python -m eval.readme_results`` (``make report``) rewrites both from the files already there,
recomputing nothing.

- The report: ``<results>/README.md`` and the same page as ``<results>/index.html`` (figures,
  sortable tables; :mod:`eval.report.site`), then every table and figure of the folder not
  shown in full above them.
- The README's section, between ``<!-- results:begin -->`` and ``<!-- results:end -->``: one
  compact table per study (:mod:`eval.report.summary`) with links into the report.

The report holds the run's stage times, the regime cards beside Table I (tuned, calibrated), the paired differences with their
intervals, the dataset spread, the paper-protocol table, the regime sweep, Fig. 4, the qualitative
figure, the ranking agreement with external data, the external benchmark (DMGM CAD pairs), the
localisation sweep and "Where we agree with the paper, and where not" — statements computed from those tables
(ranks, differences and whether their intervals exclude 0, crossovers), never typed in by hand.
Every part is optional: a results directory without a file leaves its part out, and a part whose
files this code cannot read (another version's format) is replaced by a line saying so and the
study's table as the run wrote it — the report is always written.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np
import pandas as pd

from eval.core.abstention import NO_NUMBER
from eval.core.result_files import write_text
from eval.report import summary
from eval.report.run_record import cold_record
from eval.report.site import headings, write_site
from eval.report.tables import PAPER_COLUMN, PAPER_NAMES, dataset_order, method_name, params_text
from eval.studies.agreement import readme_part as agreement_readme
from eval.studies.external import readme_part as external_readme
from eval.studies.multiagent import readme_part as multiagent_readme
from eval.studies.prior_defaults import readme_part as prior_sensitivity_readme
from eval.studies.temporal import readme_part as temporal_readme
from eval.studies.transfer import readme_part as transfer_readme
from eval.studies.v2x_boxes import readme_part as v2x_boxes_readme
from eval.studies.v2x_lidar import readme_part as v2x_lidar_readme
from eval.studies.v2x_table import readme_part as v2x_readme

BEGIN, END = "<!-- results:begin -->", "<!-- results:end -->"
ROOT = Path(__file__).resolve().parents[1]
REPORT, SITE = "README.md", "index.html"
SELF_LINK = f"The same page with sortable tables: [{SITE}](./{SITE})."
SITE_SELF_LINK = f"The same report as Markdown: [{REPORT}](./{REPORT})."
log = logging.getLogger(__name__)
RIVALS = ("mos", "rrwhm")


def _csv(path: Path) -> pd.DataFrame | None:
    return pd.read_csv(path, keep_default_na=False, na_values=[""]) if path.is_file() else None


def _n(count: int, noun: str) -> str:
    """'1 run', '2 runs'."""
    return f"{count} {noun}" + ("" if count == 1 else "s")


def _pct(value: float, digits: int = 1) -> str:
    """A fraction (as every results CSV holds them) printed in percent."""
    return "–" if pd.isna(value) else f"{100 * value:.{digits}f}"


def _interval(row) -> str:
    """A paired difference (fractions) in percentage points: +d [lo, hi]."""
    return f"{100 * row['diff']:+.1f} [{100 * row['ci_low']:+.1f}, {100 * row['ci_high']:+.1f}]"


def _header(record: dict) -> str:
    wall = record.get("wall_s", {})
    git = record.get("git", {})
    runs = record.get("runs", {}).values()
    computed = sum(r.get("computed", 0) for r in runs)
    cached = sum(r.get("cached", 0) for r in runs)
    cold = is_cold(record)
    return (
        f"Produced by `{record.get('command', 'make reproduce')}` on {record.get('created', '?')}"
        f" at commit `{str(git.get('commit', '?'))[:10]}`"
        + (" (with uncommitted changes)" if git.get("dirty") else "")
        + f"; {'a cold run (no dataset, model or cached run at its start)' if cold else 'a warm run (datasets, models or runs cached at its start: its times are not cold times)'}"
        + f"; wall time {wall.get('total', float('nan')):.0f} s ({computed} matcher runs computed, "
        f"{cached} taken from the result cache)."
    )


def is_cold(record: dict) -> bool:
    """Whether the run record's run started cold (:func:`eval.reproduce.cold_start`)."""
    return bool(record.get("cold_start", {}).get("cold"))


def stage_table(record: dict) -> list[str]:
    """A run's stage times as a Markdown table (seconds, runs computed and cached): the last cold
    run's (``cold_run.json``) when one is given, else this run's."""
    wall = record.get("wall_s", {})
    runs = record.get("runs", {})
    commit = str(record.get("git", {}).get("commit", "?"))[:10]
    where = "`cold_run.json`" if is_cold(record) else "`run_record.json`"
    lines = [
        f"Stage times of the {'last cold' if is_cold(record) else 'this warm'} run (commit "
        f"`{commit}`, {record.get('created', '?')}; seconds; {where}):",
        "",
        "| Stage | s | runs computed | runs cached |",
        "|:---|---:|---:|---:|",
    ]
    for name, seconds in wall.items():
        if name == "total":
            continue
        r = runs.get(name, {})
        lines.append(
            f"| {name.replace('_', ' ')} | {seconds:.0f} | {r.get('computed', '')} "
            f"| {r.get('cached', '')} |"
        )
    lines.append(f"| **total** | **{wall.get('total', float('nan')):.0f}** | | |")
    return lines + [""]


def paired_markdown(table: pd.DataFrame) -> str:
    """One row per (dataset, rival): maximin − rival in F1, balanced accuracy and recall (pp),
    and the minimum detectable ΔF1 (95 % confidence, 80 % power; "–" in files without it)."""
    lines = [
        "| Dataset | maximin − | ΔF1 [95 % CI] | ΔF1 MDD | Δ balanced acc. [95 % CI] "
        "| Δ recall [95 % CI] | episodes |",
        "|:---|:---|---:|---:|---:|---:|---:|",
    ]
    datasets = sorted(table["dataset"].unique(), key=dataset_order)
    for dataset in datasets:
        rows = table[table["dataset"] == dataset]
        for rival, group in rows.groupby("matcher_b", sort=False):
            by_metric = {r["metric"]: r for _, r in group.iterrows()}
            cells = [
                _interval(by_metric[m]) if m in by_metric else "–"
                for m in ("f1", "balanced_accuracy", "recall")
            ]
            f1 = by_metric.get("f1")
            mdd = float(f1["mdd"]) if f1 is not None and "mdd" in f1 else float("nan")
            cells.insert(1, f"{100 * mdd:.1f}" if np.isfinite(mdd) else "–")
            episodes = int(group["episodes"].iloc[0])
            lines.append(
                f"| {dataset} | {method_name(rival)} | " + " | ".join(cells) + f" | {episodes} |"
            )
    return "\n".join(lines)


def spread_text(table: pd.DataFrame) -> str:
    """'Maximin 31–36, MOS …' F1 ranges (percent) over the generated datasets."""
    grouped = table.groupby("matcher", sort=False)["f1"]
    parts = [
        f"{method_name(m)} {100 * lo:.1f}–{100 * hi:.1f}"
        for m, lo, hi in zip(grouped.min().index, grouped.min(), grouped.max(), strict=True)
    ]
    return ", ".join(parts)


def _f1_ranks(rows: pd.DataFrame) -> list[str]:
    return list(rows.sort_values("f1_mean", ascending=False)["matcher"])


def _agreement(table: pd.DataFrame, paired: pd.DataFrame | None, regime) -> list[str]:
    """Bullets: per dataset, where maximin ranks and whether its lead (or lag) is resolved."""
    bullets = []
    for dataset in sorted(table["dataset"].unique(), key=dataset_order):
        rows = table[(table["dataset"] == dataset) & table["matcher"].isin(PAPER_NAMES)]
        if "maximin" not in set(rows["matcher"]):
            continue
        ranks = _f1_ranks(rows)
        rank = ranks.index("maximin") + 1
        best = ranks[0] if ranks[0] != "maximin" else (ranks[1] if len(ranks) > 1 else None)
        where = _regime_phrase(regime, dataset)
        text = (
            f"**{dataset}**{where}: maximin ranks {rank} of {len(ranks)} of the paper's methods "
            f"by F1 ({_pct(rows.set_index('matcher').loc['maximin', 'f1_mean'])}"
        )
        if best is not None:
            text += f"; {method_name(best)} {_pct(rows.set_index('matcher').loc[best, 'f1_mean'])}"
        text += ")"
        if paired is not None and best is not None:
            hit = paired[
                (paired["dataset"] == dataset)
                & (paired["matcher_b"] == best)
                & (paired["metric"] == "f1")
            ]
            if len(hit):
                r = hit.iloc[0]
                resolved = r["ci_low"] > 0 or r["ci_high"] < 0
                text += f"; maximin − {method_name(best)} = {_interval(r)} pp F1, " + (
                    "an interval that excludes 0" if resolved else "an interval that includes 0"
                )
        paper = PAPER_COLUMN.get(dataset, dataset)
        verdict = (
            "as in the paper (maximin first)"
            if rank == 1
            else f"unlike the paper, where maximin is first on {paper}"
        )
        bullets.append(text + f" — {verdict}.")
    return bullets


def _regime_phrase(regime: pd.DataFrame | None, dataset: str) -> str:
    if regime is None or dataset not in set(regime["dataset"]):
        return ""
    r = regime.set_index("dataset").loc[dataset]
    parts = []
    if not pd.isna(r.get("noncovisible_share")):
        parts.append(f"{100 * r['noncovisible_share']:.0f} % non-covisible")
    if not pd.isna(r.get("appearance_auc")):
        parts.append(f"appearance AUC {r['appearance_auc']:.2f}")
    if not pd.isna(r.get("position_error_median_m")):
        parts.append(f"median position error {r['position_error_median_m']:.2f} m")
    return f" ({', '.join(parts)})" if parts else ""


def _baselines(table: pd.DataFrame) -> list[str]:
    """Bullet: what abstaining earns under each accuracy."""
    rows = table[table["matcher"] == "none"]
    if rows.empty:
        return []
    parts = []
    for _, r in rows.sort_values("dataset", key=lambda s: s.map(dataset_order)).iterrows():
        others = table[(table["dataset"] == r["dataset"]) & table["matcher"].isin(PAPER_NAMES)]
        beaten = int((others["accuracy_mean"] < r["accuracy_mean"]).sum())
        below = int((others["balanced_accuracy_mean"] < 0.5).sum())
        parts.append(
            f"{r['dataset']}: accuracy {_pct(r['accuracy_mean'])} (above {beaten} of "
            f"{len(others)} methods), balanced accuracy {_pct(r['balanced_accuracy_mean'])}, "
            f"{_n(below, 'method')} below 50"
        )
    return [
        "**Declaring nothing** (`none`) scores the non-covisible share as accuracy but exactly 50 "
        "balanced accuracy: " + "; ".join(parts) + "."
    ]


def _tuning(tuned: pd.DataFrame, untuned: pd.DataFrame | None) -> list[str]:
    """Bullet: the largest F1 changes tuning brought."""
    if untuned is None:
        return []
    merged = tuned.merge(untuned, on=["dataset", "matcher"], suffixes=("", "_untuned"))
    merged["gain"] = merged["f1_mean"] - merged["f1_mean_untuned"]
    top = merged[merged["gain"].abs() >= 0.01].sort_values("gain", ascending=False).head(4)
    if top.empty:
        return ["**Tuning** on validation changed no F1 by a point or more."]
    parts = [
        f"{method_name(r['matcher'])} on {r['dataset']} {_pct(r['f1_mean_untuned'])} → "
        f"{_pct(r['f1_mean'])} ({params_text(r.get('params'))})"
        for _, r in top.iterrows()
    ]
    return ["**Tuning** on validation moved F1 most for " + "; ".join(parts) + "."]


def _paper_protocol(paper_table: pd.DataFrame | None) -> list[str]:
    """Bullet: under the paper's protocol, does the accuracy ranking follow the paper's?"""
    if paper_table is None or "paper_accuracy_mean" not in paper_table.columns:
        return []
    parts = []
    for dataset in sorted(paper_table["dataset"].unique(), key=dataset_order):
        rows = paper_table[
            (paper_table["dataset"] == dataset) & paper_table["paper_accuracy_mean"].notna()
        ]
        if len(rows) < 3:
            continue
        ours = rows["accuracy_mean"].rank().to_numpy()
        theirs = rows["paper_accuracy_mean"].rank().to_numpy()
        rho = float(np.corrcoef(ours, theirs)[0, 1])
        order = rows.sort_values("accuracy_mean", ascending=False)["method"].tolist()
        parts.append(
            f"{dataset}: Spearman ρ = {rho:.2f} with the paper's accuracy ranking; ours by "
            f"accuracy: {', '.join(order[:3])} first"
        )
    if not parts:
        return []
    return [
        "**The paper's protocol** (image-space pairwise terms, full assignment, no τ): "
        + "; ".join(parts)
        + "."
    ]


def _crossovers(crossovers: pd.DataFrame | None, sweep: pd.DataFrame | None) -> list[str]:
    """Bullet: where (in non-covisible share) maximin's advantage appears or vanishes — only the
    crossovers whose interval excludes "no crossing" (``significant``), and plainly none else."""
    if crossovers is None or sweep is None:
        return []
    parts = []
    for (dataset, rival), group in crossovers[crossovers["metric"] == "f1"].groupby(
        ["dataset", "matcher_b"], sort=False
    ):
        rows = sweep[sweep["dataset"] == dataset]
        lo, hi = 100 * rows["share"].min(), 100 * rows["share"].max()
        name = method_name(rival)
        significant = group[group["significant"].astype(str).str.lower() == "true"]
        if significant.empty:
            a = rows[rows["matcher"] == "maximin"].set_index("keep")["f1_mean"]
            b = rows[rows["matcher"] == rival].set_index("keep")["f1_mean"]
            ahead = bool((a - b).mean() > 0)
            crossed = group["crossing_share"].notna().any()
            parts.append(
                f"{dataset}: no crossover with {name} that its interval supports"
                f"{' (the mean curves cross, within their noise)' if crossed else ''}; maximin "
                f"{'ahead' if ahead else 'behind'} on average over shares {lo:.0f}–{hi:.0f} %"
            )
            continue
        for _, r in significant.iterrows():
            at, ci = 100 * r["crossing_share"], (100 * r["share_ci_low"], 100 * r["share_ci_high"])
            where = f"{at:.0f} % non-covisible (95 % interval {ci[0]:.0f}–{ci[1]:.0f} %)"
            if r["direction"] == "a_gains":
                parts.append(f"{dataset}: maximin overtakes {name} above {where}")
            else:
                parts.append(f"{dataset}: maximin leads {name} below {where} and trails above")
    if not parts:
        return []
    return [
        "**Regime sweep** (F1 against the non-covisible share; a crossover is stated only where "
        'its interval, episodes and thinning draws resampled, excludes "no crossing"): '
        + "; ".join(parts)
        + "."
    ]


def _noise(noise: pd.DataFrame | None) -> list[str]:
    """Bullets, one per swept dataset: F1 at the lowest and highest noise rate for maximin and
    its rivals, and the rates at which the F1 leader changes (how the ranking hangs on the
    geometry's precision)."""
    if noise is None or "f1" not in noise.columns:
        return []
    bullets = []
    for dataset, rows in noise.groupby("dataset", sort=False):
        means = rows.groupby(["matcher", "noise_rate"])["f1"].mean()
        rates = sorted(rows["noise_rate"].unique())
        if len(rates) < 2:
            continue
        parts = [
            f"{method_name(m)} {_pct(means.loc[(m, rates[0])])} → {_pct(means.loc[(m, rates[-1])])}"
            for m in ("maximin", *RIVALS)
            if m in means.index.get_level_values(0)
        ]
        table = means.unstack("noise_rate")[rates]
        table = table.drop(index=[m for m in ("none",) if m in table.index])
        leaders = [str(table[r].idxmax()) for r in rates]
        changes = [f"{method_name(leaders[0])} at {rates[0]:g}"] + [
            f"{method_name(leaders[k])} from {rates[k]:g}"
            for k in range(1, len(rates))
            if leaders[k] != leaders[k - 1]
        ]
        lead = (
            f"the F1 leader stays {method_name(leaders[0])} at every rate"
            if len(changes) == 1
            else "the F1 leader changes with the noise: " + ", ".join(changes)
        )
        bullets.append(
            f"**Noise, {dataset}** (Fig. 4, F1 from rate {rates[0]:g} to {rates[-1]:g}): "
            + ", ".join(parts)
            + f"; {lead}."
        )
    return bullets


def agreement_bullets(results: Path) -> list[str]:
    """'Where we agree with the paper, and where not', from the tables in `results`."""
    table = _csv(results / "table1.csv")
    if table is None:
        return []
    paired = _csv(results / "paired_differences.csv")
    regime = _csv(results / "regime.csv")
    bullets = _agreement(table, paired, regime) + _baselines(table)
    bullets += _tuning(table, _csv(results / "table1_untuned.csv"))
    bullets += _paper_protocol(_csv(results / "table1_paper_protocol.csv"))
    bullets += _crossovers(_csv(results / "crossovers.csv"), _csv(results / "regime_sweep.csv"))
    bullets += _noise(_csv(results / "noise_runs.csv"))
    spread = _csv(results / "dataset_spread.csv")
    if spread is not None and len(spread):
        bullets.append(
            f"**Dataset spread** (F1 over {spread['generated'].nunique()} generated "
            f"{spread['dataset'].iloc[0]} datasets): {spread_text(spread)}."
        )
    return [f"- {b}" for b in bullets]


def _record(results: Path) -> dict:
    """The run record, or {} when it is missing or unreadable."""
    try:
        record = json.loads((results / "run_record.json").read_text())
    except (OSError, ValueError):
        return {}
    return record if isinstance(record, dict) else {}


def _guarded(
    name: str,
    build: Callable[[], Iterable[str]],
    results: Path,
    heading: str | None = None,
    table: str | None = None,
) -> list[str]:
    """``build()``'s lines; if it fails on this folder's files (written by another version of the
    code, or incomplete), a line saying so under ``heading`` and the study's ``table`` file as
    the run wrote it, so that the rest of the report is still written."""
    try:
        return list(build())
    except Exception as error:  # any file format this code does not read
        log.warning("results part %s left out: %s: %s", name, type(error).__name__, error)
        if heading is None:
            return []
        lines = [
            f"### {heading}",
            "",
            f"This part could not be summarised from this folder's files ({type(error).__name__}: "
            f"{error}); they may come from another version of the code, and `make reproduce` "
            "rewrites them.",
            "",
        ]
        path = results / table if table else None
        if path is not None and path.is_file():
            lines += ["The table as the run wrote it:", "", path.read_text().strip(), ""]
        return lines


def _regime_part(results: Path) -> list[str]:
    from eval.studies.regime_cards import regime_markdown

    if not (results / "regime.csv").is_file():
        return []
    return [
        "### Regime of each dataset",
        "",
        regime_markdown(results / "regime.csv").strip(),
        "",
        "Means over test frame pairs; non-covisible share pooled over both views; appearance "
        "AUC: how well feature similarity alone separates true from false candidate pairs "
        "(0.5 = not at all); position error: covisible objects' 3-D disagreement after "
        "aligning the views with the true poses.",
        "",
    ]


def _cue_caption() -> str:
    """Which cues each of the paper's methods reads as published (:mod:`eval.protocol.cues`)."""
    from eval.protocol.cues import PUBLISHED_CUES

    groups: dict[tuple[str, ...], list[str]] = {}
    for name, cues in PUBLISHED_CUES.items():
        groups.setdefault(tuple(sorted(cues)), []).append(method_name(name))
    return "; ".join(f"{', '.join(names)}: {' + '.join(cues)}" for cues, names in groups.items())


def _table1_part(results: Path, rel: str, record: dict) -> list[str]:
    if not (results / "table1.md").is_file():
        return []
    out = ["### Table I", ""]
    if (results / "table1_equal_cues.md").is_file():
        out += [
            "**Equal cues** (the headline): every one of the paper's eight methods is handed "
            "metric geometry and appearance — SM and RRWM their edge-length affinity times the "
            "appearance of both matches, the hypergraph methods (TM, HGM, BCAGM, RRWHM, maximin) "
            "their angle tensor times the metric affinity of each triangle's three edges (our "
            "extension, [docs/matchers.md](../docs/matchers.md#equal-cues)) and, where published "
            "without it, the appearance of its three matches; MOS as published (it already reads "
            "all three). Same tuning budget (8 configurations, `tuning_equal_cues.csv`), τ on "
            "validation.",
            "",
            (results / "table1_equal_cues.md").read_text().strip(),
            "",
            "**As published** — each method with the cues its paper gives it ("
            + _cue_caption()
            + "), so this table measures the cues as much as the methods:",
            "",
        ]
    out += [(results / "table1.md").read_text().strip(), ""]
    tuned = "tuned on the validation datasets (`tuning.csv`), " if record.get("tuning") else ""
    untuned = (
        f" The untuned table: [{rel}/table1_untuned.md]({rel}/table1_untuned.md)."
        if (results / "table1_untuned.md").is_file()
        else ""
    )
    return out + [
        f"Parameters {tuned}τ each matcher's acceptance threshold, calibrated on the validation "
        "datasets (other simulation seeds), never on the test pairs. Balanced accuracy averages "
        "the covisible and the non-covisible objects' shares, so declaring nothing scores 50 on "
        "every dataset (accuracy rewards it with the non-covisible share). AP: area under the "
        "precision–recall curve swept over τ." + untuned,
        "",
    ]


def _paired_part(results: Path, rel: str) -> list[str]:
    out = []
    for suffix, title in (("_equal_cues", "equal cues"), ("", "as published")):
        paired = _csv(results / f"paired_differences{suffix}.csv")
        if paired is None or not len(paired):
            continue
        shown = paired[paired["matcher_b"].isin(list(PAPER_NAMES) + ["appearance"])]
        out += [
            f"### Maximin against each rival, {title} (percentage points)",
            "",
            paired_markdown(shown),
            "",
            "Runs averaged per frame pair; the 95 % interval is a cluster-robust t-interval with "
            "the simulation episode as the unit (frame pairs of one episode are correlated; "
            "`episodes` says how many); MDD: the smallest ΔF1 these episodes detect at 95 % "
            "confidence and 80 % power: "
            f"[{rel}/paired_differences{suffix}.csv]({rel}/paired_differences{suffix}.csv).",
            "",
        ]
    return out


def _spread_part(results: Path) -> list[str]:
    spread = _csv(results / "dataset_spread.csv")
    if spread is None or not len(spread):
        return []
    return [
        "### Dataset spread",
        "",
        f"F1 range over {spread['generated'].nunique()} {spread['dataset'].iloc[0]} test "
        f"datasets generated with different scenario seeds: {spread_text(spread)}.",
        "",
    ]


def _paper_protocol_part(results: Path) -> list[str]:
    if not (results / "table1_paper_protocol.md").is_file():
        return []
    return [
        "### Under the paper's protocol",
        "",
        "SM, RRWM and MOS's pairwise term compare distances between box centres in the image; "
        "every matcher reports its full Hungarian assignment (no τ); no tuning.",
        "",
        (results / "table1_paper_protocol.md").read_text().strip(),
        "",
    ]


def _regime_sweep_part(results: Path, rel: str, record: dict) -> list[str]:
    if not (results / "fig_regime.png").is_file():
        return []
    sweep = record.get("regime_sweep", {})
    return [
        "### Regime sweep",
        "",
        f"![F1 and balanced accuracy against the non-covisible share]({rel}/fig_regime.png)",
        "",
        "Non-covisible detections thinned (keep "
        + ", ".join(f"{k:g}" for k in sweep.get("keep", []))
        + f"; seeded per frame pair, validation and test alike), τ recalibrated per level on "
        f"the thinned validation set ({_n(len(sweep.get('val_seeds', [])), 'run')}), "
        f"{_n(len(sweep.get('seeds', [])), 'run')} on the first {sweep.get('pairs') or 'all'} "
        f"test pairs. Crossovers: [{rel}/crossovers.csv]({rel}/crossovers.csv).",
        "",
    ]


def _localisation_part(results: Path, rel: str, record: dict) -> list[str]:
    if not (results / "fig_localisation.png").is_file():
        return []
    loc = record.get("localisation_sweep", {})
    return [
        "### F1 against localisation error (CAD)",
        "",
        f"![F1 against the observers' position error]({rel}/fig_localisation.png)",
        "",
        "Each observer's pose perturbed by a seeded GPS-like error (position σ per axis on "
        "the x axis, heading σ = 0.2° per 1.2 m), drawn at read time (no re-rendering); τ "
        "every matcher's parameters tuned again and τ calibrated per σ on the validation set "
        "at that σ, the matchers told the stated σ (at least 0.5 m), never the error drawn; "
        f"{_n(len(loc.get('seeds', [])), 'run')}, "
        f"first {loc.get('pairs') or 'all'} test pairs "
        f"([{rel}/localisation_sweep.csv]({rel}/localisation_sweep.csv)).",
        "",
    ]


def _noise_part(rel: str, record: dict) -> list[str]:
    noise = record.get("noise_sweep", {})
    rates = ", ".join(f"{r:g}" for r in noise.get("rates", []))
    return [
        "### Fig. 4 — against depth noise (CAD, as in the paper, and MRC)",
        "",
        f"![Fig. 4: accuracy, precision, recall against noise rate]({rel}/fig4.png)",
        "",
        f"noise_rate ∈ {{{rates}}} (σ = noise_rate · d²), {_n(len(noise.get('seeds', [])), 'run')}, "
        f"first {noise.get('pairs') or 'all'} test pairs; each rate re-applies noise to the "
        "stored clean depth and re-detects (no re-rendering).",
        "",
    ]


def _qualitative_part(rel: str) -> list[str]:
    return [
        "### Qualitative (the paper's Fig. 3 style)",
        "",
        f"![Qualitative: RRWHM, MOS, maximin on one MRC and one CAD pair]({rel}/qualitative.png)",
        "",
        "Green: correct match, red: wrong match, yellow dashed: missed (false negative).",
        "",
    ]


def _agreement_part(results: Path) -> list[str]:
    bullets = agreement_bullets(results)
    if not bullets:
        return []
    return [
        "### Where we agree with the paper, and where not",
        "",
        "(Computed from the tables above; percent, differences in percentage points.)",
        "",
        *bullets,
        "",
    ]


def _last_cold(results: Path, record: dict) -> dict | None:
    """The last cold run's record (``cold_run.json``; this run's if it was cold), or None."""
    return cold_record(results) or (record if is_cold(record) else None)


def _run_part(results: Path, record: dict) -> list[str]:
    if not record:
        return []
    out = [_header(record), ""]
    timed = _last_cold(results, record) or record
    if timed.get("wall_s"):
        out += ["### Stage times", "", *stage_table(timed)]
    return out


def results_section(results: Path, readme_dir: Path) -> str:
    """Markdown: the run and its stage times, regime cards, Table I and its companions, figures,
    the agreement summary and the studies (V2X, multi-agent, transfer), links relative to
    ``readme_dir``."""
    return "\n".join(_sections(Path(results), Path(readme_dir))).strip()


def _sections(results: Path, readme_dir: Path, groups: bool = False) -> list[str]:
    """The report's lines; ``groups`` adds a ``##`` heading above each group of parts."""
    rel = Path(os.path.relpath(results, readme_dir)).as_posix()
    record = _record(results)
    cold = _last_cold(results, record) or {}  # "≤ N min cold" goals: the last cold run's times
    stages = cold.get("wall_s", {})
    multi_s = sum(stages.get(k, 0.0) for k in ("multiagent_generate", "multiagent")) or None
    transfer_runs = cold.get("runs", {}).get("transfer", {}).get("computed")
    transfer_s = sum(stages.get(k, 0.0) for k in ("transfer_generate", "transfer")) or None
    temporal_s = sum(stages.get(k, 0.0) for k in ("temporal_generate", "temporal")) or None
    boxes_s = stages.get("v2x_boxes")

    def part(name, build, heading=None, table=None):
        return _guarded(name, build, results, heading, table)

    plan = [
        ("The run", [part("run", lambda: _run_part(results, record))]),
        (
            "The paper's benchmark",
            [
                part("regime", lambda: _regime_part(results)),
                part("table1", lambda: _table1_part(results, rel, record), "Table I", "table1.md"),
                part("paired", lambda: _paired_part(results, rel)),
                part("spread", lambda: _spread_part(results)),
                part("paper protocol", lambda: _paper_protocol_part(results)),
                part("regime sweep", lambda: _regime_sweep_part(results, rel, record)),
                part("noise", lambda: _noise_part(rel, record)),
                part("qualitative", lambda: _qualitative_part(rel)),
                part("agreement", lambda: _agreement_part(results)),
            ],
        ),
        (
            "External data",
            [
                part(
                    "external",
                    lambda: external_readme(results, rel),
                    "External data: the DMGM CAD pairs",
                    "table_external.md",
                ),
                part("prior sensitivity", lambda: prior_sensitivity_readme(results, rel)),
                part(
                    "external agreement",
                    lambda: agreement_readme(results, rel),
                    "Do these rankings hold on external data?",
                ),
            ],
        ),
        (
            "Localisation and V2X",
            [
                part("localisation", lambda: _localisation_part(results, rel, record)),
                part("v2x", lambda: v2x_readme(results, rel), "The V2X task", "table_v2x.md"),
                part(
                    "v2x boxes",
                    lambda: v2x_boxes_readme(results, rel, boxes_s),
                    "The V2X task with boxes only",
                    "table_v2x_boxes.md",
                ),
                part(
                    "v2x lidar",
                    lambda: v2x_lidar_readme(results, rel),
                    "The V2X task on LiDAR boxes",
                    "table_v2x_lidar.md",
                ),
            ],
        ),
        (
            "Multi-agent",
            [
                part(
                    "multiagent",
                    lambda: multiagent_readme(results, rel, multi_s),
                    "Multi-agent matching",
                    "table_multiagent.md",
                )
            ],
        ),
        (
            "Temporal",
            [
                part(
                    "temporal",
                    lambda: temporal_readme(results, rel, temporal_s),
                    "The temporal table",
                    "table_temporal.md",
                )
            ],
        ),
        (
            "Transfer",
            [
                part(
                    "transfer",
                    lambda: transfer_readme(results, rel, transfer_s, transfer_runs),
                    "Does simulation transfer?",
                    "table_transfer.md",
                )
            ],
        ),
    ]
    out: list[str] = []
    for title, parts in plan:
        lines = [line for p in parts for line in p]
        if lines:
            out += ([f"## {title}", ""] if groups else []) + lines
    return out


# Figures a results folder may hold that no part above shows, and what they show.
FIGURE_CAPTIONS = {
    "pr_curves.png": "Pooled precision–recall curves per dataset and matcher (test pairs)",
    "fig_localisation_presets.png": "CAD-V2X: F1 and the pose metrics against the localisation "
    "preset's error scale and latency",
}


def _appendix(results: Path, body: str, rel: str) -> list[str]:
    """Every Markdown table and PNG figure of ``results`` that ``body`` does not show in full,
    then a list of the folder's data files."""
    tables = []
    for path in sorted(results.glob("*.md")):
        text = path.read_text().strip() if path.name != REPORT else ""
        if text and text not in body:
            tables += [f"### {path.name}", "", text, ""]
    figures = []
    for path in sorted(results.rglob("*.png")):
        name = path.relative_to(results).as_posix()
        if f"]({rel}/{name})" not in body:
            caption = FIGURE_CAPTIONS.get(name, name)
            figures += [f"### {name}", "", f"![{caption}]({rel}/{name})", ""]
    files = [
        f"[{p.name}]({rel}/{p.name})"
        for p in sorted(results.iterdir())
        if p.is_file() and p.suffix in (".csv", ".json", ".tex", ".pdf") and p.name != SITE
    ]
    folders = [f"`{p.name}/`" for p in sorted(results.iterdir()) if p.is_dir()]
    out = []
    if tables or figures:
        out += [
            "## Every other table and figure",
            "",
            "Written by the same run, not shown in full above.",
            "",
        ]
        out += tables + figures
    if files or folders:
        out += ["## Files", ""]
        out += [f"Data: {', '.join(files)}." if files else ""]
        out += (
            ["", f"Per-study folders (evaluation files of each part): {', '.join(folders)}."]
            if folders
            else []
        )
        out += [""]
    return out


def report_markdown(results: Path) -> str:
    """The whole report, ``<results>/README.md``: links relative to ``results``."""
    results = Path(results)
    docs = Path(os.path.relpath(ROOT / "docs", results)).as_posix()
    body = _sections(results, results, groups=True)
    text = "\n".join(body)
    rel = "."
    lines = [
        "# cadsim results",
        "",
        "Written by `make reproduce` from the files in this folder — every number below is "
        "read from them, none typed by hand; `make report` (`python -m eval.readme_results`) "
        f"writes this page again from the same files without recomputing anything. {SELF_LINK} "
        f"How to read the numbers, and what they cannot say: "
        f"[docs/evaluation.md]({docs}/evaluation.md#reading-the-results).",
        "",
        *body,
        *_appendix(results, text, rel),
    ]
    return "\n".join(lines).rstrip() + "\n"


def _site_links(markdown: str, rel: str = ".") -> dict[str, str]:
    """On the HTML page, a link to a Markdown table shown on it points at its section."""
    return {
        f"{rel}/{text}": f"#{anchor}" for text, anchor in headings(markdown) if text.endswith(".md")
    }


def write_report(results: Path) -> tuple[Path, Path]:
    """Write ``<results>/README.md`` and ``<results>/index.html`` from the files in ``results``."""
    results = Path(results)
    markdown = report_markdown(results)
    report = write_text(results / REPORT, markdown)
    page = markdown.replace(SELF_LINK, SITE_SELF_LINK, 1)  # the page names the other form
    site = write_site(page, results, "cadsim results", _site_links(page))
    return report, site


def _anchor(report: str, prefix: str) -> str:
    """``#anchor`` of the report's first heading that starts with ``prefix`` ("" if none)."""
    return next((f"#{a}" for text, a in headings(report) if text.startswith(prefix)), "")


# The README's compact tables: (lead, table, heading of the report section it links to, caption).
SUMMARIES = (
    (
        "Table I — the paper's benchmark, equal cues",
        summary.table1,
        "Table I",
        "F1 in percent on each dataset's test pairs, every one of the paper's eight methods "
        "handed the same cues — metric geometry and appearance, each in its family's natural "
        "form ([equal cues](docs/matchers.md#equal-cues)) — τ and parameters chosen on validation "
        "seeds; rank by F1 among the eight, the paper's own rank of maximin (by accuracy) in "
        "brackets; the interval resamples simulation episodes. The table with each method's "
        "published cues is in the report.",
    ),
    (
        "Fig. 4 — depth noise",
        summary.noise,
        "Fig. 4",
        "F1 in percent from the lowest to the highest noise rate (σ = rate · d²).",
    ),
    (
        "External data — the DMGM CAD pairs",
        summary.external,
        "External data",
        "Independently simulated (CARLA + SUMO), not real-world; τ and parameters from sequence "
        "070, test on 069 + 071, sorted as the full table; *prior*: given the vehicles' noisy "
        "GPS poses.",
    ),
    (
        "V2X — CAD-V2X under each localisation preset",
        summary.v2x,
        "The V2X task",
        "F1 in percent of the paper's method, two matchers without and two with the "
        "localisation prior (last column: the same data as 3-D boxes only, its matcher chosen on "
        f"validation; {NO_NUMBER}: no prior under `denied`, so no number); every matcher, the "
        "pose metrics and the verdicts in the report.",
    ),
    (
        "Multi-agent — fusing the pairwise matchings of N views",
        summary.multiagent,
        "Multi-agent",
        "Pooled pairwise F1 in percent per two-view matcher and fusion (`independent`: no fusion).",
    ),
    (
        "Transfer — learned matchers on external data",
        summary.transfer,
        "Does simulation transfer?",
        "Pooled F1 in percent; the last row is the hand-crafted matcher each column is compared "
        "with.",
    ),
    (
        "Temporal — association over sequences of 10 frames",
        summary.temporal,
        "The temporal table",
        "Pooled F1 in percent on CAD-V2X sequences (most frames of a sequence have no true pair, "
        "so the per-frame mean is secondary, in the report), one frame (W = 1) against a "
        f"10-frame window along each agent's own tracks; {NO_NUMBER}: the method reads the "
        "localisation prior, which `denied` does not give; the goals and their verdicts in the "
        "report.",
    ),
)


def summary_section(results: Path, readme_dir: Path) -> str:
    """The README's section: the run in one line, links to the report, one compact table per
    study (those whose files are there), each with a link to its full section."""
    results = Path(results)
    rel = Path(os.path.relpath(results, readme_dir)).as_posix()
    record = _record(results)
    report_path = results / REPORT
    report = report_path.read_text() if report_path.is_file() else report_markdown(results)
    git, wall = record.get("git", {}), record.get("wall_s", {})
    run = f"From the files in `{rel}/`"
    if record:
        run += (
            f": {'a cold' if is_cold(record) else 'a warm'} run at commit "
            f"`{str(git.get('commit', '?'))[:10]}` on {str(record.get('created', '?'))[:10]}, "
            f"{wall.get('total', float('nan')):.0f} s"
        )
        if wall:
            run += f" ([stage times]({rel}/{REPORT}{_anchor(report, 'Stage times')}))"
    run += (
        f". The full report — every table, figure, interval and verdict — is "
        f"[{rel}/{REPORT}]({rel}/{REPORT}); [{rel}/{SITE}]({rel}/{SITE}) is the same page with "
        "sortable tables (open it in a browser)."
    )
    out = [run, ""]
    for lead, build, heading, caption in SUMMARIES:
        table = _guarded(lead, lambda build=build: build(results), results)
        if not table:
            continue
        link = f"{rel}/{REPORT}{_anchor(report, heading)}"
        out += [f"**{lead}** ([full]({link})). {caption}", "", *table, ""]
    return "\n".join(out).strip()


def update_readme(readme: Path, results: Path) -> bool:
    """Replace the README's results section; False (README untouched) if it has no markers."""
    readme = Path(readme)
    text = readme.read_text()
    if BEGIN not in text or END not in text:
        return False
    head, rest = text.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    body = summary_section(Path(results), readme.parent)
    write_text(readme, f"{head}{BEGIN}\n{body}\n{END}{tail}")
    return True


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m eval.readme_results",
        description="Write the results report (README.md, index.html) and the README's results "
        "section again from a results folder's files, recomputing nothing.",
    )
    parser.add_argument("--results", type=Path, default=ROOT / "results", help="default: results/")
    parser.add_argument(
        "--readme",
        type=Path,
        default=None,
        help="README whose results section to rewrite (default: the repository's README.md "
        "when --results is the repository's results/, else none)",
    )
    args = parser.parse_args(argv)
    if not args.results.is_dir():
        parser.error(f"{args.results}: no such folder")
    for path in write_report(args.results):
        print(f"wrote {path}")
    readme = args.readme
    if readme is None and args.results.resolve() == (ROOT / "results").resolve():
        readme = ROOT / "README.md"
    if readme is not None:
        if update_readme(readme, args.results):
            print(f"rewrote the results section of {readme}")
        else:
            print(f"{readme}: no {BEGIN} … {END} markers; left alone")
    return 0


if __name__ == "__main__":
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s: %(message)s")
    raise SystemExit(main())
