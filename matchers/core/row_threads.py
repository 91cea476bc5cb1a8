"""Run a compiled, GIL-free kernel over row ranges on a few threads.

The kernels this serves write each row of their output independently (a query's neighbour list,
a triangle's match indices, an entry's value), so how the rows are split never changes a bit:
the result is the same with one thread or four, on any machine. Small jobs stay on the calling
thread (handing work to a thread costs about as much as 0.1 ms of it).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from functools import cache

import numpy as np

MAX_THREADS = 4
MIN_WORK = 500_000
"""Units of work (e.g. distances) per thread below which a job is not split."""


def split_rows(job: Callable[[int, int], None], rows: int, work: int) -> None:
    """Call ``job(lo, hi)`` for consecutive row ranges covering ``0..rows``: one range when
    ``work`` (the job's size in rough units) is small, else one per thread, in parallel
    (``job`` must release the GIL — a numba ``nogil`` kernel — and write disjoint rows)."""
    parts = min(threads(), rows, max(1, work // MIN_WORK))
    if parts <= 1:
        job(0, rows)
        return
    bounds = np.linspace(0, rows, parts + 1).astype(int)
    futures = [_pool().submit(job, lo, hi) for lo, hi in zip(bounds[:-1], bounds[1:], strict=True)]
    for future in futures:
        future.result()


@cache
def threads() -> int:
    """Threads a split uses: the usable cores, at most :data:`MAX_THREADS`."""
    usable = (
        os.sched_getaffinity(0) if hasattr(os, "sched_getaffinity") else range(os.cpu_count() or 1)
    )
    return max(1, min(MAX_THREADS, len(usable)))


@cache
def _pool() -> ThreadPoolExecutor:
    return ThreadPoolExecutor(threads(), thread_name_prefix="cadsim-rows")
