"""Where tasks run: the one place that knows whether work is in this process or a process pool.

An :class:`Executor` maps a picklable function over picklable task items and yields each outcome
as it completes (in completion order). A task that raises does not stop the others: its outcome
carries the exception. A cluster backend implements the same two methods.
"""

from __future__ import annotations

import concurrent.futures as cf
import multiprocessing
import os
import time
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any


@dataclass
class Completed:
    """Outcome of task `index` (position in the submitted sequence): `value`, or `error`."""

    index: int
    value: Any = None
    error: BaseException | None = None


class Executor(ABC):
    """Runs `fn(item)` for every item; `map_unordered` yields :class:`Completed` as they finish."""

    workers: int = 1

    @abstractmethod
    def map_unordered(self, fn: Callable[[Any], Any], items: Sequence[Any]) -> Iterator[Completed]:
        """Yield one :class:`Completed` per item, in completion order."""

    def close(self) -> None:  # noqa: B027 - optional hook, not abstract
        """Release workers (no-op by default)."""

    def __enter__(self) -> Executor:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class SerialExecutor(Executor):
    """Runs tasks one after another in this process (debugging, tests, one core)."""

    workers = 1

    def map_unordered(self, fn, items):
        for index, item in enumerate(items):
            try:
                yield Completed(index, value=fn(item))
            except Exception as exc:  # the task failed; the others still run
                yield Completed(index, error=exc)


# One BLAS/OpenMP thread per worker process: the pool already uses every core.
_NATIVE_THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def _ready() -> bool:
    time.sleep(0.05)  # busy, so that each warm-up submit starts a new worker
    return True


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


class LocalProcessExecutor(Executor):
    """A pool of `workers` spawned processes on this machine (spawn: no state shared by fork).
    Started on first use; a pool broken by a dying worker is replaced on the next call."""

    def __init__(self, workers: int) -> None:
        if workers < 1:
            raise ValueError(f"workers: expected ≥ 1, got {workers}")
        self.workers = workers
        self._pool: cf.ProcessPoolExecutor | None = None
        self._broken = False

    def _started(self) -> cf.ProcessPoolExecutor:
        if self._pool is not None and not self._broken:
            return self._pool
        self.close()
        self._pool = cf.ProcessPoolExecutor(
            max_workers=self.workers, mp_context=multiprocessing.get_context("spawn")
        )
        self._broken = False
        with _single_threaded_children():  # workers start on submit while none is idle
            for future in [self._pool.submit(_ready) for _ in range(self.workers)]:
                future.result()
        return self._pool

    def map_unordered(self, fn, items):
        if not items:
            return
        pool = self._started()
        futures = {pool.submit(fn, item): index for index, item in enumerate(items)}
        try:
            for future in cf.as_completed(futures):
                index = futures[future]
                error = future.exception()
                if isinstance(error, cf.process.BrokenProcessPool):
                    self._broken = True
                yield (
                    Completed(index, error=error)
                    if error is not None
                    else Completed(index, value=future.result())
                )
        finally:
            for future in futures:
                future.cancel()

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None


def default_workers() -> int:
    """Worker processes to use by default: the cores this process may run on."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


def make_executor(workers: int | None = None) -> Executor:
    """Serial executor for 1 worker, else a local process pool (default: one per core)."""
    workers = default_workers() if workers is None else workers
    return SerialExecutor() if workers <= 1 else LocalProcessExecutor(workers)
