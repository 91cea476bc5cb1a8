"""Table I: our accuracy, balanced accuracy, precision, recall (mean ± std over runs), F1, AP, τ,
tuned parameters and median time per pair for every dataset and matcher, beside the paper's
numbers, and precision, recall and F1 pooled over each run's frame pairs (``*_pooled``, DMGM's
aggregation); Markdown, CSV and LaTeX.

Inputs are the CSV files ``cadsim evaluate`` writes into its output directory
(``metrics_per_pair.csv``, ``average_precision.csv``, ``thresholds.csv``, each also per variant:
``_untuned``, ``_paper_protocol``, :mod:`eval.protocol.variants`); rates are printed in percent, like the
paper. :func:`write_tables` writes every variant present.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from eval.core.pose_metrics import summarise_pose
from eval.core.result_files import write_csv, write_text
from eval.protocol.metrics import METRICS, POOLED, summarise_pooled, summarise_runs
from eval.protocol.variants import EQUAL, MAIN, VARIANTS, variant_path
from eval.report.markdown_cell import cell, row
from eval.report.threshold_format import rounded, tau_text

PAPER_CSV = Path(__file__).resolve().parents[1] / "data" / "paper-table1.csv"

# Registry name -> the paper's method name, in the paper's row order.
PAPER_NAMES = {
    "sm": "SM",
    "rrwm": "RRWM",
    "hgm": "HGM",
    "tm": "TM",
    "bcagm": "BCAGM",
    "rrwhm": "RRWHM",
    "mos": "MOS",
    "maximin": "Maximin",
}
EXTRA_NAMES = {
    "appearance": "Appearance only",
    "none": "None (declares nothing)",
    "consistency": "Consistency (no prior)",
    "pose": "Pose prior only",
    "pose_refine": "Pose prior, refined",
    "pose_appearance": "Pose prior × appearance",
    "maximin_pose": "Maximin + pose prior",
}
PAPER_DATASETS = ("MRC", "CAD")
# Our dataset -> the paper's column shown beside it (a variant of a paper dataset).
PAPER_COLUMN = {"CAD-dense": "CAD"}
DATASET_ORDER = ("MRC", "CAD", "CAD-dense")


def method_name(matcher: str) -> str:
    """Display name of a matcher label (options kept: ``tm[k=5]`` -> ``TM[k=5]``)."""
    base, _, rest = matcher.partition("[")
    name = PAPER_NAMES.get(base) or EXTRA_NAMES.get(base) or base
    return name + ("[" + rest if rest else "")


def matcher_order(matcher: str) -> tuple[int, str]:
    """Sort key: the paper's row order, then extras, then the rest by name."""
    base = matcher.partition("[")[0]
    order = list(PAPER_NAMES) + list(EXTRA_NAMES)
    return (order.index(base) if base in order else len(order), matcher)


def dataset_order(label: str) -> tuple[int, str]:
    """Sort key: the paper's column order (MRC, CAD, then CAD-dense), then the rest by name."""
    return (DATASET_ORDER.index(label) if label in DATASET_ORDER else len(DATASET_ORDER), label)


def load_paper(path: str | Path = PAPER_CSV) -> pd.DataFrame:
    """The paper's Table I: method, dataset, <metric>_mean, <metric>_spread (percent)."""
    paper = pd.read_csv(path)
    expected = {"method", "dataset"} | {
        f"{m}_{s}" for m in ("accuracy", "precision", "recall") for s in ("mean", "spread")
    }
    if not expected <= set(paper.columns):
        raise ValueError(f"{path}: expected columns {sorted(expected)}, got {list(paper.columns)}")
    return paper


