"""Name -> matcher registry: the built-ins, :func:`register`, and the ``cadsim.matchers``
entry-point group (third-party packages), loaded lazily on the first :func:`get`/:func:`available`.

A matcher is any callable ``matcher(problem, seed=0, threshold=None, **options) -> Matching``.
"""

from __future__ import annotations

import importlib
import logging
from collections.abc import Callable
from functools import cache
from importlib.metadata import EntryPoint, entry_points

from .matching import Matching

log = logging.getLogger(__name__)

ENTRY_POINT_GROUP = "cadsim.matchers"

Matcher = Callable[..., Matching]

_BUILTIN: dict[str, str] = {
    "appearance": "matchers.appearance:appearance",
    "bcagm": "matchers.bcagm:bcagm",
    "hgm": "matchers.hgm:hgm",
    "maximin": "matchers.maximin:maximin",
    "mos": "matchers.mos:mos",
    "rrwhm": "matchers.rrwhm:rrwhm",
    "rrwm": "matchers.rrwm:rrwm",
    "sm": "matchers.sm:sm",
    "tm": "matchers.tm:tm",
}
_registered: dict[str, Matcher] = {}


def register(name: str, fn: Matcher, *, replace: bool = False) -> None:
    """Make ``fn`` available as ``get(name)``. Re-using a taken name (built-in, registered or
    entry point) raises ValueError unless ``replace=True``."""
    if not isinstance(name, str) or not name:
        raise ValueError(f"name: expected a non-empty string, got {name!r}")
    if not callable(fn):
        raise TypeError(f"fn: expected a callable matcher, got {type(fn).__name__}")
    taken = name in _registered or name in _BUILTIN or name in _entry_points()
    if taken and not replace:
        raise ValueError(f"name: matcher {name!r} already exists; pass replace=True to override")
    _registered[name] = fn


def get(name: str) -> Matcher:
    """The matcher called ``name``: registered first, then built-in, then entry point."""
    if name in _registered:
        return _registered[name]
    if name in _BUILTIN:
        return _load(_BUILTIN[name])
    points = _entry_points()
    if name in points:
        fn = points[name].load()
        if not callable(fn):
            raise TypeError(f"entry point {name!r} ({points[name].value}) is not callable")
        _registered[name] = fn
        return fn
    raise ValueError(f"unknown matcher {name!r}; available: {', '.join(available())}")


def available() -> list[str]:
    """Sorted names of every matcher get() can return."""
    return sorted(set(_BUILTIN) | set(_registered) | set(_entry_points()))


def _load(target: str) -> Matcher:
    module, _, attr = target.partition(":")
    return getattr(importlib.import_module(module), attr)


@cache
def _entry_points() -> dict[str, EntryPoint]:
    """Entry points of the ``cadsim.matchers`` group, scanned once per process
    (``_entry_points.cache_clear()`` rescans)."""
    found = {ep.name: ep for ep in entry_points(group=ENTRY_POINT_GROUP)}
    if found:
        log.debug("matcher entry points: %s", sorted(found))
    return found
