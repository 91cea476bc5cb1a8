"""`cadsim info DIR [--json]`: objects per view, covisible and non-covisible counts, class mix,
object depth ranges and the regime card (``cadsim.dataset.regime``) of a frame-pair dataset; for
an N-view dataset also per view and per pair of views (``multi_view``); for a sequence dataset
the sequences, their frames and the interval between frames (``sequence``)."""

from __future__ import annotations

import argparse
import json
from collections import Counter

import numpy as np

from cadsim.dataset.difficulty import LevelRule, level_counts
from cadsim.dataset.lidar_regime import card_lines
from cadsim.dataset.regime import dataset_regime
from cadsim.terminal_text import display_name


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("dataset", help="dataset folder written by `cadsim generate`")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument(
        "--levels-from",
        metavar="DATASET",
        help="fit the difficulty-level rule on this dataset (the benchmark fits it on the "
        "validation split: docs/evaluation.md, 'Difficulty levels'); default: on this dataset",
    )


def _range(values: np.ndarray) -> list[float] | None:
    return [float(values.min()), float(values.max())] if values.size else None


def _stats(values: list[int]) -> dict:
    a = np.asarray(values, float)
    if not a.size:
        return {"mean": None, "min": None, "max": None}
    return {"mean": float(a.mean()), "min": float(a.min()), "max": float(a.max())}


def difficulty_summary(frame_pairs: list, reference: list | None = None) -> dict:
    """Per-pair difficulty factors and levels (:mod:`cadsim.dataset.difficulty`), the level rule
    fitted on ``reference`` pairs (default: ``frame_pairs`` themselves), and the level counts."""
    factors = [p.difficulty for p in frame_pairs]
    if not factors:
        return {"difficulty": None}
    rule_on = [p.difficulty for p in reference] if reference else factors
    rule = LevelRule.fit(rule_on)
    levels = rule.levels(factors)
    return {
        "difficulty": {
            "rule": rule.as_record() | {"fitted_on": "reference" if reference else "itself"},
            "level_counts": level_counts(levels),
            "levels": levels,
            "factors": factors,
        }
    }


def summarise(ds, reference=None) -> dict:
    """The dataset summary ``cadsim info --json`` prints. Depths are detections' z (metres along
    each observer's optical axis, from the stored noisy positions). ``reference``: the dataset
    the difficulty-level rule is fitted on (default: ``ds``)."""
    pairs, class_mix, depths, frame_pairs = [], Counter(), [], []
    for pair in ds:
        frame_pairs.append(pair)
        cov = len(pair.gt_pairs)
        z1, z2 = pair.view1.positions[:, 2], pair.view2.positions[:, 2]
        depths.extend([z1, z2])
        class_mix.update(pair.view1.true_classes + pair.view2.true_classes)
        pairs.append(
            {
                "index": pair.index,
                "name": pair.name,
                "episode": pair.episode,
                "slot": pair.slot,
                "n1": len(pair.view1),
                "n2": len(pair.view2),
                "covisible": cov,
                "non_covisible1": len(pair.view1) - cov,
                "non_covisible2": len(pair.view2) - cov,
                "classes1": dict(sorted(Counter(pair.view1.true_classes).items())),
                "classes2": dict(sorted(Counter(pair.view2.true_classes).items())),
                "depth1": _range(z1),
                "depth2": _range(z2),
            }
        )
    all_z = np.concatenate(depths) if depths else np.zeros(0)
    manifest = ds.manifest
    return (
        {
            "dataset": str(ds.path),
            "scenario": manifest["scenario"]["name"],
            "seed": manifest["seeds"]["root"],
            "source": manifest.get("source"),
            "gl": _gl_drivers(manifest),
            "checksum": ds.checksum,
            "noise": ds.noise_config,
            "n_pairs": len(pairs),
            "objects_per_view": _stats([p["n1"] for p in pairs] + [p["n2"] for p in pairs]),
            "covisible": _stats([p["covisible"] for p in pairs]),
            "non_covisible_per_view": _stats(
                [p["non_covisible1"] for p in pairs] + [p["non_covisible2"] for p in pairs]
            ),
            "class_mix": dict(class_mix.most_common()),
            "depth": {
                "min": float(all_z.min()) if all_z.size else None,
                "median": float(np.median(all_z)) if all_z.size else None,
                "max": float(all_z.max()) if all_z.size else None,
            },
            "regime": dataset_regime(frame_pairs),
            "pairs": pairs,
        }
        | difficulty_summary(frame_pairs, list(reference) if reference is not None else None)
        | _lidar_card(frame_pairs)
        | ({"multi_view": multi_view_summary(ds)} if getattr(ds, "n_views", 2) > 2 else {})
        | (sequence_summary(ds, pairs) if getattr(ds, "is_sequential", False) else {})
    )