def build_table(
    out_dir: str | Path, paper_csv: str | Path = PAPER_CSV, variant: str = MAIN
) -> pd.DataFrame:
    """One row per (dataset, matcher) of `variant`: our numbers, τ, parameters, time and the
    paper's beside. Rates are fractions in [0, 1] (the paper's percent divided by 100), as in
    every results CSV; the Markdown and LaTeX renderings print percent (:func:`as_percent`)."""
    out_dir = Path(out_dir)
    per_pair = pd.read_csv(
        variant_path(out_dir, "metrics_per_pair", variant, ".csv"),
        keep_default_na=False,
        na_values=[""],
    )
    summary = summarise_runs(per_pair, by=["dataset", "matcher"])
    if {"tp", "n_pred", "n_gt"} <= set(per_pair.columns):
        pooled = summarise_pooled(per_pair, by=["dataset", "matcher"])
        summary = summary.merge(pooled, on=["dataset", "matcher"], how="left")
    sizes = per_pair.groupby(["dataset", "matcher"]).agg(
        frames=("pair", "nunique"), time_median_ms=("time_s", lambda t: 1000 * float(np.median(t)))
    )
    table = summary.merge(sizes.reset_index(), on=["dataset", "matcher"])
    pose = summarise_pose(per_pair, ["dataset", "matcher"])
    if not pose.empty:  # the relative pose the matches recover (records with camera poses)
        table = table.merge(pose, on=["dataset", "matcher"], how="left")
    if "params" in per_pair.columns:
        params = per_pair.groupby(["dataset", "matcher"])["params"].first().reset_index()
        table = table.merge(params, on=["dataset", "matcher"], how="left")
    ap_path = variant_path(out_dir, "average_precision", variant, ".csv")
    if ap_path.is_file():
        ap = pd.read_csv(ap_path).groupby(["dataset", "matcher"])["ap"]
        ap = pd.DataFrame(
            {"ap_mean": ap.mean(), "ap_std": ap.std(ddof=1).fillna(0.0)}
        ).reset_index()
        table = table.merge(ap, on=["dataset", "matcher"], how="left")
    tau_path = variant_path(out_dir, "thresholds", variant, ".csv")
    if tau_path.is_file():
        taus = pd.read_csv(tau_path)[["dataset", "matcher", "tau"]]
        table = table.merge(taus, on=["dataset", "matcher"], how="left")
    else:
        table["tau"] = np.nan
    table.insert(1, "method", table["matcher"].map(method_name))
    paper = load_paper(paper_csv)
    paper[[c for c in paper.columns if c.endswith(("_mean", "_spread"))]] /= 100  # fractions
    paper = paper.add_prefix("paper_")
    table["_paper_dataset"] = table["dataset"].map(lambda d: PAPER_COLUMN.get(d, d))
    table = table.merge(
        paper,
        left_on=["_paper_dataset", "method"],
        right_on=["paper_dataset", "paper_method"],
        how="left",
    ).drop(columns=["paper_dataset", "paper_method", "_paper_dataset"])
    table["_d"] = table["dataset"].map(dataset_order)
    table["_m"] = table["matcher"].map(matcher_order)
    return table.sort_values(["_d", "_m"]).drop(columns=["_d", "_m"]).reset_index(drop=True)


def is_rate_column(column: str) -> bool:
    """Whether a table column holds a rate (a metric's mean, std or the paper's spread)."""
    base = column.removeprefix("paper_")
    for suffix in ("_mean", "_std", "_spread"):
        if base.endswith(suffix):
            return base[: -len(suffix)] in (*METRICS, *POOLED, "ap")
    return False


def as_percent(table: pd.DataFrame) -> pd.DataFrame:
    """A copy of ``table`` with its rate columns (:func:`is_rate_column`) in percent, to print."""
    table = table.copy()
    for column in table.columns:
        if is_rate_column(column):
            table[column] = 100 * table[column]
    return table


def _pm(mean: float, std: float, digits: int = 1) -> str:
    """``mean ± std`` of two fractions, printed in percent."""
    if pd.isna(mean):
        return "–"
    return f"{100 * mean:.{digits}f} ± {100 * std:.{digits}f}"


