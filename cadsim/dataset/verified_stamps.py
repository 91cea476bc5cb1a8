"""Which datasets were verified, remembered across processes: one small JSON file per dataset
folder under ``<cadsim cache>/verified/`` (``$CADSIM_CACHE_DIR``, else ``~/.cache/cadsim``;
:func:`matchers.core.jit.cache_root`), holding the manifest checksum and the (size, mtime,
inode) signature of every file that :meth:`cadsim.dataset.Dataset.verify` read.

``Dataset.verify_once`` skips the full read and SHA-256 of every record when the stamp matches
the files as they are now: a record rewritten since (any size, mtime or inode change) is read
and checked again — the guarantee the in-process check gave before, now also for the next run
(a rewrite that restores size and mtime on the same inode goes unseen, as it did). A stamp is a
speed-up, never trusted as a result: a missing, unreadable or foreign one means "verify".
Writes are atomic (temporary file + rename); a cache folder that cannot be written only costs
the next run a verification.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from cadsim.dataset.atomic_writer import write_file_atomic


def _stamp_path(folder: Path) -> Path:
    from matchers.core.jit import cache_root

    name = hashlib.sha256(str(Path(folder).resolve()).encode()).hexdigest()[:32]
    return cache_root() / "verified" / f"{name}.json"


def stamped(folder: Path, signature: tuple[str, str]) -> bool:
    """Whether dataset ``folder`` was verified with exactly ``signature`` (checksum, files)."""
    try:
        stored = json.loads(_stamp_path(folder).read_text())
        return stored.get("folder") == str(Path(folder).resolve()) and [
            stored.get("checksum"),
            stored.get("files"),
        ] == list(signature)
    except (OSError, ValueError, AttributeError):
        return False


def stamp(folder: Path, signature: tuple[str, str]) -> None:
    """Remember that dataset ``folder`` passed verification with ``signature``."""
    path = _stamp_path(folder)
    text = json.dumps(
        {"folder": str(Path(folder).resolve()), "checksum": signature[0], "files": signature[1]}
    )
    try:
        write_file_atomic(path, text.encode())
    except OSError:
        return
