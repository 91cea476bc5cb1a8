"""Does a ranking of matchers on our simulation predict their ranking elsewhere?

``results/agreement.csv`` (dataset, reference, matchers, rho, ci_low, ci_high): Spearman's ρ
between the matchers' F1 (mean per-pair F1 at τ, all runs) on one of our test datasets — or the
paper's Table I column, F1 = 2PR/(P+R) from its printed means — and their F1 on the external test
pairs (DMGM CAD sequences 069 + 071). The matchers are those both sides evaluated that run without
a localisation prior, ``none`` left out (its F1 is 0 everywhere by construction, a free point of
agreement). The 95 % interval is a percentile bootstrap (B = 2000, fixed seed) that resamples the
frame pairs of each side independently, with replacement — every matcher keeps the same resampled
pairs, so the matchers stay paired within a side; the paper's column has no pairs to resample and
is held fixed. Inputs: ``metrics_per_pair.csv`` and ``external/metrics_per_pair.csv`` of one
results folder; nothing is re-run.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from scipy.stats import rankdata

from eval.core.result_files import write_csv
from eval.report.tables import PAPER_CSV, PAPER_NAMES, dataset_order, load_paper

REFERENCE = "DMGM CAD 069+071"
BOOTSTRAP = 2000
SEED = 0
EXCLUDED = ("none",)
COLUMNS = ["dataset", "reference", "matchers", "rho", "ci_low", "ci_high"]


def pair_f1(per_pair: pd.DataFrame) -> pd.DataFrame:
    """(matcher × frame pair) table of F1 averaged over runs, from per-pair metrics rows of one
    dataset (columns matcher, pair, f1)."""
    return per_pair.groupby(["matcher", "pair"])["f1"].mean().unstack("pair")


def spearman_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Spearman's ρ of each row of (B, k) `a` with the same row of `b` (average ranks for ties;
    NaN where a row is constant)."""
    ra = rankdata(np.atleast_2d(a), axis=1)
    rb = rankdata(np.atleast_2d(b), axis=1)
    ra -= ra.mean(axis=1, keepdims=True)
    rb -= rb.mean(axis=1, keepdims=True)
    denom = np.sqrt((ra**2).sum(axis=1) * (rb**2).sum(axis=1))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(denom > 0, (ra * rb).sum(axis=1) / np.where(denom > 0, denom, 1), np.nan)


def _resampled_means(f1: np.ndarray, rng: np.random.Generator, draws: int) -> np.ndarray:
    """(draws, k) means over a with-replacement resample of the columns (frame pairs) of (k, P)
    `f1`, the same resample for every row."""
    n = f1.shape[1]
    idx = rng.integers(0, n, size=(draws, n))
    return f1[:, idx].mean(axis=2).T


def agreement(
    ours: pd.DataFrame | None,
    reference: pd.DataFrame,
    paper_f1: pd.Series | None = None,
    draws: int = BOOTSTRAP,
    seed: int = SEED,
) -> dict:
    """ρ and its bootstrap interval between one side (`ours`: matcher × pair F1 table, or
    `paper_f1`: F1 per matcher) and `reference` (matcher × pair F1 table)."""
    side = ours.index if ours is not None else paper_f1.index
    matchers = [m for m in reference.index if m in set(side) and m not in EXCLUDED]
    if len(matchers) < 3:
        return {"matchers": ";".join(matchers), "rho": np.nan, "ci_low": np.nan, "ci_high": np.nan}
    ref = reference.loc[matchers].to_numpy(float)
    ref = ref[:, ~np.isnan(ref).any(axis=0)]
    rng = np.random.default_rng(seed)
    ref_boot = _resampled_means(ref, rng, draws)
    if ours is not None:
        mine = ours.loc[matchers].to_numpy(float)
        mine = mine[:, ~np.isnan(mine).any(axis=0)]
        point_mine, boot_mine = mine.mean(axis=1), _resampled_means(mine, rng, draws)
    else:
        point_mine = paper_f1.loc[matchers].to_numpy(float)
        boot_mine = np.broadcast_to(point_mine, ref_boot.shape)
    rho = float(spearman_rows(point_mine, ref.mean(axis=1))[0])
    boot = spearman_rows(boot_mine, ref_boot)
    low, high = np.nanpercentile(boot, [2.5, 97.5]) if np.isfinite(boot).any() else (np.nan,) * 2
    return {"matchers": ";".join(matchers), "rho": rho, "ci_low": low, "ci_high": high}


