"""Digest-checked JSON entries under a key: the on-disk form of the studies' result caches (the
temporal study's per-preset outcomes, the multi-agent study's fused rows), so a re-run of ``make
reproduce`` reads a study's derived tables instead of recomputing them.

``ROOT/<key>.json`` holds ``{"format", "key", "digest", "payload"}``: the payload is plain JSON
(lists, objects, numbers, text; no pickle), the digest a SHA-256 of its serialised form. Python's
JSON writes NaN as ``NaN`` and None as ``null``, so both come back as they were; numpy scalars
are stored as Python ones and floats in their shortest round-trip form, so every value comes back
bit for bit. A table is stored as (columns, dtypes, values per column) (:func:`frame_payload`).
Written through :func:`cadsim.dataset.atomic_writer.write_file_atomic` (temporary file, fsync,
rename).

An entry is a local speed-up, not a trusted record: one that is too large, unreadable, of
another format or key, or whose payload does not match its digest is refused
(:meth:`DigestStore.load` logs why and returns None) and its caller recomputes it; the caller's
``restore`` adds its own shape checks. A forger who rewrites an entry with a matching digest is
not stopped (the run cache's boundary).
"""

from __future__ import annotations

import hashlib
import json
import logging
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import TypeVar

import numpy as np
import pandas as pd

from cadsim.dataset.atomic_writer import write_file_atomic

log = logging.getLogger("eval.reproduce")

T = TypeVar("T")
DTYPES = frozenset({"int64", "float64", "bool", "str", "string", "object", "Int64", "boolean"})
"""The table column dtypes :func:`frame_from_payload` restores."""
_REFUSALS = (OSError, ValueError, TypeError, KeyError, AttributeError, RecursionError)


def _plain(value):
    """A numpy scalar as its Python value, pandas' NA as None (JSON's ``default``)."""
    if isinstance(value, np.generic):
        return value.item()
    if value is pd.NA:  # a nullable column's missing value
        return None
    raise TypeError(f"{type(value).__name__} is not a table cell")


def dump(payload) -> str:
    """The canonical JSON text of `payload` (what the digest is taken over)."""
    return json.dumps(payload, default=_plain, separators=(",", ":"))


def digest(text: str) -> str:
    """Hex SHA-256 of `text`."""
    return hashlib.sha256(text.encode()).hexdigest()


def key_of(described) -> str:
    """Hex SHA-256 of the canonical JSON of `described` (what an entry is stored under)."""
    return hashlib.sha256(json.dumps(described, sort_keys=True).encode()).hexdigest()


def sources_version(tag: str, root: Path, names: Iterable[str]) -> str:
    """Hex SHA-256 over `tag` and the names and contents of the files `names` (relative to
    `root`, in the given order): a cache key's code part."""
    h = hashlib.sha256(f"{tag}\0".encode())
    for name in names:
        h.update(name.encode() + b"\0")
        h.update(hashlib.sha256((root / name).read_bytes()).digest())
    return h.hexdigest()


def frame_payload(frame: pd.DataFrame) -> dict:
    """`frame` as {columns, dtypes, values per column}; TypeError for a dtype outside
    :data:`DTYPES` (it would not come back as it was)."""
    dtypes = [str(t) for t in frame.dtypes]
    if odd := sorted(set(dtypes) - DTYPES):
        raise TypeError(f"table dtypes {odd}")
    return {
        "columns": [str(c) for c in frame.columns],
        "dtypes": dtypes,
        "values": [frame[c].tolist() for c in frame.columns],
    }


def frame_from_payload(stored: dict, where: str) -> pd.DataFrame:
    """The table of a :func:`frame_payload`; ValueError naming `where` unless its columns,
    dtypes and value lists agree and every value is a table cell."""
    columns, dtypes, values = stored["columns"], stored["dtypes"], stored["values"]
    if not (
        isinstance(columns, list)
        and isinstance(dtypes, list)
        and isinstance(values, list)
        and len(columns) == len(dtypes) == len(values) == len(set(columns))
        and all(isinstance(c, str) for c in columns)
        and all(isinstance(v, list) for v in values)
        and len({len(v) for v in values}) <= 1
        and set(dtypes) <= DTYPES
    ):
        raise ValueError(f"{where}: columns, dtypes and values do not agree")
    if any(isinstance(x, list | dict) for v in values for x in v):
        raise ValueError(f"{where}: a value that is not a table cell")
    return pd.DataFrame(
        {c: pd.Series(v, dtype=t) for c, t, v in zip(columns, dtypes, values, strict=True)},
        columns=columns,
    )


class DigestStore:
    """Entries of one kind (`what`, for log lines) under `root`, one JSON file per key, of
    format `fmt`, at most `max_bytes` each."""

    def __init__(self, root: str | Path, what: str, fmt: int, max_bytes: int) -> None:
        self.root = Path(root)
        self.what = what
        self.fmt = fmt
        self.max_bytes = max_bytes

    def path(self, key: str) -> Path:
        return self.root / f"{key}.json"

    def store(self, key: str, payload: dict) -> Path | None:
        """Write `payload` under `key` atomically; its path, or None (a warning says why) when
        a value is no JSON cell or the write fails: the caller goes on uncached."""
        path = self.path(key)
        try:
            entry = {"format": self.fmt, "key": key, "digest": digest(dump(payload))}
            write_file_atomic(path, dump(entry | {"payload": payload}).encode("utf-8"))
        except (TypeError, ValueError, OSError) as exc:
            log.warning("%s: %s not stored (%s)", self.what, path, exc)
            return None
        return path

    def load(self, key: str, restore: Callable[[dict], T]) -> T | None:
        """``restore(payload)`` of the entry under `key`; None when there is none, or when the
        entry or `restore` refuses it (a warning names it and why)."""
        path = self.path(key)
        if not path.is_file():
            return None
        try:
            return restore(self._read(path, key))
        except _REFUSALS as exc:
            why = " ".join(str(exc).split())[:200]
            log.warning("%s: refused %s (%s); recomputing it", self.what, path, why)
            return None

    def _read(self, path: Path, key: str) -> dict:
        size = path.stat().st_size
        if size > self.max_bytes:
            raise ValueError(f"{size} bytes, more than {self.max_bytes}")
        entry = json.loads(path.read_text(encoding="utf-8"))
        if (
            not isinstance(entry, dict)
            or entry.get("format") != self.fmt
            or entry.get("key") != key
        ):
            raise ValueError("another format or key")
        payload = entry["payload"]
        if not isinstance(payload, dict) or entry.get("digest") != digest(dump(payload)):
            raise ValueError("its contents do not match their digest")
        return payload
