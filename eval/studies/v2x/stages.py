"""The stages of the V2X study on cad-v2x: its three splits, the localisation preset sweep, the
V2X table, the box-only table and, on the two-sensor cad-v2x-both, the LiDAR table with the
paired camera-vs-LiDAR comparison. They fill the run record's ``v2x`` section."""

from __future__ import annotations

import logging

from eval.commands.sweep_localisation import (
    DEFAULT_LATENCIES_MS,
    DEFAULT_PRESET,
    DEFAULT_SCALES,
    preset_levels,
    sweep_presets,
    write_preset_sweep,
)
from eval.commands.sweep_localisation import DEFAULT_MATCHERS as LOCALISATION_MATCHERS
from eval.engine.matcher_list import parse_matchers, with_prior
from eval.engine.splits import open_entry
from eval.engine.validation_choice import chosen_specs
from eval.pipeline.sizes import (
    ROOT,
    V2X_LABEL,
    V2X_SCENARIO,
    VAL_SEED_OFFSET,
)
from eval.pipeline.stage import RunState, shown
from eval.report.run_record import scenario_file
from eval.studies.v2x.boxes import evaluate_boxes
from eval.studies.v2x.lidar import SCENARIO as LIDAR_SCENARIO
from eval.studies.v2x.lidar import evaluate_lidar, generate_lidar_splits
from eval.studies.v2x.table import PRESETS as V2X_PRESETS
from eval.studies.v2x.table import evaluate_v2x

log = logging.getLogger("eval.reproduce")


def v2x_seeds(state: RunState) -> list[int]:
    return list(range(state.args.v2x_runs))


def v2x_generate(state: RunState) -> None:
    """cad-v2x's test and validation splits (disjoint scenario seeds); their entry for the later
    stages. Its training split, read by the transfer study alone, is that study's to generate
    (:func:`eval.studies.transfer.stages.transfer_generate`)."""
    from cadsim.scenario import load_scenario

    record = state.record.setdefault("v2x", {})
    if not v2x_seeds(state):
        return
    path = ROOT / V2X_SCENARIO
    scenario = load_scenario(path)
    base = state.data / V2X_LABEL.lower()
    seeds = {"test": scenario.seed, "val": scenario.seed + VAL_SEED_OFFSET}
    folders = {"test": base, "val": base.with_name(f"{base.name}-val")}
    for split, folder in folders.items():
        n, seed = state.sizes.v2x[split], seeds[split]
        log.info("[v2x generate] %s %s: %d pairs (seed %d)", V2X_LABEL, split, n, seed)
        made = state.generate(path, folder, n, None if split == "test" else seed)
        record[split] = {"dir": str(folder), "pairs": n, "seed": seed}
        record[split] |= {"new_records": made.new_records}
    entry = open_entry(folders["test"], folders["val"], V2X_LABEL)
    record["scenario"] = scenario_file(path) | {"path": shown(path)}
    record["test"]["checksum"], record["val"]["checksum"] = entry.test_checksum, entry.val_checksum
    state.v2x_entry = entry


def v2x_sweep(state: RunState) -> None:
    """The preset axes (error scale, latency) with CAD's tuned parameters, τ per level."""
    entry, seeds = state.v2x_entry, v2x_seeds(state)
    if entry is None:
        return
    levels = preset_levels(DEFAULT_PRESET, DEFAULT_SCALES, DEFAULT_LATENCIES_MS)
    named, _ = chosen_specs(state.out, "CAD", parse_matchers(LOCALISATION_MATCHERS))
    log.info(
        "[v2x sweep] %s: %s × %d levels (scale, latency) × %d runs, CAD's parameters",
        V2X_LABEL, DEFAULT_PRESET, len(levels), len(seeds),
    )  # fmt: skip
    rows = sweep_presets(entry, named, seeds, levels, state.runner)
    write_preset_sweep(state.out, rows)
    state.record["v2x"] |= {"preset": DEFAULT_PRESET, "levels": [lv[1] for lv in levels]}
    state.record["v2x"] |= {"seeds": seeds, "matchers": list(named)}


def v2x_table(state: RunState) -> None:
    """Every matcher under each preset, tuned and τ calibrated on validation."""
    entry, seeds = state.v2x_entry, v2x_seeds(state)
    if entry is None:
        return
    matchers = with_prior(state.args.matchers)
    log.info(
        "[v2x table] %s: %d matchers × %d presets × %d runs",
        V2X_LABEL, len(matchers), len(V2X_PRESETS), len(seeds),
    )  # fmt: skip
    evaluate_v2x(
        entry.test_dir, entry.val_dir, V2X_LABEL, matchers, seeds, state.runner, state.out,
        tune=state.args.tune,
    )  # fmt: skip
    state.record["v2x"] |= {"table_presets": list(V2X_PRESETS)}


def v2x_boxes(state: RunState) -> None:
    """cad-v2x exported and re-imported as 3-D boxes, the table on boxes alone."""
    entry = state.v2x_entry
    if entry is None:
        return
    _, state.record["v2x"]["boxes"] = evaluate_boxes(
        entry.test_dir, entry.val_dir, state.data, with_prior(state.args.matchers),
        v2x_seeds(state), state.runner, state.out, tune=state.args.tune,
    )  # fmt: skip


def v2x_lidar(state: RunState) -> None:
    """cad-v2x-both's splits, the LiDAR table and the paired camera-vs-LiDAR comparison."""
    seeds = v2x_seeds(state)
    if not seeds or not (ROOT / LIDAR_SCENARIO).is_file():
        return
    entry = state.v2x_entry
    camera_table = None if entry is None else (entry.test_dir, entry.val_dir)
    test, val, record = generate_lidar_splits(
        ROOT, state.data, state.sizes.lidar, VAL_SEED_OFFSET, state.generate, camera_table
    )
    _, used = evaluate_lidar(
        test, val, with_prior(state.args.matchers), seeds, state.runner, state.out,
        tune=state.args.tune, camera_table=camera_table,
    )  # fmt: skip
    state.record.setdefault("v2x", {})["lidar"] = record | used
