"""The temporal table (issue 41, ``results/table_temporal.{md,csv}``): matchers that accumulate
evidence over a window of frames, on the sequences of ``cad-v2x-seq``, under three localisation
presets.

Protocol. Each sequence (10 frames, 0.2 s apart, of the same two vehicles) becomes a
:class:`~matchers.core.sequence_problem.SequenceProblem`: its odometry drift redrawn for the run
(:func:`cadsim.dataset.sequence_odometry.redraw_odometry`), every frame's pair redrawn under the
preset (``pair.localise_preset(preset, seed=run)``) and its ``.problem()``; each agent's own
tracks from its own detections and odometry (:func:`matchers.tracking.own_tracks.with_own_tracks`,
never a true id); odometry and camera mounts from the pairs. Methods (:data:`METHODS`):
``windowed:<m>`` for the two-view matchers ``consistency`` and ``pose_refine`` at W in
{1, 3, 10} and ``temporal_pose`` at W in {1, 10}. A method that reads the localisation prior
cannot run under ``denied`` (:mod:`eval.core.abstention`, from its ``requires``): it is not
run nor tuned, its rows are kept with no number (empty CSV cells,
:data:`~eval.core.abstention.NO_NUMBER` in Markdown), and it is in no "best" and no
comparison.

Tuning (the equal budget of the two-view tables, :mod:`eval.protocol.tuning`). Per (method, W,
preset) every configuration of the method's grid
(:func:`matchers.core.temporal_registry.temporal_search_space`: 8 each, the defaults among
them; W is the table's axis, never tuned) runs on the validation split (scenario seed + 1000,
run seed 0) with ``threshold=None`` (its whole Hungarian assignment); each gets its τ by the
two-view rule (:func:`eval.protocol.calibration.calibrate_ranked`: the τ maximising the mean
per-frame F1, in the middle of the best interval) and is scored by that validation F1; the best
wins (:func:`eval.protocol.tuning.best_candidate`, exact ties to the smallest parameters JSON).
The chosen parameters (``params``) and τ go to the table and ``temporal/tuning.csv`` (every
candidate). The test split never enters the choice or τ.

Metrics. Headline: pooled F1 (``f1_pooled``: 2 ΣTP / (Σ|M| + Σ|G|) over every frame of every
test sequence, :func:`eval.protocol.pooled_bootstrap.pooled_f1`; its interval an episode-level
bootstrap, :mod:`eval.protocol.pooled_bootstrap`) — many frames of a sequence have no true pair,
where the per-frame convention gives F1 1 to declaring nothing. Secondary, per frame: F1 of the
declared pairs at τ against ``pair.gt_pairs`` (``f1_mean``);
success@(1 m, 2°) of the planar fit of those pairs (:func:`eval.core.pose_metrics.
matched_planar_error`, extrinsics ``pair.camera_extrinsics``, truth
``pair.true_relative_pose()``); the ``oracle`` row is the same fit of the true pairs. Over time
(:mod:`eval.protocol.temporal_metrics`): partner changes and the cross-agent links' CLEAR-MOT
IDSW per 100 covisible object-frames,
mean frames to the first correct association (objects never matched counted apart), HOTA and
AssA of the declared pairs named by their own track ids (mean over sequences). Intervals are
episode-level cluster t-intervals (:func:`eval.protocol.cluster_interval.t_interval`; a
sequence's episode is its simulation episode), on the per-frame values.

What accumulation buys (``table_temporal_gain.csv``): per preset, the method with the best
validation F1 at W = 10 (among those that can run there), its test pooled F1 at W = 10 minus at
W = 1 with its paired episode-level bootstrap interval (headline), and the same for the mean
per-frame F1 (paired per frame, cluster t-interval). Goals (issue 41) go through :func:`eval.protocol.goal_verdict.goal_line`.

The study's pieces: the sequences (:mod:`eval.studies.temporal.sequences`), the table's layout
(:mod:`eval.studies.temporal.table`), runs and tuning (:mod:`eval.studies.temporal.runs`),
scores (:mod:`eval.studies.temporal.scores`), one preset (:mod:`eval.studies.temporal.preset`),
the gain (:mod:`eval.studies.temporal.gain`), Markdown (:mod:`eval.studies.temporal.markdown`),
the report (:mod:`eval.studies.temporal.report`) and the presets' result cache
(:mod:`eval.studies.temporal.outcome_cache`); the public names but the cache's are re-exported
here.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from eval.core.result_files import write_csv, write_text
from eval.engine.result_table import bullets
from eval.studies.temporal.gain import best_long, gain_rows
from eval.studies.temporal.markdown import params_cell, to_markdown
from eval.studies.temporal.outcome_cache import OutcomeCache, task_key
from eval.studies.temporal.preset import PresetOutcome, evaluate_preset
from eval.studies.temporal.report import (
    goals,
    readme_part,
    readme_part_lidar,
    temporal_tuning_record,
)
from eval.studies.temporal.runs import (
    calibrate_tau,
    run_method,
    run_windows,
    tune_method,
    tune_windows,
)
from eval.studies.temporal.scores import (
    continuity_rows,
    finite_interval,
    oracle_scores,
    pooled_f1,
    pooled_sums,
    score_test,
    summarise,
)
from eval.studies.temporal.sequences import Sequenced, load_split, sequence_problem
from eval.studies.temporal.table import (
    COLUMNS,
    CONTINUITY_COLUMNS,
    CONTINUITY_FILE,
    COUNT_COLUMNS,
    FIXED,
    GAIN,
    GAIN_COLUMNS,
    LABEL,
    LIDAR_LABEL,
    LIDAR_SCENARIO,
    LIDAR_TABLE,
    LONG,
    ORACLE_ROW,
    SCENARIO,
    SHORT,
    SUCCESS_BOUNDS,
    TABLE,
    TUNED,
    TUNING_COLUMNS,
    TUNING_FILE,
    abstains,
    folder_of,
)

__all__ = [
    "COLUMNS", "CONTINUITY_COLUMNS", "CONTINUITY_FILE", "COUNT_COLUMNS", "FIXED", "GAIN",
    "GAIN_COLUMNS", "LABEL", "LIDAR_LABEL", "LIDAR_SCENARIO", "LIDAR_TABLE", "LONG", "METHODS",
    "ORACLE_ROW", "PRESETS", "RUNS", "SCENARIO", "SHORT", "SUCCESS_BOUNDS", "TABLE",
    "TEST_SEQUENCES", "TUNED", "TUNING_COLUMNS", "TUNING_FILE", "VAL_SEQUENCES", "PresetOutcome",
    "Sequenced", "abstains", "best_long", "calibrate_tau", "continuity_rows", "evaluate_preset",
    "evaluate_temporal", "evaluate_temporal_lidar", "finite_interval", "folder_of", "gain_rows",
    "goals", "load_split", "oracle_scores", "params_cell", "pooled_f1", "pooled_sums",
    "readme_part", "readme_part_lidar", "run_method", "run_windows", "score_test",
    "sequence_problem", "summarise", "temporal_tuning_record", "to_markdown", "tune_method",
    "tune_windows",
]  # fmt: skip

TEST_SEQUENCES = 40
VAL_SEQUENCES = 20
PRESETS = ("gnss-open-sky", "gnss-urban", "denied")
METHODS: tuple[tuple[str, tuple[int, ...]], ...] = (
    ("windowed:consistency", (1, 3, 10)),
    ("windowed:pose_refine", (1, 3, 10)),
    ("temporal_pose", (1, 10)),
    ("trajectory_pose", (1, 10)),
)
RUNS = (0,)

log = logging.getLogger("eval.reproduce")


def evaluate_temporal(
    test_dir: Path,
    val_dir: Path,
    out: Path,
    methods: Sequence[tuple[str, Sequence[int]]] = METHODS,
    presets: Sequence[str] = PRESETS,
    seeds: Sequence[int] = RUNS,
    tune: bool = True,
    executor=None,
    name: str = TABLE,
    label: str = LABEL,
    cache: str | Path | None = None,
) -> pd.DataFrame:
    """Run the study (module docstring) and write ``out/table_temporal.{md,csv}``,
    ``out/table_temporal_gain.csv``, the per-frame scores ``out/temporal/per_frame.csv`` and
    every tuning candidate ``out/temporal/tuning.csv`` (``tune=False``: defaults only, no
    candidates). One :func:`evaluate_preset` task per preset on ``executor``
    (:class:`eval.core.executor.Executor`; None or one worker: in this process, in order);
    the outputs are assembled in preset order, whatever the completion order. ``name`` /
    ``label``: the files' stem and the caption's dataset (:func:`evaluate_temporal_lidar`: the
    LiDAR table, side files under :func:`folder_of`). ``cache``: a folder of
    :class:`~eval.studies.temporal.outcome_cache.OutcomeCache` entries; a preset found there is
    read, not run, and each one run is stored there (None: every preset is run, nothing is
    stored); the files are the same either way. Returns the table."""
    out = Path(out)
    methods = tuple((m, tuple(int(w) for w in ws)) for m, ws in methods)
    tasks = [(str(test_dir), str(val_dir), p, methods, tuple(seeds), bool(tune)) for p in presets]
    outcomes = _run_presets(tasks, executor, None if cache is None else OutcomeCache(cache), label)
    rows = [r for o in outcomes for r in o.rows]
    gains = [g for o in outcomes for g in o.gain]
    per_frame_all = [f for o in outcomes for f in o.per_frame]
    tuned = [t for o in outcomes for t in o.tuned]
    continuity = pd.DataFrame(
        [c for o in outcomes for c in o.continuity], columns=list(CONTINUITY_COLUMNS)
    )
    table = pd.DataFrame(rows, columns=list(COLUMNS))
    table[list(COUNT_COLUMNS)] = table[list(COUNT_COLUMNS)].astype("Int64")  # empty: no number
    oracle = table[table["method"] == ORACLE_ROW].set_index("preset")["success_1m_2deg"]
    ceiling = table["preset"].map(oracle).to_numpy(dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        share = np.where(ceiling > 0, table["success_1m_2deg"].to_numpy(float) / ceiling, np.nan)
    table["share_of_oracle"] = share
    declared_nothing = np.array(
        [
            m != ORACLE_ROW and abstains(m, p)
            for m, p in zip(table["method"], table["preset"], strict=True)
        ],
        dtype=bool,
    )
    for column, source in (("oracle_hota", "hota"), ("oracle_assa", "assa")):
        by_preset = table[table["method"] == ORACLE_ROW].set_index("preset")[source]
        values = table["preset"].map(by_preset).to_numpy(dtype=float)
        table[column] = np.where(declared_nothing, np.nan, values)  # no number beside none
    oracle_assa = table["oracle_assa"].to_numpy(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        table["assa_share_of_oracle"] = np.where(
            oracle_assa > 0, table["assa"].to_numpy(float) / oracle_assa, np.nan
        )
    gain = pd.DataFrame([g for g in gains if g], columns=list(GAIN_COLUMNS))
    side = out / folder_of(name)
    side.mkdir(parents=True, exist_ok=True)
    write_csv(table.round(6), out / f"{name}.csv")
    write_csv(gain.round(6), out / f"{name}_gain.csv")
    write_csv(pd.DataFrame(tuned, columns=list(TUNING_COLUMNS)).round(6), side / "tuning.csv")
    write_csv(continuity.round(6), side / "continuity.csv")
    if per_frame_all:
        write_csv(pd.concat(per_frame_all, ignore_index=True).round(6), side / "per_frame.csv")
    lines = bullets(goals(table, out, name))
    write_text(
        out / f"{name}.md", to_markdown(table, gain, label) + "\n\n" + "\n".join(lines) + "\n"
    )
    return table


def _run_presets(
    tasks: list[tuple], executor, cache: OutcomeCache | None, label: str
) -> list[PresetOutcome]:
    """Each task's :class:`PresetOutcome`, in task order: read from `cache` where it holds the
    task, the others run (on `executor` when it has several workers) and stored there."""
    if cache is None:
        keys, outcomes = [], [None] * len(tasks)
    else:
        keys = [task_key(task) for task in tasks]
        outcomes = [cache.load(key, task) for key, task in zip(keys, tasks, strict=True)]
    for task, outcome in zip(tasks, outcomes, strict=True):
        if outcome is not None:
            log.info("temporal %s %s: read from the result cache %s", label, task[2], cache.root)
    todo = [k for k, outcome in enumerate(outcomes) if outcome is None]
    if executor is None or getattr(executor, "workers", 1) <= 1 or len(todo) <= 1:
        done = ((k, evaluate_preset(tasks[k])) for k in todo)
    else:
        done = _on_executor(executor, [tasks[k] for k in todo], todo)
    for k, outcome in done:
        outcomes[k] = outcome
        if cache is not None:
            cache.store(keys[k], outcome)
    return outcomes


def _on_executor(executor, tasks: list[tuple], indices: list[int]):
    """(index, outcome) of each task as it completes on `executor`; a task's error is raised."""
    for done in executor.map_unordered(evaluate_preset, tasks):
        if done.error is not None:
            raise done.error
        yield indices[done.index], done.value


def evaluate_temporal_lidar(
    test_dir: Path, val_dir: Path, out: Path, *args, **kwargs
) -> pd.DataFrame:
    """The temporal study on LiDAR boxes (``scenarios/cad-v2x-seq-lidar.toml``'s test and
    validation splits at ``test_dir`` / ``val_dir``), the same protocol and further arguments
    (methods, presets, seeds, tune, executor) as :func:`evaluate_temporal`:
    ``out/table_temporal_lidar.{md,csv}``, ``out/table_temporal_lidar_gain.csv`` and
    ``out/temporal_lidar/`` (per-frame scores, tuning candidates, the own tracker's continuity).
    Returns the table."""
    return evaluate_temporal(
        test_dir, val_dir, out, *args, name=LIDAR_TABLE, label=LIDAR_LABEL, **kwargs
    )
