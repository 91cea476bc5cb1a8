"""The LiDAR detector's entries of a dataset's regime card: recall by range band and box-centre
error, with episode-level 95 % intervals — what the box detector misses, splits and misplaces on
this dataset, measured, not tuned (``cadsim info`` prints them).

Per view of every record with LiDAR points: the targets of the snapshot (``target`` objects but
the observer's own vehicle) whose centre lies within a band of planar range from the LiDAR;
*recall* is the share the detector reports (a box carrying the object's id), over all of them
and over those its sweep hit with at least ``MIN_HIT_POINTS`` points (the detector's own share,
occlusion aside). *Centre error*: planar distance (metres) between each true box's centre and
its object's true centre, in the world frame. *False-positive share*: boxes that are no object
(``clutter:…``); *by source*: the share of all boxes that are false positives of each source
(``cadsim.sensing.lidar.box_truth.false_positive_source``: ``building`` slivers, ``split``
pieces, roadside ``tree``/``pole``/``bin``/``trailer``, ``ground``; ``other`` for a false
positive whose id names none, e.g. of data made before sources were recorded); the shares add
up to the false-positive share. Intervals: a t-interval over episode means (frames of one episode are
correlated; docs/evaluation.md), rates' clipped to [0, 1], None with fewer than two episodes.
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Iterable

import numpy as np

from cadsim.sensing.lidar.box_truth import false_positive_source

RANGE_BANDS_M = ((0.0, 20.0), (20.0, 40.0), (40.0, 60.0), (60.0, 80.0))
MIN_HIT_POINTS = 10


def _interval(by_episode: dict[int, list[float]]) -> list[float] | None:
    """95 % t-interval of the mean of per-episode means; None below two episodes."""
    means = np.array([np.mean(v) for _, v in sorted(by_episode.items()) if v])
    if len(means) < 2:
        return None
    from scipy.stats import t

    half = (
        float(t.ppf(0.975, len(means) - 1)) * float(np.std(means, ddof=1)) / math.sqrt(len(means))
    )
    centre = float(np.mean(means))
    return [centre - half, centre + half]


def _clipped(ci: list[float] | None) -> list[float] | None:
    """A rate's interval clipped to [0, 1]."""
    return None if ci is None else [max(0.0, ci[0]), min(1.0, ci[1])]


def _lidar_frame_to_world(pose: np.ndarray, positions_camera: np.ndarray) -> np.ndarray:
    """(k, 3) box centres from the camera-frame convention (sensor origin) to the world."""
    p = np.asarray(positions_camera, dtype=np.float64).reshape(-1, 3)
    lidar = np.column_stack([p[:, 2], -p[:, 0], -p[:, 1]])
    return lidar @ pose[:3, :3].T + pose[:3, 3]


