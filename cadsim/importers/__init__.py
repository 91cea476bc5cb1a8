"""Importers of external data into our format.

Each importer reads a foreign layout without that project's libraries and without executing
anything from the files; ``restricted_pickle`` is the project's one pickle reader. Every importer
reports a malformed input as ``ImportFormatError`` (a ``ValueError``), one line starting with the
offending file's path. Must not import matchers, eval, SUMO or pyrender.
"""

from __future__ import annotations

from pathlib import Path


class ImportFormatError(ValueError):
    """A file to import is malformed or outside its format. The message starts with the path."""

    def __init__(self, path: str | Path, problem: str) -> None:
        self.path = Path(path)
        self.problem = problem
        super().__init__(f"{self.path}: {problem}")


__all__ = ["ImportFormatError"]
