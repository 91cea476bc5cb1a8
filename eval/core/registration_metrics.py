"""The V2X-Reg++ registration protocol (Zhang et al., T-ITS 2025; the v2i-calib repository's
``calib/evaluation``): success at 1 / 2 / 3 m, mean errors and seconds per frame, computed from
a per-pair table of :mod:`eval.core.pose_metrics` (``rte_m``, ``rre_deg``: the relative pose the
matcher's declared matches recover, the same robust planar fit as every other pose column) and
the matcher's time. Reads nothing but that table and, for a frame list, the records' meta.

Their definitions, as this module applies them:

- **success@λ** (λ = 1, 2, 3): RTE < λ metres *and* RRE < λ degrees (strict), over **all**
  frames: a frame whose matches give no pose (fewer than two matches, a failed fit: NaN) is a
  failure and stays in the denominator (their pipeline scores a frame without matches as RE = TE
  = ∞). Success computed over the frames that produced a pose would inflate it.
- **mRTE@λ, mRRE@λ**: mean RTE (m) and RRE (degrees) over the frames *successful at λ* — their
  convention; NaN where none succeeded. :func:`summarise_registration` adds the mean over every
  frame with a pose (``reg_mrte_all_m``, ``reg_mrre_all_deg``) beside it, and says how many
  frames had none (``reg_no_pose``).
- **seconds per frame**: the matcher's mean wall time per frame pair (their figure also counts
  box filtering and the SVD solve; the planar fit here is not timed).
- **frame list**: their JSON, a list of DAIR-V2X cooperative ``data_info.json`` entries
  (``vehicle_pointcloud_path``, ``infrastructure_pointcloud_path``, … and their ``box_count``);
  a frame pair is in the list when both point-cloud stems match the record's
  ``meta.vehicle_frame`` / ``meta.infrastructure_frame`` (``cadsim import dair-v2x``).
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence
from pathlib import Path, PurePosixPath

import numpy as np

THRESHOLDS_M = (1.0, 2.0, 3.0)
"""λ of success@λ: RTE < λ m and RRE < λ degrees."""


def _label(metres: float) -> str:
    return f"{metres:g}m"


COLUMNS = (
    *(f"reg_success_{_label(t)}" for t in THRESHOLDS_M),
    *(f"reg_mrte_{_label(t)}" for t in THRESHOLDS_M),
    *(f"reg_mrre_{_label(t)}_deg" for t in THRESHOLDS_M),
    "reg_mrte_all_m",
    "reg_mrre_all_deg",
    "reg_no_pose",
    "reg_s_per_frame",
    "reg_frames",
)
"""Columns of :func:`summarise_registration` (rates and counts as fractions / integers)."""


def registration_summary(
    rte: Sequence[float], rre: Sequence[float], seconds: Sequence[float]
) -> dict[str, float]:
    """The :data:`COLUMNS` of per-frame errors (NaN: no pose) and matcher seconds (module
    docstring).

    >>> s = registration_summary([0.5, 1.5, float("nan")], [0.2, 0.4, float("nan")], [1, 1, 1])
    >>> round(s["reg_success_1m"], 3), round(s["reg_success_2m"], 3), s["reg_mrte_2m"]
    (0.333, 0.667, 1.0)
    """
    rte, rre = np.asarray(rte, dtype=float), np.asarray(rre, dtype=float)
    seconds = np.asarray(seconds, dtype=float)
    pose = np.isfinite(rte) & np.isfinite(rre)
    out: dict[str, float] = {}
    for metres in THRESHOLDS_M:
        label = _label(metres)
        with np.errstate(invalid="ignore"):
            ok = pose & (rte < metres) & (rre < metres)
        out[f"reg_success_{label}"] = float(ok.mean()) if rte.size else float("nan")
        out[f"reg_mrte_{label}"] = float(rte[ok].mean()) if ok.any() else float("nan")
        out[f"reg_mrre_{label}_deg"] = float(rre[ok].mean()) if ok.any() else float("nan")
    out["reg_mrte_all_m"] = float(rte[pose].mean()) if pose.any() else float("nan")
    out["reg_mrre_all_deg"] = float(rre[pose].mean()) if pose.any() else float("nan")
    out["reg_no_pose"] = int((~pose).sum())
    out["reg_s_per_frame"] = float(seconds.mean()) if seconds.size else float("nan")
    out["reg_frames"] = int(rte.size)
    return {key: out[key] for key in COLUMNS}


def summarise_registration(per_pair, by: Sequence[str]):
    """One row per ``by`` group of a per-pair table (columns ``rte_m``, ``rre_deg``, ``time_s``
    and ``pose_scored``; runs pooled) with :data:`COLUMNS` over its scored frames; groups with
    nothing scored are left out."""
    import pandas as pd

    columns = [*by, *COLUMNS]
    if "pose_scored" not in per_pair.columns:
        return pd.DataFrame(columns=columns)
    scored = per_pair[per_pair["pose_scored"].astype(bool)]
    rows = []
    for key, group in scored.groupby(list(by), sort=False):
        key = key if isinstance(key, tuple) else (key,)
        summary = registration_summary(group["rte_m"], group["rre_deg"], group["time_s"])
        rows.append(dict(zip(by, key, strict=True)) | summary)
    return pd.DataFrame(rows, columns=columns)


def read_frame_list(path: str | Path) -> set[tuple[str, str]]:
    """{(vehicle frame, infrastructure frame)} of a V2X-Reg++ frame list (module docstring);
    ``ValueError`` naming the file and entry for anything else."""
    path = Path(path)
    try:
        entries = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: not a readable JSON frame list ({exc})") from None
    if not isinstance(entries, list) or not entries:
        raise ValueError(f"{path}: expected a non-empty list of cooperative frame entries")
    out = set()
    for k, entry in enumerate(entries):
        keys = ("vehicle_pointcloud_path", "infrastructure_pointcloud_path")
        if not isinstance(entry, dict) or not all(isinstance(entry.get(x), str) for x in keys):
            raise ValueError(f"{path}: [{k}]: expected an object with {' and '.join(keys)}")
        out.add(tuple(PurePosixPath(entry[x]).stem for x in keys))
    return out


def listed_pairs(records: Iterable[tuple[int, dict]], frames: set[tuple[str, str]]) -> set[int]:
    """The pair indices among ``records`` ((index, record meta)) whose (vehicle, infrastructure)
    frames are in ``frames``."""
    return {
        index
        for index, meta in records
        if (str(meta.get("vehicle_frame")), str(meta.get("infrastructure_frame"))) in frames
    }


__all__ = [
    "COLUMNS",
    "THRESHOLDS_M",
    "listed_pairs",
    "read_frame_list",
    "registration_summary",
    "summarise_registration",
]
