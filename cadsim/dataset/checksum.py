"""Checksums: a record's is a SHA-256 over its files (name and content, in name order); the
dataset's is a SHA-256 over its records' checksums in dataset order."""

from __future__ import annotations

import hashlib
from collections.abc import Iterable, Mapping
from pathlib import Path


def record_checksum(files: Mapping[str, bytes]) -> str:
    """Hex SHA-256 of a record given as {file name: bytes}."""
    h = hashlib.sha256()
    for name in sorted(files):
        h.update(name.encode() + b"\0")
        h.update(hashlib.sha256(files[name]).digest())
    return h.hexdigest()


def record_dir_checksum(record_dir: Path, names: Iterable[str]) -> str:
    """The checksum of a record directory over the files ``names`` (all must exist)."""
    record_dir = Path(record_dir)
    return record_checksum({n: (record_dir / n).read_bytes() for n in names})


def dataset_checksum(record_checksums: Iterable[str]) -> str:
    """Hex SHA-256 over the records' checksums, in dataset order."""
    h = hashlib.sha256()
    for c in record_checksums:
        h.update(bytes.fromhex(c))
    return h.hexdigest()
