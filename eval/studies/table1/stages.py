"""The stages of the paper's benchmark: generate the Table I datasets (with the spread sets),
evaluate (calibrated, untuned), equal cues, the paper's protocol, the noise, regime and
localisation sweeps, the dataset spread, and the tables and figures at the end of a run."""

from __future__ import annotations

import logging

import pandas as pd

from eval.commands.sweep_localisation import DEFAULT_MATCHERS as LOCALISATION_MATCHERS
from eval.commands.sweep_localisation import (
    parse_sigmas,
    sweep_localisation,
    sweep_specs,
)
from eval.commands.sweep_localisation import write_sweep as write_localisation_sweep
from eval.commands.sweep_noise import parse_rates, sweep
from eval.commands.sweep_regime import parse_keep, sweep_regime, write_sweep
from eval.core.result_files import write_csv
from eval.engine.matcher_list import parse_matchers
from eval.engine.protocol_run import evaluate
from eval.engine.splits import open_entry
from eval.engine.validation_choice import chosen_specs
from eval.pipeline.sizes import (
    LOCALISATION_DATASET,
    REGIME_VAL_RUNS,
    SPREAD_DATASET,
    SPREAD_SEED_OFFSETS,
    SWEEP_DATASETS,
    VAL_SEED_OFFSET,
)
from eval.pipeline.stage import RunState, shown
from eval.report.figures import render_all
from eval.report.run_record import scenario_file
from eval.report.tables import PAPER_CSV, write_tables
from eval.studies.table1.spread import spread_rows

log = logging.getLogger("eval.reproduce")


def generate(state: RunState) -> None:
    """Each scenario's test split (its seed) and validation split (seed + VAL_SEED_OFFSET), and
    for the spread dataset its extra test splits (seed + SPREAD_SEED_OFFSETS)."""
    from cadsim.scenario import load_scenario

    datasets = []
    for path, (label, pairs, val_pairs) in zip(state.scenarios, state.sizes.datasets, strict=True):
        scenario = load_scenario(path)
        test_dir, val_dir = state.data / label.lower(), state.data / f"{label.lower()}-val"
        val_seed = scenario.seed + VAL_SEED_OFFSET
        log.info(
            "[generate] %s: %d test pairs (seed %d), %d validation pairs (seed %d)",
            label, pairs, scenario.seed, val_pairs, val_seed,
        )  # fmt: skip
        made = state.generate(path, test_dir, pairs, None)
        made_val = state.generate(path, val_dir, val_pairs, val_seed)
        state.entries.append(open_entry(test_dir, val_dir))
        new_records = made.new_records + made_val.new_records
        if label == SPREAD_DATASET and state.args.spread_pairs:
            new_records += _generate_spread(state, path, label, scenario.seed, test_dir)
        datasets.append(
            {"label": label, "scenario": scenario_file(path) | {"path": shown(path)}}
            | {"test_dir": str(test_dir), "test_seed": scenario.seed, "test_pairs": pairs}
            | {"val_dir": str(val_dir), "val_seed": val_seed, "val_pairs": val_pairs}
            | {"test_checksum": state.entries[-1].test_checksum}
            | {"val_checksum": state.entries[-1].val_checksum}
            | {"new_records": new_records}
        )
    state.record["datasets"] = datasets


def _generate_spread(state: RunState, path, label: str, seed: int, test_dir) -> int:
    """The spread dataset's extra test splits; the records they added."""
    state.spread_sets.append((str(test_dir), state.entries[-1].test_checksum, seed))
    new_records = 0
    for offset in SPREAD_SEED_OFFSETS:
        extra_seed = seed + offset
        extra = state.data / f"{label.lower()}-seed{extra_seed}"
        log.info("[generate] %s spread: %d pairs (seed %d)", label, state.sizes.spread, extra_seed)
        new_records += state.generate(path, extra, state.sizes.spread, extra_seed).new_records
        checksum = open_entry(extra, None).test_checksum
        state.spread_sets.append((str(extra), checksum, extra_seed))
    return new_records


def evaluate_all(state: RunState) -> None:
    """Every matcher × run on every dataset, tuned and τ calibrated on validation."""
    log.info(
        "[evaluate] %d matchers × %d runs on %s%s",
        len(state.matchers),
        len(state.seeds),
        ", ".join(e.label for e in state.entries),
        " (parameters tuned on validation)" if state.args.tune else "",
    )
    state.taus = evaluate(
        state.entries, state.matchers, state.seeds, state.runner, state.out, tune=state.args.tune
    )


def equal_cues(state: RunState) -> None:
    log.info("[equal cues] every paper matcher handed metric geometry and appearance")
    evaluate(
        state.entries, state.matchers, state.seeds, state.runner, state.out,
        tune=state.args.tune, protocol="equal_cues",
    )  # fmt: skip
    if all(e.val_dir is not None for e in state.entries) and state.entries:
        from eval.engine.difficulty_levels import write_table1_levels

        headline = write_table1_levels(state.out, state.entries)
        state.record["difficulty_levels"] = headline
        log.info("[equal cues] headline level (chosen on validation): %s", headline["level"])


