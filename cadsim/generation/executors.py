"""Choosing an executor: a Dask scheduler when an address is given (argument or
``$CADSIM_SCHEDULER``), else this process for one worker, else a local process pool. The factory
sits above both backends; neither imports it."""

from __future__ import annotations

import argparse
import logging
import os

from cadsim.generation.executor import Executor
from cadsim.generation.local_executor import LocalProcessExecutor, SerialExecutor, default_workers

log = logging.getLogger(__name__)

SCHEDULER_ENV = "CADSIM_SCHEDULER"


def scheduler_address(given: str | None = None) -> str | None:
    """The Dask scheduler to use: `given`, else ``$CADSIM_SCHEDULER``, else None (local)."""
    address = given if given else os.environ.get(SCHEDULER_ENV, "")
    return address.strip() or None


def make_executor(workers: int | None = None, scheduler: str | None = None) -> Executor:
    """A Dask executor when a scheduler address is given (argument or ``$CADSIM_SCHEDULER``; then
    `workers` is ignored: the cluster decides), else serial for 1 worker, else a local process
    pool (default: one process per core)."""
    address = scheduler_address(scheduler)
    if address is not None:
        from cadsim.generation.dask_executor import DaskExecutor

        if workers is not None:
            log.debug("workers=%s ignored: tasks go to the Dask scheduler %s", workers, address)
        return DaskExecutor(address)
    workers = default_workers() if workers is None else workers
    return SerialExecutor() if workers <= 1 else LocalProcessExecutor(workers)


def add_scheduler_argument(parser: argparse.ArgumentParser) -> None:
    """The ``--scheduler ADDRESS`` option every parallel command shares."""
    parser.add_argument(
        "--scheduler",
        default=None,
        metavar="ADDRESS",
        help=f"run tasks on this Dask scheduler, e.g. tcp://host:8786 (default: ${SCHEDULER_ENV}, "
        "else local processes); see docs/scale-out.md",
    )
