"""Where runs execute: the runner-facing name of :mod:`cadsim.executor` (one implementation, shared
with dataset generation; the Dask backend is :mod:`cadsim.dask_executor`)."""

from cadsim.executor import (
    SCHEDULER_ENV,
    Completed,
    Executor,
    LocalProcessExecutor,
    SerialExecutor,
    add_scheduler_argument,
    default_workers,
    make_executor,
    report_progress,
    scheduler_address,
)

__all__ = [
    "SCHEDULER_ENV",
    "Completed",
    "Executor",
    "LocalProcessExecutor",
    "SerialExecutor",
    "add_scheduler_argument",
    "default_workers",
    "make_executor",
    "report_progress",
    "scheduler_address",
]
