"""Claims as data: every comparative statement the report makes is one record.

A claim is a goal verdict ("met / not met / not shown"), a difference between two methods
("ahead", "behind"), a rank, a "leader", a "gain", a "crossover" or an AUC band: what is compared
(``subject`` against ``comparison`` on ``metric``), the value and its 95 % interval (the units
of the result CSV it was read from: fractions, seconds, ranks), the bar and its ``direction``
(``>=`` / ``<=`` for a goal, ``diff`` for a difference, ``point`` for a labelled point value),
the ``verdict``, the split its method was chosen on (``chosen_on``: ``validation``, ``fixed``, or
``test`` for a point value that names a leader on the test figures themselves and says so in its
statement), what the interval resamples (``clusters``), the results file it reads
(``source``) and the ``statement``: the exact text the report prints for it. The report prints
statements, so a comparative sentence without a claim behind it is not written
(``tests/test_claims_report.py`` scans the generated report).

Verdicts: a goal's through :func:`eval.protocol.goal_verdict.verdict` (met only when the whole
interval clears the bar); a difference is ``ahead`` / ``behind`` only when its interval excludes
0, else ``not shown``; a value without an interval is a ``point value`` (or ``point
measurement`` for a time) and never a verdict.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from pathlib import Path

import pandas as pd

from eval.protocol.goal_verdict import MET, NOT_MET, NOT_SHOWN, verdict

COLUMNS = (
    "study",
    "subject",
    "comparison",
    "metric",
    "value",
    "ci_low",
    "ci_high",
    "bar",
    "direction",
    "verdict",
    "chosen_on",
    "clusters",
    "source",
    "statement",
)
FILE = "claims.csv"
AHEAD, BEHIND = "ahead", "behind"
POINT_VALUE, POINT_MEASUREMENT = "point value", "point measurement"
CROSSES = "crosses"  # a crossover whose interval excludes "no crossing"
VERDICTS = (MET, NOT_MET, NOT_SHOWN, AHEAD, BEHIND, CROSSES, POINT_VALUE, POINT_MEASUREMENT)
CHOICES = ("validation", "fixed", "test")
NAN = float("nan")


@dataclass(frozen=True)
class Claim:
    """One comparative statement (the columns of :data:`COLUMNS`)."""

    study: str
    subject: str
    comparison: str
    metric: str
    value: float
    ci_low: float
    ci_high: float
    bar: float
    direction: str
    verdict: str
    chosen_on: str
    clusters: str
    source: str
    statement: str

    def __post_init__(self) -> None:
        if self.chosen_on == "test" and self.direction != "point":
            raise ValueError(
                f"claim {self.statement!r}: chosen on test, so a point value, never a verdict"
            )
        if self.verdict not in VERDICTS:
            raise ValueError(
                f"claim {self.statement!r}: verdict {self.verdict!r} not in {VERDICTS}"
            )
        if self.chosen_on not in CHOICES:
            raise ValueError(
                f"claim {self.statement!r}: chosen_on {self.chosen_on!r}, expected one of {CHOICES}"
            )


def finite(x: object) -> bool:
    """Whether ``x`` is a finite number."""
    try:
        return math.isfinite(float(x))
    except (TypeError, ValueError):
        return False


def difference_verdict(low: float, high: float) -> str:
    """``ahead`` when the interval of a − b lies above 0, ``behind`` below, else ``not shown``."""
    if not (finite(low) and finite(high)):
        return NOT_SHOWN
    return AHEAD if low > 0 else BEHIND if high < 0 else NOT_SHOWN


def goal_claim(
    study: str,
    subject: str,
    metric: str,
    value: float,
    low: float,
    high: float,
    bar: float,
    at_least: bool,
    *,
    statement: str,
    chosen_on: str,
    clusters: str,
    source: str,
    comparison: str = "goal",
) -> Claim:
    """A goal ``value ≥ bar`` (``at_least``) or ``≤ bar`` with its verdict read off [low, high]."""
    return Claim(
        study, subject, comparison, metric, float(value), float(low), float(high), float(bar),
        ">=" if at_least else "<=", verdict(low, high, bar, at_least), chosen_on, clusters,
        source, statement,
    )  # fmt: skip


def difference_claim(
    study: str,
    subject: str,
    comparison: str,
    metric: str,
    diff: float,
    low: float,
    high: float,
    *,
    statement: str,
    chosen_on: str,
    clusters: str,
    source: str,
) -> Claim:
    """``subject − comparison`` on ``metric`` with its interval: ahead, behind or not shown."""
    return Claim(
        study, subject, comparison, metric, float(diff), float(low), float(high), 0.0, "diff",
        difference_verdict(low, high), chosen_on, clusters, source, statement,
    )  # fmt: skip


def point_claim(
    study: str,
    subject: str,
    comparison: str,
    metric: str,
    value: float,
    *,
    statement: str,
    chosen_on: str,
    source: str,
    bar: float = NAN,
    measurement: bool = False,
) -> Claim:
    """A value without an interval, labelled as one: never a verdict."""
    return Claim(
        study, subject, comparison, metric, float(value), NAN, NAN, float(bar), "point",
        POINT_MEASUREMENT if measurement else POINT_VALUE, chosen_on, "", source, statement,
    )  # fmt: skip


def printed(value: float, scale: float = 100.0, digits: int = 1) -> float:
    """``value`` as a report line prints it (× ``scale``, ``digits`` decimals): the number a
    claim records beside its statement; NaN when not finite."""
    return float(f"{scale * float(value):.{digits}f}") if finite(value) else NAN


def measurement_claim(study: str, what: str, seconds: float, bar_s: float, detail: str) -> Claim:
    """A stage time against its cold-run goal, labelled a point measurement (no interval, no
    verdict); its statement is :func:`measurement_line`'s."""
    return point_claim(
        study, what, "goal", "seconds (last cold run)", printed(seconds, 1.0, 0),
        statement=measurement_line(what, seconds, bar_s, detail), chosen_on="fixed",
        source="cold_run.json", bar=bar_s, measurement=True,
    )  # fmt: skip


