"""Result files written atomically: a table, figure or record appears whole or not at all.

The folder itself is checked first (:func:`check_outputs`, the output-path rule). Every file an
evaluation writes into its output folder goes through the three functions below, which
build the bytes in memory and replace the file in one rename (``cadsim.dataset.atomic_writer``):
a full disk or a kill during ``evaluate`` leaves the previous file, never a 0-byte or truncated
``table1.md``, and the error names the file.
"""

from __future__ import annotations

import io
from pathlib import Path

import pandas as pd

from cadsim.dataset.atomic_writer import write_file_atomic
from cadsim.dataset.output_folder import check_cache_folder, check_result_folder


def check_outputs(out: str | Path, cache: str | Path | None = None) -> Path:
    """The output-path rule (``cadsim.dataset.output_folder``) for a command's result folder
    ``out`` and its result cache, checked before anything runs: ``out`` is new, empty or a result
    folder — never a dataset, a folder inside one, a link, a file or a user's folder."""
    if cache is not None:
        check_cache_folder(cache)
    return check_result_folder(out)


def recorded_path(path: str | Path | None) -> str | None:
    """``path`` as a result file records it: relative to the working directory when it lies
    inside it (``make reproduce`` runs from the repository, so committed results hold no
    machine's absolute paths and the figures still find the datasets), else as given."""
    if path is None:
        return None
    try:
        return Path(path).resolve().relative_to(Path.cwd().resolve()).as_posix()
    except (ValueError, OSError):
        return str(path)


def check_table_files(paths, csv_start: bytes) -> list[Path]:
    """The ``--out`` files of a validation command (``.csv`` tables, ``.md`` reports), checked by
    the output-path rule before anything runs: new files, or files of the same kind written
    before (a CSV beginning with ``csv_start``, a report beginning with ``## ``); never a link, a
    folder, a user's file or a file inside a dataset."""
    from cadsim.dataset.output_folder import check_output_file, file_starts_with

    checked = []
    for path in paths:
        path = Path(path)
        if path.suffix == ".csv":
            own, what = file_starts_with(csv_start), "a table this command wrote"
        elif path.suffix == ".md":
            own, what = file_starts_with(b"## "), "a report this command wrote"
        else:
            raise ValueError(f"--out {path}: expected a .csv or .md file name")
        checked.append(check_output_file(path, what, own))
    return checked


def write_text(path: str | Path, text: str) -> Path:
    """Replace ``path`` with ``text`` (UTF-8)."""
    write_file_atomic(Path(path), text.encode("utf-8"))
    return Path(path)


def write_csv(frame: pd.DataFrame, path: str | Path, **options) -> Path:
    """Replace ``path`` with ``frame.to_csv(**options)`` (``index=False`` unless given), its
    text cells safe to open in a spreadsheet (:mod:`eval.core.spreadsheet_safe`)."""
    from eval.core.spreadsheet_safe import neutralise

    options.setdefault("index", False)
    return write_text(path, neutralise(frame).to_csv(**options))


def save_figure(fig, path: str | Path, **options) -> Path:
    """Replace ``path`` with the figure, in the format its suffix names."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format=Path(path).suffix.lstrip("."), **options)
    write_file_atomic(Path(path), buffer.getvalue())
    return Path(path)