def sequence_summary(ds, pairs: list[dict]) -> dict:
    """``{"sequence": …}`` of a sequence dataset: the number of sequences, frames per sequence
    (``frames_planned``: the scenario's ``[sequence] frames``; ``frames``: stats over the
    sequences, some of which may have ended short), the interval between frames (s) and the
    odometry model. Marks each entry of ``pairs`` (by index) with its ``sequence`` (0-based)
    and ``frame``."""
    config = ds.manifest.get("generation", {}).get("sequence", {})
    lengths, interval, model = [], config.get("interval_s"), None
    for k, frames in enumerate(ds.iter_sequences()):
        lengths.append(len(frames))
        for pair in frames:
            pairs[pair.index] |= {"sequence": k, "frame": pair.frame}
        block = frames[0].record.get("sequence") or {}
        interval, model = block.get("interval_s", interval), block.get("model", model)
    return {
        "sequence": {
            "sequences": ds.sequences,
            "frames_planned": config.get("frames"),
            "frames": _stats(lengths),
            "interval_s": interval,
            "odometry_model": model,
        }
    }


def multi_view_summary(ds) -> dict:
    """Per view (1-based, with its kind) the detections per snapshot, and per pair of views
    (i < j) the covisible objects and the regime card of those two views over all snapshots
    (``cadsim.dataset.regime``) — where a roadside unit's view differs from a vehicle's."""
    snapshots = [ds.snapshot(k) for k in range(len(ds))]
    views = []
    for v in range(1, ds.n_views + 1):
        found = [snap.view(v) for snap in snapshots]
        depths = np.concatenate([d.positions[:, 2] for d in found]) if found else np.zeros(0)
        views.append(
            {
                "view": v,
                "kind": snapshots[0].kinds[v - 1] if snapshots else None,
                "detections": _stats([len(d) for d in found]),
                "depth_median": float(np.median(depths)) if depths.size else None,
            }
        )
    view_pairs = []
    for i, j in snapshots[0].pairs() if snapshots else []:
        pairs = [snap.pair(i, j) for snap in snapshots]
        view_pairs.append(
            {
                "views": f"{i}-{j}",
                "kinds": f"{snapshots[0].kinds[i - 1]}-{snapshots[0].kinds[j - 1]}",
                "covisible": _stats([len(p.gt_pairs) for p in pairs]),
                "regime": dataset_regime(pairs),
            }
        )
    return {"n_views": ds.n_views, "views": views, "view_pairs": view_pairs}


def _fmt(stats: dict) -> str:
    if stats["mean"] is None:
        return "-"
    return f"mean {stats['mean']:.1f}  min {stats['min']:.0f}  max {stats['max']:.0f}"


def _regime_text(regime: dict) -> str:
    def num(key: str, fmt: str) -> str:
        value = regime.get(key)
        return "-" if value is None else format(value, fmt)

    return (
        f"non-covisible share {num('noncovisible_share', '.2f')}, covisible share of the smaller "
        f"view {num('covisible_share_of_smaller', '.2f')}, appearance AUC "
        f"{num('appearance_auc', '.3f')} (image alone {num('image_auc', '.3f')}, against "
        f"same-class false pairs {num('same_class_auc', '.3f')}), "
        "position error median "
        + (
            "– (needs a localisation prior and the true poses)"
            if regime.get("position_error_median_m") is None
            else f"{num('position_error_median_m', '.2f')} m"
        )
    )


