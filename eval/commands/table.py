"""``cadsim table DIR``: re-render Table I (every variant present: tuned, untuned, paper protocol),
the paired differences, the external table and the ranking agreement (when
``DIR/external/`` holds an evaluation) and every figure from the CSV/JSON files an evaluation wrote
into DIR (no matcher is run, no cache is needed; the qualitative figure needs the dataset)."""

from __future__ import annotations

import argparse

from eval.protocol.variants import VARIANTS, variant_path
from eval.report.figures import render_all
from eval.report.tables import PAPER_CSV, write_tables
from eval.studies.external.agreement import write_agreement
from eval.studies.external.evaluation import SUBDIR, write_table_external


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
    external = (out / SUBDIR / "metrics_per_pair.csv").is_file()
    if not evaluated and not swept and not external:
        raise SystemExit(
            f"{out}: no metrics_per_pair*.csv, noise_runs.csv or regime_sweep.csv "
            "(run `cadsim evaluate`)"
        )
    markdown = write_tables(out, args.paper_table) if evaluated else ""
    if external:
        write_table_external(out)
        write_agreement(out)
        print(out / "table_external.md")
    for path in render_all(out):
        print(path)
    print(markdown)
    return 0