def lidar_detector_card(pairs: Iterable) -> dict | None:
    """The card (module docstring) over ``pairs`` (``FramePair`` objects), None when none has
        LiDAR points. Keys: ``range_bands_m``, ``recall`` and ``recall_hit`` (one entry per band:
        ``objects``, ``recall``, ``ci``), ``centre_error_m`` (``boxes``, ``median``, ``mean``,
        ``ci``), ``false_positive_share``, ``false_positive_sources`` (source -> share of boxes,
    largest first)."""
    found = False
    seen = [defaultdict(list) for _ in RANGE_BANDS_M]  # band -> episode -> 1/0 per object
    seen_hit = [defaultdict(list) for _ in RANGE_BANDS_M]
    errors: dict[int, list[float]] = defaultdict(list)
    boxes = clutter = 0
    sources: dict[str, int] = defaultdict(int)
    for pair in pairs:
        sweeps = pair.lidar
        if sweeps is None:
            continue
        found = True
        objects = pair.objects
        for view, sweep, observer in zip((pair.view1, pair.view2), sweeps, pair.observer_ids, strict=True):  # fmt: skip
            detected = {oid: k for k, oid in enumerate(view.object_ids)}
            hits = np.bincount(sweep.object_index[sweep.object_index >= 0], minlength=len(objects))
            origin = sweep.pose[:2, 3]
            world = _lidar_frame_to_world(sweep.pose, view.positions)
            for index, obj in enumerate(objects):  # per object of the snapshot
                if not obj.target or obj.id == observer:
                    continue
                reach = float(np.hypot(*(np.asarray(obj.center[:2]) - origin)))
                band = next((b for b, (lo, hi) in enumerate(RANGE_BANDS_M) if lo <= reach < hi), None)  # fmt: skip
                if band is None:
                    continue
                got = float(obj.id in detected)
                seen[band][pair.episode].append(got)
                if hits[index] >= MIN_HIT_POINTS:
                    seen_hit[band][pair.episode].append(got)
                if obj.id in detected:
                    d = world[detected[obj.id], :2] - np.asarray(obj.center[:2])
                    errors[pair.episode].append(float(np.hypot(*d)))
            boxes += len(view)
            for oid in view.object_ids:
                if oid.startswith("clutter:"):
                    clutter += 1
                    sources[false_positive_source(oid) or "other"] += 1
    if not found:
        return None

    def bands(table):
        out = []
        for (lo, hi), by_episode in zip(RANGE_BANDS_M, table, strict=True):
            values = [v for vs in by_episode.values() for v in vs]
            out.append({
                "band_m": [lo, hi], "objects": len(values),
                "recall": float(np.mean(values)) if values else None,
                "ci": _clipped(_interval(by_episode)),
            })  # fmt: skip
        return out

    flat = [e for es in errors.values() for e in es]
    return {
        "range_bands_m": [list(b) for b in RANGE_BANDS_M],
        "recall": bands(seen),
        "recall_hit": bands(seen_hit),
        "centre_error_m": {
            "boxes": len(flat),
            "median": float(np.median(flat)) if flat else None,
            "mean": float(np.mean(flat)) if flat else None,
            "ci": _interval(errors),
        },
        "false_positive_share": clutter / boxes if boxes else None,
        "false_positive_sources": {
            k: n / boxes for k, n in sorted(sources.items(), key=lambda kv: (-kv[1], kv[0]))
        },
    }


def sources_text(shares: dict[str, float]) -> str:
    """``{source: share of boxes}`` as one cell, e.g. ``building 12%; split 5%`` (``-``: none)."""
    return "; ".join(f"{k} {100 * v:.0f}%" for k, v in shares.items()) or "-"


def card_lines(card: dict) -> list[str]:
    """The card as ``cadsim info`` text lines."""

    def cell(entry: dict) -> str:
        if entry["recall"] is None:
            return f"{entry['band_m'][0]:.0f}-{entry['band_m'][1]:.0f} m: -"
        ci = entry["ci"]
        interval = "" if ci is None else f" [{100 * ci[0]:.0f}, {100 * ci[1]:.0f}]"
        return f"{entry['band_m'][0]:.0f}-{entry['band_m'][1]:.0f} m {100 * entry['recall']:.0f}%{interval} (n {entry['objects']})"  # fmt: skip

    err = card["centre_error_m"]
    ci = err["ci"]
    error = "-" if err["median"] is None else (
        f"median {err['median']:.2f} m, mean {err['mean']:.2f} m"
        + ("" if ci is None else f" [{ci[0]:.2f}, {ci[1]:.2f}]") + f" ({err['boxes']} boxes)"
    )  # fmt: skip
    fp = card["false_positive_share"]
    return [
        f"  LiDAR recall by range   {'; '.join(cell(e) for e in card['recall'])}",
        f"  ... of objects hit      {'; '.join(cell(e) for e in card['recall_hit'])} (>= {MIN_HIT_POINTS} points)",
        f"  LiDAR centre error      {error}",
        f"  LiDAR false positives   {'-' if fp is None else f'{100 * fp:.0f}% of boxes'}"
        + ("" if fp is None else f" ({sources_text(card.get('false_positive_sources', {}))})"),
    ]
