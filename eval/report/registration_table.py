"""``cadsim evaluate --pose-metrics v2x-reg``: the V2X-Reg++ registration table
(:mod:`eval.core.registration_metrics`) of an evaluation's per-pair file, optionally over a
published frame list, written as ``registration.csv`` and ``registration.md`` beside Table I.
Reads the per-pair CSV and, for a frame list, the test datasets' record meta; imports no
matcher.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pandas as pd

from eval.core.registration_metrics import (
    THRESHOLDS_M,
    listed_pairs,
    read_frame_list,
    summarise_registration,
)
from eval.report.markdown_cell import cell
from eval.report.tables import method_name

log = logging.getLogger(__name__)

CSV, MARKDOWN = "registration.csv", "registration.md"


def _listed(per_pair: pd.DataFrame, tests: dict[str, str], frames: set) -> pd.DataFrame:
    """The rows of ``per_pair`` whose frame pair is in ``frames`` ({label: test dir})."""
    from cadsim.dataset import Dataset

    keep = np.zeros(len(per_pair), dtype=bool)
    for label, test_dir in tests.items():
        dataset = Dataset(test_dir)
        metas = ((k, dataset[k].record.get("meta") or {}) for k in range(len(dataset)))
        chosen = listed_pairs(metas, frames)
        keep |= (per_pair["dataset"] == label).to_numpy() & per_pair["pair"].isin(chosen).to_numpy()
        found = len(chosen)
        if found < len(frames):
            log.warning(
                "%s: %d of the frame list's %d frame pairs are in the dataset (the rest are not "
                "scored: import them to count them)", label, found, len(frames),
            )  # fmt: skip
    return per_pair[keep]


def write_registration(
    out_dir: str | Path, tests: dict[str, str], frame_list: str | Path | None = None
) -> str:
    """Write the registration table of ``out_dir/metrics_per_pair.csv`` ({dataset label: test
    dir} ``tests``; only the frame pairs of ``frame_list``, V2X-Reg++'s JSON, when given) and
    return its Markdown."""
    out_dir = Path(out_dir)
    per_pair = pd.read_csv(out_dir / "metrics_per_pair.csv", keep_default_na=False, na_values=[""])
    if frame_list is not None:
        per_pair = _listed(per_pair, tests, read_frame_list(frame_list))
    table = summarise_registration(per_pair, ["dataset", "matcher"])
    table.to_csv(out_dir / CSV, index=False)
    text = markdown(table, frame_list)
    (out_dir / MARKDOWN).write_text(text, encoding="utf-8")
    return text


def markdown(table: pd.DataFrame, frame_list: str | Path | None = None) -> str:
    """The registration table in Markdown: percent, metres, degrees, seconds."""
    labels = [f"{t:g}" for t in THRESHOLDS_M]
    head = ["Method", *(f"Success@{x} m" for x in labels)]
    head += [f"mRTE / mRRE @{x} m" for x in labels] + ["no pose", "s / frame", "frames"]
    where = f"frames of {Path(frame_list).name}" if frame_list else "every frame pair"
    lines = []
    for dataset, rows in table.groupby("dataset", sort=False):
        lines += [
            f"**{cell(dataset)}** — V2X-Reg++ protocol over {cell(where)}: success@λ = RTE < λ m "
            "and RRE < λ° over all frames (no pose: a failure); mRTE / mRRE over the frames "
            "successful at λ",
            "",
            "| " + " | ".join(head) + " |",
            "|:---|" + "---:|" * (len(head) - 1),
        ]
        for _, r in rows.iterrows():
            cells = [cell(method_name(r["matcher"]))]
            cells += [f"{100 * r[f'reg_success_{x}m']:.2f}" for x in labels]
            cells += [_pair(r[f"reg_mrte_{x}m"], r[f"reg_mrre_{x}m_deg"]) for x in labels]
            cells += [str(int(r["reg_no_pose"])), f"{r['reg_s_per_frame']:.3f}"]
            cells += [str(int(r["reg_frames"]))]
            lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines)


def _pair(metres: float, degrees: float) -> str:
    return "–" if not np.isfinite(metres) else f"{metres:.2f} / {degrees:.2f}"


__all__ = ["CSV", "MARKDOWN", "markdown", "write_registration"]
