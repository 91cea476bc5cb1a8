"""Text fields of the CSVs cadsim writes, made safe to open in a spreadsheet.

A spreadsheet runs a cell that begins with ``=``, ``+``, ``-`` or ``@`` (or a tab or carriage
return) as a formula: a dataset label or matcher name such as ``=HYPERLINK(…)`` in a results
CSV would run when the file is opened. :func:`neutralise` writes such a text value with a leading
``'`` (the spreadsheet convention for "this is text", not shown by the spreadsheet); a value that
already begins with ``'`` gets one more, so :func:`restore` (what cadsim's own readers apply)
gives back exactly what was written. Numbers, and text that reads as a number (``-0.5``), are
left alone. Imports only pandas.
"""

from __future__ import annotations

import pandas as pd

TRIGGERS = ("=", "+", "-", "@", "\t", "\r", "'")
"""First characters that make a text value be written with a leading ``'``."""


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def neutralise_text(value):
    """``value`` as written: text beginning with one of :data:`TRIGGERS` (and not a number)
    gets a leading ``'``; anything else is returned as it is."""
    if isinstance(value, str) and value.startswith(TRIGGERS) and not _is_number(value):
        return "'" + value
    return value


def restore_text(value):
    """:func:`neutralise_text` reversed."""
    if isinstance(value, str) and value.startswith("'"):
        return value[1:]
    return value


def _map_text(frame: pd.DataFrame, fn) -> pd.DataFrame:
    text = [
        c
        for c in frame.columns
        if pd.api.types.is_object_dtype(frame[c]) or pd.api.types.is_string_dtype(frame[c])
    ]
    if not text:
        return frame
    out = frame.copy()
    for column in text:
        out[column] = out[column].map(fn)
    return out


def neutralise(frame: pd.DataFrame) -> pd.DataFrame:
    """`frame` with every text cell through :func:`neutralise_text` (a copy when any changes)."""
    return _map_text(frame, neutralise_text)


def restore(frame: pd.DataFrame) -> pd.DataFrame:
    """`frame` (read from a CSV cadsim wrote) with every text cell through :func:`restore_text`."""
    return _map_text(frame, restore_text)
