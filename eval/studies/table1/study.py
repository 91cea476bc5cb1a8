"""Table I's study as one declaration: the paper's three datasets, the paper's methods under the
calibrated, untuned, equal-cue and paper protocols, the sweeps that read its tuned
configurations (noise, regime, dataset spread, localisation), its claims and its report parts.
Its ``tables_figures`` stage closes every run (the tables and figures read every study's files).
"""

from __future__ import annotations

from eval.engine.matcher_list import PAPER_ORDER
from eval.engine.study import Data, Part, Study
from eval.pipeline.sizes import DEFAULT_VAL_PAIRS, SCENARIOS
from eval.pipeline.stage import Stage
from eval.protocol.variants import PROTOCOLS
from eval.report import levels_part
from eval.report.agreement_part import agreement_part
from eval.report.benchmark_parts import (
    localisation_part,
    noise_part,
    paired_part,
    paper_protocol_part,
    qualitative_part,
    regime_sweep_part,
    spread_part,
    table1_part,
)
from eval.studies.table1 import stages
from eval.studies.table1.claims import benchmark_claims
from eval.studies.table1.power import CHECKS as POWER
from eval.studies.table1.regime_cards import readme_part as regime_part

TABLE1 = ("table1.{md,csv,tex}", "metrics_per_pair.csv", "thresholds.csv", "tuning.csv")
BENCHMARK = "The paper's benchmark"

STUDY = Study(
    name="table1",
    label="Table I",
    data=tuple(
        Data(
            name, scenario, {"val": DEFAULT_VAL_PAIRS}
        )  # test: sizes.TABLE1_TEST_PAIRS or the scenario's
        for name, scenario in zip(("cad", "mrc", "cad-dense"), SCENARIOS, strict=True)
    ),
    methods=PAPER_ORDER,
    conditions=tuple(PROTOCOLS),
    claims=benchmark_claims,
    parts=(
        Part("regime", lambda c: regime_part(c.results), BENCHMARK),
        Part(
            "table1",
            lambda c: table1_part(c.results, c.rel, c.record),
            BENCHMARK,
            "Table I",
            "table1.md",
        ),
        Part("levels", lambda c: levels_part.report_part(c.results, c.rel), BENCHMARK),
        Part("paired", lambda c: paired_part(c.results, c.rel), BENCHMARK),
        Part("spread", lambda c: spread_part(c.results), BENCHMARK),
        Part("paper protocol", lambda c: paper_protocol_part(c.results), BENCHMARK),
        Part("regime sweep", lambda c: regime_sweep_part(c.results, c.rel, c.record), BENCHMARK),
        Part("noise", lambda c: noise_part(c.rel, c.record), BENCHMARK),
        Part("qualitative", lambda c: qualitative_part(c.rel), BENCHMARK),
        Part("agreement", lambda c: agreement_part(c.results, c.claims), BENCHMARK),
        Part(
            "localisation",
            lambda c: localisation_part(c.results, c.rel, c.record),
            "Localisation and V2X",
        ),
    ),
    stages=(
        Stage(
            name="generate",
            reads=("scenarios/*.toml",),
            writes=("cad", "mrc", "cad-dense", "*-val", "cad-seed*"),
            run=stages.generate,
            budget_s=110,
            executor=False,
            counts_runs=False,
        ),
        Stage(
            name="evaluate",
            reads=("cad", "mrc", "cad-dense", "*-val"),
            writes=(*TABLE1, "table1_untuned.*"),
            run=stages.evaluate_all,
            budget_s=80,
        ),
        Stage(
            name="equal_cues",
            reads=("cad", "mrc", "cad-dense", "*-val"),
            writes=("table1_equal_cues.*",),
            run=stages.equal_cues,
            budget_s=80,
        ),
        Stage(
            name="paper_protocol",
            reads=("cad", "mrc", "cad-dense"),
            writes=("table1_paper_protocol.*",),
            run=stages.paper_protocol,
            budget_s=20,
        ),
        Stage(
            name="noise_sweep",
            reads=("cad", "mrc", "tuning.csv"),
            writes=("noise_runs.csv",),
            run=stages.noise_sweep,
            budget_s=45,
            stale=("noise_runs.csv",),
        ),
        Stage(
            name="regime_sweep",
            reads=("cad", "mrc", "cad-dense", "tuning.csv"),
            writes=("regime_sweep.csv", "crossovers.csv"),
            run=stages.regime_sweep,
            budget_s=60,
            stale=("regime_sweep.csv", "crossovers.csv"),
        ),
        Stage(
            name="dataset_spread",
            reads=("cad", "cad-seed*", "tuning.csv"),
            writes=("dataset_spread.csv",),
            run=stages.dataset_spread,
            budget_s=15,
            stale=("dataset_spread.csv",),
        ),
        Stage(
            name="localisation_sweep",
            reads=("cad", "cad-val", "tuning.csv"),
            writes=("localisation_sweep.csv",),
            run=stages.localisation_sweep,
            budget_s=25,
            stale=("localisation_sweep.csv",),
        ),
    ),
    closing_stages=(
        Stage(
            name="tables_figures",
            reads=("*.csv",),
            writes=("table1.*", "regime.csv", "fig*.{png,pdf}"),
            run=stages.tables_figures,
            budget_s=15,
            executor=False,
            counts_runs=False,
        ),
    ),
    outputs=(*TABLE1, "table1_*", "noise_runs.csv", "regime_sweep.csv", "crossovers.csv"),
    power=POWER,
)
