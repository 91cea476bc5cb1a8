"""The claims of the paper's benchmark: Table I's ranks and rivals, the agreement with the paper,
Fig. 4's F1 leaders, the regime sweep and the paper-protocol ranking — each read from the
committed result CSVs, every choice made on validation (``thresholds*.csv``: each matcher's
validation F1 at its chosen parameters and τ), every interval over simulation episodes.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd

from eval.core.spreadsheet_safe import restore
from eval.protocol.claims import (
    CROSSES,
    NOT_SHOWN,
    Claim,
    difference_claim,
    finite,
    goal_claim,
    point_claim,
)
from eval.protocol.rank_interval import rank_interval
from eval.report.tables import PAPER_COLUMN, PAPER_NAMES, dataset_order, method_name

STUDY = "benchmark"
RIVALS = ("mos", "rrwhm")
PROTOCOLS = {"_equal_cues": "equal cues", "": "as published"}


def read(path: Path) -> pd.DataFrame | None:
    """The CSV at ``path`` (empty strings as missing), or None when absent."""
    return (
        restore(pd.read_csv(path, keep_default_na=False, na_values=[""]))
        if path.is_file()
        else None
    )


def pct(value: float, digits: int = 1) -> str:
    """A fraction in percent ("–" when missing)."""
    return f"{100 * float(value):.{digits}f}" if finite(value) else "–"


def pp_interval(diff: float, low: float, high: float) -> str:
    """A difference of fractions in percentage points: ``+d [lo, hi]``."""
    return f"{100 * diff:+.1f} [{100 * low:+.1f}, {100 * high:+.1f}]"


def _validation_f1(results: Path, suffix: str, dataset: str) -> pd.Series:
    """{matcher: validation F1} of one dataset (``thresholds{suffix}.csv``); empty without it."""
    table = read(results / f"thresholds{suffix}.csv")
    if table is None or not {"dataset", "matcher", "val_f1"} <= set(table.columns):
        return pd.Series(dtype=float)
    rows = table[table["dataset"] == dataset].drop_duplicates("matcher")
    return rows.set_index("matcher")["val_f1"].astype(float)


def _rank(results: Path, suffix: str, dataset: str, names: list[str]):
    """(rank, low, high, episodes) of maximin among ``names`` by test F1, or None without the
    per-pair file."""
    per_pair = read(results / f"metrics_per_pair{suffix}.csv")
    if per_pair is None or "episode" not in per_pair.columns:
        return None
    rows = per_pair[(per_pair["dataset"] == dataset) & (per_pair["split"] == "test")]
    try:
        return rank_interval(rows, "maximin", names)
    except ValueError:
        return None


def table1_claims(results: Path, suffix: str, study: str = "table1") -> list[Claim]:
    """Per dataset of ``table1{suffix}.csv``: maximin's rank among the paper's methods (episode
    bootstrap interval; "first, as in the paper" met only when the whole interval is rank 1), the
    other paper method of highest *validation* F1 and maximin − it on test F1 (paired episode
    interval), and the matcher of highest validation F1 of all. ``study`` "table1": statements
    are the compact table's cells; "agreement": the sentences of the agreement bullets."""
    table = read(results / f"table1{suffix}.csv")
    if table is None or not {"dataset", "matcher", "f1_mean"} <= set(table.columns):
        return []
    paired = read(results / f"paired_differences{suffix}.csv")
    protocol = PROTOCOLS[suffix]
    sentences = study == "agreement"
    out = []
    for dataset in sorted(table["dataset"].unique(), key=dataset_order):
        rows = table[table["dataset"] == dataset].set_index("matcher")
        names = [m for m in rows.index if m in PAPER_NAMES]
        if "maximin" not in names:
            continue
        subject = f"maximin on {dataset} ({protocol})"
        paper = PAPER_COLUMN.get(dataset, dataset)
        ranked = _rank(results, suffix, dataset, names)
        if ranked is not None:
            rank, low, high, episodes = ranked
            claim = goal_claim(
                study, subject, "rank_f1", rank, low, high, 1.0, at_least=False,
                comparison="first of the paper's methods", statement="", chosen_on="fixed",
                clusters=f"{episodes} simulation episodes (bootstrap)",
                source=f"metrics_per_pair{suffix}.csv",
            )  # fmt: skip
            text = (
                f"maximin ranks {rank} of {len(names)} of the paper's methods by test F1 "
                f"({pct(rows.loc['maximin', 'f1_mean'])}; 95 % interval over episodes: ranks "
                f"{low}–{high}); first, as on {paper} in the paper: {claim.verdict}"
                if sentences
                else f"{rank} of {len(names)} [{low}–{high}]"
            )
            out.append(replace(claim, statement=text))
        validation = _validation_f1(results, suffix, dataset)
        others = validation[validation.index.isin([m for m in names if m != "maximin"])]
        if len(others) and paired is not None:
            rival = str(others.sort_values(ascending=False, kind="stable").index[0])
            hit = paired[
                (paired["dataset"] == dataset)
                & (paired["matcher_b"] == rival)
                & (paired["metric"] == "f1")
            ]
            if len(hit):
                r = hit.iloc[0]
                shown = pp_interval(r["diff"], r["ci_low"], r["ci_high"])
                claim = difference_claim(
                    study, subject, rival, "f1", r["diff"], r["ci_low"], r["ci_high"],
                    statement=shown, chosen_on="validation",
                    clusters=f"{int(r['episodes'])} simulation episodes (cluster t-interval)",
                    source=f"paired_differences{suffix}.csv",
                )  # fmt: skip
                if sentences:
                    shown = (
                        f"maximin − {method_name(rival)} (the other paper method of highest "
                        f"validation F1; {pct(rows.loc[rival, 'f1_mean'])} on test) = {shown} pp "
                        f"F1: maximin {claim.verdict}, an interval that "
                        + ("includes 0" if claim.verdict == NOT_SHOWN else "excludes 0")
                    )
                out.append(replace(claim, statement=shown))
        valid = validation[validation.index.isin(rows.index)]
        if len(valid) and not sentences:
            best = str(valid.sort_values(ascending=False, kind="stable").index[0])
            out.append(
                point_claim(
                    study, f"{dataset} ({protocol})", "best of all matchers on validation",
                    "f1", rows.loc[best, "f1_mean"],
                    statement=f"{method_name(best)} {pct(rows.loc[best, 'f1_mean'])}",
                    chosen_on="validation", source=f"thresholds{suffix}.csv",
                )
            )  # fmt: skip
    return out


