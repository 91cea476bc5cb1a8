"""Regime cards: where each dataset sits — objects per view, covisible objects, the share of
non-covisible objects, the covisible share of the smaller view, how well appearance alone
separates true from false candidate pairs, and how far covisible objects' positions disagree.

The numbers come from ``cadsim.dataset.regime.dataset_regime`` (the one implementation, also behind
``cadsim info --json``); this module writes them as ``regime.csv`` (one row per dataset, key
column ``dataset``) and as the Markdown table the README shows beside Table I. Beside it,
``regime_auc_intervals.csv``: the appearance and image-only AUCs with their episode-bootstrap
95 % intervals (:mod:`eval.protocol.auc_interval`), which the appearance-realism goals read.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from eval.core.keyed_csv import upsert_csv
from eval.protocol.auc_interval import episode_auc_interval

COLUMNS = (
    "dataset",
    "objects_per_view",
    "covisible",
    "noncovisible_share",
    "covisible_share_of_smaller",
    "appearance_auc",
    "image_auc",
    "same_class_auc",
    "size_only_auc",
    "position_error_median_m",
    "lidar_false_positive_sources",
    "continuity",
)
TITLES = {
    "objects_per_view": "objects / view",
    "covisible": "covisible / pair",
    "noncovisible_share": "non-covisible share",
    "covisible_share_of_smaller": "covisible / smaller view",
    "appearance_auc": "appearance AUC",
    "image_auc": "image-only AUC",
    "same_class_auc": "AUC vs same-class false pairs",
    "size_only_auc": "size-only AUC",
    "position_error_median_m": "position error (m, median)",
    "lidar_false_positive_sources": "LiDAR false positives by source (% of boxes)",
    "continuity": "own-tracker continuity by speed (% of links)",
}


def regime_of(path: str | Path) -> dict:
    """The regime fields of the dataset at `path` (``dataset_regime``), verified first, with
    ``size_only_auc`` (``cadsim.exporters.size_separability``: how well the reported sizes alone
    tell true from false pairs), ``lidar_false_positive_sources`` (``lidar_regime.sources_text`` of the LiDAR detector card;
    None for a dataset without LiDAR points)."""
    from cadsim.dataset import Dataset, lidar_regime, regime
    from cadsim.exporters.size_separability import size_only_auc

    dataset = Dataset(path, verify=True)
    card = lidar_regime.lidar_detector_card(dataset)
    sources = None if card is None else lidar_regime.sources_text(card["false_positive_sources"])
    return regime.dataset_regime(dataset) | {
        "size_only_auc": size_only_auc(dataset),
        "lidar_false_positive_sources": sources,
        "continuity": continuity_text(path) if len(dataset) > dataset.sequences else None,
    }


def continuity_text(path: str | Path) -> str:
    """The own tracker's continuity per speed band on the sequences at ``path`` (run 0's
    odometry, :func:`eval.studies.temporal.evaluation.continuity_rows`): "static 96.1 % of 1276, slow …,
    fast …" (percent of consecutive detections of one object kept on one own track)."""
    from eval.studies.temporal.evaluation import continuity_rows, load_split

    rows = continuity_rows(load_split(Path(path), "exact", (0,)), "exact")
    return ", ".join(
        f"{r['band']} {100 * r['continuity']:.1f} % of {r['links']}" if r["links"] else
        f"{r['band']} – of 0"
        for r in rows
    )  # fmt: skip


AUC_FILE = "regime_auc_intervals.csv"
AUC_COLUMNS = (
    "dataset",
    "appearance_auc",
    "appearance_auc_low",
    "appearance_auc_high",
    "image_auc",
    "image_auc_low",
    "image_auc_high",
    "episodes",
)


