"""`cadsim generate SCENARIO.toml --out DIR [--pairs N] [--seed S] [--workers W]
[--scheduler ADDRESS] [--frames-from DIR]`."""

from __future__ import annotations

import argparse
import logging
import os
import sys

from cadsim.cli import int_in
from cadsim.generation.executors import add_scheduler_argument
from cadsim.limits import MAX_PAIRS, MAX_SEED, MAX_WORKERS


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scenario", help="scenario file (.toml)")
    parser.add_argument("--out", required=True, help="dataset folder (created; resumed if present)")
    parser.add_argument(
        "--pairs",
        type=int_in(1, MAX_PAIRS),
        help=f"number of frame pairs, 1..{MAX_PAIRS} (default: the scenario's)",
    )
    parser.add_argument(
        "--seed", type=int_in(0, MAX_SEED), help="root seed >= 0 (default: the scenario's)"
    )
    parser.add_argument(
        "--workers",
        type=int_in(1, MAX_WORKERS),
        default=min(os.cpu_count() or 1, MAX_WORKERS),
        help="worker processes, one simulation each (default: CPU count)",
    )
    add_scheduler_argument(parser)
    parser.add_argument(
        "--frames-from",
        metavar="DIR",
        help='a two-sensor scenario (sensor = "both"): take the camera captures from this '
        "camera-only dataset of the same scenario settings and seed, and sweep only the LiDAR "
        "(the same records, without rendering again; ignored if it was generated otherwise)",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")


def run(args: argparse.Namespace) -> int:
    from cadsim.generation.pipeline import generate_dataset

    if not getattr(args, "verbose", False):
        for noisy in ("OpenGL", "trimesh"):  # their INFO lines say nothing a user can act on
            logging.getLogger(noisy).setLevel(logging.WARNING)

    if args.frames_from is not None:  # its records are copied: a tampered one stops here
        from cadsim.dataset import Dataset

        Dataset(args.frames_from).verify_once()
    try:
        result = generate_dataset(
            args.scenario,
            args.out,
            pairs=args.pairs,
            seed=args.seed,
            workers=args.workers,
            progress=not args.no_progress,
            scheduler=args.scheduler,
            frames_from=args.frames_from,
        )
    except KeyboardInterrupt:
        print(
            f"cadsim generate: interrupted; complete records are kept in {args.out}. "
            "Run the same command again to resume.",
            file=sys.stderr,
        )
        return 130
    print(_summary(result))
    return 0


def _summary(result) -> str:
    """The closing line. Parallel episodes may write records beyond the N asked for (the
    surplus is dropped at the end), and views are rendered for every candidate pair, also those
    refused for too few objects in common: both are said, so the counts add up."""
    kept = min(result.new_records, result.pairs)
    surplus = result.new_records - kept
    dropped = f", {surplus} more written by parallel episodes and dropped" if surplus else ""
    sensed = (
        f"{result.views} views rendered in {result.seconds:.1f} s for {result.candidates} "
        "candidates, those with too few shared objects included"
        if result.candidates or not result.views
        else f"{result.views} views sensed in {result.seconds:.1f} s, the frames taken from "
        "--frames-from"
    )
    return (
        f"{result.out}: {result.pairs} {_records_word(result.out)} ({kept} new{dropped}; "
        f"{sensed}); checksum {result.checksum}"
    )


def _records_word(out) -> str:
    """ "frame pairs", or "snapshots (N views each)" for an N-view dataset."""
    import json

    from cadsim.dataset import layout

    views = json.loads((out / layout.MANIFEST).read_text()).get("views", 2)
    return "frame pairs" if views == 2 else f"snapshots ({views} views each)"
