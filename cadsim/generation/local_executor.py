"""The local backends of :class:`cadsim.generation.executor.Executor`: this process
(:class:`SerialExecutor`) or a pool of spawned processes on this machine
(:class:`LocalProcessExecutor`), whose processes exit when their parent dies."""

from __future__ import annotations

import concurrent.futures as cf
import logging
import multiprocessing
import os
import queue as queue_module
import signal
import threading
import time
from contextlib import contextmanager
from typing import Any

from cadsim.generation.executor import Completed, Executor, progress_sink

log = logging.getLogger(__name__)


class SerialExecutor(Executor):
    """Runs each task when submitted, in this process (debugging, tests, one core)."""

    workers = 1

    def __init__(self) -> None:
        self._messages: list[Any] = []

    def _call(self, fn, item):
        token = progress_sink.set(self._messages.append)
        try:
            return fn(item)
        finally:
            progress_sink.reset(token)

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


ORPHAN_POLL_S = 0.5  # how often a pool process checks that its parent is alive
ORPHANED_EXIT_STATUS = 3


def _exit_when_orphaned(parent: int) -> None:
    """Start a daemon thread that ends this process as soon as its parent (pid ``parent``) is
    gone: once the parent dies, however it dies (SIGKILL included), this process is re-parented
    and ``os.getppid()`` changes. Portable, unlike Linux's PR_SET_PDEATHSIG, which would also
    fire when merely the parent *thread* that started the pool exits."""

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(ORPHAN_POLL_S)
        os._exit(ORPHANED_EXIT_STATUS)  # no cleanup: unfinished records are .tmp-* (removed later)

    threading.Thread(target=watch, name="cadsim-orphan-watch", daemon=True).start()


def _pool_worker_init(channel, parent: int) -> None:
    """In each pool process: exit with the parent, announce the pid, and route
    report_progress() to the parent."""
    _exit_when_orphaned(parent)
    channel.put(("pid", os.getpid()))
    progress_sink.set(lambda message: channel.put(("message", message)))


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
            initargs=(self._channel, os.getpid()),
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
