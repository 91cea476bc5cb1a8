"""The output-path rule of every command: what a command may write, checked before it writes.

One rule, three kinds of output (every ``--out`` of every command goes through one of them):

* a **dataset folder** (``generate``, ``import``) — :func:`check_output_folder`;
* a **result folder** (``evaluate``, ``sweep-*``, ``table``, ``make reproduce``) —
  :func:`check_result_folder` (and their ``--cache``: :func:`check_cache_folder`);
* a **file** (``train``'s model, ``schema``, ``show``'s figure, ``synthetic``'s tables) —
  :func:`check_output_file`.

What they share: an empty path is refused; a symbolic link is never followed (``--out`` itself,
or what a dataset or result folder holds); nothing is written over an existing dataset, nor
anywhere inside one (a dataset folder, or any folder below it, is never another command's output);
an existing folder or file is used only when it is of the kind the command writes — a cadsim
dataset (resumed), a result folder (it holds one of cadsim's result files), a file the command
itself wrote (recognised by its content: a model file's ``format``, a matplotlib figure, …) — and
is otherwise refused in one line naming what is there. The checks never change anything.

The writing itself is :mod:`cadsim.dataset.atomic_writer`'s: a new temporary name in the same
folder opened with ``O_EXCL | O_NOFOLLOW``, renamed over the target at the end, removed on
failure; the final name is checked again there (never a link or a folder).

``generate`` (and ``import``) delete what an interrupted run of theirs left behind — unfinished
``.tmp-*`` records, episode summaries, the sources' ``.work`` cache — so they must be sure the
folder is theirs first. :func:`check_output_folder` refuses: a path that is a file; a non-empty
folder holding anything a cadsim dataset does not hold (a user's files), or a ``manifest.json``
that is not a cadsim manifest; and symbolic links anywhere a dataset has folders or files
(``pairs``, ``episodes``, ``.work``, a record), which would be followed out of the folder.
"""

from __future__ import annotations

import json
import os
import re
import stat
from collections.abc import Callable
from pathlib import Path

from cadsim.dataset import layout
from cadsim.dataset.atomic_writer import OutputPathError
from cadsim.dataset.manifest import FORMAT_NAME

_TEMP = re.compile(re.escape(layout.TEMP_PREFIX) + r".+-\d+-[0-9a-f]{8}$")
_OWN = {layout.MANIFEST, layout.PAIRS_DIR, layout.EPISODES_DIR, layout.WORK_DIR, layout.LOCK_FILE}
_EPISODE = re.compile(r"^e\d{5,}\.json$")
_MAX_MANIFEST_BYTES = 1 << 30  # a manifest of 100,000 records is about 20 MB

# What makes a folder a result folder: a file one of the commands writes there first (every
# evaluation writes evaluation*.json / metrics_per_pair*.csv / thresholds.csv, each sweep its
# *_sweep.csv or noise_runs.csv, make reproduce its run record).
RESULT_FILES = re.compile(
    r"^(evaluation|metrics_per_pair|average_precision|table1)(_[a-z_]+)?\.(json|csv|md)$"
    r"|^(thresholds|noise_runs|regime_sweep|crossovers|localisation_sweep|localisation_presets"
    r"|regime|dataset_spread|pr_curves|agreement)\.csv$|^(run_record|qualitative)\.json$"
    r"|^table_[a-z0-9_]+\.(md|csv)$"
)

OutputFolderError = OutputPathError  # the name the dataset-folder rule has always raised


def _listing(names: list[str], limit: int = 4) -> str:
    shown = ", ".join(repr(n) for n in sorted(names)[:limit])
    return shown + (f" and {len(names) - limit} more" if len(names) > limit else "")


def _not_empty(out: str | Path, option: str, what: str) -> Path:
    if not str(out).strip():
        raise OutputPathError(f"{option}: expected a {what} path, got an empty one")
    return Path(out)


