"""Figures from an evaluation output directory (no matcher is re-run):

- ``fig4.png/.pdf``: accuracy, precision, recall against the depth-noise rate, one line per matcher
  (mean over runs) with a ±std band (from ``noise_runs.csv``);
- ``pr_curves.png``: pooled precision–recall curves per dataset (from ``pr_curves.csv``);
- ``fig_localisation.png/.pdf``: F1 against the observers' localisation error, one line per
  matcher with a ±std band over runs (from ``localisation_sweep.csv``);
- ``fig_regime.png/.pdf``: F1 and balanced accuracy against the achieved non-covisible share of
  the regime sweep, one line per matcher, one row of panels per dataset (from
  ``regime_sweep.csv``);
- ``qualitative.png/.pdf``: paper Fig. 3 style — one pair per paper dataset (MRC, CAD; every
  dataset when neither is there), both views side by side,
  lines for RRWHM, MOS and maximin: green correct, red wrong, yellow dashed missed (from
  ``qualitative.json`` and the dataset's images).
"""

from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np
import pandas as pd

from eval.core.result_files import save_figure
from eval.protocol.crossovers import PAIRS
from eval.report.figure_stamps import drawn_once
from eval.report.palette import styles
from eval.report.tables import PAPER_DATASETS, dataset_order, matcher_order, method_name

log = logging.getLogger(__name__)


def _inputs(*names: str):
    """The files a writer reads, relative to its output folder (:func:`drawn_once`)."""
    return lambda out_dir: [Path(out_dir) / name for name in names]


def _qualitative_inputs(out_dir: Path) -> list[Path]:
    """``qualitative.json`` and the manifest of every dataset it draws from."""
    path = Path(out_dir) / "qualitative.json"
    try:
        spec = json.loads(path.read_text(encoding="utf-8"))
        folders = [Path(str(entry["dataset_dir"])) for entry in spec.values()]
    except (OSError, ValueError, AttributeError, KeyError, TypeError):
        return [path]
    return [path, *(folder / "manifest.json" for folder in folders)]


PANELS = (
    ("accuracy", "Accuracy"), ("precision", "Precision"), ("recall", "Recall"), ("f1", "F1"),
)  # fmt: skip
FIG4_NOTE = (
    "Lines: mean over runs (seeds) of each run's mean over frame pairs; bands: ± one standard "
    "deviation over runs. F1: the README's summary metric."
)


def _figure(width: float, height: float, ncols: int = 1, nrows: int = 1):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False)
    return fig, axes


def _colors(matchers: list[str]) -> dict[str, str]:
    """Each matcher's colour (:mod:`eval.report.palette`: the same in every figure)."""
    return {m: s.color for m, s in styles(matchers).items()}


def _marker(matcher: str) -> str:
    return styles([matcher])[matcher].marker


def _save(fig, base: Path, suffixes=(".png", ".pdf")) -> list[Path]:
    paths = []
    for suffix in suffixes:
        path = base.with_suffix(suffix)
        save_figure(fig, path, dpi=150)
        paths.append(path)
    return paths


@drawn_once(_inputs("noise_runs.csv"))
def write_fig4(out_dir: str | Path) -> list[Path]:
    """Fig. 4 from ``noise_runs.csv``; returns the written paths (none without the CSV)."""
    out_dir = Path(out_dir)
    path = out_dir / "noise_runs.csv"
    if not path.is_file():
        return []
    per_run = pd.read_csv(path)
    stats = per_run.groupby(["dataset", "matcher", "noise_rate"])[[m for m, _ in PANELS]]
    mean, std = stats.mean(), stats.std(ddof=1).fillna(0.0)
    matchers = sorted(per_run["matcher"].unique(), key=matcher_order)
    colors = _colors(matchers)
    datasets = list(dict.fromkeys(per_run["dataset"]))
    fig, axes = _figure(16, 3.6 * len(datasets) + 0.8, ncols=len(PANELS), nrows=len(datasets))
    rates = np.sort(per_run["noise_rate"].unique())
    positive = rates[rates > 0]
    for row, dataset in enumerate(datasets):
        for col, (metric, title) in enumerate(PANELS):
            ax = axes[row, col]
            for matcher in matchers:
                if (dataset, matcher) not in mean.index.droplevel(2):
                    continue
                m = mean.loc[(dataset, matcher)][metric]
                s = std.loc[(dataset, matcher)][metric]
                x = m.index.to_numpy(float)
                ax.plot(
                    x,
                    100 * m,
                    marker=_marker(matcher),
                    ms=4,
                    color=colors[matcher],
                    label=method_name(matcher),
                )
                ax.fill_between(
                    x, 100 * (m - s), 100 * (m + s), color=colors[matcher], alpha=0.15, lw=0
                )
            if len(positive):
                ax.set_xscale("symlog", linthresh=float(positive.min()), linscale=0.5)
                ax.set_xticks(rates, [f"{r:g}" for r in rates], rotation=45, fontsize=7)
                ax.minorticks_off()
            ax.set_xlabel("noise rate (σ = rate · d², d in m)")
            ax.set_ylabel(f"{title} (%)")
            ax.set_title(f"{dataset}: {title if title.isupper() else title.lower()}")
            ax.set_ylim(-2, 102)
            ax.grid(alpha=0.3)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=min(len(labels), 9), fontsize=8)
    fig.suptitle(FIG4_NOTE, fontsize=8)
    return _save(fig, out_dir / "fig4")


