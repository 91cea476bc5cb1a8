"""The studies, one sub-package each: ``table1/`` (Table I's evaluation, dataset spread, regime
cards), ``v2x/`` (camera, boxes, LiDAR, sensors, realism, the GNSS calibration check),
``multiagent/``, ``temporal/`` (camera and LiDAR), ``transfer/`` and ``external/`` (the DMGM CAD
pairs, the prior matchers' defaults and whether the rankings hold there).

Each package declares itself in its ``study.py`` (``STUDY``, an :class:`eval.engine.study.Study`:
data and splits, methods, conditions, goals, the claims it emits, its report parts and its
stages); :data:`STUDIES` lists them and :func:`studies` reads them. ``make reproduce``'s stages,
``claims.csv`` and the report are derived from that list, so nothing outside a study imports a
study module.

The flat modules of the previous release (``eval.studies.v2x_table``, ``eval.studies.temporal``
as a module, …) still import for one release, as the module that replaced them, with a
:class:`DeprecationWarning` (:data:`MOVED`).
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import warnings

from eval.engine.study import Study

STUDIES = ("table1", "v2x", "external", "multiagent", "transfer", "temporal")
"""The studies, in the order ``make reproduce`` walks their stages (a study after those it reads:
``Study.needs``) and the report shows their parts within a group."""

# old flat module (under eval.studies) -> the module that replaced it; removed in the next release
MOVED = {
    "evaluation": "table1.evaluation",
    "regime_cards": "table1.regime_cards",
    "spread": "table1.spread",
    "v2x_table": "v2x.table",
    "v2x_markdown": "v2x.markdown",
    "v2x_report": "v2x.report",
    "v2x_realism": "v2x.realism",
    "v2x_boxes": "v2x.boxes",
    "v2x_lidar": "v2x.lidar",
    "v2x_sensors": "v2x.sensors",
    "gnss_calibration": "v2x.gnss_calibration",
    "multiagent_gains": "multiagent.gains",
    "multiagent_markdown": "multiagent.markdown",
    "multiagent_report": "multiagent.report",
    "temporal_gain": "temporal.gain",
    "temporal_markdown": "temporal.markdown",
    "temporal_preset": "temporal.preset",
    "temporal_report": "temporal.report",
    "temporal_runs": "temporal.runs",
    "temporal_scores": "temporal.scores",
    "temporal_sequences": "temporal.sequences",
    "temporal_table": "temporal.table",
    "transfer_gap": "transfer.gap",
    "transfer_matrix": "transfer.matrix",
    "transfer_reference": "transfer.reference",
    "transfer_report": "transfer.report",
    "transfer_sets": "transfer.sets",
    "prior_defaults": "external.prior_defaults",
    "agreement": "external.agreement",
}


def moved_warning(old: str, new: str) -> None:
    """The one-release deprecation warning of an import from a moved module."""
    warnings.warn(
        f"{old} moved to {new}; the old name goes in the next release",
        DeprecationWarning,
        stacklevel=3,
    )


class _MovedLoader(importlib.abc.Loader):
    """Loads an old flat module name as the module that replaced it (the same module object)."""

    def __init__(self, target: str) -> None:
        self.target = target
        self.spec = None

    def create_module(self, spec):
        module = importlib.import_module(self.target)
        self.spec = module.__spec__
        return module

    def exec_module(self, module) -> None:
        module.__spec__ = self.spec  # the import system set the old name's spec on it


class _MovedFinder(importlib.abc.MetaPathFinder):
    def find_spec(self, fullname, path, target=None):
        prefix, _, name = fullname.rpartition(".")
        if prefix != __name__ or name not in MOVED:
            return None
        new = f"{__name__}.{MOVED[name]}"
        moved_warning(fullname, new)
        return importlib.util.spec_from_loader(fullname, _MovedLoader(new))


if not any(isinstance(f, _MovedFinder) for f in sys.meta_path):
    sys.meta_path.append(_MovedFinder())


def __getattr__(name: str):
    """``from eval.studies import v2x_table`` of the previous release (deprecated)."""
    if name in MOVED:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def forwarding(package: str):
    """The ``__getattr__`` of a study package whose study was one module in the previous release
    (``eval.studies.temporal``, …): a name of that module, now in ``<package>.evaluation``,
    with a :class:`DeprecationWarning` (one release)."""

    def forward(name: str):
        module = importlib.import_module(f"{package}.evaluation")
        own = vars(sys.modules[package])
        if name in own:  # a sub-module, imported on the way
            return own[name]
        if name.startswith("__") or not hasattr(module, name):
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        moved_warning(f"{package}.{name}", f"{module.__name__}.{name}")
        return getattr(module, name)

    return forward


_REGISTERED: dict[str, Study] = {}  # studies declared outside this package (register)


def register(declared: Study) -> Study:
    """Add a study declared outside this package (your own, e.g. ``examples/dense_arena``) to
    the list, after the built-in ones, so that its claims and report parts are derived like
    theirs; a built-in name is refused. Returns ``declared``."""
    if declared.name in STUDIES:
        raise ValueError(f"study {declared.name!r}: a built-in study has that name")
    _REGISTERED[declared.name] = declared
    return declared


def study(name: str) -> Study:
    """The declaration of study ``name`` (``eval/studies/<name>/study.py``'s ``STUDY``, or one
    registered with :func:`register`); a ValueError naming the known ones for any other name.
    The registry names each built-in study by its package, as the matcher registry names a
    matcher, so this package imports no study module until it is asked for one."""
    if name in _REGISTERED:
        return _REGISTERED[name]
    if name not in STUDIES:
        known = ", ".join([*STUDIES, *_REGISTERED])
        raise ValueError(f"unknown study {name!r}; known: {known}")
    return importlib.import_module(f"{__name__}.{name}.study").STUDY


def studies() -> tuple[Study, ...]:
    """Every study's declaration: the built-in ones in :data:`STUDIES` order, then the
    registered ones in the order they were registered."""
    return tuple(study(name) for name in (*STUDIES, *_REGISTERED))


def power_checks() -> list:
    """Every study's power-analysis checks (``Study.power``), in :func:`studies` order."""
    return [check for declared in studies() for check in declared.power]