def noise_claims(results: Path, matchers_excluded: tuple[str, ...] = ("none",)) -> list[Claim]:
    """Fig. 4: per swept dataset and noise rate, the matcher of highest mean test F1 — a point
    value chosen on test (``chosen_on = test``, and its statement says so; ``noise_runs.csv``
    holds runs, not frame pairs: no interval), never a verdict."""
    runs = read(results / "noise_runs.csv")
    if runs is None or not {"dataset", "matcher", "noise_rate", "f1"} <= set(runs.columns):
        return []
    out = []
    for dataset, rows in runs.groupby("dataset", sort=False):
        rows = rows[~rows["matcher"].isin(matchers_excluded)]
        means = rows.groupby(["noise_rate", "matcher"])["f1"].mean()
        for rate in sorted(rows["noise_rate"].unique()):
            at = means.loc[rate]
            leader = str(at.idxmax())
            out.append(
                point_claim(
                    "fig4", f"{leader} on {dataset}", f"F1 leader at noise rate {rate:g}", "f1",
                    at.max(),
                    statement=f"F1 leader at {rate:g}: {method_name(leader)} {pct(at.max())} "
                    "(point value, chosen on test)",
                    chosen_on="test", source="noise_runs.csv",
                )
            )  # fmt: skip
    return out


