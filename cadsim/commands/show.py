"""`cadsim show DIR --pair K --out FILE.png`: both views side by side with their detection boxes
and the ground-truth correspondences as lines; for an N-view dataset, record K's N views in a
grid with object numbers shared across views (``cadsim.snapshot_drawing``). In a sequence
dataset, `--sequence K --frame T` draws frame T of sequence K (``Dataset.sequence``) instead of
naming the record by its pair index. ``--matcher NAME`` draws the pairs that matcher declares
on the record instead of the true ones: correct green, wrong red, missed yellow."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("dataset", help="dataset folder written by `cadsim generate`")
    parser.add_argument(
        "--pair", type=int, default=None, help="pair index K (default 0; not with --sequence)"
    )
    parser.add_argument(
        "--sequence",
        type=int,
        default=None,
        help="sequence K of a sequence dataset (0-based, as `cadsim info` numbers them)",
    )
    parser.add_argument(
        "--frame",
        type=int,
        default=None,
        help="frame T of --sequence (0-based, default 0)",
    )
    parser.add_argument(
        "--out",
        required=True,
        help="image file to write (.png, .pdf, .svg; no suffix: .png), or an existing folder "
        "(the image is then named after the record, e.g. e00000_s01.png)",
    )
    parser.add_argument("--no-labels", action="store_true", help="no class labels on the boxes")
    parser.add_argument(
        "--matcher",
        default=None,
        metavar="NAME",
        help="draw the pairs matcher NAME declares (a registered name or module:function): "
        "correct green, wrong red, missed yellow (default: the true pairs)",
    )
    parser.add_argument(
        "--threshold",
        type=float,
        default=None,
        metavar="TAU",
        help="with --matcher: keep the pairs scoring at least TAU (default: every pair of its "
        "full assignment)",
    )
    parser.add_argument("--seed", type=int, default=0, help="with --matcher: its seed (default 0)")
    parser.add_argument(
        "--lidar",
        action="store_true",
        help="draw the LiDAR points from above with the LiDAR boxes (records of a scenario "
        "with sensor = both; LiDAR-only records are always drawn so)",
    )


FIGURE_MARKER = b"matplotlib"  # every PNG, PDF and SVG matplotlib writes names it


def output_path(out: str | Path, record_name: str) -> Path:
    """The file ``cadsim show`` writes for ``--out``: inside an existing folder, the record's
    name with .png; a name without a suffix gets .png (what matplotlib would write). Checked by
    the output-path rule: a new file, or a figure written before (matplotlib's), never a link, a
    user's file or a file inside a dataset."""
    from cadsim.dataset.output_folder import check_output_file, file_holds

    if not str(out).strip():
        raise ValueError("--out: expected a file or folder path, got an empty one")
    out = Path(out)
    if out.is_symlink():
        path = out  # refused below, naming the link
    elif out.is_dir():
        path = out / f"{record_name}.png"
    else:
        path = out if out.suffix else out.with_name(out.name + ".png")
    return check_output_file(path, "a figure cadsim drew", file_holds(FIGURE_MARKER))


def run(args: argparse.Namespace) -> int:
    from cadsim.dataset import Dataset
    from cadsim.pair_drawing import draw_pair_from_record, save_figure

    if args.threshold is not None and args.matcher is None:
        raise ValueError("--threshold: needs --matcher (the pairs of which matcher)")
    ds = Dataset(args.dataset)
    index, where = record_index(ds, args.pair, args.sequence, args.frame)
    ds.verify_record(index)  # the record drawn is the one the manifest vouches for
    if ds.n_views > 2:
        from cadsim.snapshot_drawing import shared_objects, snapshot_figure

        snapshot = ds.snapshot(index)
        path = output_path(args.out, snapshot.name)
        path = save_figure(snapshot_figure(snapshot, labels=not args.no_labels), path)
        shared = shared_objects(snapshot)
        linked = int((np.triu(shared, 1) >= 3).sum())
        print(
            f"{path}: snapshot {snapshot.index} ({snapshot.name}){where}, {ds.n_views} views, "
            f"{linked} of {ds.n_views * (ds.n_views - 1) // 2} view pairs share >= 3 objects "
            "(record checksum verified)"
        )
        return 0
    pair = ds[index]
    path = output_path(args.out, pair.name)
    if args.matcher is not None:
        return _show_matcher(pair, args, path, where)
    if pair.lidar is not None and (args.lidar or not pair.has_images):
        from cadsim.lidar_drawing import lidar_figure

        figure = lidar_figure(pair, labels=not args.no_labels)
    elif args.lidar:
        raise ValueError(f"--lidar: record {pair.name} has no LiDAR points")
    else:
        figure = draw_pair_from_record(pair, labels=not args.no_labels)
    path = save_figure(figure, path)
    print(
        f"{path}: pair {pair.index} ({pair.name}){where}, {len(pair.gt_pairs)} ground-truth "
        "pairs (record checksum verified)"
    )
    return 0


def declared_pairs(pair, name: str, threshold: float | None, seed: int) -> np.ndarray:
    """The (k, 2) pairs matcher ``name`` declares on ``pair`` (``matchers.get``; its own
    ValueError for an unknown name, a module that does not import, or a prior it needs)."""
    import math

    from matchers import get

    if threshold is not None and not (math.isfinite(threshold) and 0 <= threshold <= 1):
        raise ValueError(f"--threshold: expected a number in [0, 1], got {threshold}")
    matching = get(name)(pair.problem(), seed=seed, threshold=threshold)
    return np.asarray(matching.pairs, dtype=int).reshape(-1, 2)


def _show_matcher(pair, args: argparse.Namespace, path: Path, where: str) -> int:
    from cadsim.pair_drawing import draw_matches_from_record, match_classes, save_figure

    declared = declared_pairs(pair, args.matcher, args.threshold, args.seed)
    figure = draw_matches_from_record(pair, declared, args.matcher, labels=not args.no_labels)
    path = save_figure(figure, path)
    correct, wrong, missed = (len(c) for c in match_classes(declared, pair.gt_pairs))
    print(
        f"{path}: pair {pair.index} ({pair.name}){where}, {args.matcher}: {correct} correct, "
        f"{wrong} wrong, {missed} missed of {len(pair.gt_pairs)} true pairs (record checksum "
        "verified)"
    )
    return 0


def record_index(ds, pair: int | None, sequence: int | None, frame: int | None) -> tuple[int, str]:
    """(dataset index, ", sequence K frame T (t = … s)" or "") of the record that ``--pair`` or
    ``--sequence``/``--frame`` name; ValueError naming the option for a conflict or an index out
    of range."""
    if sequence is None:
        if frame is not None:
            raise ValueError("--frame: needs --sequence (the frame of which sequence)")
        pair = 0 if pair is None else pair
        if not 0 <= pair < len(ds):
            raise ValueError(f"--pair: {pair} is out of range; expected 0..{len(ds) - 1}")
        return pair, ""
    if pair is not None:
        raise ValueError("--pair: give either --pair or --sequence/--frame, not both")
    if not ds.is_sequential:
        raise ValueError(
            f"--sequence: {ds.path} is not a sequence dataset (no [sequence] in its scenario); "
            "use --pair"
        )
    if not 0 <= sequence < ds.sequences:
        raise ValueError(f"--sequence: {sequence} is out of range; expected 0..{ds.sequences - 1}")
    frames = ds.sequence(sequence)
    frame = 0 if frame is None else frame
    if not 0 <= frame < len(frames):
        raise ValueError(
            f"--frame: {frame} is out of range; sequence {sequence} has frames 0..{len(frames) - 1}"
        )
    chosen = frames[frame]
    return chosen.index, f", sequence {sequence} frame {frame} (t = {chosen.time:g} s)"