def params_text(params: object) -> str:
    """Compact display of a ``params`` JSON cell: ``sigma_scale=0.05``; ``default`` for ``{}``."""
    if not isinstance(params, str) or not params.strip():
        return "–"
    options = json.loads(params)
    if not options:
        return "default"
    shown = []
    for key, value in options.items():
        if key == "model_sha256":  # the model shows as its file name and content hash
            continue
        if key == "model":
            digest = str(options.get("model_sha256", ""))[:12]
            shown.append(f"model={Path(str(value)).name}" + (f" ({digest})" if digest else ""))
        else:
            shown.append(f"{key}={value:g}" if isinstance(value, float) else f"{key}={value}")
    return ", ".join(shown) if shown else "default"


def _cells(row: pd.Series, show_params: bool) -> dict[str, str]:
    cells = {"Method": row["method"]}
    if show_params:
        cells["Parameters"] = params_text(row.get("params"))
    for metric, title in (
        ("accuracy", "Accuracy"),
        ("precision", "Precision"),
        ("recall", "Recall"),
    ):
        cells[f"{title}"] = _pm(row[f"{metric}_mean"], row[f"{metric}_std"])
        cells[f"{title} (paper)"] = _pm(
            row.get(f"paper_{metric}_mean"), row.get(f"paper_{metric}_spread"), 2
        )
        if metric == "accuracy":
            cells["Balanced acc."] = _pm(
                row.get("balanced_accuracy_mean", np.nan), row.get("balanced_accuracy_std", np.nan)
            )
    cells["F1"] = _pm(row["f1_mean"], row["f1_std"])
    cells["Pooled P / R / F1"] = pooled_text(row)
    cells["AP"] = _pm(row.get("ap_mean", np.nan), row.get("ap_std", np.nan))
    tau = row.get("tau", np.nan)
    cells["τ"] = tau_text(tau)
    cells["ms / pair"] = f"{row['time_median_ms']:.1f}"
    return cells


def pooled_text(row: pd.Series) -> str:
    """``P / R / F1`` pooled over frame pairs (mean over runs), printed in percent, or –
    without them; ``row`` holds fractions."""
    values = [row.get(f"{m}_mean", np.nan) for m in POOLED]
    if any(pd.isna(v) for v in values):
        return "–"
    return " / ".join(f"{100 * v:.1f}" for v in values)


def _show_params(table: pd.DataFrame) -> bool:
    """Whether any row ran with options other than the defaults (tuned, or a protocol's)."""
    if "params" not in table.columns:
        return False
    return any(params_text(p) not in ("default", "–") for p in table["params"])


def to_markdown(table: pd.DataFrame) -> str:
    """One Markdown table per dataset; ours beside the paper's (percent, mean ± std over runs)."""
    blocks = []
    show_params = _show_params(table)
    for dataset, rows in table.groupby("dataset", sort=False):
        cells = [_cells(r, show_params) for _, r in rows.iterrows()]
        paper = PAPER_COLUMN.get(str(dataset), dataset)
        has_paper = paper in PAPER_DATASETS  # the paper's columns only beside its own datasets
        header = [h for h in cells[0] if has_paper or "(paper)" not in h]
        runs, frames = int(rows["runs"].max()), int(rows["frames"].max())
        caption = (
            f"**{cell(dataset)}** — {frames} test frame pairs × {runs} run{'s' * (runs != 1)}; "
            "percent, mean ± std over runs"
        )
        if runs == 1:  # the tutorial's case: a spread needs several runs
            caption += " (one run: every ± 0.0 is no spread measured; --runs N gives one)"
        if has_paper:
            caption += (
                f"; paper ({paper}): mean ± its printed spread, from the paper's own data and "
                "protocol, not these pairs — compare orders and gaps, not digits"
            )
        lines = [
            caption,
            "",
            row(header),
            "|" + "|".join(":---" if h == "Method" else "---:" for h in header) + "|",
        ]
        lines += [row([c[h] for h in header]) for c in cells]
        blocks.append("\n".join(lines))
    return "\n\n".join(blocks) + "\n"


