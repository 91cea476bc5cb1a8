"""The temporal study as one declaration: sequences of cad-v2x-seq (camera) and
cad-v2x-seq-lidar (LiDAR boxes), methods that accumulate over W frames against W = 1, under each
preset. It reads no other study's output.
"""

from __future__ import annotations

from eval.engine.study import Data, Part, Study
from eval.pipeline.stage import Stage
from eval.studies.temporal import stages
from eval.studies.temporal.evaluation import (
    LIDAR_SCENARIO,
    METHODS,
    PRESETS,
    SCENARIO,
    TEST_SEQUENCES,
    VAL_SEQUENCES,
    readme_part,
    readme_part_lidar,
)
from eval.studies.temporal.goals import GOALS
from eval.studies.temporal.power import CHECKS as POWER
from eval.studies.temporal.report import claims as table_claims
from eval.studies.temporal.table import LIDAR_TABLE

SPLITS = {"test": TEST_SEQUENCES, "val": VAL_SEQUENCES}

STUDY = Study(
    name="temporal",
    label="Temporal",
    data=(
        Data("cad-v2x-seq", SCENARIO, SPLITS, "sequences"),
        Data("cad-v2x-seq-lidar", LIDAR_SCENARIO, SPLITS, "sequences"),
    ),
    methods=tuple(name for name, _ in METHODS),
    conditions=(*PRESETS, *sorted({f"W = {w}" for _, ws in METHODS for w in ws})),
    goals=GOALS,
    claims=lambda results: [*table_claims(results), *table_claims(results, LIDAR_TABLE)],
    parts=(
        Part(
            "temporal",
            lambda c: readme_part(c.results, c.rel, c.seconds["temporal"]),
            "Temporal",
            "The temporal table",
            "table_temporal.md",
        ),
        Part(
            "temporal_lidar",
            lambda c: readme_part_lidar(c.results, c.rel, c.seconds["temporal_lidar"]),
            "Temporal",
            "The temporal table on LiDAR boxes",
            "table_temporal_lidar.md",
        ),
    ),
    stages=(
        Stage(
            name="temporal_generate",
            reads=(SCENARIO,),
            writes=("cad-v2x-seq", "cad-v2x-seq-val"),
            run=stages.temporal_generate,
            budget_s=50,
            skip="temporal",
            executor=False,
            counts_runs=False,
            about=f"the temporal table on {SCENARIO} (also skipped without the file)",
        ),
        Stage(
            name="temporal",
            reads=("cad-v2x-seq", "cad-v2x-seq-val"),
            writes=("table_temporal.*", "temporal/"),
            run=stages.temporal,
            budget_s=20,
            skip="temporal",
            counts_runs=False,
            stale=("table_temporal.csv", "table_temporal.md", "table_temporal_gain.csv"),
        ),
        Stage(
            name="temporal_lidar_generate",
            reads=(LIDAR_SCENARIO,),
            writes=("cad-v2x-seq-lidar", "cad-v2x-seq-lidar-val"),
            run=stages.temporal_lidar_generate,
            budget_s=240,
            skip="temporal-lidar",
            executor=False,
            counts_runs=False,
            about=f"the temporal table on LiDAR boxes, {LIDAR_SCENARIO} (also skipped "
            "without the file)",
        ),
        Stage(
            name="temporal_lidar",
            reads=("cad-v2x-seq-lidar", "cad-v2x-seq-lidar-val"),
            writes=("table_temporal_lidar.*", "temporal_lidar/"),
            run=stages.temporal_lidar,
            budget_s=240,
            skip="temporal-lidar",
            counts_runs=False,
            stale=(
                "table_temporal_lidar.csv",
                "table_temporal_lidar.md",
                "table_temporal_lidar_gain.csv",
            ),
        ),
    ),
    outputs=("table_temporal*", "temporal/", "temporal_lidar/"),
    power=POWER,
    budget_units=(
        ("the temporal camera table", ("temporal_generate", "temporal")),
        ("the temporal LiDAR table", ("temporal_lidar_generate", "temporal_lidar")),
    ),
)