def auc_intervals_of(path: str | Path) -> dict:
    """The pooled appearance (whole feature) and image-only AUCs of the dataset at ``path``
    over every candidate pair, each with its episode-bootstrap 95 % interval."""
    from cadsim.dataset import Dataset
    from cadsim.dataset.regime import cosine_similarity, image_similarity

    scores: dict[int, list[list[np.ndarray]]] = {}
    for pair in Dataset(path, verify=True):
        gt = np.asarray(pair.gt_pairs, dtype=np.int64).reshape(-1, 2)
        f1, f2 = pair.view1.features, pair.view2.features
        whole, image = cosine_similarity(f1, f2), image_similarity(f1, f2)
        true = np.zeros(whole.shape, dtype=bool)
        true[gt[:, 0], gt[:, 1]] = True
        lists = scores.setdefault(pair.episode, [[], [], [], []])
        for k, values in enumerate((whole[true], whole[~true], image[true], image[~true])):
            lists[k].append(values)
    episodes = [[np.concatenate(v) for v in scores[e]] for e in sorted(scores)]
    row: dict = {"episodes": len(episodes)}
    for name, (t, f) in (("appearance_auc", (0, 1)), ("image_auc", (2, 3))):
        auc, low, high = episode_auc_interval([e[t] for e in episodes], [e[f] for e in episodes])
        row |= {name: auc, f"{name}_low": low, f"{name}_high": high}
    return row


def write_regime(out_dir: str | Path, datasets: Mapping[str, str | Path]) -> Path:
    """Rows for `datasets` ({table label: test dataset directory}) into ``out_dir/regime.csv``
    and their AUC intervals into ``out_dir/regime_auc_intervals.csv`` (other datasets' rows
    kept); returns the first's path."""
    rows, intervals = [], []
    for label, path in datasets.items():
        regime = regime_of(path)
        rows.append({"dataset": label} | {c: regime.get(c) for c in COLUMNS[1:]})
        intervals.append({"dataset": label} | auc_intervals_of(path))
    path = Path(out_dir) / "regime.csv"
    upsert_csv(path, pd.DataFrame(rows, columns=list(COLUMNS)).round(4))
    upsert_csv(
        Path(out_dir) / AUC_FILE, pd.DataFrame(intervals, columns=list(AUC_COLUMNS)).round(4)
    )
    return path


def regime_markdown(path: str | Path) -> str:
    """``regime.csv`` as a Markdown table (shares in percent; empty cells as –)."""
    from eval.report.markdown_cell import cell as md_cell
    from eval.report.tables import dataset_order

    table = pd.read_csv(path, keep_default_na=False, na_values=[""])
    table = table.sort_values("dataset", key=lambda s: s.map(dataset_order))
    header = ["Dataset", *(TITLES[c] for c in COLUMNS[1:])]
    lines = ["| " + " | ".join(header) + " |", "|:---|" + "---:|" * (len(header) - 1)]
    for _, r in table.iterrows():
        cells = [md_cell(r["dataset"])]
        for c in COLUMNS[1:]:
            v = r.get(c)
            if pd.isna(v):
                cells.append("–")
            elif isinstance(v, str):
                cells.append(v)
            elif c in ("noncovisible_share", "covisible_share_of_smaller"):
                cells.append(f"{100 * v:.0f} %")
            elif c in ("appearance_auc", "image_auc", "same_class_auc", "position_error_median_m"):
                cells.append(f"{v:.2f}")  # MRC's 0.06 m would read "0.1" at one decimal
            else:
                cells.append(f"{v:.1f}")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def readme_part(results: Path) -> list[str]:
    """The report's "Regime of each dataset" section from ``results/regime.csv`` (none without
    it)."""
    if not (Path(results) / "regime.csv").is_file():
        return []
    return [
        "### Regime of each dataset",
        "",
        regime_markdown(Path(results) / "regime.csv").strip(),
        "",
        "Means over test frame pairs; non-covisible share pooled over both views; appearance "
        "AUC: how well feature similarity alone separates true from false candidate pairs "
        "(0.5 = not at all); position error: covisible objects' 3-D disagreement after "
        "aligning the views with the true poses.",
        "",
    ]
