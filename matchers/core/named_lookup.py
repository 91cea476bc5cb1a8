"""The lookup shared by the name registries (matchers, :mod:`matchers.core.registry`; fusions,
:mod:`matchers.fusion.registry`): registered first, then built-in, then entry point, then a
``package.module:function`` import path (what a command line can name without registering
anything; worker processes import it themselves).

An entry point that cannot be loaded (its module does not import, the attribute is missing, it is
not callable) raises :class:`~matchers.core.plugin_guard.PluginError` naming it when asked for by
name; :func:`usable` — what ``all`` means — leaves it out with one warning line, so one broken
package does not take every other matcher down with it."""

from __future__ import annotations

import importlib
import logging
import sys
from collections.abc import Callable, Iterable, Mapping
from importlib.metadata import EntryPoint

from matchers.core.plugin_guard import PluginError

log = logging.getLogger(__name__)

_warned: set[tuple[str, str]] = set()  # (kind, name) of the broken entry points reported


def load(target: str) -> Callable:
    """The attribute named by ``package.module:attribute``."""
    module, _, attr = target.partition(":")
    return getattr(importlib.import_module(module), attr)


def _load_entry_point(name: str, kind: str, point: EntryPoint) -> Callable:
    try:
        fn = point.load()
    except Exception as exc:  # noqa: BLE001 - whatever a third-party module raises on import
        raise PluginError(
            f"{kind} {name!r}: entry point {point.value!r} cannot be loaded "
            f"({type(exc).__name__}: {exc})"
        ) from exc
    if not callable(fn):
        raise PluginError(
            f"{kind} {name!r}: entry point {point.value!r} is not callable (a {type(fn).__name__})"
        )
    return fn


def lookup(
    name: str,
    kind: str,
    registered: dict[str, Callable],
    builtin: Mapping[str, str],
    points: Mapping[str, EntryPoint],
    available: Callable[[], list[str]],
    families: Mapping[str, Callable[[str], Callable]] | None = None,
) -> Callable:
    """The ``kind`` (e.g. "matcher") called ``name``; an entry point, once loaded, is kept in
    ``registered``. ``families``: prefix -> resolver for parametrised names ``prefix:rest``
    (``windowed:sm``), asked before the import-path reading of a name with a colon. Unknown names and unimportable paths raise ValueError naming them; an entry
    point that cannot be loaded or is not callable raises PluginError naming it."""
    if name in registered:
        return registered[name]
    if name in builtin:
        return load(builtin[name])
    if name in points:
        fn = _load_entry_point(name, kind, points[name])
        registered[name] = fn
        return fn
    prefix, _, rest = name.partition(":")
    if families and rest and prefix in families:
        return families[prefix](rest)
    if ":" in name:  # not added to available(): an import path names itself
        module, _, attr = name.partition(":")
        try:
            fn = load(name)
        except ImportError as exc:
            raise ValueError(
                f"{kind} {name!r}: module {module!r} could not be imported "
                f"({type(exc).__name__}: {exc}); put the folder holding it on PYTHONPATH "
                f"(PYTHONPATH=/path/to/folder) or install its package"
            ) from None
        except AttributeError:
            raise ValueError(
                f"{kind} {name!r}: module {module!r} imports but has no {attr!r}"
            ) from None
        if not callable(fn):
            raise ValueError(f"{kind} {name!r} is not callable")
        return fn
    raise ValueError(f"unknown {kind} {name!r}; available: {', '.join(available())}")


def usable(names: Iterable[str], kind: str, get: Callable[[str], Callable]) -> list[str]:
    """``names`` without those that cannot be loaded (a broken entry point), each reported once
    per process as a warning line naming it and why."""
    kept = []
    for name in names:
        try:
            get(name)
        except PluginError as exc:
            if (kind, name) not in _warned:
                _warned.add((kind, name))
                log.warning("%s; left out of 'all'", exc)
            continue
        kept.append(name)
    return kept


def is_builtin(fn: Callable, builtin: Mapping[str, str]) -> bool:
    """Whether ``fn`` is the callable of one of the ``builtin`` targets (``module:attribute``;
    only modules already imported are looked at — a built-in's callable comes from its module)."""
    for target in builtin.values():
        module, _, attr = target.partition(":")
        loaded = sys.modules.get(module)
        if loaded is not None and getattr(loaded, attr, None) is fn:
            return True
    return False
