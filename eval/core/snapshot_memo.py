"""N-view snapshots read once per process, across tasks.

An N-view study runs every pair of views of a snapshot as a task of its own (one per view pair,
:mod:`eval.studies.multiagent`: 15 pairs of 6 views), and each task used to open, parse and
verify every snapshot again (``Dataset.snapshot(k)``: its ``record.json``, every view's arrays
of ``detections.npz`` and their checks) — on ``cad-multi`` about two thirds of a view-pair
task's time, more than the matching itself. A worker process runs many such tasks one after the
other, so it keeps the last :data:`SNAPSHOTS` snapshots it read, keyed by dataset folder,
dataset checksum (verified against the task's before anything is read), sensor and index.

What is kept is what ``Dataset.snapshot`` returns, read-only in use: a task derives its frame
pair from it (``pair(i, j)``, then thinning, re-localisation, re-detection, each a new object),
and the matchers of one task already share each pair's problem, so sharing it between the tasks
of a process adds no new trust. Results are the same bits with or without it
(``tests/test_multi_view.py``). About 0.75 MB per ``cad-multi`` snapshot: at most ~0.2 GB per
process.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from typing import Any

SNAPSHOTS = 256
"""Snapshots kept per process: the test and validation splits of a study (60 + 30 on
``cad-multi``) with room, so that a scan over them in index order does not evict itself."""

_kept: OrderedDict[tuple, Any] = OrderedDict()
_lock = threading.Lock()  # a Dask worker may run tasks on several threads


def snapshot(dataset: Any, dataset_dir: str, checksum: str, sensor: str | None, k: int) -> Any:
    """``dataset.snapshot(k)``, read once per process for each (``dataset_dir``, ``checksum``,
    ``sensor``, ``k``); the least recently used is dropped beyond :data:`SNAPSHOTS`."""
    key = (str(dataset_dir), checksum, sensor, int(k))
    with _lock:
        kept = _kept.get(key)
        if kept is not None:
            _kept.move_to_end(key)
            return kept
    kept = dataset.snapshot(k)  # outside the lock: two threads may both read it, once
    with _lock:
        _kept[key] = kept
        while len(_kept) > SNAPSHOTS:
            _kept.popitem(last=False)
    return kept


def forget() -> None:
    """Drop every kept snapshot."""
    with _lock:
        _kept.clear()


__all__ = ["SNAPSHOTS", "forget", "snapshot"]
