"""Where tasks run: the one place that knows whether work is in this process, a local process pool
or a Dask cluster.

An :class:`Executor` runs a picklable, module-level function on picklable task items:
:meth:`Executor.submit` returns a :class:`concurrent.futures.Future` whatever the backend, and
:meth:`Executor.map_unordered` yields each outcome as it completes (in completion order). A task
that raises does not stop the others: its outcome carries the exception. Tasks may call
:func:`report_progress` to send small messages (e.g. "one record written") to the submitting
process, which collects them with :meth:`Executor.progress`.

Backends: :class:`SerialExecutor` (this process), :class:`LocalProcessExecutor` (spawned processes
on this machine) and ``cadsim.dask_executor.DaskExecutor`` (a Dask scheduler; imported only when
asked for). :func:`make_executor` picks one from ``workers`` and a scheduler address (argument or
``CADSIM_SCHEDULER``).
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import contextvars
import logging
import multiprocessing
import os
import queue as queue_module
import signal
import time
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

log = logging.getLogger(__name__)

SCHEDULER_ENV = "CADSIM_SCHEDULER"

# Where report_progress() sends messages in the current task (None: nowhere).
_progress_sink: contextvars.ContextVar[Callable[[Any], None] | None] = contextvars.ContextVar(
    "cadsim_progress_sink", default=None
)


def report_progress(message: Any) -> None:
    """Send `message` (small, picklable, msgpack-able: tuples of str/int) from inside a task to
    the process that submitted it; a no-op outside an executor's task."""
    sink = _progress_sink.get()
    if sink is not None:
        sink(message)


@dataclass
class Completed:
    """Outcome of task `index` (position in the submitted sequence): `value`, or `error`."""

    index: int
    value: Any = None
    error: BaseException | None = None


class Executor(ABC):
    """Runs `fn(item)` for items; `workers` is how many tasks run at the same time."""

    workers: int = 1

    @abstractmethod
    def submit(
        self, fn: Callable[[Any], Any], item: Any, resources: dict[str, float] | None = None
    ) -> cf.Future:
        """Start `fn(item)`; its future (exception set if the task raised or its worker was lost
        for good). `resources`: abstract resources the task holds while it runs, e.g.
        ``{"simulation": 1}`` — Dask worker resources; local backends run one task per process
        and ignore them."""

    def map_unordered(self, fn: Callable[[Any], Any], items: Sequence[Any]) -> Iterator[Completed]:
        """Yield one :class:`Completed` per item, in completion order. Closing the iterator early
        cancels the tasks not yet started."""
        if not items:
            return
        futures = {self.submit(fn, item): index for index, item in enumerate(items)}
        try:
            for future in cf.as_completed(futures):
                error = future.exception()
                yield (
                    Completed(futures[future], error=error)
                    if error is not None
                    else Completed(futures[future], value=future.result())
                )
        finally:
            for future in futures:
                future.cancel()

    def progress(self) -> list[Any]:
        """Messages tasks sent with :func:`report_progress` since the last call (oldest first)."""
        return []

    def terminate(self) -> None:
        """Stop now: cancel queued tasks and stop running ones where the backend can."""
        self.close()

    def close(self) -> None:  # noqa: B027 - optional hook, not abstract
        """Release workers (no-op by default)."""

    def __enter__(self) -> Executor:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class SerialExecutor(Executor):
    """Runs each task when submitted, in this process (debugging, tests, one core)."""

    workers = 1

    def __init__(self) -> None:
        self._messages: list[Any] = []

    def _call(self, fn, item):
        token = _progress_sink.set(self._messages.append)
        try:
            return fn(item)
        finally:
            _progress_sink.reset(token)

    def submit(self, fn, item, resources=None) -> cf.Future:
        future: cf.Future = cf.Future()
        try:
            future.set_result(self._call(fn, item))
        except Exception as exc:  # the task failed; the caller sees it on the future
            future.set_exception(exc)
        return future

    def map_unordered(self, fn, items):
        for index, item in enumerate(items):  # lazily: each outcome as soon as it exists
            try:
                yield Completed(index, value=self._call(fn, item))
            except Exception as exc:  # the task failed; the others still run
                yield Completed(index, error=exc)

    def progress(self) -> list[Any]:
        messages, self._messages = self._messages, []
        return messages


# One BLAS/OpenMP thread per worker process: the pool already uses every core.
_NATIVE_THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


@contextmanager
def _single_threaded_children():
    """Set the thread-count variables while child processes start (they inherit the env)."""
    saved = {var: os.environ.get(var) for var in _NATIVE_THREAD_VARS}
    os.environ.update({var: "1" for var in _NATIVE_THREAD_VARS if saved[var] is None})
    try:
        yield
    finally:
        for var, value in saved.items():
            if value is None:
                os.environ.pop(var, None)


def _pool_worker_init(channel) -> None:
    """In each pool process: announce the pid, and route report_progress() to the parent."""
    channel.put(("pid", os.getpid()))
    _progress_sink.set(lambda message: channel.put(("message", message)))


def _ready() -> bool:
    time.sleep(0.05)  # busy, so that each warm-up submit starts a new worker
    return True


class LocalProcessExecutor(Executor):
    """A pool of `workers` spawned processes on this machine (spawn: no state shared by fork; one
    task at a time per process). Started on first use; a pool broken by a dying worker is
    replaced on the next submit."""

    def __init__(self, workers: int) -> None:
        if workers < 1:
            raise ValueError(f"workers: expected ≥ 1, got {workers}")
        self.workers = workers
        self._pool: cf.ProcessPoolExecutor | None = None
        self._channel = None
        self._pids: set[int] = set()
        self._messages: list[Any] = []
        self._broken = False

    def _started(self) -> cf.ProcessPoolExecutor:
        if self._pool is not None and not self._broken:
            return self._pool
        self.close()
        ctx = multiprocessing.get_context("spawn")
        self._channel = ctx.Queue()
        self._pool = cf.ProcessPoolExecutor(
            max_workers=self.workers,
            mp_context=ctx,
            initializer=_pool_worker_init,
            initargs=(self._channel,),
        )
        self._broken = False
        with _single_threaded_children():  # workers start on submit while none is idle
            for future in [self._pool.submit(_ready) for _ in range(self.workers)]:
                future.result()
        return self._pool

    def _mark_broken(self, future: cf.Future) -> None:
        if not future.cancelled() and isinstance(future.exception(), cf.process.BrokenProcessPool):
            self._broken = True

    def submit(self, fn, item, resources=None) -> cf.Future:
        future = self._started().submit(fn, item)
        future.add_done_callback(self._mark_broken)
        return future

    def _drain(self) -> None:
        while self._channel is not None:
            try:
                kind, value = self._channel.get_nowait()
            except (queue_module.Empty, OSError, ValueError):
                return
            if kind == "pid":
                self._pids.add(value)
            else:
                self._messages.append(value)

    def progress(self) -> list[Any]:
        self._drain()
        messages, self._messages = self._messages, []
        return messages

    def terminate(self) -> None:
        """Cancel queued tasks and SIGTERM the worker processes (running tasks die with them)."""
        if self._pool is None:
            return
        self._drain()
        self._pool.shutdown(wait=False, cancel_futures=True)
        for pid in self._pids:
            try:
                os.kill(pid, signal.SIGTERM)
            except (ProcessLookupError, PermissionError):
                pass
        self.close()

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
        self._drain()
        if self._channel is not None:
            self._channel.close()
            self._channel = None
        self._pids.clear()


def default_workers() -> int:
    """Worker processes to use by default: the cores this process may run on."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


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
        from cadsim.dask_executor import DaskExecutor

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
