"""Whether a folder may be written as a dataset: it is new, empty, or already a cadsim dataset.

``generate`` (and ``import``) delete what an interrupted run of theirs left behind — unfinished
``.tmp-*`` records, episode summaries, the sources' ``.work`` cache — so they must be sure the
folder is theirs first. :func:`check_output_folder` refuses, in one line naming what is there:
an empty path; a path that is a file; a non-empty folder holding anything a cadsim dataset does
not hold (a user's files), or a ``manifest.json`` that is not a cadsim manifest; and symbolic
links anywhere a dataset has folders or files (``pairs``, ``episodes``, ``.work``, a record), which
would be followed out of the folder. It never changes anything.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

from cadsim.dataset import layout
from cadsim.dataset.manifest import FORMAT_NAME

_TEMP = re.compile(re.escape(layout.TEMP_PREFIX) + r".+-\d+-[0-9a-f]{8}$")
_OWN = {layout.MANIFEST, layout.PAIRS_DIR, layout.EPISODES_DIR, layout.WORK_DIR, layout.LOCK_FILE}
_EPISODE = re.compile(r"^e\d{5,}\.json$")


class OutputFolderError(ValueError):
    """The output folder is not a new, empty or cadsim dataset folder."""


def _listing(names: list[str], limit: int = 4) -> str:
    shown = ", ".join(repr(n) for n in sorted(names)[:limit])
    return shown + (f" and {len(names) - limit} more" if len(names) > limit else "")


def check_output_folder(out: str | Path, option: str = "--out") -> Path:
    """``out`` as a Path if a dataset may be written there, else :class:`OutputFolderError`."""
    if not str(out).strip():
        raise OutputFolderError(f"{option}: expected a folder path, got an empty one")
    path = Path(out)
    if path.is_symlink():
        raise OutputFolderError(f"{path}: is a symbolic link; give the folder it points to")
    if not path.exists():
        return path
    if not path.is_dir():
        raise OutputFolderError(f"{path}: exists and is not a folder")
    entries = list(path.iterdir())
    if not entries:
        return path
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


def _is_record(entry: Path) -> bool:
    return layout.parse_record_name(entry.name) is not None and entry.is_dir()


def _is_episode(entry: Path) -> bool:
    return bool(_EPISODE.match(entry.name))


def _is_cadsim_manifest(path: Path) -> bool:
    """Whether ``path``'s manifest is one cadsim wrote, of this format version or another (the
    resume check then reads it in full and names what differs)."""
    try:
        manifest = json.loads((path / layout.MANIFEST).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return False
    return isinstance(manifest, dict) and manifest.get("format") == FORMAT_NAME
