"""The V2X study as one declaration: cad-v2x (camera) and cad-v2x-both (camera and LiDAR on the
same frames), every matcher under every localisation preset, the box-only and LiDAR tables and
camera against LiDAR. It reads Table I's tuned configurations (``tuning.csv``: the preset sweep
starts from CAD's), so Table I runs first.
"""

from __future__ import annotations

from pathlib import Path

from eval.engine.study import Data, Part, Study
from eval.pipeline.sizes import V2X_PAIRS, V2X_SCENARIO, V2X_VAL_PAIRS
from eval.pipeline.stage import Stage
from eval.protocol.claims import Claim
from eval.report.run_part import read_record, study_seconds
from eval.studies.v2x import stages
from eval.studies.v2x.boxes import readme_part as boxes_part
from eval.studies.v2x.boxes import timing_claims
from eval.studies.v2x.lidar import SCENARIO as LIDAR_SCENARIO
from eval.studies.v2x.lidar import readme_part as lidar_part
from eval.studies.v2x.power import CHECKS as POWER
from eval.studies.v2x.report import GOALS
from eval.studies.v2x.report import claims as camera_claims
from eval.studies.v2x.report import readme_part as camera_part
from eval.studies.v2x.sensors import sensor_claims
from eval.studies.v2x.table import PRESETS

GROUP = "Localisation and V2X"


def claims(results: Path) -> list[Claim]:
    """The V2X study's claims, as its three parts state them: the camera table's goals,
    best-against-runner-up and realism, the box table's stage time, camera against LiDAR."""
    results = Path(results)
    seconds = study_seconds(results, read_record(results))
    shown = lambda name: (results / f"table_{name}.md").is_file()  # noqa: E731
    return [
        *camera_claims(results),
        *(timing_claims(seconds["v2x_boxes"]) if shown("v2x_boxes") else []),
        *(sensor_claims(results) if shown("v2x_lidar") else []),
    ]


STUDY = Study(
    name="v2x",
    label="V2X",
    data=(
        Data(
            "cad-v2x", V2X_SCENARIO, {"test": V2X_PAIRS, "val": V2X_VAL_PAIRS, "train": V2X_PAIRS}
        ),
        Data("cad-v2x-both", LIDAR_SCENARIO, {"test": V2X_PAIRS, "val": V2X_VAL_PAIRS}),
    ),
    methods=("all", "every prior matcher"),
    conditions=PRESETS,
    goals=GOALS,
    claims=claims,
    parts=(
        Part("v2x", lambda c: camera_part(c.results, c.rel), GROUP, "The V2X task", "table_v2x.md"),
        Part(
            "v2x boxes",
            lambda c: boxes_part(c.results, c.rel, c.seconds["v2x_boxes"]),
            GROUP,
            "The V2X task with boxes only",
            "table_v2x_boxes.md",
        ),
        Part(
            "v2x lidar",
            lambda c: lidar_part(c.results, c.rel),
            GROUP,
            "The V2X task on LiDAR boxes",
            "table_v2x_lidar.md",
        ),
    ),
    stages=(
        Stage(
            name="v2x_generate",
            reads=("scenarios/cad-v2x.toml",),
            writes=("cad-v2x", "cad-v2x-val"),
            run=stages.v2x_generate,
            budget_s=60,
            executor=False,
            counts_runs=False,
        ),
        Stage(
            name="v2x_sweep",
            reads=("cad-v2x", "cad-v2x-val", "tuning.csv"),
            writes=("localisation_presets.csv",),
            run=stages.v2x_sweep,
            budget_s=15,
            stale=("localisation_presets.csv",),
        ),
        Stage(
            name="v2x_table",
            reads=("cad-v2x", "cad-v2x-val"),
            writes=("table_v2x.*", "v2x/"),
            run=stages.v2x_table,
            budget_s=25,
        ),
        Stage(
            name="v2x_boxes",
            reads=("cad-v2x", "cad-v2x-val"),
            writes=("table_v2x_boxes.*", "v2x_boxes/"),
            run=stages.v2x_boxes,
            budget_s=25,
            skip="boxes",
            about="the box-only V2X table (cad-v2x exported and re-imported as 3-D boxes)",
        ),
        Stage(
            name="v2x_lidar",
            reads=(LIDAR_SCENARIO, "cad-v2x", "cad-v2x-val"),
            writes=("cad-v2x-both", "table_v2x_lidar.*", "table_v2x_sensors.csv", "v2x_lidar/"),
            run=stages.v2x_lidar,
            budget_s=110,
            skip="lidar",
            about=f"the LiDAR V2X table ({LIDAR_SCENARIO}: boxes from cadsim's LiDAR detector)",
        ),
    ),
    needs={"table1": "tuning.csv"},
    outputs=("localisation_presets.csv", "table_v2x*", "v2x/", "v2x_boxes/", "v2x_lidar/"),
    power=POWER,
    budget_units=(
        ("the V2X camera table and its preset sweep", ("v2x_generate", "v2x_sweep", "v2x_table")),
        ("the V2X box-only table", ("v2x_boxes",)),
        ("the V2X LiDAR table", ("v2x_lidar",)),
    ),
)
