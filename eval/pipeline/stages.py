"""``make reproduce``'s stages, in the order a run walks them, derived from the list of studies
(:func:`eval.studies.studies`): every study's stages in the studies' order, then every study's
closing stages (tables and figures that read every study's files). Each stage is declared once,
in its study's ``study.py``, with what it reads (datasets under ``--data``; ``eval/data/…``
shipped) and writes (under ``--out``), the function it runs, its cold budget in seconds on 2
cores (together 15 min) and, where a study can be left out, its ``--no-X`` option. Adding a
stage is one entry in its study's declaration (docs/architecture.md)."""

from __future__ import annotations

from eval.pipeline.stage import Stage
from eval.studies import studies


def stages_of(declared) -> tuple[Stage, ...]:
    """The stages of ``declared`` studies in walking order: each study's stages, then each
    study's closing stages."""
    return tuple(s for study in declared for s in study.stages) + tuple(
        s for study in declared for s in study.closing_stages
    )


STAGES: tuple[Stage, ...] = stages_of(studies())
"""The stages; ``wall_s`` of the run record, ``results/cold_run.json`` and the report's stage
table name exactly these."""
