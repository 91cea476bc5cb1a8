"""Name -> multi-way fusion registry, shaped like the matcher registry
(:mod:`matchers.core.registry`): the built-ins, :func:`register_fusion`, and the
``cadsim.fusions`` entry-point group (third-party packages), loaded lazily.

A fusion is any callable ``fusion(evidence, **options) -> Universe``: it reads every pair of
views' two-view matching of one snapshot (:class:`~matchers.fusion.evidence.PairwiseEvidence`)
and assigns every detection to a universe object (:class:`~matchers.fusion.universe.Universe`).
It may carry ``memory_bytes(evidence)`` (its working memory; checked against the per-process
budget before it runs) and ``deterministic = True``. The harness runs a fusion that is not a
built-in through :func:`checked_fusion`: under the per-problem time limit, its result held to the
contract of :mod:`matchers.fusion.checks`.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache
from importlib.metadata import EntryPoint, entry_points

from matchers.core.named_lookup import is_builtin, lookup, usable
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
    """Sorted names of every fusion :func:`get_fusion` can return (entry points listed without
    importing them; :func:`usable_fusions` leaves out those that cannot be loaded)."""
    return sorted(set(_BUILTIN) | set(_registered) | set(_entry_points()))


def usable_fusions() -> list[str]:
    """:func:`available_fusions` without the entry points that cannot be loaded, each reported
    once as a warning line (what every fusion of the registry means)."""
    return usable(available_fusions(), "fusion", get_fusion)


def checked_fusion(name: str, fn: Fusion | None = None, time_limit_s: float | None = None):
    """The callable the harness runs for fusion ``name`` (``fn``: already looked up): a built-in
    as it is; any other wrapped so that each call runs under the per-problem time limit
    (``time_limit_s``, None: ``$CADSIM_PLUGIN_TIME_LIMIT_S`` or 600 s) and its result is held to
    the contract (:func:`matchers.fusion.checks.check_universe`); a failure is a
    :class:`~matchers.core.plugin_guard.PluginError` naming it."""
    from matchers.fusion.checks import guard_fusion

    fn = get_fusion(name) if fn is None else fn
    if is_builtin(fn, _BUILTIN):
        return fn
    point = _entry_points().get(name)
    where = f" (entry point {point.value})" if point is not None and name not in _BUILTIN else ""
    return guard_fusion(f"fusion {name!r}{where}", fn, time_limit_s)


@cache
def _entry_points() -> dict[str, EntryPoint]:
    """Entry points of the ``cadsim.fusions`` group, scanned once per process."""
    return {ep.name: ep for ep in entry_points(group=ENTRY_POINT_GROUP)}
