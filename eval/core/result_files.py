"""Result files written atomically: a table, figure or record appears whole or not at all.

Every file an evaluation writes into its output folder goes through these three functions, which
build the bytes in memory and replace the file in one rename (``cadsim.dataset.atomic_writer``):
a full disk or a kill during ``evaluate`` leaves the previous file, never a 0-byte or truncated
``table1.md``, and the error names the file.
"""

from __future__ import annotations

import io
from pathlib import Path

import pandas as pd

from cadsim.dataset.atomic_writer import write_file_atomic


def write_text(path: str | Path, text: str) -> Path:
    """Replace ``path`` with ``text`` (UTF-8)."""
    write_file_atomic(Path(path), text.encode("utf-8"))
    return Path(path)


def write_csv(frame: pd.DataFrame, path: str | Path, **options) -> Path:
    """Replace ``path`` with ``frame.to_csv(**options)`` (``index=False`` unless given)."""
    options.setdefault("index", False)
    return write_text(path, frame.to_csv(**options))


def save_figure(fig, path: str | Path, **options) -> Path:
    """Replace ``path`` with the figure, in the format its suffix names."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format=Path(path).suffix.lstrip("."), **options)
    write_file_atomic(Path(path), buffer.getvalue())
    return Path(path)
