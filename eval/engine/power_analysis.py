"""Power analysis: how many test clusters (episodes) each headline comparison would need, measured
on a results folder's committed per-item files (per pair, per frame, per snapshot).

For a paired comparison (a − b per item, items grouped by episode) the cluster-robust (CR1)
standard error SE of the mean difference over G clusters gives the per-cluster spread s = SE·√G.
Held fixed, a sample of g clusters has

- half-width of the 95 % interval (``kind = "half_width"``): t_{0.975, g − 1} · s / √g;
- MDD at 80 % power, two-sided α = 0.05 (``kind = "mdd"``): (t_{0.975, g − 1} + t_{0.8, g − 1}) ·
  s / √g (:mod:`eval.protocol.detectable_difference`).

:func:`needed_clusters` returns the smallest g at which that figure is ≤ the goal (5 F1 points):
for large g it is n_now · (now / goal)², the t quantiles making it a little larger for small g.
The cluster-robust SE already holds the intra-cluster correlation (ICC) and the design effect, so
the ICC (:func:`eval.protocol.cluster_correlation.intra_cluster_correlation`) is reported beside
it for reading, not used to extrapolate: most splits draw one item per episode, where the ICC is
undefined (NaN) and the design effect is 1. docs/evaluation.md, "Power analysis", states the
method; the studies name what they cover (``Study.power``); :func:`write_power_analysis` writes
``power_analysis.csv`` for the report (``make report``: from the files alone, in seconds). Imports
``eval/protocol/`` (and, to write, ``eval/core/`` and the list of studies).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.stats import norm
from scipy.stats import t as student_t

from eval.protocol.cluster_correlation import design_effect, intra_cluster_correlation
from eval.protocol.cluster_interval import cluster_standard_error
from eval.protocol.detectable_difference import LEVEL, mdd_factor

GOAL = 0.05
"""The half-width or MDD (F1, fraction: 5 points) every covered comparison is sized for."""
KINDS = ("half_width", "mdd")
MAX_CLUSTERS = 1_000_000
FILE = "power_analysis.csv"
Z_LEVEL = float(norm.ppf(0.5 + LEVEL / 2))
COLUMNS = (
    "study",
    "comparison",
    "condition",
    "kind",
    "clusters",
    "items",
    "now",
    "goal",
    "icc",
    "design_effect",
    "clusters_needed",
)
"""``power_analysis.csv``'s columns: ``condition`` the preset or level; ``kind`` half_width or
mdd; ``now`` that figure at ``clusters`` (F1 fraction); ``clusters_needed`` for ``goal``."""


def figure_factor(clusters: int, kind: str) -> float:
    """The multiplier of SE for ``kind`` at G = ``clusters``: t_{0.975, G − 1} (half-width) or
    t_{0.975} + t_{0.8} (MDD); NaN below two clusters."""
    if kind not in KINDS:
        raise ValueError(f"kind: expected one of {KINDS}, got {kind!r}")
    if clusters < 2:
        return float("nan")
    if kind == "mdd":
        return mdd_factor(clusters)
    return float(student_t.ppf(0.5 + LEVEL / 2, clusters - 1))


def needed_clusters(se: float, clusters: int, goal: float = GOAL, kind: str = "mdd") -> int | None:
    """The fewest clusters g ≥ 2 at which ``kind``'s figure, the per-cluster spread SE·√G held
    fixed, is ≤ ``goal`` (module docstring); None without a finite SE over ≥ 2 clusters."""
    if clusters < 2 or not np.isfinite(se) or goal <= 0:
        return None
    spread = se * math.sqrt(clusters)

    def fits(g: int) -> bool:
        return figure_factor(g, kind) * spread / math.sqrt(g) <= goal

    if fits(2):
        return 2
    low, high = 2, 4
    while not fits(high):  # the figure falls monotonically in g
        if high >= MAX_CLUSTERS:
            return None
        low, high = high, min(2 * high, MAX_CLUSTERS)
    while high - low > 1:
        mid = (low + high) // 2
        low, high = (low, mid) if fits(mid) else (mid, high)
    return high


def clusters_needed(
    differences: np.ndarray, clusters: np.ndarray, target: float = GOAL, kind: str = "mdd"
) -> int | None:
    """:func:`needed_clusters` of per-item paired ``differences`` grouped by ``clusters`` (one
    label per item)."""
    se, groups = cluster_standard_error(differences, clusters)
    return needed_clusters(se, groups, target, kind)


def _design_effect(icc: float, items: int | None, clusters: int) -> float:
    """1 + (n̄ − 1) · ICC for ``items`` over ``clusters``: 1 with one item per cluster, NaN
    when unknown."""
    if items is None or clusters < 1:
        return float("nan")
    if items == clusters:
        return 1.0
    return design_effect(icc, items / clusters) if np.isfinite(icc) else float("nan")


def paired_row(
    study: str,
    comparison: str,
    condition: str,
    differences: np.ndarray,
    clusters: np.ndarray,
    kind: str,
    goal: float = GOAL,
) -> dict:
    """One ``power_analysis.csv`` row (:data:`COLUMNS`) of per-item paired ``differences``
    grouped by ``clusters``: the figure now, the ICC, the design effect and the clusters
    needed."""
    differences = np.asarray(differences, dtype=float).reshape(-1)
    se, groups = cluster_standard_error(differences, clusters)
    icc = intra_cluster_correlation(differences, clusters)
    return {
        "study": study,
        "comparison": comparison,
        "condition": condition,
        "kind": kind,
        "clusters": groups,
        "items": len(differences),
        "now": figure_factor(groups, kind) * se,
        "goal": goal,
        "icc": icc,
        "design_effect": _design_effect(icc, len(differences), groups),
        "clusters_needed": needed_clusters(se, groups, goal, kind),
    }


def interval_row(
    study: str,
    comparison: str,
    condition: str,
    low: float,
    high: float,
    clusters: int,
    kind: str,
    icc: float = float("nan"),
    items: int | None = None,
    goal: float = GOAL,
) -> dict:
    """A row for a comparison known by a written 95 % interval [``low``, ``high``] over
    ``clusters`` (an episode bootstrap's, not per-item differences): SE = (high − low) /
    (2 z_{0.975}) under the normal approximation, then as :func:`paired_row`; ``icc`` and
    ``items`` (per-item figures measured elsewhere, when known) give the design effect."""
    se = (high - low) / (2 * Z_LEVEL) if np.isfinite(low) and np.isfinite(high) else np.nan
    return {
        "study": study,
        "comparison": comparison,
        "condition": condition,
        "kind": kind,
        "clusters": clusters,
        "items": float("nan") if items is None else items,
        "now": figure_factor(clusters, kind) * se,
        "goal": goal,
        "icc": icc,
        "design_effect": _design_effect(icc, items, clusters),
        "clusters_needed": needed_clusters(se, clusters, goal, kind),
    }


def read_csv(path: Path) -> pd.DataFrame | None:
    """A results CSV as written (the matcher ``none`` kept as text); None when absent."""
    path = Path(path)
    return pd.read_csv(path, keep_default_na=False, na_values=[""]) if path.is_file() else None


def run_mean_differences(
    per_item: pd.DataFrame, a: str, b: str, item: str = "pair", metric: str = "f1"
) -> tuple[np.ndarray, np.ndarray]:
    """(differences, episodes): per ``item`` the mean over runs of ``metric`` of matcher ``a``
    minus that of ``b`` (items both scored), with each item's episode."""
    rows = per_item[per_item["matcher"].isin([a, b])]
    means = rows.groupby([item, "matcher"], sort=True)[metric].mean().unstack("matcher")
    episodes = rows.groupby(item, sort=True)["episode"].first()
    both = means.dropna(subset=[a, b]) if {a, b} <= set(means.columns) else means.iloc[:0]
    return (both[a] - both[b]).to_numpy(float), episodes.loc[both.index].to_numpy()


def best_vs_runner_up(
    results: Path, study: str, comparison: str, table: str, per_pair: str
) -> list[dict]:
    """Half-width rows, per preset, of the best-against-runner-up F1 difference of
    ``table_<table>_intervals.csv`` (which names the two per preset), measured on
    ``<per_pair>`` (per-pair metrics with ``preset`` and ``episode``); none without both."""
    results = Path(results)
    intervals = read_csv(results / f"table_{table}_intervals.csv")
    pairs = read_csv(results / per_pair)
    if intervals is None or pairs is None:
        return []
    rows = []
    for entry in intervals.itertuples(index=False):
        here = pairs[pairs["preset"] == entry.preset]
        diff, episodes = run_mean_differences(here, str(entry.best), str(entry.runner_up))
        if len(diff):
            name = f"{comparison}: {entry.best} − {entry.runner_up}"
            rows.append(paired_row(study, name, str(entry.preset), diff, episodes, "half_width"))
    return rows


def pooled_f1_terms(frames: pd.DataFrame) -> np.ndarray:
    """Per item the linearised contribution to a pooled F1 = 2 Σ tp / Σ (n_pred + n_gt): (2 tp −
    F1 · (n_pred + n_gt)) / mean(n_pred + n_gt), whose mean is 0 and whose cluster-robust SE is
    the pooled F1's (delta method)."""
    tp = frames["tp"].to_numpy(float)
    size = frames["n_pred"].to_numpy(float) + frames["n_gt"].to_numpy(float)
    total = size.sum()
    f1 = 2 * tp.sum() / total if total > 0 else 0.0
    return (2 * tp - f1 * size) / (total / len(size)) if total > 0 else np.zeros_like(tp)


@dataclass(frozen=True)
class PowerCheck:
    """One comparison a study's power analysis covers: its ``name`` and ``rows`` (the
    :data:`COLUMNS` rows it yields from a results folder; none when its files are absent)."""

    name: str
    rows: Callable[[Path], list[dict]]


def power_table(results: Path, checks: Iterable[PowerCheck]) -> pd.DataFrame:
    """Every check's rows from ``results``, in :data:`COLUMNS` order."""
    rows = [row for check in checks for row in check.rows(Path(results))]
    table = pd.DataFrame(rows, columns=list(COLUMNS))
    counts = ["clusters", "items", "clusters_needed"]
    table[counts] = table[counts].apply(pd.to_numeric).round().astype("Int64")
    return table


def write_power_analysis(results: Path, checks: Iterable[PowerCheck]) -> Path | None:
    """``<results>/power_analysis.csv`` from the checks (the report passes every study's
    ``power``: :func:`eval.studies.power_checks`); None, and nothing written, when no check
    finds its files."""
    from eval.core.result_files import write_csv

    table = power_table(results, checks)
    if table.empty:
        return None
    path = Path(results) / FILE
    write_csv(table.round(6), path)
    return path


__all__ = [
    "COLUMNS",
    "FILE",
    "GOAL",
    "PowerCheck",
    "best_vs_runner_up",
    "clusters_needed",
    "interval_row",
    "needed_clusters",
    "paired_row",
    "pooled_f1_terms",
    "power_table",
    "run_mean_differences",
    "write_power_analysis",
]
