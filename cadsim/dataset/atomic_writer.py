"""Crash-safe writes: a record directory or a file appears completely or not at all.

A record is built in a temporary directory inside the dataset directory (same file system), every
file and the directory are fsync'ed, and one ``os.replace`` moves it to ``pairs/NAME``. A killed
writer leaves only a ``.tmp-*`` directory, which the next run removes (``remove_stale_temp``).
"""

from __future__ import annotations

import errno
import os
import shutil
import uuid
from collections.abc import Mapping
from pathlib import Path

from cadsim.dataset.layout import EPISODES_DIR, PAIRS_DIR, TEMP_PREFIX


def _fsync_dir(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _write_synced(path: Path, data: bytes, shown: Path | None = None) -> None:
    """Write and fsync ``path``; an ``OSError`` (a full disk, a quota) names ``shown`` — the
    file being written, not its temporary name — so the one-line error says where."""
    try:
        with open(path, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
    except OSError as exc:
        if exc.filename is not None and shown is None:
            raise
        raise OSError(exc.errno, exc.strerror or str(exc), str(shown or path)) from exc


def _temp_path(dataset_dir: Path, label: str) -> Path:
    return dataset_dir / f"{TEMP_PREFIX}{label}-{os.getpid()}-{uuid.uuid4().hex[:8]}"


def write_record(dataset_dir: Path, name: str, files: Mapping[str, bytes]) -> bool:
    """Write ``files`` as record ``pairs/NAME`` atomically. Returns False (and writes nothing) if
    a complete record of that name already exists."""
    dataset_dir = Path(dataset_dir)
    pairs = dataset_dir / PAIRS_DIR
    pairs.mkdir(parents=True, exist_ok=True)
    target = pairs / name
    if target.exists():
        return False
    tmp = _temp_path(dataset_dir, name)
    tmp.mkdir()
    try:
        for fname, data in files.items():
            _write_synced(tmp / fname, data, target / fname)
        _fsync_dir(tmp)
        try:
            os.replace(tmp, target)
        except OSError as exc:  # another writer finished the same record first
            if exc.errno in (errno.ENOTEMPTY, errno.EEXIST):
                return False
            raise
        _fsync_dir(pairs)
        return True
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)


def write_file_atomic(path: Path, data: bytes) -> None:
    """Replace ``path`` with ``data`` atomically (temp file in the same folder, fsync, rename)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.parent / f"{TEMP_PREFIX}{path.name}-{os.getpid()}-{uuid.uuid4().hex[:8]}"
    try:
        _write_synced(tmp, data, path)
        os.replace(tmp, path)
        _fsync_dir(path.parent)
    finally:
        if tmp.exists():
            tmp.unlink()


def remove_record(dataset_dir: Path, name: str) -> None:
    """Remove record ``pairs/NAME`` atomically (renamed away first, then deleted)."""
    dataset_dir = Path(dataset_dir)
    target = dataset_dir / PAIRS_DIR / name
    if not target.exists():
        return
    trash = _temp_path(dataset_dir, f"removed-{name}")
    os.replace(target, trash)
    shutil.rmtree(trash, ignore_errors=True)


def remove_stale_temp(dataset_dir: Path) -> list[str]:
    """Delete leftovers of interrupted writes (``.tmp-*`` entries, also in ``episodes/``).
    Returns their names."""
    dataset_dir = Path(dataset_dir)
    removed = []
    for folder in (dataset_dir, dataset_dir / EPISODES_DIR):
        if not folder.is_dir():
            continue
        for entry in folder.iterdir():
            if entry.name.startswith(TEMP_PREFIX):
                if entry.is_dir():
                    shutil.rmtree(entry, ignore_errors=True)
                else:
                    entry.unlink(missing_ok=True)
                removed.append(entry.name)
    return sorted(removed)
