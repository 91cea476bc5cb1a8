"""``cadsim table DIR``: re-render Table I (every variant present: tuned, untuned, paper protocol),
the paired differences, every study's tables that its files allow (``Study.tables``: the
external table and the ranking agreement when ``DIR/external/`` holds an evaluation) and every
figure from the CSV/JSON files an evaluation wrote
into DIR (no matcher is run, no cache is needed; the qualitative figure needs the dataset)."""

from __future__ import annotations

import argparse

from eval.protocol.variants import VARIANTS, variant_path
from eval.report.figures import render_all
from eval.report.tables import PAPER_CSV, write_tables
from eval.studies import studies


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("dir", metavar="DIR", help="output directory of `cadsim evaluate`")
    parser.add_argument(
        "--paper-table", default=str(PAPER_CSV), help="the paper's Table I (CSV) shown beside ours"
    )


def run(args: argparse.Namespace) -> int:
    from eval.core.result_files import check_outputs

    out = check_outputs(args.dir)
    evaluated = any(variant_path(out, "metrics_per_pair", v, ".csv").is_file() for v in VARIANTS)
    swept = any(
        (out / n).is_file()
        for n in ("noise_runs.csv", "regime_sweep.csv", "localisation_sweep.csv")
    )
    markdown = write_tables(out, args.paper_table) if evaluated else ""
    written = [path for study in studies() if study.tables for path in study.tables(out)]
    if not evaluated and not swept and not written:
        raise SystemExit(
            f"{out}: no metrics_per_pair*.csv, noise_runs.csv or regime_sweep.csv "
            "(run `cadsim evaluate`)"
        )
    for path in written:
        print(path)
    for path in render_all(out):
        print(path)
    print(markdown)
    return 0