def measurement_line(what: str, seconds: float, bar_s: float, detail: str) -> str:
    """A time without a sampling interval, labelled as a point measurement (never "met"):
    ``what: 42 s (detail) — a point measurement (goal ≤ 120 s cold; no interval, no verdict)``."""
    return (
        f"{what}: {seconds:.0f} s ({detail}) — a point measurement (goal ≤ {bar_s:.0f} s cold; no interval, "
        "so no verdict)"
    )


def to_frame(claims: list[Claim]) -> pd.DataFrame:
    """The claims as a table of :data:`COLUMNS`; a claim built twice is one row."""
    frame = pd.DataFrame([asdict(c) for c in claims], columns=list(COLUMNS))
    return frame.drop_duplicates(ignore_index=True)


def read_claims(path: str | Path) -> pd.DataFrame:
    """``claims.csv`` (:data:`COLUMNS`); an empty table when the file is absent."""
    path = Path(path)
    if not path.is_file():
        return pd.DataFrame(columns=list(COLUMNS))
    from eval.core.spreadsheet_safe import restore

    frame = pd.read_csv(path, keep_default_na=False, na_values=[""])
    missing = [c for c in COLUMNS if c not in frame.columns]
    if missing:
        raise ValueError(f"{path}: columns {missing} missing; expected {list(COLUMNS)}")
    return restore(frame)  # the statements as built (a leading ' marks text for spreadsheets)


def statements(
    frame: pd.DataFrame, study: str | None = None, metric: str | None = None
) -> list[str]:
    """The statements of ``frame``'s claims (of one study / metric when given), in order."""
    keep = pd.Series(True, index=frame.index)
    if study is not None:
        keep &= frame["study"] == study
    if metric is not None:
        keep &= frame["metric"] == metric
    return [str(s) for s in frame.loc[keep, "statement"]]


def lines_of(items) -> list[str]:
    """A report part's lines from its items: a claim prints its statement, a plain line (no
    comparison: a definition, a note) itself."""
    return [item.statement if isinstance(item, Claim) else str(item) for item in items]


def claims_in(items) -> list[Claim]:
    """The claims among a report part's items (:func:`lines_of`)."""
    return [item for item in items if isinstance(item, Claim)]
