"""The stages of the temporal study: cad-v2x-seq's test and validation sequences, then every
(method, window) under each preset (:mod:`eval.studies.temporal.evaluation`); the same on LiDAR boxes
(cad-v2x-seq-lidar) under the presets its goals name. They fill the run record's ``temporal``
section (LiDAR under ``temporal.lidar``); each is skipped without its scenario file. Each
preset's outcome goes through the temporal result cache (:mod:`eval.studies.temporal.outcome_cache`,
``<--cache>/temporal``): a warm run reads it instead of recomputing it."""

from __future__ import annotations

import logging
from pathlib import Path

from eval.pipeline.stage import RunState, generate_splits
from eval.studies.temporal.evaluation import LABEL as TEMPORAL_LABEL
from eval.studies.temporal.evaluation import (
    LIDAR_LABEL,
    LIDAR_SCENARIO,
    evaluate_temporal,
    evaluate_temporal_lidar,
    temporal_tuning_record,
)
from eval.studies.temporal.evaluation import METHODS as TEMPORAL_METHODS
from eval.studies.temporal.evaluation import PRESETS as TEMPORAL_PRESETS
from eval.studies.temporal.evaluation import RUNS as TEMPORAL_RUNS
from eval.studies.temporal.evaluation import SCENARIO as TEMPORAL_SCENARIO
from eval.studies.temporal.outcome_cache import FOLDER as OUTCOME_FOLDER

log = logging.getLogger("eval.reproduce")


LIDAR_PRESETS = ("gnss-urban", "denied")
"""The LiDAR sequences' presets: the two its goals are read under (docs/evaluation.md)."""


def outcome_cache(state: RunState) -> Path:
    """The folder of the temporal result cache: ``temporal`` in the run cache's folder."""
    return state.runner.cache.root / OUTCOME_FOLDER


def temporal_generate(state: RunState) -> None:
    """The camera sequences (cad-v2x-seq)."""
    record = state.record.setdefault("temporal", {})
    state.temporal_dirs = generate_splits(
        state, TEMPORAL_SCENARIO, (TEMPORAL_LABEL, "cad-v2x-seq"), state.sizes.temporal,
        "sequences", record,
    )  # fmt: skip


def temporal_lidar_generate(state: RunState) -> None:
    """The LiDAR sequences (cad-v2x-seq-lidar)."""
    record = state.record.setdefault("temporal", {}).setdefault("lidar", {})
    state.temporal_lidar_dirs = generate_splits(
        state, LIDAR_SCENARIO, (LIDAR_LABEL, "cad-v2x-seq-lidar"), state.sizes.temporal,
        "sequences", record,
    )  # fmt: skip


def temporal_lidar(state: RunState) -> None:
    """The temporal table on LiDAR boxes under :data:`LIDAR_PRESETS`, the camera's protocol."""
    if state.temporal_lidar_dirs is None:
        return
    evaluate_temporal_lidar(
        *state.temporal_lidar_dirs, state.out, TEMPORAL_METHODS, LIDAR_PRESETS, TEMPORAL_RUNS,
        tune=state.args.tune, executor=state.executor, cache=outcome_cache(state),
    )  # fmt: skip
    record = state.record.setdefault("temporal", {}).setdefault("lidar", {})
    record |= {"presets": list(LIDAR_PRESETS), "seeds": list(TEMPORAL_RUNS)}


def temporal(state: RunState) -> None:
    """The temporal table, one task per preset on the run's executor, each read from the
    temporal result cache when it holds it."""
    if state.temporal_dirs is None:
        return
    log.info(
        "[temporal] %s: %d methods × windows × %d presets × %d runs",
        TEMPORAL_LABEL, len(TEMPORAL_METHODS), len(TEMPORAL_PRESETS), len(TEMPORAL_RUNS),
    )  # fmt: skip
    table = evaluate_temporal(
        *state.temporal_dirs, state.out, tune=state.args.tune, executor=state.executor,
        cache=outcome_cache(state),
    )  # fmt: skip
    record = state.record.setdefault("temporal", {})
    record |= {"presets": list(TEMPORAL_PRESETS), "seeds": list(TEMPORAL_RUNS)}
    record |= {"methods": {m: list(w) for m, w in TEMPORAL_METHODS}}
    record |= {"tuning": temporal_tuning_record(table)}
