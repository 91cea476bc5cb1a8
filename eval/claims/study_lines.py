"""The claims the studies state (V2X, boxes, LiDAR, multi-agent, temporal, transfer, external):
each study writes its verdicts through :func:`eval.protocol.goal_verdict.goal_line` and its
differences as ``d [low, high]`` in its part of the report; this module reads those lines into
claim records with the numbers they print (percent points where the line prints percent), the
split the method was chosen on, what the interval resamples and the file they read.

A study line that carries a comparative word but none of the shapes below makes no claim, and
the report test (``tests/test_claims_report.py``) fails on it: a verdict is never written that
claims.csv does not hold.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import pandas as pd

from eval.engine.study import ReportContext
from eval.protocol.claims import (
    AHEAD,
    BEHIND,
    NAN,
    NOT_SHOWN,
    POINT_MEASUREMENT,
    Claim,
    difference_verdict,
    finite,
    parse_goal_line,
)
from eval.report.run_part import read_record, study_seconds
from eval.studies import studies

COMPARATIVE = re.compile(
    r"\b(not met|not shown|met|ahead|behind|leaders?|leads|trails|overtakes|favours|gains?|"
    r"crossovers?|beats)\b",
    re.IGNORECASE,
)
_BAR = re.compile(r"(≥|≤) ([-+]?\d+(?:\.\d+)?)")
_DIFF = re.compile(r"([-+]?\d+(?:\.\d+)?) \[([-+]?\d+(?:\.\d+)?), ([-+]?\d+(?:\.\d+)?)\]")
_MEASURED = re.compile(r"^(?P<what>.+?): (?P<seconds>\d+(?:\.\d+)?) s\b.* — a point measurement")
_BLOCKS = re.compile(r"over (\d+) blocks of (\d+) pairs")


# report part (``Part.name``) -> (its claims' study, the file they read), in claims.csv's order
_SOURCES = {
    "v2x": ("v2x", "table_v2x.csv"),
    "v2x boxes": ("v2x_boxes", "table_v2x_boxes.csv"),
    "v2x lidar": ("v2x_lidar", "table_v2x_sensors.csv"),
    "multiagent": ("multiagent", "table_multiagent.csv"),
    "temporal": ("temporal", "table_temporal_gain.csv"),
    "temporal_lidar": ("temporal_lidar", "table_temporal_lidar_gain.csv"),
    "transfer": ("transfer", "table_transfer.csv"),
    "external": ("external", "table_external.csv"),
    "prior sensitivity": ("prior_sensitivity", "external/prior_sensitivity.csv"),
}


def _parts(results: Path) -> list[tuple[str, str, Callable[[], list[str]]]]:
    """(study, the file its claims read, its part's lines) for every study part that states
    claims, the parts taken from the list of studies."""
    record = read_record(results)
    context = ReportContext(results, ".", record, study_seconds(results, record), None)
    parts = {part.name: part for study in studies() for part in study.parts}
    return [
        (study, source, lambda part=parts[name]: part.build(context))
        for name, (study, source) in _SOURCES.items()
        if name in parts
    ]


_CHOSEN = re.compile(r"chosen on|on the validation|on validation")
_PAIR = re.compile(r"^([\w:]+ \+ [\w:]+)")


def _chosen_on(text: str) -> str:
    return "validation" if _CHOSEN.search(text) else "fixed"


def _subject(goal: str, detail: str) -> str:
    """The method a goal line is about: the first `name` of its detail, a multi-agent
    "matcher + fusion", else the goal itself."""
    tick = re.search(r"`([^`]+)`", detail)
    if tick:
        return tick[1]
    pair = _PAIR.match(detail)
    return pair[1] if pair else goal.split(" (")[0]


def _clusters(text: str) -> str:
    """What an interval resamples, as the line says; DMGM's blocks of consecutive pairs are
    not independent (two sequences), and the claim says so."""
    blocks = _BLOCKS.search(text)
    if blocks:
        return (
            f"{blocks[1]} blocks of {blocks[2]} consecutive DMGM pairs from 2 sequences "
            "(not independent clusters)"
        )
    if "episode" in text:
        return "simulation episodes"
    return ""


def _goal(study: str, source: str, parsed: dict) -> Claim:
    bars = _BAR.findall(parsed["goal"])
    sign, bar = bars[-1] if bars else ("≥", "nan")
    text = parsed["goal"] + " " + parsed["detail"]
    return Claim(
        study, _subject(parsed["goal"], parsed["detail"]), "goal",
        parsed["goal"], parsed["value"], parsed["low"], parsed["high"], float(bar),
        ">=" if sign == "≥" else "<=", parsed["verdict"], _chosen_on(text),
        _clusters(text) or ("simulation episodes" if finite(parsed["low"]) else ""),
        source, parsed["statement"],
    )  # fmt: skip


def _difference(study: str, source: str, line: str) -> Claim | None:
    found = _DIFF.search(line)
    if found is None or " — " not in line:
        return None
    diff, low, high = (float(x) for x in found.groups())
    if "favours" in line or " — ahead" in line:
        state = AHEAD
    elif " — behind" in line:
        state = BEHIND
    elif "Holm" in line:
        state = NOT_SHOWN  # beyond 0 only before the adjustment, or not at all
    else:
        state = difference_verdict(low, high)
    subject = line.split(":")[0].replace("`", "")
    return Claim(
        study, subject, "difference", "f1 points", diff, low, high, 0.0, "diff", state,
        _chosen_on(line), _clusters(line) or "simulation episodes", source, line,
    )  # fmt: skip


_GAIN = re.compile(
    r"^`(?P<preset>[^`]+)`: W = 10 against W = 1 (?:\((?P<parameters>[^)]*)\) )?"
    r"for `(?P<method>[^`]+)`"
)


def _temporal_gain(results: Path, study: str, source: str, line: str) -> Claim | None:
    """A temporal "W = 10 against W = 1 (tuned per W | fixed: …)" line, its numbers from the
    study's gain table ``source`` (``table_temporal_gain.csv`` or its LiDAR twin)."""
    path = results / source
    head = _GAIN.match(line)
    if head is None or not path.is_file():
        return None
    gain = pd.read_csv(path)
    row = gain[(gain["preset"] == head["preset"]) & (gain["method"] == head["method"])]
    if head["parameters"] and "parameters" in gain.columns:
        row = row[row["parameters"] == head["parameters"]]
    if row.empty:
        return None
    r = row.iloc[0]
    fixed = f", {head['parameters']}" if head["parameters"] else ""
    return Claim(
        study, f"{head['method']} W = 10 ({head['preset']}{fixed})", "W = 1", "pooled F1 points",
        100 * r["pooled_diff"], 100 * r["pooled_low"], 100 * r["pooled_high"], 0.0, "diff",
        difference_verdict(r["pooled_low"], r["pooled_high"]), "validation",
        f"{int(r['episodes'])} simulation episodes (bootstrap)", source, line,
    )  # fmt: skip


def _measurement(study: str, source: str, line: str) -> Claim | None:
    found = _MEASURED.match(line)
    if found is None:
        return None
    bars = _BAR.findall(line)
    return Claim(
        study, found["what"], "goal", "seconds (last cold run)", float(found["seconds"]), NAN,
        NAN, float(bars[-1][1]) if bars else NAN, "point", POINT_MEASUREMENT, "fixed", "",
        "cold_run.json", line,
    )  # fmt: skip


def line_claim(results: Path, study: str, source: str, line: str) -> Claim | None:
    """The claim a study's report line states — a goal line, a timed point measurement, a
    temporal W = 10 against W = 1 line, or a "`subject` … d [low, high] … — verdict" difference
    line — or None (then a comparative word on the line fails the report test)."""
    line = line.strip().removeprefix("- ").rstrip(".")
    parsed = parse_goal_line(line)
    if parsed is not None:
        return _goal(study, source, parsed)
    for build in (
        lambda: _measurement(study, source, line),
        lambda: (
            _temporal_gain(results, study, source, line) if study.startswith("temporal") else None
        ),
        lambda: _difference(study, source, line) if line.startswith("`") else None,
    ):
        claim = build()
        if claim is not None:
            return claim
    return None


def _same_choice(claims: list[Claim]) -> list[Claim]:
    """A study's goals on a method it chose on validation (one line says so, the next names the
    method only) are all ``chosen_on = validation``."""
    chosen = {(c.study, c.subject) for c in claims if c.chosen_on == "validation"}
    return [
        replace(c, chosen_on="validation") if (c.study, c.subject) in chosen else c for c in claims
    ]


def study_claims(results: Path) -> list[Claim]:
    """Every claim the study parts of the report state."""
    results = Path(results)
    out = []
    for study, source, build in _parts(results):
        try:
            lines = build()
        except Exception:  # a study file this code cannot read: its part is replaced, no claim
            continue
        for line in lines:
            if line.startswith("|"):
                continue
            claim = line_claim(results, study, source, line)
            if claim is not None:
                out.append(claim)
    return _same_choice(out)