REGIME_PANELS = (("f1_mean", "F1"), ("balanced_accuracy_mean", "Balanced accuracy"))


CROSSOVER_RIVALS = tuple(b for _, b in PAIRS)


@drawn_once(_inputs("regime_sweep.csv"))
def write_fig_regime(out_dir: str | Path) -> list[Path]:
    """The regime-sweep figure from ``regime_sweep.csv``; none without the CSV."""
    out_dir = Path(out_dir)
    path = out_dir / "regime_sweep.csv"
    if not path.is_file():
        return []
    sweep = pd.read_csv(path, keep_default_na=False, na_values=[""])
    if sweep.empty:
        return []
    datasets = sorted(sweep["dataset"].unique(), key=dataset_order)
    matchers = sorted(sweep["matcher"].unique(), key=matcher_order)
    colors = _colors(matchers)
    fig, axes = _figure(10, 3.4 * len(datasets) + 0.6, ncols=2, nrows=len(datasets))
    for row, dataset in enumerate(datasets):
        rows = sweep[sweep["dataset"] == dataset]
        for col, (column, title) in enumerate(REGIME_PANELS):
            ax = axes[row, col]
            for matcher in matchers:
                c = rows[rows["matcher"] == matcher].sort_values("share")
                if c.empty:
                    continue
                style = {"lw": 2.2} if matcher == "maximin" else {"lw": 1.2}
                ax.plot(
                    100 * c["share"],
                    100 * c[column],
                    marker=_marker(matcher),
                    ms=4,
                    color=colors[matcher],
                    label=method_name(matcher),
                    **style,
                )
                if (
                    column == "f1_mean"
                    and matcher in ("maximin", *CROSSOVER_RIVALS)
                    and {"f1_ci_low", "f1_ci_high"} <= set(c.columns)
                ):  # the curves a crossover is read from, with their 95 % band
                    ax.fill_between(
                        100 * c["share"],
                        100 * c["f1_ci_low"],
                        100 * c["f1_ci_high"],
                        color=colors[matcher],
                        alpha=0.15,
                        lw=0,
                    )
            ax.set_xlabel("non-covisible share of all objects (%)")
            ax.set_ylabel(f"{title} (%)")
            ax.set_title(f"{dataset}: {title} vs distractor share")
            ax.set_ylim(-2, 102)
            ax.grid(alpha=0.3)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=min(len(labels), 6), fontsize=8)
    return _save(fig, out_dir / "fig_regime")


def _curves(ax, rows: pd.DataFrame, x_col: str, metric: str, matchers, colors) -> None:
    """One line per matcher of ``metric`` (a fraction, drawn in percent) against ``x_col``; for
    ``f1_mean`` a band of ± ``f1_std`` (none where every run gave the same F1)."""
    for matcher in matchers:
        c = rows[rows["matcher"] == matcher].sort_values(x_col)
        if c.empty:
            continue
        x, m = c[x_col], 100 * c[metric]
        ax.plot(x, m, marker=_marker(matcher), ms=4, color=colors[matcher], label=method_name(matcher))  # fmt: skip
        if metric == "f1_mean":
            s = 100 * c["f1_std"].fillna(0.0)
            ax.fill_between(x, m - s, m + s, color=colors[matcher], alpha=0.15, lw=0)


