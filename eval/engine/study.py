"""A study as one declaration (:class:`Study`): its data and splits, its methods, its conditions,
its goals, the claims it emits, its parts of the results report and the stages it adds to
``make reproduce``. ``eval/pipeline/stages.py``, ``eval/claims`` and the report read the list of
studies (:func:`eval.studies.studies`) and nothing else of a study, so adding a study is writing
one declaration and its metric (docs/architecture.md, "Adding a study").
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from eval.engine.goal import Goal
from eval.engine.power_analysis import PowerCheck
from eval.protocol.claims import Claim


@dataclass(frozen=True)
class Data:
    """One dataset a study reads: ``name`` (its folder under ``--data``; the validation split is
    ``<name>-val``), the ``scenario`` file it is generated from (or the shipped folder), the
    records per split at scale 1 (``splits``: ``{"test": 60, "val": 30}``) and what a record is
    (``unit``: pairs, snapshots, sequences)."""

    name: str
    scenario: str
    splits: Mapping[str, int] = field(default_factory=dict)
    unit: str = "pairs"


@dataclass(frozen=True)
class ReportContext:
    """What every part of the report is given: the results folder, its path relative to the
    page (``rel``, for links), the run record, the last cold run's study times (``seconds``:
    ``{stage or study: s}``, empty keys None) and the folder's claims."""

    results: Path
    rel: str
    record: Mapping[str, Any]
    seconds: Mapping[str, float | None]
    claims: Any  # pandas.DataFrame of eval.protocol.claims.COLUMNS


@dataclass(frozen=True)
class Part:
    """One part of the results report: ``name`` (for the log when it cannot be built),
    ``build`` (Markdown lines; none when its files are absent), ``group`` (the ``##`` heading it
    sits under), ``heading`` and ``table`` (the section and table a failed part names)."""

    name: str
    build: Callable[[ReportContext], list[str]]
    group: str
    heading: str | None = None
    table: str | None = None


@dataclass(frozen=True)
class Study:
    """One study. ``name``: its package under ``eval/studies/`` and its ``study`` column in
    ``claims.csv``; ``label``: how the report names it; ``data``: the datasets it reads with
    their splits; ``methods``: the matchers (or methods) it compares; ``conditions``: presets,
    windows, N, sensors; ``goals``: its declared goals; ``claims``: the claims it emits from
    the files of a results folder (every comparative sentence of its report parts is one of
    them); ``parts``: its parts of the report, in order; ``stages``: the stages it adds to
    ``make reproduce`` (``eval.pipeline.stage.Stage``), in order; ``closing_stages``: stages
    that run after every study's (tables and figures that read every study's files);
    ``needs``: {study: the result file of it that this study reads ("" when it reads only
    that study's datasets)} — those run first; ``outputs``: the
    result files it writes under ``--out``; ``tables``: re-writes its tables from its result
    files, runs nothing (None: it has none to re-write); ``power``: the comparisons its power
    analysis covers (:class:`eval.engine.power_analysis.PowerCheck`: the test clusters each
    would need for a ±5-point half-width or a 5-point MDD, in ``power_analysis.csv``);
    ``budget_units``: the tables it adds, each as (what, the names of the stages that make it)
    — the unit of the cold-run budget (``eval.claims.budget``: each added table with its
    sweep ≤ 240 s); empty: the study is one unit."""

    name: str
    label: str
    data: tuple[Data, ...] = ()
    methods: tuple[str, ...] = ()
    conditions: tuple[str, ...] = ()
    goals: tuple[Goal, ...] = ()
    claims: Callable[[Path], list[Claim]] | None = None
    parts: tuple[Part, ...] = ()
    stages: tuple[Any, ...] = ()
    closing_stages: tuple[Any, ...] = ()
    needs: Mapping[str, str] = field(default_factory=dict)
    outputs: tuple[str, ...] = ()
    tables: Callable[[Path], object] | None = None
    power: tuple[PowerCheck, ...] = ()
    budget_units: tuple[tuple[str, tuple[str, ...]], ...] = ()

    def data_named(self, name: str) -> Data:
        """The declared dataset ``name`` (KeyError naming the study when it has none)."""
        for data in self.data:
            if data.name == name:
                return data
        raise KeyError(f"study {self.name}: no dataset {name!r}")

    def emitted(self, results: Path) -> list[Claim]:
        """The claims this study emits from ``results`` (none without a claims function)."""
        return [] if self.claims is None else list(self.claims(Path(results)))


__all__ = ["Data", "Part", "ReportContext", "Study"]
