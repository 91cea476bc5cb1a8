"""A report part built so that a folder written by another version of the code (or an
incomplete one) replaces the part with a line saying so, never stops the report."""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable
from pathlib import Path

log = logging.getLogger(__name__)


def guarded(
    name: str,
    build: Callable[[], Iterable[str]],
    results: Path,
    heading: str | None = None,
    table: str | None = None,
) -> list[str]:
    """``build()``'s lines; if it fails on this folder's files (written by another version of the
    code, or incomplete), a line saying so under ``heading`` and the study's ``table`` file as
    the run wrote it, so that the rest of the report is still written."""
    try:
        return list(build())
    except Exception as error:  # any file format this code does not read
        log.warning("results part %s left out: %s: %s", name, type(error).__name__, error)
        if heading is None:
            return []
        lines = [
            f"### {heading}",
            "",
            f"This part could not be summarised from this folder's files ({type(error).__name__}: "
            f"{error}); they may come from another version of the code, and `make reproduce` "
            "rewrites them.",
            "",
        ]
        path = results / table if table else None
        if path is not None and path.is_file():
            lines += ["The table as the run wrote it:", "", path.read_text().strip(), ""]
        return lines