@drawn_once(_inputs("localisation_sweep.csv"))
def write_fig_localisation(out_dir: str | Path) -> list[Path]:
    """F1 against localisation error from ``localisation_sweep.csv``; none without the CSV."""
    out_dir = Path(out_dir)
    path = out_dir / "localisation_sweep.csv"
    if not path.is_file():
        return []
    sweep = pd.read_csv(path)
    if sweep.empty:
        return []
    datasets = sorted(sweep["dataset"].unique(), key=dataset_order)
    matchers = sorted(sweep["matcher"].unique(), key=matcher_order)
    colors = _colors(matchers)
    fig, axes = _figure(6.4 * len(datasets), 4.2, ncols=len(datasets))
    for col, dataset in enumerate(datasets):
        ax = axes[0, col]
        rows = sweep[sweep["dataset"] == dataset]
        _curves(ax, rows, "position_sigma_m", "f1_mean", matchers, colors)
        ax.axvline(1.2, color="grey", ls=":", lw=1)
        ax.text(1.2, 1, " GPS σ of the DMGM data", color="grey", fontsize=7, va="bottom")
        ax.set_xlabel("position error σ per axis (m); heading σ = 0.2° per 1.2 m")
        ax.set_ylabel("F1 (%)")
        ax.set_title(f"{dataset}: F1 against localisation error")
        ax.set_ylim(-2, 102)
        ax.grid(alpha=0.3)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=min(len(labels), 4), fontsize=8)
    return _save(fig, out_dir / "fig_localisation")


@drawn_once(_inputs("localisation_presets.csv"))
def write_fig_localisation_presets(out_dir: str | Path) -> list[Path]:
    """F1 against a GNSS-like preset's error scale and its message latency, from
    ``localisation_presets.csv`` (one panel per axis); none without the CSV."""
    out_dir = Path(out_dir)
    path = out_dir / "localisation_presets.csv"
    if not path.is_file():
        return []
    sweep = pd.read_csv(path)
    if sweep.empty:
        return []
    matchers = sorted(sweep["matcher"].unique(), key=matcher_order)
    colors = _colors(matchers)
    axes_info = (
        ("scale", "scale", "error scale (× the preset's bias, drift, noise, heading, outliers)"),
        ("latency", "latency_ms", "message latency (ms)"),
    )
    panels = [("f1_mean", "F1 (%)")]
    if "success_1m_2deg" in sweep.columns:
        panels.append(("success_1m_2deg", "success@(1 m, 2°) (%)"))
    fig, axes = _figure(12.8, 3.6 * len(panels), nrows=len(panels), ncols=2)
    preset = str(sweep["preset"].iloc[0]).split("*")[0].split("+")[0]
    for r, (metric, y_label) in enumerate(panels):
        for col, (axis, x_col, x_label) in enumerate(axes_info):
            ax = axes[r, col]
            rows = sweep[sweep["axis"] == axis]
            _curves(ax, rows, x_col, metric, matchers, colors)
            ax.set_xlabel(x_label)
            ax.set_ylabel(y_label)
            title = "error scale" if axis == "scale" else "latency"
            where = ", ".join(sorted(rows["dataset"].unique()))
            ax.set_title(f"{where}: {y_label.split(' (')[0]} against {preset} {title}")
            ax.set_ylim(-2, 102)
            ax.grid(alpha=0.3)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=min(len(labels), 4), fontsize=8)
    return _save(fig, out_dir / "fig_localisation_presets")


@drawn_once(_inputs("pr_curves.csv"))
def write_pr_curves(out_dir: str | Path) -> list[Path]:
    """Precision–recall curves from ``pr_curves.csv`` (one panel per dataset)."""
    out_dir = Path(out_dir)
    path = out_dir / "pr_curves.csv"
    if not path.is_file():
        return []
    curves = pd.read_csv(path)
    if curves.empty:
        return []
    datasets = sorted(curves["dataset"].unique(), key=dataset_order)
    matchers = sorted(curves["matcher"].unique(), key=matcher_order)
    colors = _colors(matchers)
    fig, axes = _figure(5 * len(datasets), 4, ncols=len(datasets))
    for ax, dataset in zip(axes[0], datasets, strict=True):
        for matcher in matchers:
            c = curves[(curves["dataset"] == dataset) & (curves["matcher"] == matcher)]
            if c.empty:
                continue
            recall = np.concatenate([[0.0], c["recall"].to_numpy()])
            precision = np.concatenate([[c["precision"].iloc[0]], c["precision"].to_numpy()])
            ax.step(
                recall, precision, where="pre", color=colors[matcher], label=method_name(matcher)
            )
        ax.set(xlim=(0, 1), ylim=(0, 1.02), xlabel="recall", ylabel="precision")
        ax.set_title(f"{dataset}: precision–recall over τ (test, runs pooled)")
        ax.grid(alpha=0.3)
    axes[0, -1].legend(fontsize=7)
    return _save(fig, out_dir / "pr_curves", (".png",))


