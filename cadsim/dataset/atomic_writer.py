"""Crash-safe writes: a record directory or a file appears completely or not at all.

A record is built in a temporary directory inside the dataset directory (same file system), every
file and the directory are fsync'ed, and one ``os.replace`` moves it to ``pairs/NAME``. A killed
writer leaves only a ``.tmp-*`` directory, which the next run removes (``remove_stale_temp``).

Every file is created new (``O_CREAT | O_EXCL | O_NOFOLLOW``): a temporary name that someone made
into a symbolic link (or any file) beforehand is never opened, so nothing is written through it;
another random name is drawn instead. A temporary file is removed when the write fails. The final
name is never a symbolic link or a folder (:class:`OutputPathError`); what may be replaced there
is decided by :mod:`cadsim.dataset.output_folder`, the output-path rule of every command.
"""

from __future__ import annotations

import errno
import os
import shutil
import stat
import uuid
from collections.abc import Mapping
from pathlib import Path

from cadsim.dataset.layout import EPISODES_DIR, PAIRS_DIR, TEMP_PREFIX

_NEW_FILE = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0)
_NEW_FILE |= getattr(os, "O_CLOEXEC", 0)


class OutputPathError(ValueError):
    """An output path a command may not write (one line naming it and why)."""


def _fsync_dir(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _write_synced(path: Path, data: bytes, shown: Path | None = None) -> None:
    """Create ``path`` (it must not exist, so it is never opened through a link), write and
    fsync it; when writing fails the file is removed again. An ``OSError`` (a full disk, a
    quota) names ``shown`` — the file being written, not its temporary name — so the one-line
    error says where. ``FileExistsError`` (the name is taken) is raised as it is."""
    try:
        fd = os.open(path, _NEW_FILE, 0o666)
    except FileExistsError:
        raise
    except OSError as exc:
        raise OSError(exc.errno, exc.strerror or str(exc), str(shown or path)) from exc
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
    except BaseException as exc:
        Path(path).unlink(missing_ok=True)
        if not isinstance(exc, OSError) or (exc.filename is not None and shown is None):
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


def check_replaceable(path: Path) -> None:
    """Refuse (:class:`OutputPathError`) a final name that is a symbolic link (it is never
    written through, nor replaced) or anything but a regular file."""
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        return
    if stat.S_ISLNK(mode):
        raise OutputPathError(
            f"{path}: is a symbolic link; it is not written through — give the path of a file"
        )
    if not stat.S_ISREG(mode):
        kind = "a folder" if stat.S_ISDIR(mode) else "not a regular file"
        raise OutputPathError(f"{path}: is {kind}; give a file name")


def write_file_atomic(path: Path, data: bytes) -> None:
    """Replace ``path`` with ``data`` atomically: a new temporary file in the same folder (created
    with ``O_EXCL``, never through a link), fsync, one rename; the temporary file is removed when
    anything fails. ``path`` itself must not be a symbolic link or a folder."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    check_replaceable(path)
    for _ in range(100):
        tmp = path.parent / f"{TEMP_PREFIX}{path.name}-{os.getpid()}-{uuid.uuid4().hex[:8]}"
        try:
            _write_synced(tmp, data, path)
            break
        except FileExistsError:  # the name is taken (by a link, say): never opened, draw another
            continue
    else:  # pragma: no cover - 100 random names all taken
        raise OSError(errno.EEXIST, "no free temporary name", str(path))
    try:
        os.replace(tmp, path)
        _fsync_dir(path.parent)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


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
