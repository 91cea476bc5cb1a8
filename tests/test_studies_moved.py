"""The studies' flat modules of the previous release still import, as the module that replaced
them, with a DeprecationWarning (one release)."""

from __future__ import annotations

import importlib
import pathlib

import pytest

import eval.studies
from eval.studies import MOVED


@pytest.mark.parametrize("old", sorted(MOVED))
def test_an_old_module_name_is_the_new_module_with_a_warning(old):
    new = importlib.import_module(f"eval.studies.{MOVED[old]}")
    with pytest.warns(DeprecationWarning, match=f"eval.studies.{old} moved"):
        module = importlib.import_module(f"eval.studies.{old}")
    assert module is new
    assert module.__spec__.name == new.__name__  # the alias does not rename the module


def test_a_name_of_a_study_that_was_one_module_is_forwarded_with_a_warning():
    from eval.studies import temporal
    from eval.studies.temporal.evaluation import evaluate_temporal

    with pytest.warns(DeprecationWarning, match="temporal.evaluation.evaluate_temporal"):
        assert temporal.evaluate_temporal is evaluate_temporal
    with pytest.raises(AttributeError):
        temporal.no_such_name  # noqa: B018


def test_no_study_file_sits_outside_a_study_package():
    root = eval.studies.__path__[0]
    flat = [p.name for p in pathlib.Path(root).glob("*.py") if p.name != "__init__.py"]
    assert flat == []


def test_the_engine_names_table1_re_exported_are_forwarded_with_a_warning():
    from eval.engine.matcher_list import parse_matchers
    from eval.engine.splits import open_entry
    from eval.studies.table1 import evaluation

    with pytest.warns(DeprecationWarning, match="eval.engine.matcher_list.parse_matchers"):
        assert evaluation.parse_matchers is parse_matchers
    with pytest.warns(DeprecationWarning, match="eval.engine.splits.open_entry"):
        assert evaluation.open_entry is open_entry
