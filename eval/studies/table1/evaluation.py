"""Deprecated (removed in the next release): ``eval.studies.evaluation`` re-exported the study
engine's names and the matcher-list parser for every command and study. They live where they
belong — ``parse_matchers`` and ``PAPER_ORDER`` in :mod:`eval.engine.matcher_list`,
``DEFAULT_CACHE`` in :mod:`eval.core.cache`, the rest in :mod:`eval.engine` (splits, named runs,
the protocol run, ranking quality, validation choice, variant files) — and this module only
forwards them, with a :class:`DeprecationWarning`.
"""

from __future__ import annotations

import importlib

_MODULES = {
    "eval.engine.matcher_list": ("PAPER_ORDER", "parse_matchers"),
    "eval.core.cache": ("DEFAULT_CACHE",),
    "eval.engine.named_runs": (
        "as_named",
        "calibrate_entry",
        "calibrate_named",
        "run_named",
        "score_runs",
    ),
    "eval.engine.protocol_run": ("evaluate", "evaluate_entry"),
    "eval.engine.ranking_quality": (
        "QUALITATIVE_MATCHERS",
        "qualitative_entry",
        "ranking_quality",
        "representative_pair",
    ),
    "eval.engine.splits": (
        "DATASET_LABELS",
        "PAPER_FAMILIES",
        "DatasetEntry",
        "Named",
        "dataset_label",
        "open_entry",
        "val_dirs",
    ),
    "eval.engine.validation_choice": ("chosen_specs",),
    "eval.engine.variant_files": ("THRESHOLD_COLUMNS", "EntryResult"),
}
MOVED = {name: module for module, names in _MODULES.items() for name in names}
"""name -> the module that holds it now."""


def __getattr__(name: str):
    from eval.studies import moved_warning

    if name not in MOVED:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    moved_warning(f"{__name__}.{name}", f"{MOVED[name]}.{name}")
    return getattr(importlib.import_module(MOVED[name]), name)


__all__ = sorted(MOVED)
