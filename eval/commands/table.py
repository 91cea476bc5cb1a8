"""``cadsim table DIR``: re-render Table I and every figure from the CSV/JSON files an evaluation
wrote into DIR (no matcher is run, no cache is needed; the qualitative figure needs the dataset)."""

from __future__ import annotations

import argparse
from pathlib import Path

from eval.figures import render_all
from eval.tables import PAPER_CSV, write_table1


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("dir", metavar="DIR", help="output directory of `cadsim evaluate`")
    parser.add_argument("--paper", default=str(PAPER_CSV), help="the paper's Table I (CSV)")


def run(args: argparse.Namespace) -> int:
    out = Path(args.dir)
    if not (out / "metrics_per_pair.csv").is_file() and not (out / "noise_runs.csv").is_file():
        raise SystemExit(
            f"{out}: no metrics_per_pair.csv or noise_runs.csv (run `cadsim evaluate`)"
        )
    markdown = write_table1(out, args.paper) if (out / "metrics_per_pair.csv").is_file() else ""
    for path in render_all(out):
        print(path)
    print(markdown)
    return 0
