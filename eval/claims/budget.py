"""The cold-run budget, per added table, as claims: the stages of each table an added study
makes, summed from the last cold run (``results/cold_run.json``), against its share of the
budget — the paper's part (Table I with its sweeps and figures, and the external benchmark)
≤ 600 s, each added table with its sweep ≤ 240 s, the whole run ≤ 1,800 s on the 2-core machine.
A study that adds several tables (V2X: camera, box-only, LiDAR; temporal: camera, LiDAR) names
them in ``Study.budget_units``; its whole package is stated beside them against 240 s per table.
Each is a point measurement (one run, no interval, no verdict); its statement says by how much
it is within or past its budget. No cold run in the folder: no claims. docs/evaluation.md,
"The cold-run budget", says why the table is the unit.
"""

from __future__ import annotations

import json
from pathlib import Path

from eval.protocol.claims import Claim, measurement_claim

PAPER_STUDIES = ("table1", "external")
"""The studies that make the paper's part of ``make reproduce``."""
PAPER_BUDGET_S = 600.0
STUDY_BUDGET_S = 240.0
TOTAL_BUDGET_S = 1800.0
STUDY = "budget"
DETAIL = "last cold run, results/cold_run.json"


def _stage_names(study) -> list[str]:
    return [stage.name for stage in (*study.stages, *study.closing_stages)]


def budget_parts(record: dict) -> list[tuple[str, float, float]]:
    """(what, seconds, budget s) of the paper's part, each added table (each study's
    ``budget_units``; a study without them is one), each study of several tables as a whole,
    and the whole run, from a run record's ``wall_s``; a unit none of whose stages ran is left
    out."""
    from eval.studies import studies

    wall = record.get("wall_s", {})
    found = {s.name: s for s in studies()}
    parts = []
    paper = [n for name in PAPER_STUDIES if name in found for n in _stage_names(found[name])]
    if any(n in wall for n in paper):
        what = "the paper's part (Table I, Fig. 4, the sweeps, the external benchmark)"
        parts.append((what, sum(wall.get(n, 0.0) for n in paper), PAPER_BUDGET_S))
    for name, study in found.items():
        if name in PAPER_STUDIES:
            continue
        label = study.label if study.label[:2].isupper() else study.label[:1].lower() + study.label[1:]  # fmt: skip
        units = study.budget_units or ((f"the {label} study", tuple(_stage_names(study))),)
        ran = [(what, [n for n in names if n in wall]) for what, names in units]
        ran = [(what, names) for what, names in ran if names]
        parts += [(what, sum(wall[n] for n in names), STUDY_BUDGET_S) for what, names in ran]
        if len(units) > 1 and ran:
            seconds = sum(wall[n] for _, names in ran for n in names)
            what = f"the {label} study as a whole ({len(ran)} tables, {STUDY_BUDGET_S:.0f} s each)"
            parts.append((what, seconds, STUDY_BUDGET_S * len(ran)))
    if "total" in wall:
        parts.append(("the whole `make reproduce`", float(wall["total"]), TOTAL_BUDGET_S))
    return parts


def budget_claims(results: str | Path) -> list[Claim]:
    """The claims of :func:`budget_parts` for the folder's last cold run (none without one)."""
    path = Path(results) / "cold_run.json"  # eval.report.run_record's COLD_RECORD; read here,
    if not path.is_file():  # since eval.report reads these claims (no folder loop)
        return []
    record = json.loads(path.read_text())
    claims = []
    for what, seconds, budget in budget_parts(record):
        margin = budget - round(seconds)
        where = (
            f"{margin:.0f} s inside the budget"
            if margin >= 0
            else f"{-margin:.0f} s past the budget"
        )
        claims.append(
            measurement_claim(STUDY, f"{what}, cold", seconds, budget, f"{DETAIL}; {where}")
        )
    return claims
