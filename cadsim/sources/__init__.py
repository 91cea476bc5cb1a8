"""Traffic source registry: ``[traffic] source = KIND`` -> the class that simulates it.

A source module registers a factory ``(scenario, seed, workdir) -> TrafficSource`` with
:func:`register_source` and the schema of its ``[traffic]`` table with
``cadsim.scenario.register_source_schema``. Built-in kinds are imported on first use, so that
loading this module needs neither SUMO nor any other simulator.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from pathlib import Path

from cadsim.scenario import Scenario, ScenarioError
from cadsim.sources.base import TrafficSource

SourceFactory = Callable[[Scenario, int, Path], TrafficSource]

_FACTORIES: dict[str, SourceFactory] = {}
# kind -> "module:attribute" of its factory, imported on first use.
_BUILTIN: dict[str, str] = {
    "sumo": "cadsim.sources.sumo.source:SumoSource",
    "arena": "cadsim.sources.arena.source:make_arena_source",
    "highway-env": "cadsim.sources.highway.source:make_highway_source",
}


def register_source(kind: str, factory: SourceFactory) -> None:
    """Make ``[traffic] source = kind`` build its source with ``factory(scenario, seed, workdir)``."""
    _FACTORIES[kind] = factory


def source_kinds() -> list[str]:
    """Every ``[traffic] source`` kind: built-in and registered."""
    return sorted(set(_BUILTIN) | set(_FACTORIES))


def make_source(scenario: Scenario, seed: int, workdir: Path) -> TrafficSource:
    """The traffic source of ``scenario`` for ``seed``; ``workdir`` caches generated networks
    and routes (created if missing)."""
    kind = scenario.traffic["source"]
    if kind not in _FACTORIES and kind in _BUILTIN:
        module, attribute = _BUILTIN[kind].split(":")
        register_source(kind, getattr(importlib.import_module(module), attribute))
    if kind not in _FACTORIES:
        raise ScenarioError(
            scenario.path,
            "traffic.source",
            f"no source is registered for {kind!r}",
            "one of " + ", ".join(sorted(set(_FACTORIES) | set(_BUILTIN))),
        )
    workdir = Path(workdir)
    workdir.mkdir(parents=True, exist_ok=True)
    return _FACTORIES[kind](scenario, int(seed), workdir)
