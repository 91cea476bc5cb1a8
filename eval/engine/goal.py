"""A goal as a study declares it: under one condition, a metric of the method chosen on
validation against a bar, read off the metric's episode-level interval
(:func:`eval.protocol.goal_verdict.goal_line`: met only when the whole interval clears the bar).
Imports ``eval/protocol/`` only."""

from __future__ import annotations

from dataclasses import dataclass

import pandas as pd

from eval.protocol.claims import Claim, finite, printed
from eval.protocol.goal_verdict import NOT_SHOWN, goal_line, verdict


@dataclass(frozen=True)
class Goal:
    """``metric`` (a table row's ``(value, low, high)`` columns) of a method under
    ``condition`` against ``bar`` (``≥`` when ``at_least``, else ``≤``); ``text`` is the goal as
    the report states it; ``chosen_on``: how the method was chosen (``validation``: the one
    best on validation; ``fixed``: the goal names it); ``scale``, ``digits``, ``unit``: how the
    line prints a value (100: percent points). The claim's bar, direction and chosen-on come
    from these fields, never from the text.

    >>> Goal("gnss-urban", "`gnss-urban` F1 ≥ 90", ("f1_mean", "f1_low", "f1_high"), 0.9).bar
    0.9
    """

    condition: str
    text: str
    metric: tuple[str, str, str]
    bar: float
    at_least: bool = True
    chosen_on: str = "validation"
    scale: float = 100.0
    digits: int = 1
    unit: str = ""

    def line(self, row: pd.Series, detail: str) -> str:
        """The goal line of table row ``row`` (the chosen method's), with ``detail``."""
        value, low, high = (getattr(row, column) for column in self.metric)
        return self.line_of(value, low, high, detail)

    def line_of(self, value: float, low: float, high: float, detail: str = "") -> str:
        """The goal line of a value and its interval (fractions when ``scale`` is 100)."""
        return goal_line(
            self.text, value, low, high, self.bar, self.at_least, self.scale, self.digits,
            self.unit, detail,
        )  # fmt: skip

    def claim(self, row, detail: str, *, study: str, subject: str, source: str, **kw) -> Claim:
        """The claim of table row ``row`` (``metric``'s columns): :meth:`claim_of`."""
        value, low, high = (getattr(row, column) for column in self.metric)
        return self.claim_of(value, low, high, detail, study=study, subject=subject, source=source, **kw)  # fmt: skip

    def claim_of(
        self,
        value: float,
        low: float,
        high: float,
        detail: str = "",
        *,
        study: str,
        subject: str,
        source: str,
        clusters: str | None = None,
    ) -> Claim:
        """The goal as a claim record: value and interval as the line prints them, the bar in
        the same units, the direction, verdict and chosen-on from this declaration, and the
        line itself as its statement. ``clusters``: what the interval resamples (simulation
        episodes by default, none without an interval)."""
        if clusters is None:  # what the interval resamples
            clusters = "simulation episodes" if finite(low) and finite(high) else ""
        return Claim(
            study, subject, "goal", self.text, printed(value, self.scale, self.digits),
            printed(low, self.scale, self.digits), printed(high, self.scale, self.digits),
            round(self.scale * self.bar, 9), ">=" if self.at_least else "<=",
            verdict(low, high, self.bar, self.at_least), self.chosen_on, clusters, source,
            self.line_of(value, low, high, detail),
        )  # fmt: skip

    def not_shown(self, why: str, *, study: str, subject: str, source: str) -> Claim:
        """The goal as a claim with no figure to read (``why``: no validation figures to choose
        on, nothing scored): *not shown*, its statement ``<text>: not shown — <why>``."""
        nan = float("nan")
        return Claim(
            study, subject, "goal", self.text, nan, nan, nan, round(self.scale * self.bar, 9),
            ">=" if self.at_least else "<=", NOT_SHOWN, self.chosen_on, "", source,
            f"{self.text}: {NOT_SHOWN} — {why}",
        )  # fmt: skip


__all__ = ["Goal"]
