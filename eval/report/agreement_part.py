"""The report's "Where we agree with the paper, and where not": per dataset the claims on
maximin's rank and its rival chosen on validation, what abstaining earns, what tuning moved, the
paper-protocol ranking, the regime sweep's crossovers and Fig. 4's leaders — each comparative
sentence a claim's statement (``claims.csv``), the rest read from the tables."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from eval.protocol.claims import statements
from eval.report.benchmark_parts import pct, plural, read_table, spread_text
from eval.report.tables import PAPER_NAMES, dataset_order, method_name, params_text

RIVALS = ("mos", "rrwhm")


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
            f"{r['dataset']}: accuracy {pct(r['accuracy_mean'])} (above {beaten} of "
            f"{len(others)} methods), balanced accuracy {pct(r['balanced_accuracy_mean'])}, "
            f"{plural(below, 'method')} below 50"
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
        f"{method_name(r['matcher'])} on {r['dataset']} {pct(r['f1_mean_untuned'])} → "
        f"{pct(r['f1_mean'])} ({params_text(r.get('params'))})"
        for _, r in top.iterrows()
    ]
    return ["**Tuning** on validation moved F1 most for " + "; ".join(parts) + "."]


def _subject_claims(claims: pd.DataFrame, study: str, subject: str) -> list[str]:
    rows = claims[(claims["study"] == study) & (claims["subject"] == subject)]
    return [str(x) for x in rows["statement"]]


def _agreement(claims: pd.DataFrame, regime: pd.DataFrame | None) -> list[str]:
    """Bullets: per dataset, maximin's rank with its interval and its rival chosen on
    validation (the "agreement" claims)."""
    bullets = []
    mine = claims[claims["study"] == "agreement"]
    for subject in dict.fromkeys(mine["subject"]):
        dataset = str(subject).removeprefix("maximin on ").rsplit(" (", 1)[0]
        said = _subject_claims(claims, "agreement", subject)
        bullets.append(f"**{dataset}**{_regime_phrase(regime, dataset)}: " + "; ".join(said) + ".")
    return bullets


def _paper_protocol(claims: pd.DataFrame) -> list[str]:
    said = statements(claims, "paper_protocol")
    if not said:
        return []
    return [
        "**The paper's protocol** (image-space pairwise terms, full assignment, no τ): "
        + "; ".join(said)
        + "."
    ]


def _crossovers(claims: pd.DataFrame) -> list[str]:
    """Bullet: the regime sweep's claims — a crossover only where its interval excludes "no
    crossing", the mean difference over the swept shares as a labelled point value."""
    said = statements(claims, "regime_sweep")
    if not said:
        return []
    return [
        "**Regime sweep** (F1 against the non-covisible share; a crossover is stated only where "
        'its interval, episodes and thinning draws resampled, excludes "no crossing"): '
        + "; ".join(said)
        + "."
    ]


def _noise(noise: pd.DataFrame | None, claims: pd.DataFrame) -> list[str]:
    """Bullets, one per swept dataset: F1 at the lowest and highest noise rate for maximin and
    its rivals, and the Fig. 4 claims at the rates where the F1 leader changes (point values)."""
    if noise is None or "f1" not in noise.columns:
        return []
    fig4 = claims[claims["study"] == "fig4"]
    bullets = []
    for dataset, rows in noise.groupby("dataset", sort=False):
        means = rows.groupby(["matcher", "noise_rate"])["f1"].mean()
        rates = sorted(rows["noise_rate"].unique())
        mine = fig4[fig4["subject"].str.endswith(f" on {dataset}")]
        if len(rates) < 2 or mine.empty:
            continue
        parts = [
            f"{method_name(m)} {pct(means.loc[(m, rates[0])])} → {pct(means.loc[(m, rates[-1])])}"
            for m in ("maximin", *RIVALS)
            if m in means.index.get_level_values(0)
        ]
        leaders = [str(s).rsplit(" on ", 1)[0] for s in mine["subject"]]
        said = [
            str(mine["statement"].iloc[k])
            for k in range(len(leaders))
            if k == 0 or leaders[k] != leaders[k - 1]
        ]
        lead = said[0] + (
            ", the same at every rate" if len(said) == 1 else "; " + "; ".join(said[1:])
        )
        bullets.append(
            f"**Noise, {dataset}** (Fig. 4, F1 from rate {rates[0]:g} to {rates[-1]:g}): "
            + ", ".join(parts)
            + f"; {lead}."
        )
    return bullets


def agreement_bullets(results: Path, claims: pd.DataFrame) -> list[str]:
    """'Where we agree with the paper, and where not', from the tables in ``results`` and the
    claims built from them."""
    table = read_table(results / "table1.csv")
    if table is None:
        return []
    regime = read_table(results / "regime.csv")
    bullets = _agreement(claims, regime) + _baselines(table)
    bullets += _tuning(table, read_table(results / "table1_untuned.csv"))
    bullets += _paper_protocol(claims)
    bullets += _crossovers(claims)
    bullets += _noise(read_table(results / "noise_runs.csv"), claims)
    spread = read_table(results / "dataset_spread.csv")
    if spread is not None and len(spread):
        bullets.append(
            f"**Dataset spread** (F1 over {spread['generated'].nunique()} generated "
            f"{spread['dataset'].iloc[0]} datasets): {spread_text(spread)}."
        )
    return [f"- {b}" for b in bullets]


def agreement_part(results: Path, claims: pd.DataFrame) -> list[str]:
    """The section: its heading and :func:`agreement_bullets`."""
    bullets = agreement_bullets(results, claims)
    if not bullets:
        return []
    return [
        "### Where we agree with the paper, and where not",
        "",
        "(Computed from the tables above and their claims, `claims.csv`; percent, differences "
        "in percentage points. These bullets compare like with like: each matcher with the cues "
        "the paper published for it, `table1.csv` — the headline Table I above gives every "
        "matcher the same cues, `table1_equal_cues.csv`, so its figures differ.)",
        "",
        *bullets,
        "",
    ]