def paper_f1(path: str | Path = PAPER_CSV) -> dict[str, pd.Series]:
    """{paper dataset: F1 per registry matcher name} from the paper's printed P and R (percent)."""
    paper = load_paper(path)
    names = {v: k for k, v in PAPER_NAMES.items()}
    out = {}
    for dataset, rows in paper.groupby("dataset"):
        p, r = rows["precision_mean"] / 100, rows["recall_mean"] / 100
        f1 = np.where(p + r > 0, 2 * p * r / np.where(p + r > 0, p + r, 1), 0.0)
        out[str(dataset)] = pd.Series(f1, index=rows["method"].map(names)).dropna()
    return out


def write_agreement(out_dir: str | Path, paper_csv: str | Path = PAPER_CSV) -> pd.DataFrame:
    """Write ``out_dir/agreement.csv`` from ``out_dir/metrics_per_pair.csv`` and
    ``out_dir/external/metrics_per_pair.csv``; an empty table when either is missing."""
    from eval.studies.external import SUBDIR, prior_matchers

    out_dir = Path(out_dir)
    ours_path = out_dir / "metrics_per_pair.csv"
    ext_path = out_dir / SUBDIR / "metrics_per_pair.csv"
    rows = []
    if ours_path.is_file() and ext_path.is_file():
        priors = set(prior_matchers())
        external = pd.read_csv(ext_path, keep_default_na=False, na_values=[""])
        external = external[~external["matcher"].str.partition("[")[0].isin(priors)]
        reference = pair_f1(external)
        per_pair = pd.read_csv(ours_path, keep_default_na=False, na_values=[""])
        for dataset in sorted(per_pair["dataset"].unique(), key=dataset_order):
            table = pair_f1(per_pair[per_pair["dataset"] == dataset])
            rows.append({"dataset": dataset, "reference": REFERENCE} | agreement(table, reference))
        for dataset, f1 in sorted(paper_f1(paper_csv).items(), key=lambda kv: dataset_order(kv[0])):
            rows.append(
                {"dataset": f"paper {dataset}", "reference": REFERENCE}
                | agreement(None, reference, paper_f1=f1)
            )
    table = pd.DataFrame(rows, columns=COLUMNS)
    write_csv(table.round(4), out_dir / "agreement.csv")
    return table


def to_markdown(table: pd.DataFrame) -> str:
    """A short Markdown table of ρ with its interval."""
    lines = [
        "| Ranking on | vs ranking on | matchers | Spearman ρ [95 % CI] |",
        "|:---|:---|---:|---:|",
    ]
    for _, r in table.iterrows():
        count = len(str(r["matchers"]).split(";")) if r["matchers"] else 0
        cell = (
            "–" if pd.isna(r["rho"]) else f"{r['rho']:.2f} [{r['ci_low']:.2f}, {r['ci_high']:.2f}]"
        )
        lines.append(f"| {r['dataset']} | {r['reference']} | {count} | {cell} |")
    return "\n".join(lines) + "\n"


def readme_part(results: Path, rel: str) -> list[str]:
    """README lines for ``agreement.csv`` (none without it or when it is empty)."""
    path = Path(results) / "agreement.csv"
    if not path.is_file():
        return []
    table = pd.read_csv(path, keep_default_na=False, na_values=[""])
    if table.empty:
        return []
    return [
        "### Do these rankings hold on external data?",
        "",
        to_markdown(table).strip(),
        "",
        "Spearman's ρ between the matchers' F1 on each dataset (or the paper's Table I column) "
        f"and on the external DMGM CAD test pairs, same matchers, none given the localisation "
        f"prior; 95 % interval from a bootstrap over frame pairs of both sides "
        f"(`{rel}/agreement.csv`).",
        "",
    ]