def paper_protocol(state: RunState) -> None:
    log.info("[paper protocol] image-space pairwise terms, full assignment, no τ")
    evaluate(state.entries, state.matchers, state.seeds, state.runner, state.out, protocol="paper")


def noise_sweep(state: RunState) -> None:
    """Fig. 4: the first sweep pairs of CAD and MRC re-detected at every noise rate."""
    rates, seeds = parse_rates(state.args.rates), list(range(state.args.sweep_runs))
    entries = [e for e in state.entries if e.label in SWEEP_DATASETS]
    if not entries:
        log.warning("[noise sweep] skipped: none of %s", ", ".join(SWEEP_DATASETS))
    for entry in entries:
        log.info("[noise sweep] %s: rates %s × %d runs", entry.label, rates, len(seeds))
        sweep(entry, state.matchers, seeds, rates, state.runner, state.out, state.sizes.sweep)
    state.record["noise_sweep"] = {"datasets": [e.label for e in entries], "rates": rates} | {
        "seeds": seeds,
        "pairs": state.sizes.sweep,
    }


def regime_sweep(state: RunState) -> None:
    """Every dataset thinned to each keep level, τ recalibrated per level."""
    args, pairs = state.args, state.sizes.regime
    keeps = parse_keep(args.keep) if args.keep.strip() else []
    seeds, val_seeds = list(range(args.regime_runs)), list(range(REGIME_VAL_RUNS))
    for entry in state.entries if keeps else []:
        log.info(
            "[regime sweep] %s: keep %s × %d runs, first %s test pairs",
            entry.label, keeps, len(seeds), pairs or "all",
        )  # fmt: skip
        named, _ = chosen_specs(state.out, entry.label, state.matchers)
        result = sweep_regime(entry, named, seeds, keeps, state.runner, pairs, val_seeds)
        write_sweep(state.out, result, draw=False)  # drawn once, with every figure (tables_figures)
    state.record["regime_sweep"] = {
        "datasets": [e.label for e in state.entries] if keeps else [],
        "keep": keeps,
    } | {"seeds": seeds, "val_seeds": val_seeds, "pairs": pairs}


def dataset_spread(state: RunState) -> None:
    """The spread dataset's main and extra test splits with its tuned matchers and τ."""
    seeds, extra_seeds = state.seeds, list(range(state.args.spread_runs))
    if state.spread_sets:
        named, taus = chosen_specs(state.out, SPREAD_DATASET, state.matchers)
        log.info("[dataset spread] %s: %d datasets", SPREAD_DATASET, len(state.spread_sets))
        main_set, extra_sets = state.spread_sets[:1], state.spread_sets[1:]
        table = pd.concat(
            [
                spread_rows(SPREAD_DATASET, main_set, named, taus, seeds, state.runner),
                spread_rows(SPREAD_DATASET, extra_sets, named, taus, extra_seeds, state.runner),
            ],
            ignore_index=True,
        )
        write_csv(table.round(6), state.out / "dataset_spread.csv")
    state.record["dataset_spread"] = {
        "dataset": SPREAD_DATASET if state.spread_sets else None,
        "generated": [{"dir": d, "scenario_seed": s} for d, _, s in state.spread_sets],
        "seeds": {"main": seeds, "extra": extra_seeds},
        "pairs": state.sizes.spread if state.spread_sets else None,
    }


def localisation_sweep(state: RunState) -> None:
    """CAD with its prior re-drawn at each position error, τ per error."""
    args, pairs = state.args, state.sizes.localisation
    entry = next((e for e in state.entries if e.label == LOCALISATION_DATASET), None)
    sigmas = parse_sigmas(args.localisation_sigmas) if args.localisation_sigmas.strip() else []
    seeds = list(range(args.localisation_runs))
    if entry is not None and sigmas:
        base = parse_matchers(LOCALISATION_MATCHERS)
        named = base if args.tune else sweep_specs(state.out, entry, base)
        log.info(
            "[localisation sweep] %s: position σ %s m × %d runs, first %s test pairs",
            entry.label, sigmas, len(seeds), pairs or "all",
        )  # fmt: skip
        rows = sweep_localisation(entry, named, seeds, sigmas, state.runner, pairs, tune=args.tune)
        write_localisation_sweep(state.out, rows)
    state.record["localisation_sweep"] = {
        "dataset": LOCALISATION_DATASET if entry and sigmas else None,
        "position_sigmas_m": sigmas,
        "yaw_sigma_deg_per_m": 0.2 / 1.2,
        "seeds": seeds,
        "pairs": pairs,
    }


def tables_figures(state: RunState) -> None:
    """Table I and its companions, the regime cards and every figure, from the result files."""
    from eval.studies.table1.regime_cards import write_regime

    state.table1_markdown = write_tables(state.out, PAPER_CSV)
    entries = state.entries + ([state.v2x_entry] if state.v2x_entry is not None else [])
    (state.out / "regime.csv").unlink(missing_ok=True)
    write_regime(state.out, {e.label: e.test_dir for e in entries})
    figures = render_all(state.out)
    log.info("[figures] %s", ", ".join(str(f) for f in figures))
