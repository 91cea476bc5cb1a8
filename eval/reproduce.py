"""``make reproduce`` = ``python -m eval.reproduce``: Table I, Fig. 4, the PR curves, the
qualitative figure and the run record, from nothing but the repository.

Stages (each cached, so a second run only re-renders): generate every scenario's test dataset
(the scenario's seed) and validation dataset (seed + VAL_SEED_OFFSET: other simulation seeds) under
``--data``; evaluate all matchers × runs on both (τ calibrated on validation only); the CAD noise
sweep (re-detection on stored clean depth); tables and figures; run record. Ends by printing
Table I beside the paper's.

Tiny run (the test suite's): ``python -m eval.reproduce --pairs 2 --matchers sm,maximin
--rates 0,0.01 --out DIR --data DIR --cache DIR``.
"""

from __future__ import annotations

import argparse
import logging
import sys
import time
from dataclasses import asdict
from pathlib import Path

from eval.cache import ResultCache, code_version
from eval.commands.evaluate import (
    DEFAULT_CACHE,
    dataset_label,
    evaluate,
    open_entry,
    parse_matchers,
)
from eval.commands.sweep_noise import DEFAULT_RATES, parse_rates, sweep
from eval.executor import add_scheduler_argument, make_executor
from eval.figures import render_all
from eval.readme_results import update_readme
from eval.run_record import StageTimer, scenario_file, write_run_record
from eval.runner import Runner
from eval.tables import PAPER_CSV, write_table1

log = logging.getLogger("eval.reproduce")

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ("scenarios/cad-intersection.toml", "scenarios/mrc-arena.toml")
VAL_SEED_OFFSET = 1000
DEFAULT_VAL_PAIRS = 25
# The noise sweep is lighter than Table I to keep a cold `make reproduce` within ~15 minutes on two
# cores: the first SWEEP_PAIRS test pairs, SWEEP_RUNS seeds (docs/evaluation.md).
SWEEP_PAIRS = 25
SWEEP_RUNS = 4
SWEEP_DATASET = "CAD"


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m eval.reproduce", description=__doc__.splitlines()[0]
    )
    p.add_argument(
        "--scenarios",
        nargs="+",
        default=None,
        help="scenario files (default: those of SCENARIOS that exist)",
    )
    p.add_argument(
        "--pairs",
        type=int,
        default=None,
        help="test pairs per dataset (default: the scenario's, 50)",
    )
    p.add_argument(
        "--val-pairs",
        type=int,
        default=None,
        help=f"validation pairs (default: min({DEFAULT_VAL_PAIRS}, --pairs))",
    )
    p.add_argument("--matchers", default="all", help="'all' or a comma list")
    p.add_argument("--runs", type=int, default=4, help="runs (seeds 0..RUNS-1) for Table I")
    p.add_argument(
        "--rates", default=",".join(map(str, DEFAULT_RATES)), help="noise rates for Fig. 4"
    )
    p.add_argument(
        "--sweep-runs",
        type=int,
        default=SWEEP_RUNS,
        help=f"runs per noise rate (default {SWEEP_RUNS})",
    )
    p.add_argument(
        "--sweep-pairs",
        type=int,
        default=SWEEP_PAIRS,
        help=f"sweep the first N test pairs (default {SWEEP_PAIRS}; 0: all)",
    )
    p.add_argument("--out", default="results", help="output directory (default: results)")
    p.add_argument("--data", default="data", help="dataset directory (default: data)")
    p.add_argument(
        "--cache", default=DEFAULT_CACHE, help=f"result cache (default: {DEFAULT_CACHE})"
    )
    p.add_argument("--workers", type=int, default=None, help="processes (default: one per core)")
    add_scheduler_argument(p)
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    return p


def _shown(path: Path) -> str:
    """`path` relative to the repository when inside it (records stay machine-independent)."""
    try:
        return path.resolve().relative_to(ROOT).as_posix()
    except ValueError:
        return str(path)


