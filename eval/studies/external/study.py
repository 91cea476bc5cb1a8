"""The external study as one declaration: every matcher on the DMGM CAD pairs shipped in
``eval/data/dmgm-cad/`` (τ and parameters from sequence 070, test on 069 + 071), the prior
matchers' sensitivity to their defaults, and whether our rankings hold there (agreement, which
reads Table I's and V2X's tables where a run wrote them).
"""

from __future__ import annotations

from pathlib import Path

from eval.engine.study import Data, Part, Study
from eval.pipeline.stage import Stage
from eval.studies.external import stages
from eval.studies.external.agreement import readme_part as agreement_part
from eval.studies.external.agreement import write_agreement
from eval.studies.external.evaluation import SUBDIR, write_table_external
from eval.studies.external.prior_defaults import SENSITIVITY
from eval.studies.external.prior_defaults import readme_part as prior_part
from eval.studies.external.report import claims as external_claims
from eval.studies.external.report import readme_part as external_part

GROUP = "External data"


def rewrite_tables(out: Path) -> list[Path]:
    """``table_external.*`` and ``agreement.csv`` again from ``out/external/`` (runs nothing;
    none without an evaluation there)."""
    if not (Path(out) / SUBDIR / "metrics_per_pair.csv").is_file():
        return []
    write_table_external(out)
    write_agreement(out)
    return [Path(out) / "table_external.md"]


STUDY = Study(
    name="external",
    label="External data",
    data=(
        Data("dmgm-cad/val-070", "eval/data/dmgm-cad/val-070"),
        Data("dmgm-cad/test-069-071", "eval/data/dmgm-cad/test-069-071"),
    ),
    methods=("all", "every prior matcher"),
    claims=external_claims,
    parts=(
        Part(
            "external",
            lambda c: external_part(c.results, c.rel),
            GROUP,
            "External data: the DMGM CAD pairs",
            "table_external.md",
        ),
        Part("prior sensitivity", lambda c: prior_part(c.results, c.rel), GROUP),
        Part(
            "external agreement",
            lambda c: agreement_part(c.results, c.rel),
            GROUP,
            "Do these rankings hold on external data?",
        ),
    ),
    stages=(
        Stage(
            name="external",
            reads=("eval/data/dmgm-cad",),
            writes=("table_external.*", "external/", "agreement.csv"),
            run=stages.external,
            budget_s=25,
        ),
        Stage(
            name="prior_sensitivity",
            reads=("eval/data/dmgm-cad",),
            writes=(f"external/{SENSITIVITY}",),
            run=stages.prior_sensitivity,
            budget_s=5,
            stale=(f"external/{SENSITIVITY}",),
        ),
    ),
    outputs=("table_external.*", "external/", "agreement.csv"),
    tables=rewrite_tables,
)
