"""The executor interface: where tasks run, seen from the code that submits them.

An :class:`Executor` runs a picklable, module-level function on picklable task items:
:meth:`Executor.submit` returns a :class:`concurrent.futures.Future` whatever the backend, and
:meth:`Executor.map_unordered` yields each outcome as it completes (in completion order). A task
that raises does not stop the others: its outcome carries the exception. Tasks may call
:func:`report_progress` to send small messages (e.g. "one record written") to the submitting
process, which collects them with :meth:`Executor.progress`.

Backends live below this module (``local_executor``: this process or a local process pool;
``dask_executor``: a Dask scheduler) and the factory above them (``executors.make_executor``).
This module imports neither.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextvars
import logging
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

log = logging.getLogger(__name__)

# Where report_progress() sends messages in the current task (None: nowhere).
progress_sink: contextvars.ContextVar[Callable[[Any], None] | None] = contextvars.ContextVar(
    "cadsimprogress_sink", default=None
)


def report_progress(message: Any) -> None:
    """Send `message` (small, picklable, msgpack-able: tuples of str/int) from inside a task to
    the process that submitted it; a no-op outside an executor's task."""
    sink = progress_sink.get()
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
