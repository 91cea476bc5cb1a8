"""The lookup shared by the name registries (matchers, :mod:`matchers.core.registry`; fusions,
:mod:`matchers.fusion.registry`): registered first, then built-in, then entry point, then a
``package.module:function`` import path (what a command line can name without registering
anything; worker processes import it themselves)."""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from importlib.metadata import EntryPoint


def load(target: str) -> Callable:
    """The attribute named by ``package.module:attribute``."""
    module, _, attr = target.partition(":")
    return getattr(importlib.import_module(module), attr)


def lookup(
    name: str,
    kind: str,
    registered: dict[str, Callable],
    builtin: Mapping[str, str],
    points: Mapping[str, EntryPoint],
    available: Callable[[], list[str]],
) -> Callable:
    """The ``kind`` (e.g. "matcher") called ``name``; an entry point, once loaded, is kept in
    ``registered``. Unknown names and unimportable paths raise ValueError naming them; an entry
    point that is not callable raises TypeError."""
    if name in registered:
        return registered[name]
    if name in builtin:
        return load(builtin[name])
    if name in points:
        fn = points[name].load()
        if not callable(fn):
            raise TypeError(f"entry point {name!r} ({points[name].value}) is not callable")
        registered[name] = fn
        return fn
    if ":" in name:  # not added to available(): an import path names itself
        try:
            fn = load(name)
        except (ImportError, AttributeError) as exc:
            raise ValueError(f"{kind} {name!r}: cannot import it ({exc})") from None
        if not callable(fn):
            raise ValueError(f"{kind} {name!r} is not callable")
        return fn
    raise ValueError(f"unknown {kind} {name!r}; available: {', '.join(available())}")
