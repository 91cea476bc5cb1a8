"""Does a ranking of matchers on our simulation predict their ranking elsewhere?

``results/agreement.csv`` (dataset, reference, matchers, rho, ci_low, ci_high): Spearman's ρ
between the matchers' F1 (mean per-pair F1 at τ, all runs) on one of our test datasets — or the
paper's Table I column, F1 = 2PR/(P+R) from its printed means — and their F1 on the external test
pairs (DMGM CAD sequences 069 + 071). The matchers are those both sides evaluated that run without
a localisation prior, ``none`` left out (its F1 is 0 everywhere by construction, a free point of
agreement). The 95 % interval is a percentile bootstrap (B = 2000, fixed seed) over *clusters*,
never single pairs: on each side, independently, its clusters are drawn with replacement — our
datasets' simulation episodes, and on the external side blocks of :data:`EXTERNAL_BLOCK`
consecutive frame pairs of one driving sequence (its two sequences are too few clusters, and
consecutive frames are near-copies) — and every matcher keeps the same drawn pairs, so the
matchers stay paired within a side; the paper's column has no pairs and is held fixed. A rank
statistic has no t-interval, and a delete-one-cluster jackknife gives zero width whenever no
single cluster changes the ranking, so the bootstrap it is; with 10 episodes it is still a little
optimistic (a percentile bootstrap of a mean covers about 90 % at 10 clusters). Inputs: ``metrics_per_pair.csv`` and ``external/metrics_per_pair.csv`` of one
results folder; nothing is re-run.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from scipy.stats import rankdata

from eval.core.result_files import write_csv
from eval.engine.result_table import read_result
from eval.report.tables import PAPER_CSV, PAPER_NAMES, dataset_order, load_paper

REFERENCE = "DMGM CAD 069+071"
BOOTSTRAP = 2000
SEED = 0
EXTERNAL_BLOCK = 10  # consecutive frame pairs of one sequence per cluster
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


def pair_clusters(per_pair: pd.DataFrame, block: int | None = None) -> pd.Series:
    """The cluster of each frame pair (index: pair, as :func:`pair_f1`'s columns): its episode,
    or with ``block`` the episode and the block of ``block`` consecutive pairs within it."""
    episodes = per_pair.groupby("pair")["episode"].first().sort_index()
    if block is None:
        return episodes.astype(str)
    rank = episodes.groupby(episodes).cumcount()
    return episodes.astype(str) + "/" + (rank // block).astype(str)


def _cluster_sums(
    table: pd.DataFrame, clusters: pd.Series | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(per-matcher mean over complete pairs (k,), per-cluster sums (k, G), pairs per cluster
    (G,)); each pair its own cluster when ``clusters`` is None."""
    values = table.to_numpy(float)
    complete = ~np.isnan(values).any(axis=0)
    labels = (
        np.arange(values.shape[1]).astype(str)
        if clusters is None
        else clusters.reindex(table.columns).astype(str).to_numpy()
    )
    values, labels = values[:, complete], labels[complete]
    _, index = np.unique(labels, return_inverse=True)
    sums = np.zeros((values.shape[0], index.max(initial=-1) + 1))
    np.add.at(sums.T, index, values.T)
    return values.mean(axis=1), sums, np.bincount(index).astype(float)


def _resampled_means(
    sums: np.ndarray, counts: np.ndarray, rng: np.random.Generator, draws: int
) -> np.ndarray:
    """(draws, k) pair-weighted means over with-replacement draws of the clusters, the same
    draw for every matcher."""
    g = len(counts)
    weights = rng.multinomial(g, np.full(g, 1 / g), size=draws).astype(float)  # (draws, G)
    return (weights @ sums.T) / (weights @ counts)[:, None]


def agreement(
    ours: pd.DataFrame | None,
    reference: pd.DataFrame,
    paper_f1: pd.Series | None = None,
    ours_clusters: pd.Series | None = None,
    reference_clusters: pd.Series | None = None,
    draws: int = BOOTSTRAP,
    seed: int = SEED,
) -> dict:
    """ρ and its cluster-bootstrap interval between one side (`ours`: matcher × pair F1 table,
    or `paper_f1`: F1 per matcher, held fixed) and `reference` (matcher × pair F1 table); the
    clusters map each pair (column) to its cluster (None: every pair its own)."""
    side = ours.index if ours is not None else paper_f1.index
    matchers = [m for m in reference.index if m in set(side) and m not in EXCLUDED]
    if len(matchers) < 3:
        return {"matchers": ";".join(matchers), "rho": np.nan, "ci_low": np.nan, "ci_high": np.nan}
    rng = np.random.default_rng(seed)
    ref_point, ref_sums, ref_counts = _cluster_sums(reference.loc[matchers], reference_clusters)
    ref_boot = _resampled_means(ref_sums, ref_counts, rng, draws)
    if ours is not None:
        point_mine, sums, counts = _cluster_sums(ours.loc[matchers], ours_clusters)
        boot_mine = _resampled_means(sums, counts, rng, draws)
    else:
        point_mine = paper_f1.loc[matchers].to_numpy(float)
        boot_mine = np.broadcast_to(point_mine, ref_boot.shape)
    rho = float(spearman_rows(point_mine, ref_point)[0])
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
    """Write ``out_dir/agreement.csv`` from ``out_dir/metrics_per_pair.csv`` (and the V2X task's
    ``out_dir/v2x/metrics_per_pair.csv`` under its own preset, when there) and
    ``out_dir/external/metrics_per_pair.csv``; an empty table when either of the first and the
    last is missing."""
    from eval.engine.matcher_list import prior_matchers
    from eval.studies.external.evaluation import SUBDIR
    from eval.studies.v2x.table import SUBDIR as V2X_SUBDIR
    from eval.studies.v2x.table import TUNE_PRESET as V2X_PRESET

    out_dir = Path(out_dir)
    ours_path = out_dir / "metrics_per_pair.csv"
    ext_path = out_dir / SUBDIR / "metrics_per_pair.csv"
    rows = []
    if ours_path.is_file() and ext_path.is_file():
        priors = set(prior_matchers())
        external = pd.read_csv(ext_path, keep_default_na=False, na_values=[""])
        external = external[~external["matcher"].str.partition("[")[0].isin(priors)]
        reference = pair_f1(external)
        blocks = pair_clusters(external, EXTERNAL_BLOCK)
        per_pair = pd.read_csv(ours_path, keep_default_na=False, na_values=[""])
        v2x_path = out_dir / V2X_SUBDIR / "metrics_per_pair.csv"
        if v2x_path.is_file():  # the V2X task, under its scenario's own preset
            v2x = pd.read_csv(v2x_path, keep_default_na=False, na_values=[""])
            per_pair = pd.concat([per_pair, v2x[v2x["preset"] == V2X_PRESET]], ignore_index=True)
        for dataset in sorted(per_pair["dataset"].unique(), key=dataset_order):
            mine = per_pair[per_pair["dataset"] == dataset]
            found = agreement(pair_f1(mine), reference, None, pair_clusters(mine), blocks)
            rows.append({"dataset": dataset, "reference": REFERENCE} | found)
        for dataset, f1 in sorted(paper_f1(paper_csv).items(), key=lambda kv: dataset_order(kv[0])):
            rows.append(
                {"dataset": f"paper {dataset}", "reference": REFERENCE}
                | agreement(None, reference, paper_f1=f1, reference_clusters=blocks)
            )
    table = pd.DataFrame(rows, columns=COLUMNS)
    write_csv(table.round(4), out_dir / "agreement.csv")
    return table


def to_markdown(table: pd.DataFrame) -> str:
    """A short Markdown table of ρ with its interval."""
    from eval.report.markdown_cell import cell as md_cell

    lines = [
        "| Ranking on | vs ranking on | matchers | Spearman ρ [95 % CI] |",
        "|:---|:---|---:|---:|",
    ]
    for _, r in table.iterrows():
        count = len(str(r["matchers"]).split(";")) if r["matchers"] else 0
        cell = (
            "–" if pd.isna(r["rho"]) else f"{r['rho']:.2f} [{r['ci_low']:.2f}, {r['ci_high']:.2f}]"
        )
        lines.append(f"| {md_cell(r['dataset'])} | {md_cell(r['reference'])} | {count} | {cell} |")
    return "\n".join(lines) + "\n"


def readme_part(results: Path, rel: str) -> list[str]:
    """README lines for ``agreement.csv`` (none without it or when it is empty)."""
    table = read_result(results, "agreement.csv")
    if table is None:
        return []
    return [
        "### Do these rankings hold on external data?",
        "",
        to_markdown(table).strip(),
        "",
        "Spearman's ρ between the matchers' F1 on each dataset (or the paper's Table I column) "
        f"and on the external DMGM CAD test pairs, same matchers, none given the localisation "
        f"prior; 95 % interval from a bootstrap over clusters of both sides (simulation "
        f"episodes; blocks of 10 consecutive external pairs), never single pairs "
        f"(`{rel}/agreement.csv`).",
        "",
    ]
