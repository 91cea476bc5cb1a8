"""One writer per dataset folder: an exclusive ``flock`` on ``DIR/.generate.lock``.

``cadsim generate`` holds the lock from before it looks at the folder until it has written the
final manifest, so a second run on the same ``--out`` cannot delete the first one's unfinished
records. The lock file records who holds it (pid, host, start time); the second run stops at
once with that in its message. The kernel drops the lock when the holder exits, however it
exits (kill -9 included), so a stale lock file never blocks anyone. The holder removes the
file when it is done (while it still holds the lock), so a finished dataset holds none; one
left by a killed run is harmless.
"""

from __future__ import annotations

import fcntl
import json
import os
import socket
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from cadsim.dataset.layout import LOCK_FILE


class DatasetBusy(RuntimeError):
    """Another process holds the writer lock of a dataset folder (a user error: wait, or use
    another folder)."""

    user_error = True


def _holder(fd: int) -> str:
    try:
        info = json.loads(os.pread(fd, 4096, 0).decode("utf-8"))
        return f"pid {info['pid']} on {info['host']}, started {info['started']}"
    except (OSError, ValueError, KeyError, TypeError):
        return "holder unknown: it is just starting"


@contextmanager
def exclusive_writer(dataset_dir: str | Path) -> Iterator[None]:
    """Hold the writer lock of ``dataset_dir`` (which must exist) for the ``with`` block;
    :class:`DatasetBusy` naming the holder if another process has it."""
    path = Path(dataset_dir) / LOCK_FILE
    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise DatasetBusy(
                f"{dataset_dir}: another `cadsim generate` is writing this folder "
                f"({_holder(fd)}); wait for it to finish, or use another --out"
            ) from None
        info = {
            "pid": os.getpid(),
            "host": socket.gethostname(),
            "started": time.strftime("%Y-%m-%d %H:%M:%S %z"),
        }
        os.ftruncate(fd, 0)
        os.pwrite(fd, json.dumps(info).encode("utf-8"), 0)
        try:
            yield
        finally:
            path.unlink(missing_ok=True)  # still ours: nobody else can hold it until we close
    finally:
        os.close(fd)  # releases the lock
