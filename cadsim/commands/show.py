"""`cadsim show DIR --pair K --out FILE.png`: both views side by side with their detection boxes
and the ground-truth correspondences as lines."""

from __future__ import annotations

import argparse
import sys


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("dataset", help="dataset folder written by `cadsim generate`")
    parser.add_argument("--pair", type=int, default=0, help="pair index K (default 0)")
    parser.add_argument("--out", required=True, help="image file to write (.png, .pdf, .svg)")
    parser.add_argument("--no-labels", action="store_true", help="no class labels on the boxes")


def run(args: argparse.Namespace) -> int:
    from cadsim.dataset import Dataset
    from cadsim.pair_drawing import draw_pair_from_record, save_figure

    try:
        ds = Dataset(args.dataset)
        if args.pair < 0:
            raise IndexError(f"--pair: expected a pair index 0..{len(ds) - 1}, got {args.pair}")
        pair = ds[args.pair]
        fig = draw_pair_from_record(pair, labels=not args.no_labels)
    except (ValueError, IndexError) as exc:
        print(f"cadsim show: error: {exc}", file=sys.stderr)
        return 2
    path = save_figure(fig, args.out)
    print(f"{path}: pair {pair.index} ({pair.name}), {len(pair.gt_pairs)} ground-truth pairs")
    return 0
