"""``make reproduce`` = ``python -m eval.reproduce``: Table I (tuned, untuned, paper protocol),
paired differences, regime cards, the regime sweep, dataset spread, Fig. 4, the PR curves, the
qualitative figure and the run record, from nothing but the repository.

Stages (each cached, so a second run only re-renders): generate every scenario's test dataset
(the scenario's seed) and validation dataset (seed + VAL_SEED_OFFSET: other simulation seeds) under
``--data``, and for the default CAD two more test datasets (seed + SPREAD_SEED_OFFSETS); evaluate
all matchers × runs (parameters tuned and τ calibrated on validation only; the untuned table
beside); the paper's protocol; the CAD noise sweep (re-detection on stored clean depth); the regime
sweep on every dataset; the dataset spread; the localisation sweep on CAD (prior re-drawn per
position error); the V2X task on cad-v2x and its box-only table (:mod:`eval.studies.v2x_boxes`,
``--no-boxes`` skips it), the LiDAR table and the paired camera-vs-LiDAR comparison on the
two-sensor cad-v2x-both (:mod:`eval.studies.v2x_lidar`, :mod:`eval.studies.v2x_sensors`,
``--no-lidar``); the multi-agent table on cad-multi
(:mod:`eval.studies.multiagent`); the temporal table on cad-v2x-seq (:mod:`eval.studies.temporal`,
``--no-temporal`` skips it); the external benchmark on the shipped DMGM CAD pairs (``eval/data/dmgm-cad``,
:mod:`eval.studies.external`) and the ranking agreement with it (:mod:`eval.studies.agreement`); tables and
figures; run record. Ends by printing Table I beside the paper's.

Tiny run (the test suite's): ``python -m eval.reproduce --pairs 2 --matchers sm,maximin
--rates 0,0.01 --out DIR --data DIR --cache DIR``.
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
import time
from dataclasses import asdict
from pathlib import Path

import pandas as pd

from eval.commands.sweep_localisation import (
    DEFAULT_LATENCIES_MS,
    DEFAULT_PRESET,
    DEFAULT_SCALES,
    DEFAULT_SIGMAS,
    parse_sigmas,
    preset_levels,
    sweep_localisation,
    sweep_presets,
    sweep_specs,
    write_preset_sweep,
)
from eval.commands.sweep_localisation import (
    DEFAULT_MATCHERS as LOCALISATION_MATCHERS,
)
from eval.commands.sweep_localisation import write_sweep as write_localisation_sweep
from eval.commands.sweep_noise import DEFAULT_RATES, parse_rates, sweep
from eval.commands.sweep_regime import DEFAULT_KEEP, parse_keep, sweep_regime, write_sweep
from eval.core.cache import ResultCache, code_version
from eval.core.executor import add_scheduler_argument, make_executor
from eval.core.result_files import write_csv
from eval.core.runner import Runner
from eval.protocol.cues import EQUAL_CUE_OPTIONS
from eval.protocol.variants import PAPER_OPTIONS
from eval.readme_results import update_readme, write_report
from eval.report.figures import render_all
from eval.report.run_record import (
    COLD_RECORD,
    StageTimer,
    keep_cold_record,
    scenario_file,
    write_run_record,
)
from eval.report.tables import PAPER_CSV, write_tables
from eval.studies.agreement import write_agreement
from eval.studies.evaluation import (
    DEFAULT_CACHE,
    chosen_specs,
    dataset_label,
    evaluate,
    open_entry,
    parse_matchers,
)
from eval.studies.external import (
    CALIBRATION_DIR,
    SUBDIR,
    TEST_DIR,
    evaluate_external,
    external_matchers,
)
from eval.studies.multiagent import LABEL as MA_LABEL
from eval.studies.multiagent import MATCHERS as MA_MATCHERS
from eval.studies.multiagent import PRESETS as MA_PRESETS
from eval.studies.multiagent import SCENARIO as MA_SCENARIO
from eval.studies.multiagent import SUBSETS as MA_SUBSETS
from eval.studies.multiagent import TEST_SNAPSHOTS as MA_TEST_SNAPSHOTS
from eval.studies.multiagent import VAL_SNAPSHOTS as MA_VAL_SNAPSHOTS
from eval.studies.multiagent import evaluate_multiagent
from eval.studies.prior_defaults import SENSITIVITY, write_sensitivity
from eval.studies.spread import spread_rows
from eval.studies.temporal import LABEL as TEMPORAL_LABEL
from eval.studies.temporal import METHODS as TEMPORAL_METHODS
from eval.studies.temporal import PRESETS as TEMPORAL_PRESETS
from eval.studies.temporal import RUNS as TEMPORAL_RUNS
from eval.studies.temporal import SCENARIO as TEMPORAL_SCENARIO
from eval.studies.temporal import TEST_SEQUENCES as TEMPORAL_TEST
from eval.studies.temporal import VAL_SEQUENCES as TEMPORAL_VAL
from eval.studies.temporal import evaluate_temporal, temporal_tuning_record
from eval.studies.transfer import evaluate_transfer, test_sets, train_models, train_sets
from eval.studies.v2x_boxes import evaluate_boxes
from eval.studies.v2x_lidar import SCENARIO as LIDAR_SCENARIO
from eval.studies.v2x_lidar import evaluate_lidar, generate_lidar_splits
from eval.studies.v2x_table import PRESETS as V2X_PRESETS
from eval.studies.v2x_table import evaluate_v2x
from matchers.fusion import usable_fusions

log = logging.getLogger("eval.reproduce")

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = (
    "scenarios/cad-intersection.toml",
    "scenarios/mrc-arena.toml",
    "scenarios/cad-dense.toml",
)
VAL_SEED_OFFSET = 1000
DEFAULT_VAL_PAIRS = 50
# The sweeps are lighter than Table I to keep a cold `make reproduce` within 15 minutes on two
# cores (docs/evaluation.md). Noise: the first SWEEP_PAIRS test pairs, SWEEP_RUNS seeds.
SWEEP_PAIRS = 25
SWEEP_RUNS = 4
SWEEP_DATASETS = ("CAD", "MRC")  # Fig. 4 rows: the paper's CAD, and MRC for its geometry
# Regime sweep: every dataset, the first REGIME_PAIRS test pairs × REGIME_RUNS runs per level (each
# run its own thinning draw: 5 independent draws), τ recalibrated per level on the thinned
# validation set with run 0 alone.
REGIME_PAIRS = 25
REGIME_RUNS = 5
REGIME_VAL_RUNS = 1
# Dataset spread: the default CAD generated again with these scenario-seed offsets.
SPREAD_DATASET = "CAD"
SPREAD_SEED_OFFSETS = (2000, 3000)
SPREAD_PAIRS = 25
SPREAD_RUNS = 4
# Localisation sweep (CAD): the first LOCALISATION_PAIRS test pairs × LOCALISATION_RUNS seeds per
# position error, τ per error on the validation set re-drawn at that error.
LOCALISATION_DATASET = "CAD"
LOCALISATION_PAIRS = 25
LOCALISATION_RUNS = 4
# External benchmark (DMGM CAD): EXTERNAL_RUNS seeds; parameters tuned and τ calibrated on all of
# sequence 070 (EXTERNAL_TUNE_PAIRS = 0: every pair), as the prior defaults were derived
# (docs/external-data.md).
EXTERNAL_RUNS = 1
EXTERNAL_TUNE_PAIRS = 0
# V2X realism (cad-v2x, outside Table I): test, validation and training splits on disjoint
# scenario seeds (seed, seed + VAL_SEED_OFFSET, seed + V2X_TRAIN_SEED_OFFSET; the training split,
# V2X_TRAIN_FACTOR × the test pairs, is for learned matchers and is never evaluated on), then the
# localisation sweep's preset axes (error scale, latency) with CAD's tuned parameters, τ per level.
V2X_SCENARIO = "scenarios/cad-v2x.toml"
V2X_LABEL = "CAD-V2X"
V2X_PAIRS = 25
V2X_TRAIN_SEED_OFFSET = 2000
V2X_TRAIN_FACTOR = 2
V2X_RUNS = 3
# Multi-agent (cad-multi: 4 vehicles + 2 roadside units per snapshot): test and validation
# snapshots on disjoint scenario seeds, two-view matchers on every pair of views, fused per
# subset of N views (eval.studies.multiagent), MULTIAGENT_RUNS seeds.
MULTIAGENT_RUNS = 2
# Transfer of the learned matchers (eval.studies.transfer): CAD's training split on its own
# scenario seed (seed + CAD_TRAIN_SEED_OFFSET; 1000 is validation, 2000/3000 the spread sets),
# CAD_TRAIN_PAIRS pairs; models trained into DATA/models.
CAD_TRAIN_SEED_OFFSET = 4000
CAD_TRAIN_PAIRS = 50


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
    p.add_argument(
        "--no-tune",
        dest="tune",
        action="store_false",
        help="skip the parameter search (Table I then runs every matcher with its defaults)",
    )
    p.add_argument(
        "--keep",
        default=",".join(f"{k:g}" for k in DEFAULT_KEEP),
        help="keep levels of the regime sweep (empty: no sweep)",
    )
    p.add_argument(
        "--regime-pairs",
        type=int,
        default=REGIME_PAIRS,
        help=f"regime sweep on the first N test pairs (default {REGIME_PAIRS}; 0: all)",
    )
    p.add_argument(
        "--regime-runs",
        type=int,
        default=REGIME_RUNS,
        help=f"runs (= thinning draws) per keep level (default {REGIME_RUNS})",
    )
    p.add_argument(
        "--spread-pairs",
        type=int,
        default=SPREAD_PAIRS,
        help=f"pairs of each extra {SPREAD_DATASET} dataset (default {SPREAD_PAIRS}; 0: no spread)",
    )
    p.add_argument(
        "--spread-runs",
        type=int,
        default=SPREAD_RUNS,
        help=f"runs on each extra dataset (default {SPREAD_RUNS})",
    )
    p.add_argument(
        "--localisation-sigmas",
        default=",".join(f"{s:g}" for s in DEFAULT_SIGMAS),
        help="position errors (m) of the localisation sweep (empty: no sweep)",
    )
    p.add_argument(
        "--localisation-pairs",
        type=int,
        default=LOCALISATION_PAIRS,
        help=f"localisation sweep on the first N test pairs (default {LOCALISATION_PAIRS}; 0: all)",
    )
    p.add_argument(
        "--localisation-runs",
        type=int,
        default=LOCALISATION_RUNS,
        help=f"runs per position error (default {LOCALISATION_RUNS})",
    )
    p.add_argument(
        "--external-runs",
        type=int,
        default=EXTERNAL_RUNS,
        help=f"runs on the DMGM CAD pairs (default {EXTERNAL_RUNS}; 0: skip the external stage)",
    )
    p.add_argument(
        "--external-tune-pairs",
        type=int,
        default=EXTERNAL_TUNE_PAIRS,
        help=f"tune on the first N pairs of sequence 070 (default {EXTERNAL_TUNE_PAIRS}; 0: all)",
    )
    p.add_argument(
        "--v2x-runs",
        type=int,
        default=V2X_RUNS,
        help=f"runs per level of the cad-v2x preset sweep (default {V2X_RUNS}; 0: skip cad-v2x)",
    )
    p.add_argument(
        "--multiagent-runs",
        type=int,
        default=MULTIAGENT_RUNS,
        help=f"runs of the multi-agent table (default {MULTIAGENT_RUNS}; 0: skip cad-multi)",
    )
    p.add_argument(
        "--no-transfer",
        action="store_true",
        help="skip the learned matchers' transfer matrix (also skipped without cad-v2x)",
    )
    p.add_argument(
        "--no-boxes",
        action="store_true",
        help="skip the box-only V2X table (cad-v2x exported and re-imported as 3-D boxes)",
    )
    p.add_argument(
        "--no-lidar",
        action="store_true",
        help=f"skip the LiDAR V2X table ({LIDAR_SCENARIO}: boxes from cadsim's LiDAR detector)",
    )
    p.add_argument(
        "--no-temporal",
        action="store_true",
        help=f"skip the temporal table on {TEMPORAL_SCENARIO} (also skipped without the file)",
    )
    p.add_argument("--out", default="results", help="output directory (default: results)")
    p.add_argument("--data", default="data", help="dataset directory (default: data)")
    p.add_argument(
        "--cache", default=DEFAULT_CACHE, help=f"result cache (default: {DEFAULT_CACHE})"
    )
    p.add_argument("--workers", type=int, default=None, help="processes (default: one per core)")
    add_scheduler_argument(p)
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
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
        progress=not args.no_progress,
        scheduler=args.scheduler,
    )
    log.info(
        "%s: %d pairs (%d new) in %.1f s", out, result.pairs, result.new_records, result.seconds
    )
    return result


def _tuning_record(out: Path) -> dict:
    """{dataset: {matcher: {"params": chosen options, "val_f1": its validation F1}}} from
    ``tuning.csv`` (empty without it)."""
    path = out / "tuning.csv"
    if not path.is_file():
        return {}
    table = pd.read_csv(path, keep_default_na=False, na_values=[""])
    chosen = table[table["chosen"].astype(str) == "True"]
    record: dict = {}
    for row in chosen.itertuples(index=False):
        record.setdefault(row.dataset, {})[row.matcher] = {
            "params": json.loads(row.params),
            "val_f1": float(row.val_f1),
            "configs": int(
                (table["dataset"].eq(row.dataset) & table["matcher"].eq(row.matcher)).sum()
            ),
        }
    return record


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    logging.basicConfig(
        level=logging.INFO, format="%(asctime)s %(name)s: %(message)s", datefmt="%H:%M:%S"
    )
    from cadsim.scenario import load_scenario

    started = time.perf_counter()
    timer = StageTimer()
    progress = not args.no_progress
    paths = (
        [Path(s) for s in args.scenarios]
        if args.scenarios
        else [ROOT / s for s in SCENARIOS if (ROOT / s).is_file()]
    )
    if not paths:
        raise SystemExit(f"no scenario files found ({', '.join(SCENARIOS)})")
    from eval.core.result_files import check_outputs

    data, out = Path(args.data), check_outputs(args.out, args.cache)
    cold = cold_start(data, Path(args.cache))
    out.mkdir(parents=True, exist_ok=True)
    matchers = parse_matchers(args.matchers)
    seeds = list(range(args.runs))
    sweep_seeds = list(range(args.sweep_runs))
    sweep_pairs = args.sweep_pairs or None
    rates = parse_rates(args.rates)
    keeps = parse_keep(args.keep) if args.keep.strip() else []
    regime_seeds = list(range(args.regime_runs))
    regime_val_seeds = list(range(REGIME_VAL_RUNS))
    regime_pairs = args.regime_pairs or None
    spread_seeds = list(range(args.spread_runs))

    entries, datasets_record, spread_sets = [], [], []
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
            new_records = made.new_records + made_val.new_records
            if label == SPREAD_DATASET and args.spread_pairs:
                spread_sets.append((str(test_dir), entries[-1].test_checksum, scenario.seed))
                spread_pairs = min(args.spread_pairs, pairs)
                for offset in SPREAD_SEED_OFFSETS:
                    seed = scenario.seed + offset
                    extra = data / f"{label.lower()}-seed{seed}"
                    log.info("[generate] %s spread: %d pairs (seed %d)", label, spread_pairs, seed)
                    new_records += _generate(path, extra, spread_pairs, seed, args).new_records
                    checksum = open_entry(extra, None).test_checksum
                    spread_sets.append((str(extra), checksum, seed))
            datasets_record.append(
                {"label": label, "scenario": scenario_file(path) | {"path": _shown(path)}}
                | {"test_dir": str(test_dir), "test_seed": scenario.seed, "test_pairs": pairs}
                | {"val_dir": str(val_dir), "val_seed": val_seed, "val_pairs": val_pairs}
                | {"test_checksum": entries[-1].test_checksum}
                | {"val_checksum": entries[-1].val_checksum}
                | {"new_records": new_records}
            )

    runs: dict[str, dict] = {}

    def count(stage: str, before: dict) -> None:
        now = asdict(runner.totals)
        runs[stage] = {k: v - before.get(k, 0) for k, v in now.items()}

    with make_executor(args.workers, args.scheduler) as executor:
        runner = Runner(ResultCache(args.cache), executor, progress=progress)
        with timer.stage("evaluate"):
            log.info(
                "[evaluate] %d matchers × %d runs on %s%s",
                len(matchers),
                len(seeds),
                ", ".join(e.label for e in entries),
                " (parameters tuned on validation)" if args.tune else "",
            )
            taus = evaluate(entries, matchers, seeds, runner, out, tune=args.tune)
        count("evaluate", {})
        with timer.stage("equal_cues"):
            before = asdict(runner.totals)
            log.info("[equal cues] every paper matcher handed metric geometry and appearance")
            evaluate(entries, matchers, seeds, runner, out, tune=args.tune, protocol="equal_cues")
        count("equal_cues", before)
        with timer.stage("paper_protocol"):
            before = asdict(runner.totals)
            log.info("[paper protocol] image-space pairwise terms, full assignment, no τ")
            evaluate(entries, matchers, seeds, runner, out, protocol="paper")
        count("paper_protocol", before)
        sweep_entries = [e for e in entries if e.label in SWEEP_DATASETS]
        with timer.stage("noise_sweep"):
            before = asdict(runner.totals)
            (out / "noise_runs.csv").unlink(missing_ok=True)
            if not sweep_entries:
                log.warning("[noise sweep] skipped: none of %s", ", ".join(SWEEP_DATASETS))
            for sweep_entry in sweep_entries:
                log.info(
                    "[noise sweep] %s: rates %s × %d runs",
                    sweep_entry.label,
                    rates,
                    len(sweep_seeds),
                )
                sweep(sweep_entry, matchers, sweep_seeds, rates, runner, out, sweep_pairs)
        count("noise_sweep", before)
        with timer.stage("regime_sweep"):
            before = asdict(runner.totals)
            (out / "regime_sweep.csv").unlink(missing_ok=True)
            (out / "crossovers.csv").unlink(missing_ok=True)
            for entry in entries if keeps else []:
                log.info(
                    "[regime sweep] %s: keep %s × %d runs, first %s test pairs",
                    entry.label,
                    keeps,
                    len(regime_seeds),
                    regime_pairs or "all",
                )
                named, _ = chosen_specs(out, entry.label, matchers)
                result = sweep_regime(
                    entry, named, regime_seeds, keeps, runner, regime_pairs, regime_val_seeds
                )
                write_sweep(out, result)
        count("regime_sweep", before)
        with timer.stage("dataset_spread"):
            before = asdict(runner.totals)
            (out / "dataset_spread.csv").unlink(missing_ok=True)
            if spread_sets:
                named, spread_taus = chosen_specs(out, SPREAD_DATASET, matchers)
                log.info("[dataset spread] %s: %d datasets", SPREAD_DATASET, len(spread_sets))
                main_set, extra_sets = spread_sets[:1], spread_sets[1:]
                table = pd.concat(
                    [
                        spread_rows(SPREAD_DATASET, main_set, named, spread_taus, seeds, runner),
                        spread_rows(
                            SPREAD_DATASET, extra_sets, named, spread_taus, spread_seeds, runner
                        ),
                    ],
                    ignore_index=True,
                )
                write_csv(table.round(6), out / "dataset_spread.csv")
        count("dataset_spread", before)
        loc_entry = next((e for e in entries if e.label == LOCALISATION_DATASET), None)
        loc_sigmas = (
            parse_sigmas(args.localisation_sigmas) if args.localisation_sigmas.strip() else []
        )
        loc_seeds = list(range(args.localisation_runs))
        with timer.stage("localisation_sweep"):
            before = asdict(runner.totals)
            (out / "localisation_sweep.csv").unlink(missing_ok=True)
            if loc_entry is not None and loc_sigmas:
                loc_base = parse_matchers(LOCALISATION_MATCHERS)
                loc_named = loc_base if args.tune else sweep_specs(out, loc_entry, loc_base)
                log.info(
                    "[localisation sweep] %s: position σ %s m × %d runs, first %s test pairs",
                    loc_entry.label,
                    loc_sigmas,
                    len(loc_seeds),
                    args.localisation_pairs or "all",
                )
                rows = sweep_localisation(
                    loc_entry,
                    loc_named,
                    loc_seeds,
                    loc_sigmas,
                    runner,
                    args.localisation_pairs or None,
                    tune=args.tune,
                )
                write_localisation_sweep(out, rows)
        count("localisation_sweep", before)
        v2x_seeds = list(range(args.v2x_runs))
        v2x_record: dict = {}
        with timer.stage("v2x_generate"):
            v2x_entry = _generate_v2x(data, args, v2x_record) if v2x_seeds else None
        with timer.stage("v2x_sweep"):
            before = asdict(runner.totals)
            (out / "localisation_presets.csv").unlink(missing_ok=True)
            if v2x_entry is not None:
                levels = preset_levels(DEFAULT_PRESET, DEFAULT_SCALES, DEFAULT_LATENCIES_MS)
                v2x_named, _ = chosen_specs(out, "CAD", parse_matchers(LOCALISATION_MATCHERS))
                log.info(
                    "[v2x sweep] %s: %s × %d levels (scale, latency) × %d runs, CAD's parameters",
                    V2X_LABEL,
                    DEFAULT_PRESET,
                    len(levels),
                    len(v2x_seeds),
                )
                rows = sweep_presets(v2x_entry, v2x_named, v2x_seeds, levels, runner)
                write_preset_sweep(out, rows)
                v2x_record |= {"preset": DEFAULT_PRESET, "levels": [lv[1] for lv in levels]}
                v2x_record |= {"seeds": v2x_seeds, "matchers": list(v2x_named)}
        count("v2x_sweep", before)
        with timer.stage("v2x_table"):
            before = asdict(runner.totals)
            if v2x_entry is not None:
                v2x_matchers = external_matchers(args.matchers)
                log.info(
                    "[v2x table] %s: %d matchers × %d presets × %d runs",
                    V2X_LABEL,
                    len(v2x_matchers),
                    len(V2X_PRESETS),
                    len(v2x_seeds),
                )
                evaluate_v2x(
                    v2x_entry.test_dir,
                    v2x_entry.val_dir,
                    V2X_LABEL,
                    v2x_matchers,
                    v2x_seeds,
                    runner,
                    out,
                    tune=args.tune,
                )
                v2x_record |= {"table_presets": list(V2X_PRESETS)}
        count("v2x_table", before)
        with timer.stage("v2x_boxes"):
            before = asdict(runner.totals)
            if v2x_entry is not None and not args.no_boxes:
                _, v2x_record["boxes"] = evaluate_boxes(
                    v2x_entry.test_dir,
                    v2x_entry.val_dir,
                    data,
                    external_matchers(args.matchers),
                    v2x_seeds,
                    runner,
                    out,
                    tune=args.tune,
                )
        count("v2x_boxes", before)
        with timer.stage("v2x_lidar"):
            before = asdict(runner.totals)
            if v2x_seeds and not args.no_lidar and (ROOT / LIDAR_SCENARIO).is_file():
                lidar_pairs = V2X_PAIRS if args.pairs is None else min(args.pairs, V2X_PAIRS)
                test, val, v2x_record["lidar"] = generate_lidar_splits(
                    ROOT, data, lidar_pairs, VAL_SEED_OFFSET,
                    lambda path, folder, n, seed: _generate(path, folder, n, seed, args),
                )  # fmt: skip
                camera_table = None if v2x_entry is None else (v2x_entry.test_dir, v2x_entry.val_dir)  # fmt: skip
                _, used = evaluate_lidar(
                    test, val, external_matchers(args.matchers), v2x_seeds, runner, out,
                    tune=args.tune, camera_table=camera_table,
                )  # fmt: skip
                v2x_record["lidar"] |= used
        count("v2x_lidar", before)
        external_seeds = list(range(args.external_runs))
        with timer.stage("external"):
            before = asdict(runner.totals)
            if external_seeds:
                external = external_matchers(args.matchers)
                log.info(
                    "[external] DMGM CAD: %d matchers × %d runs; τ and tuning on sequence 070",
                    len(external),
                    len(external_seeds),
                )
                evaluate_external(
                    runner,
                    out,
                    external,
                    external_seeds,
                    tune=args.tune,
                    tune_pairs=args.external_tune_pairs or None,
                )
                write_agreement(out)
        count("external", before)
        with timer.stage("prior_sensitivity"):
            before = asdict(runner.totals)
            (out / SUBDIR / SENSITIVITY).unlink(missing_ok=True)
            if external_seeds and args.tune:
                log.info("[prior sensitivity] every grid point of the prior matchers on 069 + 071")
                write_sensitivity(out, runner)
        count("prior_sensitivity", before)
        multiagent_seeds = list(range(args.multiagent_runs))
        multiagent_record: dict = {}
        with timer.stage("multiagent_generate"):
            multi_dirs = (
                _generate_multi(data, args, multiagent_record) if multiagent_seeds else None
            )
        with timer.stage("multiagent"):
            before = asdict(runner.totals)
            for stale in ("table_multiagent.csv", "table_multiagent.md"):
                (out / stale).unlink(missing_ok=True)
            if multi_dirs is not None:
                multi_named, _ = chosen_specs(out, "CAD", parse_matchers(",".join(MA_MATCHERS)))
                log.info(
                    "[multiagent] %s: %d matchers × %d fusions × N in %s × %d presets × %d runs",
                    MA_LABEL,
                    len(multi_named),
                    len(usable_fusions()),
                    sorted(MA_SUBSETS),
                    len(MA_PRESETS),
                    len(multiagent_seeds),
                )
                evaluate_multiagent(*multi_dirs, multi_named, multiagent_seeds, runner, out)
                multiagent_record |= {"seeds": multiagent_seeds, "matchers": list(multi_named)}
                multiagent_record |= {"presets": list(MA_PRESETS), "fusions": usable_fusions()}
                multiagent_record |= {"subsets": {str(n): list(v) for n, v in MA_SUBSETS.items()}}
        count("multiagent", before)
        transfer_record: dict = {}
        do_transfer = not args.no_transfer and v2x_entry is not None and external_seeds
        with timer.stage("transfer_generate"):
            cad_train = _generate_cad_train(data, args, transfer_record) if do_transfer else None
        with timer.stage("transfer"):
            before = asdict(runner.totals)
            for stale in ("table_transfer.csv", "table_transfer.md"):
                (out / stale).unlink(missing_ok=True)
            if cad_train is not None:
                sets = train_sets(data, cad_train, CALIBRATION_DIR)
                tests = test_sets(data, out, TEST_DIR, CALIBRATION_DIR)
                log.info(
                    "[transfer] %d models × %d test sets × 4 learned matchers",
                    len(sets),
                    len(tests),
                )
                models = train_models(sets, data / "models", progress)
                evaluate_transfer(models, tests, runner, out)
                transfer_record |= {
                    "train": {k: [_shown(d) for d in v] for k, v in sets.items()},
                    "test": [t.label for t in tests],
                    "train_s": {k: round(v[1], 2) for k, v in models.items()},
                }
        count("transfer", before)
        temporal_record: dict = {}
        with timer.stage("temporal_generate"):
            temporal_dirs = (
                None if args.no_temporal else _generate_temporal(data, args, temporal_record)
            )
        with timer.stage("temporal"):
            for stale in ("table_temporal.csv", "table_temporal.md", "table_temporal_gain.csv"):
                (out / stale).unlink(missing_ok=True)
            if temporal_dirs is not None:
                log.info(
                    "[temporal] %s: %d methods × windows × %d presets × %d runs",
                    TEMPORAL_LABEL,
                    len(TEMPORAL_METHODS),
                    len(TEMPORAL_PRESETS),
                    len(TEMPORAL_RUNS),
                )
                table = evaluate_temporal(
                    *temporal_dirs, out, tune=args.tune, executor=executor
                )  # one task per preset
                temporal_record |= {"presets": list(TEMPORAL_PRESETS), "seeds": list(TEMPORAL_RUNS)}
                temporal_record |= {"methods": {m: list(w) for m, w in TEMPORAL_METHODS}}
                temporal_record |= {"tuning": temporal_tuning_record(table)}

    with timer.stage("tables_figures"):
        markdown = write_tables(out, PAPER_CSV)
        _write_regime_cards(out, entries + ([v2x_entry] if v2x_entry is not None else []))
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
        tuning=_tuning_record(out) if args.tune else {},
        paper_protocol={"options": PAPER_OPTIONS, "threshold": None, "tuned": False},
        equal_cues={
            "options": {k: dict(v) for k, v in EQUAL_CUE_OPTIONS.items()},
            "tuned": bool(args.tune),
        },
        noise_sweep={"datasets": [e.label for e in sweep_entries], "rates": rates}
        | {"seeds": sweep_seeds, "pairs": sweep_pairs},
        regime_sweep={"datasets": [e.label for e in entries] if keeps else [], "keep": keeps}
        | {"seeds": regime_seeds, "val_seeds": regime_val_seeds, "pairs": regime_pairs},
        localisation_sweep={
            "dataset": LOCALISATION_DATASET if loc_entry and loc_sigmas else None,
            "position_sigmas_m": loc_sigmas,
            "yaw_sigma_deg_per_m": 0.2 / 1.2,
            "seeds": loc_seeds,
            "pairs": args.localisation_pairs or None,
        },
        external={
            "test_dir": _shown(TEST_DIR),
            "calibration_dir": _shown(CALIBRATION_DIR),
            "seeds": external_seeds,
            "tune_pairs": args.external_tune_pairs or None,
        },
        dataset_spread={
            "dataset": SPREAD_DATASET if spread_sets else None,
            "generated": [{"dir": d, "scenario_seed": s} for d, _, s in spread_sets],
            "seeds": {"main": seeds, "extra": spread_seeds},
        },
        v2x=v2x_record,
        multiagent=multiagent_record,
        transfer=transfer_record,
        temporal=temporal_record,
        thresholds=taus,
        runs=runs,
        cold_start=cold,
        code_version=code_version(),
        cache=str(args.cache),
    )
    log.info("run record: %s", record)
    if keep_cold_record(out, json.loads(record.read_text())):
        log.info("cold stage times: %s", out / COLD_RECORD)
    for path in write_report(out):  # the report: out/README.md, out/index.html
        log.info("report written: %s", path)
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


def cold_start(data: Path, cache: Path) -> dict[str, bool]:
    """Whether this run starts cold: no dataset (nor trained model) under ``data`` and no cached
    run under ``cache``. Stage times are quoted as cold only from a run where ``cold`` is true
    (the README's stage table and every "≤ N min cold" goal line)."""

    def empty(path: Path) -> bool:
        return not path.is_dir() or not any(path.iterdir())

    out = {"data_empty": empty(data), "cache_empty": empty(cache)}
    return out | {"cold": out["data_empty"] and out["cache_empty"]}


def _generate_v2x(data: Path, args: argparse.Namespace, record: dict):
    """Generate cad-v2x's test, validation and training splits (module constants); its test +
    validation entry. ``record`` gets what the run record keeps of them."""
    from cadsim.scenario import load_scenario

    path = ROOT / V2X_SCENARIO
    scenario = load_scenario(path)
    pairs = V2X_PAIRS if args.pairs is None else min(args.pairs, V2X_PAIRS)
    base = data / V2X_LABEL.lower()
    splits = {
        "test": (base, pairs, scenario.seed),
        "val": (data / f"{base.name}-val", pairs, scenario.seed + VAL_SEED_OFFSET),
        "train": (
            data / f"{base.name}-train",
            V2X_TRAIN_FACTOR * pairs,
            scenario.seed + V2X_TRAIN_SEED_OFFSET,
        ),
    }
    for split, (folder, n, seed) in splits.items():
        log.info("[v2x generate] %s %s: %d pairs (seed %d)", V2X_LABEL, split, n, seed)
        made = _generate(path, folder, n, None if split == "test" else seed, args)
        record[split] = {"dir": str(folder), "pairs": n, "seed": seed}
        record[split] |= {"new_records": made.new_records}
    entry = open_entry(splits["test"][0], splits["val"][0], V2X_LABEL)
    record["scenario"] = scenario_file(path) | {"path": _shown(path)}
    record["test"]["checksum"], record["val"]["checksum"] = entry.test_checksum, entry.val_checksum
    return entry


def _generate_multi(data: Path, args: argparse.Namespace, record: dict) -> tuple[Path, Path]:
    """Generate cad-multi's test and validation snapshots (:mod:`eval.studies.multiagent`'s
    counts; disjoint scenario seeds); their folders. ``record`` gets what the run record keeps."""
    from cadsim.scenario import load_scenario

    path = ROOT / MA_SCENARIO
    scenario = load_scenario(path)
    splits = {
        "test": (data / "cad-multi", MA_TEST_SNAPSHOTS, scenario.seed),
        "val": (data / "cad-multi-val", MA_VAL_SNAPSHOTS, scenario.seed + VAL_SEED_OFFSET),
    }
    for split, (folder, n, seed) in splits.items():
        n = n if args.pairs is None else min(args.pairs, n)
        log.info("[multiagent generate] %s %s: %d snapshots (seed %d)", MA_LABEL, split, n, seed)
        made = _generate(path, folder, n, None if split == "test" else seed, args)
        record[split] = {"dir": str(folder), "snapshots": n, "seed": seed}
        record[split] |= {"new_records": made.new_records}
    record["scenario"] = scenario_file(path) | {"path": _shown(path)}
    return splits["test"][0], splits["val"][0]


def _generate_temporal(
    data: Path, args: argparse.Namespace, record: dict
) -> tuple[Path, Path] | None:
    """Generate the temporal table's test (scenario seed) and validation (seed +
    VAL_SEED_OFFSET) sequences of cad-v2x-seq (:mod:`eval.studies.temporal`'s counts, capped by
    ``--pairs``); their folders, or None without the scenario file."""
    from cadsim.scenario import load_scenario

    path = ROOT / TEMPORAL_SCENARIO
    if not path.is_file():
        log.warning("[temporal] skipped: no %s", TEMPORAL_SCENARIO)
        return None
    scenario = load_scenario(path)
    splits = {
        "test": (data / "cad-v2x-seq", TEMPORAL_TEST, scenario.seed),
        "val": (data / "cad-v2x-seq-val", TEMPORAL_VAL, scenario.seed + VAL_SEED_OFFSET),
    }
    for split, (folder, n, seed) in splits.items():
        n = n if args.pairs is None else min(args.pairs, n)
        log.info(
            "[temporal generate] %s %s: %d sequences (seed %d)", TEMPORAL_LABEL, split, n, seed
        )
        made = _generate(path, folder, n, None if split == "test" else seed, args)
        record[split] = {"dir": str(folder), "sequences": n, "seed": seed}
        record[split] |= {"new_records": made.new_records}
    record["scenario"] = scenario_file(path) | {"path": _shown(path)}
    return splits["test"][0], splits["val"][0]


def _generate_cad_train(data: Path, args: argparse.Namespace, record: dict) -> Path | None:
    """Generate CAD's training split for the learned matchers (scenario seed +
    CAD_TRAIN_SEED_OFFSET); its folder, or None without the CAD scenario."""
    from cadsim.scenario import load_scenario

    path = ROOT / SCENARIOS[0]
    if not path.is_file():
        return None
    scenario = load_scenario(path)
    seed = scenario.seed + CAD_TRAIN_SEED_OFFSET
    pairs = CAD_TRAIN_PAIRS if args.pairs is None else min(args.pairs, CAD_TRAIN_PAIRS)
    folder = data / "cad-train"
    log.info("[transfer generate] CAD train: %d pairs (seed %d)", pairs, seed)
    made = _generate(path, folder, pairs, seed, args)
    record["cad_train"] = {"dir": str(folder), "pairs": pairs, "seed": seed}
    record["cad_train"] |= {"new_records": made.new_records}
    return folder


def _write_regime_cards(out: Path, entries) -> None:
    """``regime.csv`` for every evaluated test dataset."""
    from eval.studies.regime_cards import write_regime

    (out / "regime.csv").unlink(missing_ok=True)
    write_regime(out, {e.label: e.test_dir for e in entries})


if __name__ == "__main__":
    sys.exit(main())
