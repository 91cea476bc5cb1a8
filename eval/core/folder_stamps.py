"""Stamps about a folder, kept outside it: one small JSON object per (kind, folder) under
``<cadsim cache>/<kind>/`` (``$CADSIM_CACHE_DIR``, else ``~/.cache/cadsim``;
:func:`matchers.core.jit.cache_root`), named by a digest of the folder's resolved path and
holding that path. What the figures (``eval/report/figure_stamps.py``) and the box-only splits
(``eval/studies/v2x/boxes.py``) remember between runs.

A stamp is a speed-up, never a result: a missing, unreadable or foreign one reads as None, and a
cache folder that cannot be written only costs the next run the work. Written through
:func:`cadsim.dataset.atomic_writer.write_file_atomic`.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from cadsim.dataset.atomic_writer import write_file_atomic


def stamp_path(kind: str, folder: Path) -> Path:
    """Where the `kind` stamp of `folder` lives."""
    from matchers.core.jit import cache_root

    name = hashlib.sha256(str(Path(folder).resolve()).encode()).hexdigest()[:32]
    return cache_root() / kind / f"{name}.json"


def read_stamp(kind: str, folder: Path) -> dict | None:
    """The `kind` stamp of `folder` (without its ``folder`` field); None when there is none or
    it is unreadable or another folder's."""
    try:
        stored = json.loads(stamp_path(kind, folder).read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(stored, dict) or stored.get("folder") != str(Path(folder).resolve()):
        return None
    return {k: v for k, v in stored.items() if k != "folder"}


def write_stamp(kind: str, folder: Path, content: dict) -> None:
    """Replace the `kind` stamp of `folder` with `content` (JSON); a write that fails is let go."""
    path = stamp_path(kind, folder)
    text = json.dumps(content | {"folder": str(Path(folder).resolve())})
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_file_atomic(path, text.encode())
    except (OSError, ValueError):  # ValueError: the path is a link or a folder
        return
