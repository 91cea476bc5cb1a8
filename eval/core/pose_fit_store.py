"""The pose fits of the scoring (:mod:`eval.core.pose_metrics`' per-process memo of planar and
6-DoF fits, keyed by a digest of their inputs) kept on disk beside the result cache, so that a
rerun whose runs all come from the cache does not fit every declared match set again — the
largest cost of a fully cached ``make reproduce`` (≈ 50 of 218 s, profiled 2026-12-06).

``<cache>/pose_fits.npz``: the keys (fixed-width digests), the (RTE, RRE) values, the code
version they were computed under (:func:`eval.core.cache.code_version`: an edit of
``pose_metrics.py`` or anything else that shapes a result discards the file) and a SHA-256 over
both arrays. Like the run cache, it is a local speed-up: a file that is unreadable, of another
format or version, or unlike its digest is ignored (logged) and rebuilt; an entry can only
stand for the fit of exactly the inputs its digest names. Written atomically
(:func:`cadsim.dataset.atomic_writer.write_file_atomic`) after each stage, so an interrupted run
keeps what its finished stages fitted. No pickle.
"""

from __future__ import annotations

import hashlib
import io
import logging
from pathlib import Path

import numpy as np

from cadsim.dataset.atomic_writer import write_file_atomic
from eval.core import pose_metrics

log = logging.getLogger(__name__)

FILE = "pose_fits.npz"
FORMAT = 1
RUN_FITS = 600_000
"""The process memo's bound once the store is in use (a full run fits fewer)."""
_saved = 0  # memo entries at the last save
KEY_BYTES = 24
"""A memo key as stored: a 6-DoF fit's key (b"6dof" + its 20-byte digest) as it is, a planar
fit's 20-byte digest after four zero bytes (so the two kinds never collide)."""


def _digest(keys: np.ndarray, values: np.ndarray, version: str) -> str:
    h = hashlib.sha256(f"{FORMAT} {version}\0".encode())
    h.update(keys.tobytes())
    h.update(values.tobytes())
    return h.hexdigest()


def load(cache_root: str | Path) -> int:
    """Fill the process's pose-fit memo from ``cache_root/pose_fits.npz`` (when it holds this
    code version's fits and matches its digest); the number of fits read."""
    from eval.core.cache import code_version

    # a whole run's fits fit in memory (≈ 200 B each), so the memo is not cleared mid-run
    pose_metrics._PLANAR_MEMO_LIMIT = max(pose_metrics._PLANAR_MEMO_LIMIT, RUN_FITS)
    path = Path(cache_root) / FILE
    if not path.is_file():
        return 0
    try:
        with np.load(path, allow_pickle=False) as data:
            keys, values = data["keys"], data["values"]
            version, digest = str(data["version"]), str(data["digest"])
            fmt = int(data["format"])
        if (
            fmt != FORMAT
            or version != code_version()
            or keys.dtype != np.uint8
            or keys.ndim != 2
            or keys.shape[1] != KEY_BYTES
            or values.dtype != np.float64
            or values.shape != (len(keys), 2)
            or digest != _digest(keys, values, version)
        ):
            log.info("pose fits: %s is not this code's (or not its digest); rebuilding it", path)
            return 0
    except (OSError, ValueError, KeyError, EOFError) as exc:
        log.warning("pose fits: %s unreadable (%s); rebuilding it", path, exc)
        return 0
    global _saved
    memo = pose_metrics._PLANAR_MEMO
    # room for what was stored and for what this run adds (the memo is cleared when full)
    pose_metrics._PLANAR_MEMO_LIMIT = max(pose_metrics._PLANAR_MEMO_LIMIT, 2 * len(keys))
    for row, (rte, rre) in zip(keys, values.tolist(), strict=True):
        key = row.tobytes()
        memo.setdefault(key[4:] if key[:4] == bytes(4) else key, (rte, rre))
    _saved = len(memo)
    return len(keys)


def save(cache_root: str | Path) -> int:
    """Write the process's pose-fit memo to ``cache_root/pose_fits.npz`` (atomically); the
    number of fits written (0 when the folder cannot be written: the next run fits again)."""
    from eval.core.cache import code_version

    global _saved
    memo = pose_metrics._PLANAR_MEMO
    if not memo or len(memo) == _saved:
        return 0  # nothing new since the last save
    stored = [k if len(k) == KEY_BYTES else bytes(KEY_BYTES - len(k)) + k for k in memo]
    if any(len(k) != KEY_BYTES for k in stored):
        return 0  # not a memo of this module's keys
    keys = np.frombuffer(b"".join(stored), dtype=np.uint8).reshape(-1, KEY_BYTES)
    values = np.array(list(memo.values()), dtype=np.float64).reshape(-1, 2)
    version = code_version()
    path = Path(cache_root) / FILE
    buffer = io.BytesIO()
    np.savez(
        buffer, keys=keys, values=values, version=np.array(version),
        digest=np.array(_digest(keys, values, version)), format=np.array(FORMAT),
    )  # fmt: skip
    try:
        write_file_atomic(path, buffer.getvalue())
    except (OSError, ValueError) as exc:  # ValueError: the path is a link or a folder
        log.warning("pose fits: could not write %s (%s)", path, exc)
        return 0
    _saved = len(memo)
    return len(keys)