def check_output_folder(out: str | Path, option: str = "--out", resumable: bool = True) -> Path:
    """``out`` as a Path if a dataset may be written there (new, empty, or — when
    ``resumable`` — a cadsim dataset), else :class:`OutputFolderError`."""
    path = _not_empty(out, option, "folder")
    if path.is_symlink():
        raise OutputFolderError(f"{path}: is a symbolic link; give the folder it points to")
    _refuse_inside_a_dataset(path)
    if not path.exists():
        return path
    if not path.is_dir():
        raise OutputFolderError(f"{path}: exists and is not a folder")
    entries = list(path.iterdir())
    if not entries:
        return path
    if not resumable:
        raise OutputFolderError(
            f"{path}: exists and is not an empty folder (it holds "
            f"{_listing([e.name for e in entries])}); "
            "give a new or empty folder"
        )
    foreign = [e.name for e in entries if e.name not in _OWN and not _TEMP.match(e.name)]
    if foreign:
        raise OutputFolderError(
            f"{path}: not empty and not a cadsim dataset (it holds {_listing(foreign)}); "
            "give a new or empty folder"
        )
    links = [e.name for e in entries if e.is_symlink()]
    strays = []
    for sub, own in ((layout.PAIRS_DIR, _is_record), (layout.EPISODES_DIR, _is_episode)):
        folder = path / sub
        if folder.is_symlink() or not folder.exists():
            continue
        if not folder.is_dir():
            strays.append(sub)
            continue
        for e in folder.iterdir():
            if e.is_symlink():
                links.append(f"{sub}/{e.name}")
            elif not own(e) and not _TEMP.match(e.name):
                strays.append(f"{sub}/{e.name}")
    if links:
        raise OutputFolderError(
            f"{path}: holds symbolic links ({_listing(links)}), which a dataset never does; "
            "they are not followed — give a new or empty folder"
        )
    if strays:
        raise OutputFolderError(
            f"{path}: not a cadsim dataset (it holds {_listing(strays)}); give a new or empty folder"
        )
    if (path / layout.MANIFEST).exists() and not _is_cadsim_manifest(path):
        raise OutputFolderError(
            f"{path}: its manifest.json is not a cadsim manifest; give a new or empty folder"
        )
    return path


def check_result_folder(out: str | Path, option: str = "--out") -> Path:
    """``out`` as a Path if a command may write results there: a new or empty folder, or a result
    folder (it holds one of :data:`RESULT_FILES`); never a dataset, a folder inside one, a
    symbolic link, a file, or a user's folder. :class:`OutputPathError` otherwise."""
    path = _not_empty(out, option, "folder")
    if path.is_symlink():
        raise OutputPathError(f"{path}: is a symbolic link; give the folder it points to")
    if path.exists() and not path.is_dir():
        raise OutputPathError(f"{path}: exists and is not a folder; give a folder for the results")
    if path.is_dir() and _is_dataset(path):
        raise OutputPathError(
            f"{path}: is a cadsim dataset; results go in a folder of their own (e.g. {path}-results)"
        )
    _refuse_inside_a_dataset(path)
    if not path.exists():
        return path
    entries = [e for e in path.iterdir() if not _TEMP.match(e.name)]
    links = [e.name for e in entries if e.is_symlink()]
    if links:
        raise OutputPathError(
            f"{path}: holds symbolic links ({_listing(links)}), which a result folder never "
            "does; they are not followed — give a new or empty folder"
        )
    if entries and not any(RESULT_FILES.match(e.name) and e.is_file() for e in entries):
        raise OutputPathError(
            f"{path}: not empty and not a cadsim result folder (it holds "
            f"{_listing([e.name for e in entries])}); give a new or empty folder"
        )
    return path


def check_cache_folder(out: str | Path, option: str = "--cache") -> Path:
    """``out`` as a Path if the result cache may live there: a folder (new or not) that is not a
    dataset, not inside one and not a file. (A cache's own files are written atomically by
    ``eval.core.cache``; a link to the cache folder is allowed — caches are often moved to another
    disk that way.)"""
    path = _not_empty(out, option, "folder")
    if path.exists() and not path.is_dir():
        raise OutputPathError(f"{path}: exists and is not a folder; give a folder for the cache")
    if path.is_dir() and _is_dataset(path):
        raise OutputPathError(f"{path}: is a cadsim dataset; the result cache goes elsewhere")
    _refuse_inside_a_dataset(path)
    return path


