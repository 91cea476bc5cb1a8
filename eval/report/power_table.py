"""``power_analysis.md``: the power analysis (:mod:`eval.engine.power_analysis`) as the report's
Markdown table, rates printed in points; the report's appendix shows it in full."""

from __future__ import annotations

import math

import pandas as pd

from eval.report.markdown_cell import cell, row

FILE = "power_analysis.md"
HEADER = (
    "study",
    "comparison",
    "condition",
    "goal",
    "clusters now",
    "now (points)",
    "ICC",
    "design effect",
    "clusters needed",
)


def _number(value: object, digits: int, scale: float = 1.0) -> str:
    try:
        number = float(value)
    except (TypeError, ValueError):
        return "—"
    return f"{scale * number:.{digits}f}" if math.isfinite(number) else "—"


def power_markdown(table: pd.DataFrame) -> str:
    """The table of ``power_analysis.csv`` rows (:data:`eval.engine.power_analysis.COLUMNS`):
    the goal as "half-width ≤ ±5" or "MDD ≤ 5", the figure now in F1 points."""
    lines = [
        "Test clusters each comparison would need for its goal, the per-cluster spread of its "
        'paired difference held at today\'s (docs/evaluation.md, "Power analysis"); split sizes '
        "are not changed by it.",
        "",
        row(list(HEADER)),
        row(["---"] * len(HEADER)),
    ]
    for r in table.itertuples(index=False):
        goal = _number(r.goal, 0, 100)
        goal = f"half-width ≤ ±{goal}" if r.kind == "half_width" else f"MDD ≤ {goal}"
        needed = _number(r.clusters_needed, 0)
        lines.append(
            row(
                [
                    cell(r.study),
                    cell(r.comparison),
                    cell(r.condition),
                    goal,
                    _number(r.clusters, 0),
                    _number(r.now, 1, 100),
                    _number(r.icc, 2),
                    _number(r.design_effect, 2),
                    needed,
                ]
            )  # fmt: skip
        )
    return "\n".join(lines) + "\n"
