"""The stages of the temporal study on cad-v2x-seq: its test and validation sequences, then
every (method, window) under each preset (:mod:`eval.studies.temporal`). They fill the run
record's ``temporal`` section; skipped without the scenario file."""

from __future__ import annotations

import logging

from eval.pipeline.sizes import ROOT, VAL_SEED_OFFSET
from eval.pipeline.stage import RunState, shown
from eval.report.run_record import scenario_file
from eval.studies.temporal import LABEL as TEMPORAL_LABEL
from eval.studies.temporal import METHODS as TEMPORAL_METHODS
from eval.studies.temporal import PRESETS as TEMPORAL_PRESETS
from eval.studies.temporal import RUNS as TEMPORAL_RUNS
from eval.studies.temporal import SCENARIO as TEMPORAL_SCENARIO
from eval.studies.temporal import evaluate_temporal, temporal_tuning_record

log = logging.getLogger("eval.reproduce")


def temporal_generate(state: RunState) -> None:
    """The test (scenario seed) and validation (seed + VAL_SEED_OFFSET) sequences."""
    from cadsim.scenario import load_scenario

    path = ROOT / TEMPORAL_SCENARIO
    if not path.is_file():
        log.warning("[temporal] skipped: no %s", TEMPORAL_SCENARIO)
        return
    record = state.record.setdefault("temporal", {})
    scenario = load_scenario(path)
    splits = {
        "test": (state.data / "cad-v2x-seq", scenario.seed),
        "val": (state.data / "cad-v2x-seq-val", scenario.seed + VAL_SEED_OFFSET),
    }
    for split, (folder, seed) in splits.items():
        n = state.sizes.temporal[split]
        log.info(
            "[temporal generate] %s %s: %d sequences (seed %d)", TEMPORAL_LABEL, split, n, seed
        )
        made = state.generate(path, folder, n, None if split == "test" else seed)
        record[split] = {"dir": str(folder), "sequences": n, "seed": seed}
        record[split] |= {"new_records": made.new_records}
    record["scenario"] = scenario_file(path) | {"path": shown(path)}
    state.temporal_dirs = splits["test"][0], splits["val"][0]


def temporal(state: RunState) -> None:
    """The temporal table, one task per preset on the run's executor (not cached)."""
    if state.temporal_dirs is None:
        return
    log.info(
        "[temporal] %s: %d methods × windows × %d presets × %d runs",
        TEMPORAL_LABEL, len(TEMPORAL_METHODS), len(TEMPORAL_PRESETS), len(TEMPORAL_RUNS),
    )  # fmt: skip
    table = evaluate_temporal(
        *state.temporal_dirs, state.out, tune=state.args.tune, executor=state.executor
    )
    record = state.record.setdefault("temporal", {})
    record |= {"presets": list(TEMPORAL_PRESETS), "seeds": list(TEMPORAL_RUNS)}
    record |= {"methods": {m: list(w) for m, w in TEMPORAL_METHODS}}
    record |= {"tuning": temporal_tuning_record(table)}
