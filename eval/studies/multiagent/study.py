"""The multi-agent study as one declaration: cad-multi's snapshots seen by 4 vehicles and 2
roadside units, CAD's tuned two-view matchers on every pair of views fused per subset of N
views. It reads Table I's chosen configurations (``tuning.csv``), so Table I runs first.
"""

from __future__ import annotations

from eval.engine.study import Data, Part, Study
from eval.pipeline.stage import Stage
from eval.report.run_part import read_record, study_seconds
from eval.studies.multiagent import stages
from eval.studies.multiagent.evaluation import (
    MATCHERS,
    PRESETS,
    SCENARIO,
    SUBSETS,
    TEST_SNAPSHOTS,
    VAL_SNAPSHOTS,
)
from eval.studies.multiagent.power import CHECKS as POWER
from eval.studies.multiagent.report import claims as part_claims
from eval.studies.multiagent.report import readme_part

STUDY = Study(
    name="multiagent",
    label="Multi-agent",
    data=(
        Data("cad-multi", SCENARIO, {"test": TEST_SNAPSHOTS, "val": VAL_SNAPSHOTS}, "snapshots"),
    ),
    methods=MATCHERS,
    claims=lambda results: part_claims(
        results, study_seconds(results, read_record(results))["multiagent"]
    ),
    conditions=(*PRESETS, *(f"N = {n}" for n in sorted(SUBSETS))),
    parts=(
        Part(
            "multiagent",
            lambda c: readme_part(c.results, c.rel, c.seconds["multiagent"]),
            "Multi-agent",
            "Multi-agent matching",
            "table_multiagent.md",
        ),
    ),
    stages=(
        Stage(
            name="multiagent_generate",
            reads=("scenarios/cad-multi.toml",),
            writes=("cad-multi", "cad-multi-val"),
            run=stages.multiagent_generate,
            budget_s=30,
            executor=False,
            counts_runs=False,
        ),
        Stage(
            name="multiagent",
            reads=("cad-multi", "cad-multi-val", "tuning.csv"),
            writes=("table_multiagent.*", "multiagent/"),
            run=stages.multiagent,
            budget_s=30,
            stale=("table_multiagent.csv", "table_multiagent.md"),
        ),
    ),
    needs={"table1": "tuning.csv"},
    outputs=("table_multiagent.*", "multiagent/", "fig_multiagent.*"),
    power=POWER,
)