def _generate(
    scenario: Path, out: Path, pairs: int | None, seed: int | None, args: argparse.Namespace
):
    from cadsim.generation.pipeline import generate_dataset

    result = generate_dataset(
        scenario,
        out.resolve(),
        pairs=pairs,
        seed=seed,
        workers=args.workers,
        progress=not args.quiet,
        scheduler=args.scheduler,
    )
    log.info(
        "%s: %d pairs (%d new) in %.1f s", out, result.pairs, result.new_records, result.seconds
    )
    return result


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    logging.basicConfig(
        level=logging.INFO, format="%(asctime)s %(name)s: %(message)s", datefmt="%H:%M:%S"
    )
    from cadsim.scenario import load_scenario

    started = time.perf_counter()
    timer = StageTimer()
    progress = not args.quiet
    paths = (
        [Path(s) for s in args.scenarios]
        if args.scenarios
        else [ROOT / s for s in SCENARIOS if (ROOT / s).is_file()]
    )
    if not paths:
        raise SystemExit(f"no scenario files found ({', '.join(SCENARIOS)})")
    data, out = Path(args.data), Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    matchers = parse_matchers(args.matchers)
    seeds = list(range(args.runs))
    sweep_seeds = list(range(args.sweep_runs))
    sweep_pairs = args.sweep_pairs or None
    rates = parse_rates(args.rates)

    entries, datasets_record = [], []
    with timer.stage("generate"):
        for path in paths:
            scenario = load_scenario(path)
            label = dataset_label(scenario.name)
            pairs = scenario.pairs if args.pairs is None else args.pairs
            val_pairs = args.val_pairs or min(DEFAULT_VAL_PAIRS, pairs)
            test_dir, val_dir = data / label.lower(), data / f"{label.lower()}-val"
            val_seed = scenario.seed + VAL_SEED_OFFSET
            log.info(
                "[generate] %s: %d test pairs (seed %d), %d validation pairs (seed %d)",
                label,
                pairs,
                scenario.seed,
                val_pairs,
                val_seed,
            )
            made = _generate(path, test_dir, pairs, None, args)
            made_val = _generate(path, val_dir, val_pairs, val_seed, args)
            entries.append(open_entry(test_dir, val_dir))
            datasets_record.append(
                {"label": label, "scenario": scenario_file(path) | {"path": _shown(path)}}
                | {"test_dir": str(test_dir), "test_seed": scenario.seed, "test_pairs": pairs}
                | {"val_dir": str(val_dir), "val_seed": val_seed, "val_pairs": val_pairs}
                | {"test_checksum": entries[-1].test_checksum}
                | {"val_checksum": entries[-1].val_checksum}
                | {"new_records": made.new_records + made_val.new_records}
            )

    with make_executor(args.workers, args.scheduler) as executor:
        runner = Runner(ResultCache(args.cache), executor, progress=progress)
        with timer.stage("evaluate"):
            log.info(
                "[evaluate] %d matchers × %d runs on %s",
                len(matchers),
                len(seeds),
                ", ".join(e.label for e in entries),
            )
            taus = evaluate(entries, matchers, seeds, runner, out)
        runs = {"evaluate": asdict(runner.totals)}
        sweep_entry = next((e for e in entries if e.label == SWEEP_DATASET), None)
        with timer.stage("noise_sweep"):
            if sweep_entry is None:
                log.warning("[noise sweep] skipped: no %s dataset", SWEEP_DATASET)
            else:
                log.info(
                    "[noise sweep] %s: rates %s × %d runs",
                    sweep_entry.label,
                    rates,
                    len(sweep_seeds),
                )
                sweep(sweep_entry, matchers, sweep_seeds, rates, runner, out, sweep_pairs)
        runs["noise_sweep"] = {k: v - runs["evaluate"][k] for k, v in asdict(runner.totals).items()}

    with timer.stage("tables_figures"):
        markdown = write_table1(out, PAPER_CSV)
        figures = render_all(out)
        log.info("[figures] %s", ", ".join(str(f) for f in figures))

    record = write_run_record(
        out / "run_record.json",
        timer,
        command=" ".join(
            ["python -m eval.reproduce", *(argv if argv is not None else sys.argv[1:])]
        ),
        datasets=datasets_record,
        matchers=[m.label for m in matchers],
        seeds=seeds,
        noise_sweep={"dataset": SWEEP_DATASET if sweep_entry else None, "rates": rates}
        | {"seeds": sweep_seeds, "pairs": sweep_pairs},
        thresholds=taus,
        runs=runs,
        code_version=code_version(),
        cache=str(args.cache),
    )
    log.info("run record: %s", record)
    if out.resolve() == (ROOT / "results").resolve() and update_readme(ROOT / "README.md", out):
        log.info("README.md results section rewritten from %s", out)
    print()
    print("Table I — ours beside the paper's (results/table1.md)")
    print()
    print(markdown)
    print(
        f"wall time: {time.perf_counter() - started:.1f} s "
        + ", ".join(f"{k} {v:.1f} s" for k, v in timer.seconds.items())
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