def _line_classes(pred: np.ndarray, gt: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(correct, wrong, missed) pair arrays of a prediction against the ground truth."""
    pred, gt = np.asarray(pred, int).reshape(-1, 2), np.asarray(gt, int).reshape(-1, 2)
    in_gt = (pred[:, None, :] == gt[None, :, :]).all(axis=2).any(axis=1)
    found = (gt[:, None, :] == pred[None, :, :]).all(axis=2).any(axis=1)
    return pred[in_gt], pred[~in_gt], gt[~found]


def _verified_pair(dataset_dir: str, index: int):
    """Pair ``index`` of the dataset at ``dataset_dir``, its record verified first (as
    ``cadsim show`` does: the record drawn is the one its manifest vouches for)."""
    from cadsim.dataset import Dataset

    dataset = Dataset(dataset_dir)
    dataset.verify_record(index)
    return dataset[index]


@drawn_once(_qualitative_inputs)
def write_qualitative(out_dir: str | Path) -> list[Path]:
    """The Fig. 3-style figure from ``qualitative.json``; skipped (with a log line) when the
    datasets' images are not on this machine."""
    from cadsim.pair_drawing import (
        CORRECT,
        MISSED,
        WRONG,
        draw_birdseye,
        draw_pair,
        side_by_side,
    )

    out_dir = Path(out_dir)
    path = out_dir / "qualitative.json"
    if not path.is_file():
        return []
    spec = json.loads(path.read_text(encoding="utf-8"))
    if not spec:
        return []
    # The paper's datasets (MRC, CAD) when present — not their variants such as CAD-dense.
    datasets = sorted([d for d in spec if d in PAPER_DATASETS] or spec, key=dataset_order)
    missing = [
        spec[d]["dataset_dir"] for d in datasets if not Path(spec[d]["dataset_dir"]).is_dir()
    ]
    if missing:
        log.warning("qualitative figure skipped: datasets not found: %s", ", ".join(missing))
        return []
    pairs = {d: _verified_pair(spec[d]["dataset_dir"], spec[d]["pair"]) for d in datasets}
    datasets = [d for d in datasets if pairs[d].has_images]  # imported data: no images to draw
    if not datasets:
        return []
    methods = sorted({m for d in datasets for m in spec[d]["methods"]}, key=matcher_order)
    first = pairs[datasets[0]]
    canvas, _ = side_by_side(first.color1, first.color2)
    aspect = canvas.shape[0] / canvas.shape[1]
    width, above = 5.0, 3.6  # inches per panel; height of a bird's-eye panel
    from matplotlib.figure import Figure

    fig = Figure(
        figsize=(width * len(methods), (width * aspect + above) * len(datasets) + 0.6),
        layout="constrained",
    )
    ratios = [width * aspect, above] * len(datasets)
    axes = fig.subplots(2 * len(datasets), len(methods), squeeze=False, height_ratios=ratios)
    from matplotlib.collections import LineCollection

    for row, dataset in enumerate(datasets):
        pair, entry = pairs[dataset], spec[dataset]
        gt = np.asarray(entry["gt_pairs"], int).reshape(-1, 2)
        for col, method in enumerate(methods):
            ax = axes[2 * row, col]
            pred = np.asarray(entry["methods"].get(method, []), int).reshape(-1, 2)
            correct, wrong, missed = _line_classes(pred, gt)
            shown = np.vstack([correct, wrong])
            colors = [CORRECT] * len(correct) + [WRONG] * len(wrong)
            draw_pair(
                ax, pair.color1, pair.color2, pair.view1.boxes, pair.view2.boxes, shown, colors
            )
            if len(missed):
                _, offset = side_by_side(pair.color1, pair.color2)
                b1, b2 = np.asarray(pair.view1.boxes, float), np.asarray(pair.view2.boxes, float)
                c1 = (b1[missed[:, 0], :2] + b1[missed[:, 0], 2:]) / 2
                c2 = (b2[missed[:, 1], :2] + b2[missed[:, 1], 2:]) / 2 + [offset, 0]
                ax.add_collection(
                    LineCollection(
                        np.stack([c1, c2], axis=1), colors=MISSED, linewidths=1.5, linestyles="--"
                    )
                )
            ax.set_title(
                f"{dataset} pair {entry['pair']} — {method_name(method)}: {len(correct)} correct, "
                f"{len(wrong)} wrong, {len(missed)} missed",
                fontsize=8,
            )
            birdseye = axes[2 * row + 1, col]
            if pair.cameras is None:
                birdseye.set_axis_off()
                continue
            draw_birdseye(
                birdseye,
                pair,
                [(correct, CORRECT, "-"), (wrong, WRONG, "-"), (missed, MISSED, "--")],
            )
            birdseye.set_title("from above (true positions)", fontsize=7)
    return _save(fig, out_dir / "qualitative")


@drawn_once(_inputs("external/prior_sensitivity.csv"))
def write_fig_prior_sensitivity(out_dir: str | Path) -> list[Path]:
    """``fig_prior_sensitivity.png/.pdf``: per prior matcher, pooled test F1 of every grid
    configuration (dots), the one chosen on sequence 070 ringed, the defaults marked."""
    out_dir = Path(out_dir)
    path = (
        out_dir / "external" / "prior_sensitivity.csv"
    )  # eval.studies.external.prior_defaults writes it
    if not path.is_file():
        return []
    table = pd.read_csv(path)
    matchers = list(dict.fromkeys(table["matcher"]))
    colors = _colors(matchers)
    fig, axes = _figure(7.0, 3.6)
    ax = axes[0, 0]
    for x, name in enumerate(matchers):
        rows = table[table["matcher"] == name]
        y = 100 * rows["test_f1_pooled"].to_numpy()
        offsets = (rows["config"].to_numpy() - (len(rows) - 1) / 2) * 0.06
        ax.scatter(x + offsets, y, s=22, color=colors[name], zorder=3)
        chosen = rows["chosen"].to_numpy(bool)
        ax.scatter(x + offsets[chosen], y[chosen], s=110, facecolor="none", edgecolor="black",
                   zorder=4, label="chosen on 070" if x == 0 else None)  # fmt: skip
        default = (rows["params"] == "{}").to_numpy()
        ax.scatter(x + offsets[default], y[default], marker="x", s=40, color="black", zorder=5,
                   label="defaults" if x == 0 else None)  # fmt: skip
    ax.set_xticks(range(len(matchers)), [method_name(m) for m in matchers], fontsize=8)
    ax.set_ylabel("pooled F1 on 069 + 071 (%)")
    ax.set_title("Prior matchers: test F1 over each tuning grid (8 configurations)", fontsize=9)
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=7, loc="lower left")
    return _save(fig, out_dir / "fig_prior_sensitivity")


