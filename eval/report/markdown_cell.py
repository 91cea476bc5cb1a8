"""Text placed in a Markdown table cell: a name that holds ``|`` (a plug-in matcher ``a|b``, a
``--label``) or a line break must stay in its cell, or every later column shifts; one that holds
Markdown or HTML (``<script>``, ``[x](javascript:…)``, a backtick) must read as the text it is.

``cell`` escapes ``|`` as ``\\|`` (GitHub's and :mod:`eval.report.site`'s reading of it: a
literal bar), backslash-escapes ``<``, ``>``, ``[``, ``]`` and backticks (CommonMark: a literal
character, so no tag, link or code span starts) and turns line breaks into spaces. Every
dataset label, matcher name and other data text of a report table goes through it; ``row``
escapes every cell of a row the same way but for the brackets of the code's own intervals.
Imports only ``re``.
"""

from __future__ import annotations

import re

ESCAPED = "|<>[]`"
"""Characters a data cell writes as ``\\`` + the character."""

_LINK_CLOSE = re.compile(r"(?<!\\)\](?=\s*[(\[])")  # a "]" that would close a link's text


def cell(text: object, brackets: bool = True) -> str:
    """``text`` as one Markdown table cell's content: ``|``, ``<``, ``>``, backticks and (with
    ``brackets``, for data: a label, a name) ``[`` and ``]`` backslash-escaped, no line break.
    Without ``brackets`` (a cell the code composed, such as an interval ``[-3.7, +11.6]``) only
    a ``]`` that would close a link's or image's text is escaped. An already escaped character
    is not escaped twice."""
    out = str(text)
    for ch in "|<>`" + ("[]" if brackets else ""):
        out = out.replace("\\" + ch, ch).replace(ch, "\\" + ch)
    if not brackets:
        out = _LINK_CLOSE.sub(r"\\]", out)
    return " ".join(out.splitlines()) if "\n" in out or "\r" in out else out


def row(cells: list) -> str:
    """One Markdown table row of ``cells``, each through :func:`cell` without ``brackets``
    (pass data through :func:`cell` first to escape its brackets too)."""
    return "| " + " | ".join(cell(c, brackets=False) for c in cells) + " |"


__all__ = ["ESCAPED", "cell", "row"]
