"""The temporal study's scores of one method's test outcome: per frame F1 and success@(1 m, 2°)
of the planar fit, per sequence the metrics over time (partner changes, cross-agent IDSW, frames
to the first correct association, HOTA), pooled F1 with its episode-level bootstrap, a table
row's metric columns with episode-level intervals, the own tracker's continuity per speed band
and the oracle row (the true pairs)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from eval.core.pose_metrics import matched_planar_error
from eval.protocol import pooled_bootstrap
from eval.protocol.cluster_interval import t_interval
from eval.protocol.metrics import pair_metrics
from eval.protocol.temporal_metrics import (
    SPEED_BANDS,
    combine_sequences,
    correspondence_hota,
    cross_agent_idsw,
    frames_to_first_correct,
    partner_changes,
    track_continuity,
)
from eval.studies.temporal.sequences import Sequenced
from eval.studies.temporal.table import ORACLE_ROW, SUCCESS_BOUNDS


def _pose_success(item: Sequenced, t: int, pairs: np.ndarray) -> float:
    ext, truth = item.extrinsics[t], item.truth[t]
    if ext is None or truth is None:
        return float("nan")
    if len(pairs) < 2:
        return 0.0
    frame = item.seq.frames[t]
    rte, rre = matched_planar_error(frame.points1, frame.points2, pairs, ext, truth)
    if not (np.isfinite(rte) and np.isfinite(rre)):
        return 0.0
    return float(rte <= SUCCESS_BOUNDS[0] and rre <= SUCCESS_BOUNDS[1])


def score_test(item: Sequenced, frames: list, tau: float, seed: int) -> tuple[list[dict], dict]:
    """Per-frame rows and the sequence's temporal metrics of one method's test outcome at τ."""
    declared = [pairs[scores >= tau] for pairs, scores in frames]
    rows = []
    for t, pairs in enumerate(declared):
        f = item.seq.frames[t]
        rows.append(
            {
                "seed": seed,
                "sequence": item.sequence,
                "episode": item.episode,
                "frame": t,
                **_frame_counts(pair_metrics(pairs, item.gt[t], f.n1, f.n2)),
                "success": _pose_success(item, t, pairs),
            }
        )
    switches = partner_changes(declared, item.true1, item.true2)
    idsw = cross_agent_idsw(declared, item.true1, item.true2, item.seq.tracks1, item.seq.tracks2)
    first = frames_to_first_correct(declared, item.true1, item.true2)
    h = correspondence_hota(
        declared, item.true1, item.true2, item.seq.tracks1, item.seq.tracks2, arrays=True
    )
    temporal = {
        "seed": seed,
        "sequence": item.sequence,
        "episode": item.episode,
        "switches": switches["switches"],
        "object_frames": switches["object_frames"],
        "first": [v for v in first["per_object"].values() if v is not None],
        "never": first["never"],
        "objects": len(first["per_object"]),
        "idsw": idsw["idsw"],
        "hota": h,
    }
    return rows, temporal


def _frame_counts(metrics) -> dict:
    """A frame's per-frame F1 and the counts pooled F1 sums: true positives, declared pairs,
    true pairs."""
    return {"f1": metrics.f1, "tp": metrics.tp, "n_pred": metrics.n_pred, "n_gt": metrics.n_gt}


def pooled_sums(per_frame: pd.DataFrame) -> pooled_bootstrap.Sums:
    """Per-frame counts summed per episode and run (one group) for the pooled bootstrap."""
    counts = per_frame.rename(
        columns={"tp": "true_positives", "n_pred": "declared", "n_gt": "true_pairs"}
    ).assign(_all=0)
    return pooled_bootstrap.group_sums(counts, ["_all"], pooled_bootstrap.F1_COUNTS)


def pooled_f1(per_frame: pd.DataFrame) -> tuple[float, float, float]:
    """(pooled F1, low, high): 2 ΣTP / (Σ|M| + Σ|G|) over every frame of ``per_frame`` (its
    ``tp``, ``n_pred``, ``n_gt`` columns, all runs together) with its 95 % episode-level
    bootstrap interval (NaN with one episode)."""
    if not len(per_frame):
        return (float("nan"),) * 3
    sums = pooled_sums(per_frame)
    point = float(pooled_bootstrap.f1_of(sums)[0])
    if not pooled_bootstrap.resamplable(sums):
        return point, float("nan"), float("nan")
    resampled = pooled_bootstrap.f1_of(sums, pooled_bootstrap.weights_for(sums))
    low, high = pooled_bootstrap.interval(resampled)
    return point, float(low[0]), float(high[0])


def finite_interval(values, episodes, bounds=(0.0, 1.0)) -> tuple[float, float, float, int]:
    """(mean, low, high, episodes) of the finite ``values`` with their 95 % episode-level cluster
    t-interval within ``bounds``; NaNs and 0 episodes without a finite value."""
    values = np.asarray(values, dtype=float)
    episodes = np.asarray(episodes)
    keep = np.isfinite(values)
    if not keep.any():
        return float("nan"), float("nan"), float("nan"), 0
    return t_interval(values[keep], episodes[keep], bounds=bounds)


def _switch_interval(temporal: list[dict]) -> tuple[float, float, float]:
    """Switches per object-frame with its episode-level interval: each covisible object-frame an
    item (1 where a switch was counted), clustered by episode."""
    values, episodes = [], []
    for s in temporal:
        n = max(s["object_frames"], s["switches"])
        values += [1.0] * s["switches"] + [0.0] * (n - s["switches"])
        episodes += [s["episode"]] * n
    if not values:
        return float("nan"), float("nan"), float("nan")
    mean, low, high, _ = t_interval(np.array(values), np.array(episodes), bounds=(0.0, 1.0))
    return mean, low, high


def summarise(per_frame: pd.DataFrame, temporal: list[dict]) -> dict:
    """One table row's metric columns from a method's per-frame rows and sequence metrics."""
    f1, f1_low, f1_high, episodes = finite_interval(per_frame["f1"], per_frame["episode"])
    pooled, pooled_low, pooled_high = pooled_f1(per_frame)
    success, s_low, s_high, _ = finite_interval(per_frame["success"], per_frame["episode"])
    sw, sw_low, sw_high = _switch_interval(temporal)
    first = [v for s in temporal for v in s["first"]]
    combined = combine_sequences([s["hota"] for s in temporal])
    object_frames = sum(s["object_frames"] for s in temporal)
    idsw = sum(s["idsw"] for s in temporal)
    return {
        "f1_pooled": pooled,
        "f1_pooled_low": pooled_low,
        "f1_pooled_high": pooled_high,
        "f1_mean": f1,
        "f1_low": f1_low,
        "f1_high": f1_high,
        "success_1m_2deg": success,
        "success_low": s_low,
        "success_high": s_high,
        "partner_changes_per_100": 100 * sw,
        "partner_changes_low": 100 * sw_low,
        "partner_changes_high": 100 * sw_high,
        "idsw_per_100": 100 * idsw / object_frames if object_frames else float("nan"),
        "frames_to_first": float(np.mean(first)) if first else float("nan"),
        "never_matched": int(sum(s["never"] for s in temporal)),
        "hota": combined["HOTA"],
        "deta": combined["DetA"],
        "assa": combined["AssA"],
        "frames": len(per_frame),
        "sequences": len({(s["seed"], s["sequence"]) for s in temporal}),
        "episodes": episodes,
    }


def continuity_rows(items: list[tuple[int, Sequenced]], preset: str) -> list[dict]:
    """The own tracker's continuity per speed band over ``items`` (both views, every run):
    :func:`~eval.protocol.temporal_metrics.track_continuity` summed, ``continuity`` = kept /
    links (NaN without a link) with its episode-level t-interval (each link an item, 1 when
    kept, clustered by episode)."""
    values: dict[str, list[float]] = {name: [] for name, _, _ in SPEED_BANDS}
    episodes: dict[str, list[int]] = {name: [] for name, _, _ in SPEED_BANDS}
    for _, item in items:
        if item.speed1 is None:
            continue
        for tracks, true, speeds in (
            (item.seq.tracks1, item.true1, item.speed1),
            (item.seq.tracks2, item.true2, item.speed2),
        ):
            for name, (kept, links) in track_continuity(tracks, true, speeds).items():
                values[name] += [1.0] * kept + [0.0] * (links - kept)
                episodes[name] += [item.episode] * links
    rows = []
    for name, low, high in SPEED_BANDS:
        kept, links = int(sum(values[name])), len(values[name])
        share, c_low, c_high = np.nan, np.nan, np.nan
        if links:
            share, c_low, c_high, _ = t_interval(
                np.array(values[name]), np.array(episodes[name]), bounds=(0.0, 1.0)
            )
        rows.append(
            {
                "preset": preset,
                "band": name,
                "low_m_s": low,
                "high_m_s": high,
                "kept": kept,
                "links": links,
                "continuity": share,
                "continuity_low": c_low,
                "continuity_high": c_high,
            }  # fmt: skip
        )
    return rows


def oracle_scores(items: list[tuple[int, Sequenced]], preset: str) -> tuple[dict, pd.DataFrame]:
    """The oracle's table row (the true pairs declared) and per-frame rows over ``items``."""
    rows, temporal = [], []
    for seed, item in items:
        frames = [(gt, np.ones(len(gt))) for gt in item.gt]
        r, s = score_test(item, frames, 0.5, seed)
        rows += r
        temporal.append(s)
    per_frame = pd.DataFrame(rows)
    row = {"method": ORACLE_ROW, "window": 0, "preset": preset, "tau": np.nan, "val_f1": np.nan}
    row["params"] = ""
    return row | summarise(per_frame, temporal) | {"ms_per_frame": np.nan}, per_frame