FUSION_LINES = {"independent": "-", "spectral": "--", "clear": "-.", "transitive": ":"}


@drawn_once(_inputs("table_multiagent.csv"))
def write_fig_multiagent(out_dir: str | Path) -> list[Path]:
    """Pooled pairwise F1 and the cycle-violation rate against the number of agents, from
    ``table_multiagent.csv``: one column per preset, colour per two-view matcher, line style per
    fusion; none without the CSV."""
    out_dir = Path(out_dir)
    path = out_dir / "table_multiagent.csv"
    if not path.is_file():
        return []
    table = pd.read_csv(path)
    if table.empty:
        return []
    presets = list(dict.fromkeys(table["preset"]))
    matchers = sorted(table["matcher"].unique(), key=matcher_order)
    colors = _colors(matchers)
    panels = (
        ("f1_pooled", "pooled pairwise F1 (%)"),
        ("cycle_violation_rate", "cycle violations (%)"),
    )
    fig, axes = _figure(6.4 * len(presets), 7.2, nrows=2, ncols=len(presets))
    for col, preset in enumerate(presets):
        for r, (metric, y_label) in enumerate(panels):
            ax = axes[r, col]
            rows = table[table["preset"] == preset]
            for (matcher, fusion), line in rows.groupby(["matcher", "fusion"], sort=False):
                line = line.sort_values("n_agents")
                ax.plot(
                    line["n_agents"],
                    100 * line[metric],
                    color=colors[matcher],
                    ls=FUSION_LINES.get(fusion, "-"),
                    marker=_marker(matcher),
                    ms=4,
                    label=f"{matcher} + {fusion}",
                )
            ax.set_xlabel("agents N (views 1-2 vehicles, a roadside unit from N = 3)")
            ax.set_ylabel(y_label)
            ax.set_title(f"{preset}: {y_label.split(' (')[0]} against N")
            ax.set_xticks(sorted(table["n_agents"].unique()))
            ax.set_ylim(-2, 102)
            ax.grid(alpha=0.3)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=4, fontsize=7)
    return _save(fig, out_dir / "fig_multiagent")


def render_all(out_dir: str | Path) -> list[Path]:
    """Every figure whose inputs are in `out_dir`."""
    return (
        write_fig4(out_dir)
        + write_pr_curves(out_dir)
        + write_fig_regime(out_dir)
        + write_fig_localisation(out_dir)
        + write_fig_localisation_presets(out_dir)
        + write_qualitative(out_dir)
        + write_fig_prior_sensitivity(out_dir)
        + write_fig_multiagent(out_dir)
    )
