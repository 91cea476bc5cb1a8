"""Where runs execute: the runner-facing name of :mod:`cadsim.generation.executor` and its
backends (one implementation, shared with dataset generation; the Dask backend is :mod:`cadsim.generation.dask_executor`), plus
:func:`map_in_order` for the benchmarks that just need a parallel map."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from tqdm import tqdm

from cadsim.generation.executor import Completed, Executor, report_progress
from cadsim.generation.executors import (
    SCHEDULER_ENV,
    add_scheduler_argument,
    make_executor,
    scheduler_address,
)
from cadsim.generation.local_executor import LocalProcessExecutor, SerialExecutor, default_workers

__all__ = [
    "SCHEDULER_ENV",
    "Completed",
    "Executor",
    "LocalProcessExecutor",
    "SerialExecutor",
    "add_scheduler_argument",
    "default_workers",
    "make_executor",
    "map_in_order",
    "report_progress",
    "scheduler_address",
]


def map_in_order(
    fn: Callable[[Any], Any],
    items: Sequence[Any],
    workers: int,
    *,
    desc: str,
    unit: str,
    progress: bool = True,
) -> list[Any]:
    """``[fn(item) for item in items]`` on `workers` local processes (in this process for one
    worker or one item), with a tqdm bar; results in item order whatever the completion order.
    The first failed task's exception is raised. `fn` must be a picklable module-level function."""
    executor = LocalProcessExecutor(workers) if workers > 1 and len(items) > 1 else SerialExecutor()
    results: list[Any] = [None] * len(items)
    with (
        executor,
        tqdm(total=len(items), desc=desc, unit=unit, disable=not progress, leave=False) as bar,
    ):
        for done in executor.map_unordered(fn, items):
            if done.error is not None:
                raise done.error
            results[done.index] = done.value
            bar.update()
    return results
