"""The list of studies: every study package declares one ``Study``, and ``make reproduce``'s
stages, claims.csv and the report are derived from that list."""

from __future__ import annotations

import pathlib

import pytest

import eval.studies
from eval.engine.study import Study
from eval.pipeline.stages import STAGES
from eval.studies import STUDIES, studies, study


def test_every_study_package_declares_itself_and_is_listed():
    root = pathlib.Path(eval.studies.__path__[0])
    packages = sorted(p.parent.name for p in root.glob("*/study.py"))
    assert packages == sorted(STUDIES)
    for declared in studies():
        assert isinstance(declared, Study)
        assert declared.name in STUDIES
        assert set(declared.needs) <= set(STUDIES)
        # a study runs after the studies it reads
        assert all(STUDIES.index(n) < STUDIES.index(declared.name) for n in declared.needs)


def test_the_stages_are_every_studys_stages_in_order_then_the_closing_ones():
    own = [s.name for d in studies() for s in d.stages]
    closing = [s.name for d in studies() for s in d.closing_stages]
    assert [s.name for s in STAGES] == own + closing
    assert len(set(own + closing)) == len(STAGES)
    assert closing == ["tables_figures"]


def test_report_parts_have_unique_names_and_a_group():
    parts = [p for d in studies() for p in d.parts]
    assert len({p.name for p in parts}) == len(parts)
    assert all(p.group for p in parts)


def test_an_unknown_study_is_one_line_naming_the_known_ones():
    with pytest.raises(ValueError, match="unknown study 'v3x'; known: table1, v2x"):
        study("v3x")
