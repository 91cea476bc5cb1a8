"""``make reproduce``'s stages, in the order a run walks them: each declared once with what it
reads (datasets under ``--data``; ``eval/data/…`` shipped) and writes (under ``--out``), the
function it runs, its cold budget in seconds on 2 cores (together 15 min) and, where a study can
be left out, its ``--no-X`` option. Adding a stage is one entry here (docs/architecture.md)."""

from __future__ import annotations

from eval.pipeline import (
    external_stages,
    multiagent_stages,
    paper_stages,
    temporal_stages,
    transfer_stages,
    v2x_stages,
)
from eval.pipeline.stage import Stage
from eval.studies.external.prior_defaults import SENSITIVITY
from eval.studies.temporal.evaluation import LIDAR_SCENARIO as TEMPORAL_LIDAR_SCENARIO
from eval.studies.temporal.evaluation import SCENARIO as TEMPORAL_SCENARIO
from eval.studies.v2x.lidar import SCENARIO as LIDAR_SCENARIO

TABLE1 = ("table1.{md,csv,tex}", "metrics_per_pair.csv", "thresholds.csv", "tuning.csv")

STAGES: tuple[Stage, ...] = (
    Stage(
        name="generate",
        reads=("scenarios/*.toml",),
        writes=("cad", "mrc", "cad-dense", "*-val", "cad-seed*"),
        run=paper_stages.generate,
        budget_s=110,
        executor=False,
        counts_runs=False,
    ),
    Stage(
        name="evaluate",
        reads=("cad", "mrc", "cad-dense", "*-val"),
        writes=(*TABLE1, "table1_untuned.*"),
        run=paper_stages.evaluate_all,
        budget_s=80,
    ),
    Stage(
        name="equal_cues",
        reads=("cad", "mrc", "cad-dense", "*-val"),
        writes=("table1_equal_cues.*",),
        run=paper_stages.equal_cues,
        budget_s=80,
    ),
    Stage(
        name="paper_protocol",
        reads=("cad", "mrc", "cad-dense"),
        writes=("table1_paper_protocol.*",),
        run=paper_stages.paper_protocol,
        budget_s=20,
    ),
    Stage(
        name="noise_sweep",
        reads=("cad", "mrc", "tuning.csv"),
        writes=("noise_runs.csv",),
        run=paper_stages.noise_sweep,
        budget_s=45,
        stale=("noise_runs.csv",),
    ),
    Stage(
        name="regime_sweep",
        reads=("cad", "mrc", "cad-dense", "tuning.csv"),
        writes=("regime_sweep.csv", "crossovers.csv"),
        run=paper_stages.regime_sweep,
        budget_s=60,
        stale=("regime_sweep.csv", "crossovers.csv"),
    ),
    Stage(
        name="dataset_spread",
        reads=("cad", "cad-seed*", "tuning.csv"),
        writes=("dataset_spread.csv",),
        run=paper_stages.dataset_spread,
        budget_s=15,
        stale=("dataset_spread.csv",),
    ),
    Stage(
        name="localisation_sweep",
        reads=("cad", "cad-val", "tuning.csv"),
        writes=("localisation_sweep.csv",),
        run=paper_stages.localisation_sweep,
        budget_s=25,
        stale=("localisation_sweep.csv",),
    ),
    Stage(
        name="v2x_generate",
        reads=("scenarios/cad-v2x.toml",),
        writes=("cad-v2x", "cad-v2x-val", "cad-v2x-train"),
        run=v2x_stages.v2x_generate,
        budget_s=60,
        executor=False,
        counts_runs=False,
    ),
    Stage(
        name="v2x_sweep",
        reads=("cad-v2x", "cad-v2x-val", "tuning.csv"),
        writes=("localisation_presets.csv",),
        run=v2x_stages.v2x_sweep,
        budget_s=15,
        stale=("localisation_presets.csv",),
    ),
    Stage(
        name="v2x_table",
        reads=("cad-v2x", "cad-v2x-val"),
        writes=("table_v2x.*", "v2x/"),
        run=v2x_stages.v2x_table,
        budget_s=25,
    ),
    Stage(
        name="v2x_boxes",
        reads=("cad-v2x", "cad-v2x-val"),
        writes=("table_v2x_boxes.*", "v2x_boxes/"),
        run=v2x_stages.v2x_boxes,
        budget_s=25,
        skip="boxes",
        about="the box-only V2X table (cad-v2x exported and re-imported as 3-D boxes)",
    ),
    Stage(
        name="v2x_lidar",
        reads=(LIDAR_SCENARIO, "cad-v2x"),
        writes=("cad-v2x-both", "table_v2x_lidar.*", "table_v2x_sensors.csv", "v2x_lidar/"),
        run=v2x_stages.v2x_lidar,
        budget_s=110,
        skip="lidar",
        about=f"the LiDAR V2X table ({LIDAR_SCENARIO}: boxes from cadsim's LiDAR detector)",
    ),
    Stage(
        name="external",
        reads=("eval/data/dmgm-cad",),
        writes=("table_external.*", "external/", "agreement.csv"),
        run=external_stages.external,
        budget_s=25,
    ),
    Stage(
        name="prior_sensitivity",
        reads=("eval/data/dmgm-cad",),
        writes=(f"external/{SENSITIVITY}",),
        run=external_stages.prior_sensitivity,
        budget_s=5,
        stale=(f"external/{SENSITIVITY}",),
    ),
    Stage(
        name="multiagent_generate",
        reads=("scenarios/cad-multi.toml",),
        writes=("cad-multi", "cad-multi-val"),
        run=multiagent_stages.multiagent_generate,
        budget_s=30,
        executor=False,
        counts_runs=False,
    ),
    Stage(
        name="multiagent",
        reads=("cad-multi", "cad-multi-val", "tuning.csv"),
        writes=("table_multiagent.*", "multiagent/"),
        run=multiagent_stages.multiagent,
        budget_s=30,
        stale=("table_multiagent.csv", "table_multiagent.md"),
    ),
    Stage(
        name="transfer_generate",
        reads=("scenarios/cad-intersection.toml",),
        writes=("cad-train",),
        run=transfer_stages.transfer_generate,
        budget_s=20,
        skip="transfer",
        executor=False,
        counts_runs=False,
        about="the learned matchers' transfer matrix (also skipped without cad-v2x)",
    ),
    Stage(
        name="transfer",
        reads=("cad-train", "cad-v2x-train", "eval/data/dmgm-cad"),
        writes=("models", "table_transfer.*", "transfer/"),
        run=transfer_stages.transfer,
        budget_s=35,
        skip="transfer",
        stale=("table_transfer.csv", "table_transfer.md"),
    ),
    Stage(
        name="temporal_generate",
        reads=(TEMPORAL_SCENARIO,),
        writes=("cad-v2x-seq", "cad-v2x-seq-val"),
        run=temporal_stages.temporal_generate,
        budget_s=50,
        skip="temporal",
        executor=False,
        counts_runs=False,
        about=f"the temporal table on {TEMPORAL_SCENARIO} (also skipped without the file)",
    ),
    Stage(
        name="temporal",
        reads=("cad-v2x-seq", "cad-v2x-seq-val"),
        writes=("table_temporal.*", "temporal/"),
        run=temporal_stages.temporal,
        budget_s=20,
        skip="temporal",
        counts_runs=False,
        stale=("table_temporal.csv", "table_temporal.md", "table_temporal_gain.csv"),
    ),
    Stage(
        name="temporal_lidar_generate",
        reads=(TEMPORAL_LIDAR_SCENARIO,),
        writes=("cad-v2x-seq-lidar", "cad-v2x-seq-lidar-val"),
        run=temporal_stages.temporal_lidar_generate,
        budget_s=240,
        skip="temporal-lidar",
        executor=False,
        counts_runs=False,
        about=f"the temporal table on LiDAR boxes, {TEMPORAL_LIDAR_SCENARIO} (also skipped "
        "without the file)",
    ),
    Stage(
        name="temporal_lidar",
        reads=("cad-v2x-seq-lidar", "cad-v2x-seq-lidar-val"),
        writes=("table_temporal_lidar.*", "temporal_lidar/"),
        run=temporal_stages.temporal_lidar,
        budget_s=240,
        skip="temporal-lidar",
        counts_runs=False,
        stale=(
            "table_temporal_lidar.csv",
            "table_temporal_lidar.md",
            "table_temporal_lidar_gain.csv",
        ),
    ),
    Stage(
        name="tables_figures",
        reads=("*.csv",),
        writes=("table1.*", "regime.csv", "fig*.{png,pdf}"),
        run=paper_stages.tables_figures,
        budget_s=15,
        executor=False,
        counts_runs=False,
    ),
)
"""The stages; ``wall_s`` of the run record, ``results/cold_run.json`` and the report's stage
table name exactly these."""
