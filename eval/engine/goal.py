"""A goal as a study declares it: under one condition, a metric of the method chosen on
validation against a bar, read off the metric's episode-level interval
(:func:`eval.protocol.goal_verdict.goal_line`: met only when the whole interval clears the bar).
Imports ``eval/protocol/`` only."""

from __future__ import annotations

from dataclasses import dataclass

import pandas as pd

from eval.protocol.goal_verdict import goal_line


@dataclass(frozen=True)
class Goal:
    """``metric`` (a table row's ``(value, low, high)`` columns) of the method chosen on
    validation under ``condition`` against ``bar`` (``≥`` when ``at_least``, else ``≤``);
    ``text`` is the goal as the report states it.

    >>> Goal("gnss-urban", "`gnss-urban` F1 ≥ 90", ("f1_mean", "f1_low", "f1_high"), 0.9).bar
    0.9
    """

    condition: str
    text: str
    metric: tuple[str, str, str]
    bar: float
    at_least: bool = True

    def line(self, row: pd.Series, detail: str) -> str:
        """The goal line of table row ``row`` (the chosen method's), with ``detail``."""
        value, low, high = (getattr(row, column) for column in self.metric)
        return goal_line(self.text, value, low, high, self.bar, self.at_least, detail=detail)


__all__ = ["Goal"]
