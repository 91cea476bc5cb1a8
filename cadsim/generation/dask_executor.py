"""The Dask distributed backend of :class:`cadsim.generation.executor.Executor`: every task is a Dask future.

Connects a ``distributed.Client`` to a running scheduler (``dask scheduler``; workers started with
``dask worker ADDRESS --nthreads 1``). Each task is submitted with ``pure=False`` (a fresh key:
identical items still run) and comes back as a :class:`concurrent.futures.Future`, so callers do
not know which backend ran it.

Failures: a task that raises is not retried (``retries``: 0; tasks are deterministic). A worker
that dies mid-task costs only its running task: the scheduler reruns it elsewhere, up to the
scheduler's ``distributed.scheduler.allowed-failures`` (default 3) deaths per task, after which the
task's future holds ``KilledWorker``.

Progress: a task's :func:`cadsim.generation.executor.report_progress` messages travel as Dask events on a
topic private to this executor, and :meth:`DaskExecutor.progress` returns them.
"""

from __future__ import annotations

import concurrent.futures as cf
import logging
import queue as queue_module
import uuid
from typing import Any

from distributed import Client, get_worker

from cadsim.generation.executor import Executor, progress_sink

log = logging.getLogger(__name__)


def _run_reporting(fn, item, topic: str):
    """Worker side: run `fn(item)` with report_progress() sending events to `topic`."""
    worker = get_worker()
    token = progress_sink.set(lambda message: worker.log_event(topic, message))
    try:
        return fn(item)
    finally:
        progress_sink.reset(token)


class _DaskFuture(cf.Future):
    """A concurrent.futures view of a Dask future; cancelling it cancels the Dask task."""

    def __init__(self, dask_future) -> None:
        super().__init__()
        self.dask_future = dask_future
        dask_future.add_done_callback(self._settle)  # runs in a Dask callback thread

    def _settle(self, dask_future) -> None:
        if self.done():
            return
        try:
            if dask_future.status == "finished":
                self.set_result(dask_future.result())
            elif dask_future.status == "cancelled":
                self.set_exception(cf.CancelledError(f"Dask task {dask_future.key} cancelled"))
            else:
                self.set_exception(dask_future.exception())
        except cf.InvalidStateError:  # cancelled here meanwhile
            pass
        except Exception as exc:  # result could not be fetched (lost data, connection)
            try:
                self.set_exception(exc)
            except cf.InvalidStateError:
                pass

    def cancel(self) -> bool:
        if not self.done():
            self.dask_future.cancel()
        return super().cancel()


class DaskExecutor(Executor):
    """Tasks on the Dask cluster behind `scheduler` (an address, or a connected Client, which is
    then not closed here). `workers`: the cluster's worker processes when connected (at least 1).
    """

    def __init__(self, scheduler: str | Client, connect_timeout: float = 30.0) -> None:
        if isinstance(scheduler, Client):
            self.client, self._owns_client = scheduler, False
        else:
            try:
                self.client = Client(scheduler, timeout=connect_timeout, set_as_default=False)
            except OSError as exc:
                raise ConnectionError(
                    f"--scheduler / $CADSIM_SCHEDULER {scheduler!r}: no Dask scheduler reachable "
                    f"({exc}); start one with `dask scheduler` (docs/scale-out.md)"
                ) from exc
            self._owns_client = True
        info = self.client.scheduler_info()["workers"]
        self.workers = max(1, len(info))
        self._resources = {name for w in info.values() for name in (w.get("resources") or {})}
        if not info:
            log.warning("Dask scheduler %s has no workers yet; tasks wait for one", self.address)
        else:
            log.info(
                "Dask scheduler %s: %d workers, %d threads",
                self.address,
                len(info),
                sum(w["nthreads"] for w in info.values()),
            )
        self._topic = f"cadsim-progress-{uuid.uuid4().hex}"
        self._messages: queue_module.SimpleQueue = queue_module.SimpleQueue()
        self.client.subscribe_topic(self._topic, lambda event: self._messages.put(event[1]))

    @property
    def address(self) -> str:
        return self.client.scheduler.address

    def submit(self, fn, item, resources: dict[str, float] | None = None) -> cf.Future:
        """Submit `fn(item)`. `resources` (e.g. ``{"simulation": 1}``) are requested only when a
        worker declared those names (``dask worker --resources simulation=1``); otherwise a task
        would wait forever."""
        wanted = {k: v for k, v in (resources or {}).items() if k in self._resources} or None
        future = self.client.submit(
            _run_reporting, fn, item, self._topic, pure=False, retries=0, resources=wanted
        )
        return _DaskFuture(future)

    def progress(self) -> list[Any]:
        messages = []
        while True:
            try:
                messages.append(self._messages.get_nowait())
            except queue_module.Empty:
                return messages

    def close(self) -> None:
        if self.client is None:
            return
        try:
            self.client.unsubscribe_topic(self._topic)
        except Exception:  # the connection may already be gone
            log.debug("unsubscribe from %s failed", self._topic, exc_info=True)
        if self._owns_client:
            self.client.close()
        self.client = None
