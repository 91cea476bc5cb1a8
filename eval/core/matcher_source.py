"""The source a plug-in matcher's runs depend on, for their cache key.

The cache's code version (:func:`eval.core.cache.code_version`) covers the ``matchers`` and
``cadsim`` packages, so a built-in's edit reruns it. A plug-in (``module:function``, a
``register``-ed callable, an entry point) lives elsewhere: its runs' version is the code version
plus a hash of the bytes of the module file that defines it, so editing the plug-in reruns it.
What that module imports is not followed (edit the file named, or clear the cache).

Imports nothing from cadsim; ``matchers.core.registry`` lazily.
"""

from __future__ import annotations

import hashlib
import inspect
import sys
from pathlib import Path


def plugin_source_digest(name: str) -> str | None:
    """Hex SHA-256 (16 digits) of the module file defining matcher `name`, None for a built-in
    or a name that cannot be resolved here (its task then reports why). A callable without a
    source file (defined interactively) hashes its qualified name only."""
    from matchers.core.named_lookup import is_builtin
    from matchers.core.registry import _BUILTIN, get

    try:
        fn = get(name)
    except Exception:  # noqa: BLE001 - an unknown or broken plug-in: the run reports it
        return None
    if is_builtin(fn, _BUILTIN):
        return None
    target = inspect.unwrap(fn)
    module = sys.modules.get(getattr(target, "__module__", None) or "")
    source = getattr(module, "__file__", None)
    h = hashlib.sha256(
        f"{getattr(target, '__module__', '')}:{getattr(target, '__qualname__', '')}".encode()
    )
    if source and Path(source).is_file():
        h.update(Path(source).read_bytes())
    return h.hexdigest()[:16]


def run_version(base: str, matcher_name: str) -> str:
    """The code version of a run of `matcher_name`: `base` for a built-in, ``base+<digest>``
    for a plug-in (:func:`plugin_source_digest`)."""
    digest = plugin_source_digest(matcher_name)
    return base if digest is None else f"{base}+{digest}"
