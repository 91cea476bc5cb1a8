"""Text placed in a Markdown table cell: a name that holds ``|`` (a plug-in matcher ``a|b``, a
``--label``) or a line break must stay in its cell, or every later column shifts.

``cell`` escapes ``|`` as ``\\|`` (GitHub's and :mod:`eval.report.site`'s reading of it: a
literal bar) and turns line breaks into spaces. Imports nothing.
"""

from __future__ import annotations


def cell(text: object) -> str:
    """``text`` as one Markdown table cell's content (``|`` escaped, no line break)."""
    out = str(text).replace("\\|", "|").replace("|", "\\|")
    return " ".join(out.splitlines()) if "\n" in out or "\r" in out else out


def row(cells: list) -> str:
    """One Markdown table row of ``cells`` (each through :func:`cell`)."""
    return "| " + " | ".join(cell(c) for c in cells) + " |"


__all__ = ["cell", "row"]