def regime_sweep_claims(results: Path) -> list[Claim]:
    """The regime sweep: a crossover stated only where ``crossovers.csv``'s interval excludes "no
    crossing" (the share interval); else "no crossover" and the mean F1 difference over the
    swept shares as a point value (``regime_sweep.csv`` holds no paired frame-pair figures)."""
    crossovers = read(results / "crossovers.csv")
    sweep = read(results / "regime_sweep.csv")
    if crossovers is None or sweep is None:
        return []
    out = []
    f1 = crossovers[crossovers["metric"] == "f1"]
    for (dataset, rival), group in f1.groupby(["dataset", "matcher_b"], sort=False):
        rows = sweep[sweep["dataset"] == dataset]
        lo, hi = 100 * rows["share"].min(), 100 * rows["share"].max()
        name = method_name(rival)
        subject = f"maximin on {dataset}"
        significant = group[group["significant"].astype(str).str.lower() == "true"]
        for _, r in significant.iterrows():
            at, low, high = (
                100 * r[k] for k in ("crossing_share", "share_ci_low", "share_ci_high")
            )
            where = f"{at:.0f} % non-covisible (95 % interval {low:.0f}–{high:.0f} %)"
            text = (
                f"maximin overtakes {name} above {where}"
                if r["direction"] == "a_gains"
                else f"maximin leads {name} below {where} and trails above"
            )
            out.append(
                Claim(
                    "regime_sweep", subject, rival, "f1 crossover share", r["crossing_share"],
                    r["share_ci_low"], r["share_ci_high"], np.nan, "crossover", CROSSES,
                    "fixed", "episodes and thinning draws (bootstrap)", "crossovers.csv",
                    f"{dataset}: {text}",
                )
            )  # fmt: skip
        if len(significant):
            continue
        crossed = group["crossing_share"].notna().any()
        a = rows[rows["matcher"] == "maximin"].set_index("keep")["f1_mean"]
        b = rows[rows["matcher"] == rival].set_index("keep")["f1_mean"]
        mean = float((a - b).mean())
        out.append(
            Claim(
                "regime_sweep", subject, rival, "f1 crossover share", np.nan, np.nan, np.nan,
                np.nan, "crossover", NOT_SHOWN, "fixed",
                "episodes and thinning draws (bootstrap)", "crossovers.csv",
                f"{dataset}: no crossover with {name} that its interval supports"
                + (" (the mean curves cross, within their noise)" if crossed else ""),
            )
        )  # fmt: skip
        if not finite(mean):  # the rival is not in the sweep's table
            continue
        out.append(
            point_claim(
                "regime_sweep", subject, rival, "mean f1 difference over shares", mean,
                statement=f"maximin − {name} {100 * mean:+.1f} points F1 on average over shares "
                f"{lo:.0f}–{hi:.0f} % (point value: no paired interval, the sweep keeps no "
                "per-pair figures)",
                chosen_on="fixed", source="regime_sweep.csv",
            )
        )  # fmt: skip
    return out


def paper_protocol_claims(results: Path) -> list[Claim]:
    """Under the paper's protocol: Spearman ρ between our accuracy ranking and the paper's (a
    point value; eight methods, no interval)."""
    table = read(results / "table1_paper_protocol.csv")
    if table is None or "paper_accuracy_mean" not in table.columns:
        return []
    out = []
    for dataset in sorted(table["dataset"].unique(), key=dataset_order):
        rows = table[(table["dataset"] == dataset) & table["paper_accuracy_mean"].notna()]
        if len(rows) < 3:
            continue
        ours = rows["accuracy_mean"].rank().to_numpy()
        theirs = rows["paper_accuracy_mean"].rank().to_numpy()
        rho = float(np.corrcoef(ours, theirs)[0, 1])
        order = rows.sort_values("accuracy_mean", ascending=False)["method"].tolist()
        out.append(
            point_claim(
                "paper_protocol", f"our accuracy ranking on {dataset}", "the paper's ranking",
                "spearman_rho", rho,
                statement=f"{dataset}: Spearman ρ = {rho:.2f} with the paper's accuracy ranking "
                f"(point value); ours by accuracy: {', '.join(order[:3])} first",
                chosen_on="fixed", source="table1_paper_protocol.csv",
            )
        )  # fmt: skip
    return out


def benchmark_claims(results: Path) -> list[Claim]:
    """Every claim of the paper's benchmark part of the report."""
    results = Path(results)
    suffix = "_equal_cues" if (results / "table1_equal_cues.csv").is_file() else ""
    return [
        *table1_claims(results, suffix),
        *table1_claims(results, "", "agreement"),
        *noise_claims(results),
        *regime_sweep_claims(results),
        *paper_protocol_claims(results),
    ]
