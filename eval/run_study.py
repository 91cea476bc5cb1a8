"""``python -m eval.studies.<study>``: one study alone, against the datasets under ``--data`` and
an existing results folder ``--out`` (``make reproduce``'s options and defaults, the same result
cache). It runs the study's own stages — and the dataset stages of the studies whose datasets it
reads (transfer: cad-v2x's training split), which only generate what is missing — then writes ``claims.csv``, the report and, for the
repository's ``results/``, README.md's results section again. Where the study reads another
study's results (``Study.needs``: V2X and multi-agent read Table I's chosen configurations,
``tuning.csv``) and ``--out`` lacks them, it stops with one line naming the study to run first.
The run record and ``cold_run.json`` stay those of the last full run (a study alone is never a
cold run of the benchmark). A user error is one line on stderr, exit status 2.
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

from eval.engine.study import Study
from eval.pipeline.sizes import ROOT
from eval.pipeline.stage import walk
from eval.readme_results import update_readme, write_report
from eval.report.run_record import StageTimer
from eval.reproduce import _start, build_parser
from eval.studies import register, studies
from eval.studies import study as declared

log = logging.getLogger("eval.reproduce")


def study_parser(study: Study) -> argparse.ArgumentParser:
    """The options of ``python -m eval.studies.<name>``: :func:`eval.reproduce.build_parser`'s
    (the same sizes, folders and cache as a full run), described for this study."""
    parser = build_parser()
    parser.prog = f"python -m eval.studies.{study.name}"
    first = ", ".join(f"`python -m eval.studies.{name}`" for name in study.needs)
    parser.description = (
        f"Run the {study.label} study alone against the datasets under --data and the results "
        "folder --out: generate only the datasets it lacks (matcher runs come from the same "
        "cache as `make reproduce`), write its tables, then claims.csv and the report again."
        + (f" It reads what {first} writes: run that first." if study.needs else "")
    )
    return parser


def missing_inputs(study: Study, out: Path) -> list[str]:
    """One line per result file of another study that ``study`` reads and ``out`` lacks."""
    return [
        f"{out / path} missing: the {study.label} study reads it; run "
        f"`python -m eval.studies.{name} --out {out}` first"
        for name, path in study.needs.items()
        if path and not (out / path).exists()
    ]


def run_study(name: str | Study, argv: list[str] | None = None) -> int:
    """Run study ``name`` alone (module docstring), or a declaration of one that is not in the
    list of studies (an example of your own); returns the exit status."""
    from cadsim.user_errors import is_user_error, one_line
    from eval.report.figures import render_all

    study = declared(name) if isinstance(name, str) else name
    if not isinstance(name, str) and study.name not in [s.name for s in studies()]:
        register(study)  # its claims and report part go into the report like a built-in's
    name = study.name
    args = study_parser(study).parse_args(argv)
    logging.basicConfig(
        level=logging.INFO, format="%(asctime)s %(name)s: %(message)s", datefmt="%H:%M:%S"
    )
    try:
        missing = missing_inputs(study, Path(args.out))
        if missing:
            raise ValueError("; ".join(missing))
        state, _ = _start(args)
        # the dataset stages of a study whose datasets (not results) this one reads
        needed = [declared(n) for n, path in study.needs.items() if not path]
        stages = [s for other in needed for s in other.stages if not s.executor]
        stages += [*study.stages, *study.closing_stages]
        timer = StageTimer()
        walk(stages, state, timer)
        if not study.closing_stages:  # Table I's closing stage renders every figure itself
            render_all(state.out)
        for path in write_report(state.out):
            log.info("report written: %s", path)
        if state.out.resolve() == (ROOT / "results").resolve():
            update_readme(ROOT / "README.md", state.out)
        log.info(
            "%s: %s", study.label, ", ".join(f"{k} {v:.1f} s" for k, v in timer.seconds.items())
        )
    except Exception as error:
        if not is_user_error(error):
            raise
        print(f"python -m eval.studies.{name}: {one_line(error)}", file=sys.stderr)
        return 2
    return 0