def check_output_file(
    out: str | Path,
    what: str,
    own: Callable[[Path], bool],
    option: str = "--out",
) -> Path:
    """``out`` as a Path if a command may write the file there: a new name in a folder that is
    not (inside) a dataset, or an existing regular file that ``own(path)`` recognises as one the
    command wrote (``what`` names that kind: "a cadsim model file"). Refused: an empty path, a
    symbolic link (never written through), a folder, anything but a regular file, a file of
    another kind (left as it is). :class:`OutputPathError` naming the path."""
    path = _not_empty(out, option, "file")
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        mode = None
    except OSError as exc:
        raise OutputPathError(f"{path}: cannot be checked ({exc.strerror})") from None
    if mode is not None and stat.S_ISLNK(mode):
        raise OutputPathError(
            f"{path}: is a symbolic link; it is not written through — give the file's own path"
        )
    if mode is not None and stat.S_ISDIR(mode):
        raise OutputPathError(f"{path}: is a folder; give a file name (e.g. {path / 'name'})")
    if mode is not None and not stat.S_ISREG(mode):
        raise OutputPathError(f"{path}: exists and is not a regular file; give a new file name")
    if path.parent.exists() and not path.parent.is_dir():
        raise OutputPathError(f"{path.parent}: is not a folder")
    _refuse_inside_a_dataset(path)
    if mode is not None and not own(path):
        raise OutputPathError(
            f"{path}: exists and is not {what}; it is left as it is — give a new file name "
            "(or remove it yourself)"
        )
    return path


def file_holds(marker: bytes, span: int = 1 << 16) -> Callable[[Path], bool]:
    """An ``own`` test for :func:`check_output_file`: whether ``marker`` is in the first or last
    ``span`` bytes of the file (case-insensitive; read without blocking, a regular file only)."""
    marker = marker.lower()

    def own(path: Path) -> bool:
        head, tail = _head_and_tail(path, span)
        return marker in head.lower() or marker in tail.lower()

    return own


def file_starts_with(prefix: bytes) -> Callable[[Path], bool]:
    """An ``own`` test: whether the file begins with ``prefix``."""

    def own(path: Path) -> bool:
        return _head_and_tail(path, len(prefix))[0] == prefix

    return own


def _head_and_tail(path: Path, span: int) -> tuple[bytes, bytes]:
    """The first and last ``span`` bytes of the regular file at ``path`` (b"" for anything else:
    a FIFO or device is never read)."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOFOLLOW", 0))
    except OSError:
        return b"", b""
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            return b"", b""
        head = os.pread(fd, span, 0)
        tail = os.pread(fd, span, max(0, info.st_size - span)) if info.st_size > span else b""
        return head, tail
    finally:
        os.close(fd)


def dataset_root(path: str | Path) -> Path | None:
    """The dataset folder ``path`` is inside (or is), or None; the path's links are resolved, so
    a link into a dataset counts."""
    here = Path(os.path.abspath(path))
    try:
        here = here.resolve()
    except (OSError, RuntimeError):
        pass
    for folder in (here, *here.parents):
        if _is_dataset(folder):
            return folder
    return None


def _refuse_inside_a_dataset(path: Path) -> None:
    parent = Path(os.path.abspath(path)).parent
    root = dataset_root(parent)
    if root is not None:
        raise OutputPathError(
            f"{path}: is inside the cadsim dataset {root}; a command never writes into another's "
            "dataset — give a path outside it"
        )


def _is_dataset(folder: Path) -> bool:
    """Whether ``folder`` is a cadsim dataset: a cadsim manifest, or a generate lock (a dataset
    being written before its first manifest)."""
    try:
        if not folder.is_dir():
            return False
        if (folder / layout.LOCK_FILE).is_file():
            return True
        return (folder / layout.MANIFEST).is_file() and _is_cadsim_manifest(folder)
    except OSError:
        return False


def _is_record(entry: Path) -> bool:
    return layout.parse_record_name(entry.name) is not None and entry.is_dir()


def _is_episode(entry: Path) -> bool:
    return bool(_EPISODE.match(entry.name))


def _is_cadsim_manifest(path: Path) -> bool:
    """Whether ``path``'s manifest is one cadsim wrote, of this format version or another (the
    resume check then reads it in full and names what differs). A manifest that is not a regular
    file (a FIFO, a device) is never opened for a blocking read."""
    manifest_path = path / layout.MANIFEST
    try:
        info = os.stat(manifest_path)
        if not stat.S_ISREG(info.st_mode) or info.st_size > _MAX_MANIFEST_BYTES:
            return False
        fd = os.open(manifest_path, os.O_RDONLY | os.O_NONBLOCK)
        try:
            if not stat.S_ISREG(os.fstat(fd).st_mode):
                return False
            with os.fdopen(os.dup(fd), "rb") as f:
                data = f.read(_MAX_MANIFEST_BYTES + 1)
        finally:
            os.close(fd)
        manifest = json.loads(data.decode("utf-8"))
    except (OSError, UnicodeDecodeError, ValueError, RecursionError):
        return False
    return isinstance(manifest, dict) and manifest.get("format") == FORMAT_NAME