def _lidar_card(frame_pairs) -> dict:
    """``{"lidar_detector": card}`` for a dataset with LiDAR points, else nothing."""
    from cadsim.dataset.lidar_regime import lidar_detector_card

    card = lidar_detector_card(frame_pairs)
    return {} if card is None else {"lidar_detector": card}


def _import_notes(src: dict) -> list[str]:
    """What an import could not give every record: agents without a stored prior, objects
    without a track id, how ground truth was recovered (lines of ``cadsim info``)."""
    lines = []
    if src.get("agents_without_prior"):
        missing = src["agents_without_prior"]
        shown = ", ".join(display_name(m) for m in missing[:4]) + (
            f", … ({len(missing)} in all)" if len(missing) > 4 else ""
        )
        lines.append(f"  no stored prior for     {shown} (pairs with them have none)")
    if src.get("untracked_objects"):
        lines.append(f"  objects without track   {src['untracked_objects']} (one frame's id each)")
    if "link_gate_m" in src:
        lines.append(
            f"  ground truth            recovered by matching boxes within {src['link_gate_m']:g} m"
        )
    return lines


def _gl_drivers(manifest: dict) -> list[dict]:
    """The manifest's ``gl`` entries (the GL drivers that drew the records), as plain text
    fields on one line each (a hand-edited manifest cannot break the output)."""
    found = manifest.get("gl")
    keys = ("backend", "vendor", "renderer", "version")
    return [
        {k: " ".join(str(g.get(k, "")).split())[:120] for k in keys}
        | {"gpu_driver": g.get("gpu_driver") is True}
        for g in (found if isinstance(found, list) else [])
        if isinstance(g, dict)
    ]


def _gl_lines(drivers: list[dict]) -> list[str]:
    """``rendered by`` lines, with a warning for a vendor GPU driver's dataset."""
    lines = [
        f"  rendered by             {g['backend']}: {g['renderer']} ({g['vendor']}, {g['version']})"
        for g in drivers
    ]
    if any(g["gpu_driver"] for g in drivers):
        lines.append(
            "  note                    drawn by a vendor GPU's EGL driver: its pixels (and so "
            "its detections) differ from what Mesa's llvmpipe (OSMesa or Mesa EGL) draws for the "
            "same scenario and seed; regenerate with CADSIM_GL_BACKEND=osmesa for the reference "
            "dataset"
        )
    return lines


