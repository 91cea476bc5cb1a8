"""Text placed in a Markdown table cell: a name that holds ``|`` (a plug-in matcher ``a|b``, a
``--label``) or a line break must stay in its cell, or every later column shifts; one that holds
Markdown or HTML (``<script>``, ``[x](javascript:…)``, a backtick) must read as the text it is.

``cell`` escapes ``|`` as ``\\|`` (GitHub's and :mod:`eval.report.site`'s reading of it: a
literal bar), backslash-escapes ``<``, ``>``, ``[``, ``]`` and backticks (CommonMark: a literal
character, so no tag, link or code span starts) and turns line breaks into spaces. Every
dataset label, matcher name and other data text of a report table goes through it. Imports
nothing.
"""

from __future__ import annotations

ESCAPED = "|<>[]`"
"""Characters a cell writes as ``\\`` + the character."""


def cell(text: object) -> str:
    """``text`` as one Markdown table cell's content (``|``, ``<``, ``>``, ``[``, ``]`` and
    backticks backslash-escaped, no line break). An already escaped character is not escaped
    twice."""
    out = str(text)
    for ch in ESCAPED:
        out = out.replace("\\" + ch, ch).replace(ch, "\\" + ch)
    return " ".join(out.splitlines()) if "\n" in out or "\r" in out else out


def row(cells: list) -> str:
    """One Markdown table row of ``cells`` (each through :func:`cell`)."""
    return "| " + " | ".join(cell(c) for c in cells) + " |"


__all__ = ["ESCAPED", "cell", "row"]