def _latex_escape(text: str) -> str:
    return text.replace("_", r"\_").replace("%", r"\%").replace("&", r"\&")


def to_latex(table: pd.DataFrame) -> str:
    """A booktabs table per dataset: ours (paper) for each metric, then F1, AP, τ, ms per pair."""
    table = as_percent(table)
    out = []
    for dataset, rows in table.groupby("dataset", sort=False):
        out += [
            r"\begin{table}[t]",
            r"\centering",
            rf"\caption{{Correspondence identification on {_latex_escape(dataset)} (\%, mean $\pm$ "
            r"std over runs; the paper's numbers in parentheses).}",
            r"\begin{tabular}{lcccccccrr}",
            r"\toprule",
            r"Method & Accuracy & Bal.\ acc. & Precision & Recall & F1 & F1 pooled & AP & $\tau$ & "
            r"ms/pair \\",
            r"\midrule",
        ]
        for _, r in rows.iterrows():
            cells = [_latex_escape(r["method"])]
            for metric in ("accuracy", "balanced_accuracy", "precision", "recall"):
                if pd.isna(r.get(f"{metric}_mean", np.nan)):
                    cells.append("--")
                    continue
                ours = f"{r[f'{metric}_mean']:.1f} $\\pm$ {r[f'{metric}_std']:.1f}"
                paper = r.get(f"paper_{metric}_mean", np.nan)
                cells.append(ours if pd.isna(paper) else f"{ours} ({paper:.1f})")
            cells.append(f"{r['f1_mean']:.1f} $\\pm$ {r['f1_std']:.1f}")
            pooled = r.get("f1_pooled_mean", np.nan)
            cells.append("--" if pd.isna(pooled) else f"{pooled:.1f}")
            ap = r.get("ap_mean", np.nan)
            cells.append("--" if pd.isna(ap) else f"{ap:.1f}")
            tau = r.get("tau", np.nan)
            cells.append(tau_text(tau, "--"))
            cells.append(f"{r['time_median_ms']:.1f}")
            out.append(" & ".join(cells) + r" \\")
        out += [r"\bottomrule", r"\end{tabular}", r"\end{table}", ""]
    return "\n".join(out)


def write_table1(
    out_dir: str | Path, paper_csv: str | Path = PAPER_CSV, variant: str = MAIN
) -> str:
    """Write ``table1[_variant].md`` and ``.csv`` (and, for the main variant, ``table1.tex``)
    into `out_dir`; returns the Markdown."""
    out_dir = Path(out_dir)
    table = build_table(out_dir, paper_csv, variant)
    markdown = to_markdown(table)
    write_text(variant_path(out_dir, "table1", variant, ".md"), markdown)
    write_csv(rounded(table), variant_path(out_dir, "table1", variant, ".csv"))
    if variant == MAIN:
        write_text(out_dir / "table1.tex", to_latex(table))
    return markdown


def write_tables(
    out_dir: str | Path, paper_csv: str | Path = PAPER_CSV, reference: str | None = None
) -> str:
    """Table I of every variant whose per-pair metrics are in `out_dir`, and the paired
    differences (`reference` − every other matcher; None: maximin) of the main and equal-cue
    ones; returns the main variant's Markdown (else the first written)."""
    from eval.protocol.paired_differences import REFERENCE, write_paired_differences

    out_dir = Path(out_dir)
    written = {
        v: write_table1(out_dir, paper_csv, v)
        for v in VARIANTS
        if variant_path(out_dir, "metrics_per_pair", v, ".csv").is_file()
    }
    for variant in (MAIN, EQUAL):
        if variant in written:
            write_paired_differences(out_dir, variant, reference or REFERENCE)
    return written.get(MAIN) or next(iter(written.values()), "")
