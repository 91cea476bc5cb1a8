"""A dataset's strings made safe to print on one terminal line (``cadsim info``).

Class names, observer ids and source fields come from the data, and an imported dataset's come
from someone else's files: a name may hold a newline (a forged second line of output), an
escape sequence (a terminal command), a bidirectional override (text shown in another order)
or markup such as ``<script>`` (pasted into a page). :func:`display_name` keeps every printable
character but ``< > & ` \\`` as it is and writes the others as Python escapes (``\\n``,
``\\x1b``, ``\\x3c``, ``\\u202e``), so the text stays on one line, unambiguous, and inert.
Imports nothing from cadsim.
"""

from __future__ import annotations

MAX_SHOWN = 80
"""Characters shown of one name; a longer one is cut, ending in ``…``."""
_ESCAPED = frozenset("<>&`\\")
_NAMED = {"\n": "\\n", "\t": "\\t", "\r": "\\r", "\\": "\\\\"}


def _shown_char(c: str) -> str:
    if c.isprintable() and c not in _ESCAPED:
        return c
    if c in _NAMED:
        return _NAMED[c]
    code = ord(c)
    if code < 0x100:
        return f"\\x{code:02x}"
    return f"\\u{code:04x}" if code < 0x10000 else f"\\U{code:08x}"


def display_name(value: object) -> str:
    """``value`` as one inert line (module docstring), at most :data:`MAX_SHOWN` characters
    of it shown.

    >>> display_name("car\\n<script>")
    'car\\\\n\\\\x3cscript\\\\x3e'
    >>> display_name("the dataset's own terms (not redistributed)")
    "the dataset's own terms (not redistributed)"
    """
    text = str(value)
    shown = "".join(_shown_char(c) for c in text[:MAX_SHOWN])
    return shown + ("…" if len(text) > MAX_SHOWN else "")


__all__ = ["MAX_SHOWN", "display_name"]
