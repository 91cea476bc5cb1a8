"""The transfer study as one declaration: learned matchers trained on cadsim's training splits or
on DMGM's calibration sequence, tested on every test set. It trains on cad-v2x's training split
and reads the external study's pairs, so V2X runs first.
"""

from __future__ import annotations

from eval.engine.study import Data, Part, Study
from eval.pipeline.sizes import CAD_TRAIN_PAIRS, SCENARIOS
from eval.pipeline.stage import Stage
from eval.report.run_part import read_record, study_seconds
from eval.studies.transfer import stages
from eval.studies.transfer.reference import LEARNED
from eval.studies.transfer.report import claims as part_claims
from eval.studies.transfer.report import readme_part


def claims(results):
    """The transfer part's claims (its goals, the cold-run time when the run computed)."""
    seconds = study_seconds(results, read_record(results))
    return part_claims(results, seconds["transfer"], seconds["transfer_runs"])


STUDY = Study(
    name="transfer",
    label="Transfer",
    data=(
        Data("cad-train", SCENARIOS[0], {"train": CAD_TRAIN_PAIRS}),
        Data("dmgm-cad/val-070", "eval/data/dmgm-cad/val-070"),
    ),
    methods=LEARNED,
    claims=claims,
    parts=(
        Part(
            "transfer",
            lambda c: readme_part(
                c.results, c.rel, c.seconds["transfer"], c.seconds["transfer_runs"]
            ),
            "Transfer",
            "Does simulation transfer?",
            "table_transfer.md",
        ),
    ),
    stages=(
        Stage(
            name="transfer_generate",
            reads=("scenarios/cad-intersection.toml", "scenarios/cad-v2x.toml"),
            writes=("cad-train", "cad-v2x-train"),
            run=stages.transfer_generate,
            budget_s=50,
            skip="transfer",
            executor=False,
            counts_runs=False,
            about="the learned matchers' transfer matrix (also skipped without cad-v2x)",
        ),
        Stage(
            name="transfer",
            reads=("cad-train", "cad-v2x-train", "eval/data/dmgm-cad"),
            writes=("models", "table_transfer.*", "transfer/"),
            run=stages.transfer,
            budget_s=35,
            skip="transfer",
            stale=("table_transfer.csv", "table_transfer.md"),
        ),
    ),
    needs={"v2x": ""},  # cad-v2x's test split (a test set) and its scenario's generation
    outputs=("table_transfer.*", "transfer/"),
)
