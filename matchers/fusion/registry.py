"""Name -> multi-way fusion registry, shaped like the matcher registry
(:mod:`matchers.core.registry`): the built-ins, :func:`register_fusion`, and the
``cadsim.fusions`` entry-point group (third-party packages), loaded lazily.

A fusion is any callable ``fusion(evidence, **options) -> Universe``: it reads every pair of
views' two-view matching of one snapshot (:class:`~matchers.fusion.evidence.PairwiseEvidence`)
and assigns every detection to a universe object (:class:`~matchers.fusion.universe.Universe`).
It may carry ``memory_bytes(evidence)`` (its working memory; checked against the per-process
budget before it runs) and ``deterministic = True``.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache
from importlib.metadata import EntryPoint, entry_points

from matchers.core.named_lookup import lookup
from matchers.fusion.universe import Universe

ENTRY_POINT_GROUP = "cadsim.fusions"

Fusion = Callable[..., Universe]

_BUILTIN: dict[str, str] = {
    "independent": "matchers.fusion.independent:independent",
    "spectral": "matchers.fusion.spectral:spectral",
    "clear": "matchers.fusion.clear:clear",
    "transitive": "matchers.fusion.transitive:transitive",
}
_registered: dict[str, Fusion] = {}


def register_fusion(name: str, fn: Fusion, *, replace: bool = False) -> None:
    """Make ``fn`` available as ``get_fusion(name)``; a taken name raises ValueError unless
    ``replace=True``."""
    if not isinstance(name, str) or not name:
        raise ValueError(f"name: expected a non-empty string, got {name!r}")
    if not callable(fn):
        raise TypeError(f"fn: expected a callable fusion, got {type(fn).__name__}")
    taken = name in _registered or name in _BUILTIN or name in _entry_points()
    if taken and not replace:
        raise ValueError(f"name: fusion {name!r} already exists; pass replace=True to override")
    _registered[name] = fn


def get_fusion(name: str) -> Fusion:
    """The fusion called ``name``: registered, built-in, entry point, or a
    ``package.module:function`` import path."""
    return lookup(name, "fusion", _registered, _BUILTIN, _entry_points(), available_fusions)


def available_fusions() -> list[str]:
    """Sorted names of every fusion :func:`get_fusion` can return."""
    return sorted(set(_BUILTIN) | set(_registered) | set(_entry_points()))


@cache
def _entry_points() -> dict[str, EntryPoint]:
    """Entry points of the ``cadsim.fusions`` group, scanned once per process."""
    return {ep.name: ep for ep in entry_points(group=ENTRY_POINT_GROUP)}
