"""A dataset's strings made safe to print on one terminal line (``cadsim info``).

Class names, observer ids and source fields come from the data, and an imported dataset's come
from someone else's files: a name may hold a newline (a forged second line of output), an
escape sequence (a terminal command) or markup such as ``<script>`` (pasted into a page).
:func:`display_name` keeps letters, digits, spaces and ``_ - . : / + # ( ) @ ,`` as they are and
writes every other character as a Python escape (``\\n``, ``\\x1b``, ``\\x3c``), so the text
stays on one line, unambiguous, and inert. Imports nothing from cadsim.
"""

from __future__ import annotations

MAX_SHOWN = 80
"""Characters shown of one name; a longer one is cut, ending in ``…``."""
_PLAIN = frozenset(" _-.:/+#()@,")


def _shown_char(c: str) -> str:
    if (c.isalnum() and c.isprintable()) or c in _PLAIN:
        return c
    code = ord(c)
    if c in "\n\t\r":
        return repr(c)[1:-1]
    return (
        f"\\x{code:02x}"
        if code < 0x100
        else f"\\u{code:04x}"
        if code < 0x10000
        else f"\\U{code:08x}"
    )


def display_name(value: object) -> str:
    """``value`` as one inert line (module docstring), at most :data:`MAX_SHOWN` characters
    of it shown.

    >>> display_name("car\\n<script>")
    'car\\\\n\\\\x3cscript\\\\x3e'
    """
    text = str(value)
    shown = "".join(_shown_char(c) for c in text[:MAX_SHOWN])
    return shown + ("…" if len(text) > MAX_SHOWN else "")


__all__ = ["MAX_SHOWN", "display_name"]