def _text(s: dict) -> str:
    total = sum(s["class_mix"].values()) or 1
    mix = ", ".join(
        f"{display_name(c)} {n} ({100 * n / total:.0f}%)" for c, n in s["class_mix"].items()
    )
    d = s["depth"]
    depth = (
        "-"
        if d["min"] is None
        else f"min {d['min']:.1f}  median {d['median']:.1f}  max {d['max']:.1f}"
    )
    lines = [
        f"{s['dataset']}: scenario {display_name(s['scenario'])}, {s['n_pairs']} pairs, "
        + ("imported (no seed), " if s["seed"] is None else f"seed {s['seed']}, ")
        + f"checksum {s['checksum'][:16]}"
        + (" (every record verified against it)" if s.get("verified") else ""),
        *(
            [
                f"  imported from           {display_name(src['repository'])} @ "
                f"{display_name(src['commit'])} ({display_name(src['licence'])})"
            ]
            if (src := s.get("source"))
            else []
        ),
        *_import_notes(s.get("source") or {}),
        *_gl_lines(s.get("gl") or []),
        f"  objects per view        {_fmt(s['objects_per_view'])}",
        f"  covisible per pair      {_fmt(s['covisible'])}",
        f"  non-covisible per view  {_fmt(s['non_covisible_per_view'])}",
        f"  object depth (m)        {depth}",
        f"  class mix               {mix}",
        f"  regime                  {_regime_text(s['regime'])}",
        f"  cues for matchers       {s['regime'].get('cues') or '-'}",
        *(card_lines(s["lidar_detector"]) if "lidar_detector" in s else []),
        *_difficulty_lines(s.get("difficulty")),
        "",
        f"  {'pair':>4}  {'name':<12} {'n1':>3} {'n2':>3} {'cov':>3}  {'depth1 (m)':>12}  {'depth2 (m)':>12}",
    ]
    if "multi_view" in s:  # before the per-pair table (of views 1 and 2)
        lines[-2:-2] = ["", *_multi_view_text(s["multi_view"])[:-1]]
    if "sequence" in s:  # after the counts: what a "pair" of the table below is
        lines[-2:-2] = [_sequence_text(s["sequence"])]
        lines[-1] += f"  {'seq':>4} {'frame':>5}"
    for p in s["pairs"]:
        r1 = "-" if p["depth1"] is None else f"{p['depth1'][0]:.1f}-{p['depth1'][1]:.1f}"
        r2 = "-" if p["depth2"] is None else f"{p['depth2'][0]:.1f}-{p['depth2'][1]:.1f}"
        lines.append(
            f"  {p['index']:>4}  {p['name']:<12} {p['n1']:>3} {p['n2']:>3} {p['covisible']:>3}  "
            f"{r1:>12}  {r2:>12}"
            + (f"  {p['sequence']:>4} {p['frame']:>5}" if "sequence" in p else "")
        )
    return "\n".join(lines)


def _difficulty_lines(d: dict | None) -> list[str]:
    if not d:
        return []
    counts = ", ".join(f"{level} {n}" for level, n in d["level_counts"].items())
    where = "this dataset" if d["rule"]["fitted_on"] == "itself" else "--levels-from"
    return [f"  difficulty levels       {counts} (terciles of the composite on {where})"]


def _sequence_text(q: dict) -> str:
    frames = q["frames"]
    found = "-" if frames["mean"] is None else f"{frames['min']:.0f}"
    if frames["mean"] is not None and frames["max"] != frames["min"]:
        found += f"-{frames['max']:.0f}"
    interval = "-" if q["interval_s"] is None else f"{q['interval_s']:g} s"
    planned = "" if q["frames_planned"] is None else f" (planned {q['frames_planned']})"
    return (
        f"  sequences               {q['sequences']} of {found} frames{planned}, "
        f"{interval} apart (pairs below are frames)"
    )


def _multi_view_text(m: dict) -> list[str]:
    def num(value, fmt: str) -> str:
        return "-" if value is None else format(value, fmt)

    lines = [f"  {m['n_views']} views per snapshot (pairs below: views 1-2)", ""]
    lines.append(f"  {'view':>4}  {'kind':<9} {'detections':<30} {'depth median (m)':>16}")
    for v in m["views"]:
        lines.append(
            f"  {v['view']:>4}  {v['kind'] or '-':<9} {_fmt(v['detections']):<30} "
            f"{num(v['depth_median'], '.1f'):>16}"
        )
    lines += ["", f"  {'view pair':<9} {'kinds':<18} {'covisible mean':>14} {'cov. share':>10} {'app. AUC':>8}"]  # fmt: skip
    for p in m["view_pairs"]:
        r = p["regime"]
        lines.append(
            f"  {p['views']:<9} {p['kinds']:<18} {num(p['covisible']['mean'], '.1f'):>14} "
            f"{num(r.get('covisible_share_of_smaller'), '.2f'):>10} "
            f"{num(r.get('appearance_auc'), '.3f'):>8}"
        )
    return [*lines, ""]


def run(args: argparse.Namespace) -> int:
    from cadsim.dataset import Dataset

    # Verified first (every record re-hashed against the manifest): what it prints is the data.
    reference = Dataset(args.levels_from) if args.levels_from else None
    summary = summarise(Dataset(args.dataset, verify=True), reference) | {"verified": True}
    print(json.dumps(summary, indent=1) if args.json else _text(summary))
    return 0
