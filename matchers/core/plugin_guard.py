"""The boundary between the harness and a *plug-in*: a matcher or fusion that is not one of the
built-ins (``register()``-ed, an entry point of ``cadsim.matchers`` / ``cadsim.fusions``, or a
``package.module:function`` import path).

The harness calls a plug-in through :func:`call_with_time_limit` and reads its result only after
:func:`check_matching` (or :func:`matchers.fusion.checks.check_universe`) accepted it. Whatever a
plug-in does wrong — raises, returns ``None`` or another type, pairs of the wrong shape or outside
the views, an index matched twice, NaN/inf or out-of-range scores, a negative or non-finite time,
never returns — ends in one :class:`PluginError` naming the plug-in and what it returned; it is a
user error (``user_error = True``: the CLI prints one line and exits with status 2, the runner
counts the task as failed on bad input). The checks only read the result: nothing is copied,
clipped or rounded, so a result that passes is used exactly as returned.

Time limit. Each call of a plug-in on one problem (a frame pair for a matcher, a snapshot for a
fusion) runs on a daemon thread of the calling process, and the caller waits at most the limit
(``$CADSIM_PLUGIN_TIME_LIMIT_S`` seconds, default 600; ``--plugin-time-limit`` on the runner's
commands, which the coordinator puts into every task, so pool and Dask workers apply the same
value). Past it, :class:`PluginTimeout` names the plug-in and the limit, and the thread is asked to
stop (an exception raised in it at its next Python instruction); a thread blocked in native code
or a sleep stays parked until that returns, costing no CPU in a sleep, and dies with its process.
A thread rather than a signal or a child process: it works in any thread of any executor (a Dask
worker runs tasks on its own threads, where ``SIGALRM`` cannot be used) and costs about 0.5 ms a
call (outside the plug-in's own ``time_s``), against a process start and a copy of the problem. Built-in matchers and fusions are exempt
(they terminate, and run on the calling thread exactly as before).
"""

from __future__ import annotations

import contextvars
import ctypes
import functools
import math
import os
import reprlib
import threading
from collections.abc import Callable
from typing import Any

import numpy as np

from matchers.core.matching import Matching

TIME_LIMIT_ENV = "CADSIM_PLUGIN_TIME_LIMIT_S"
DEFAULT_TIME_LIMIT_S = 600.0
"""Seconds per problem: more than three orders of magnitude above the slowest built-in on the
benchmark's frame pairs (rrwhm, at most 0.15 s), so only a plug-in that is stuck reaches it."""
MAX_TIME_LIMIT_S = 7 * 86400.0
"""The largest limit accepted: one week."""


class PluginError(RuntimeError):
    """A plug-in matcher or fusion failed at the harness boundary: it raised, returned something
    that breaks its contract, or ran past the time limit. The message names the plug-in and what
    it returned. A user error (the CLI reports one line, exit status 2)."""

    user_error = True


class PluginTimeout(PluginError):
    """A plug-in did not return within the per-problem time limit."""


class _Abandoned(BaseException):
    """Raised inside a plug-in's thread once its caller stopped waiting for it (a BaseException,
    so that the plug-in's own ``except Exception`` does not keep it running)."""


def parse_time_limit(value: Any, where: str = f"${TIME_LIMIT_ENV}") -> float:
    """``value`` (a number or its text) as a time limit in seconds: positive, finite, at most
    :data:`MAX_TIME_LIMIT_S`; a ValueError naming ``where`` otherwise."""
    try:
        seconds = float(value) if not isinstance(value, bool) else float("nan")
    except (TypeError, ValueError):
        seconds = float("nan")
    if not (0 < seconds <= MAX_TIME_LIMIT_S):
        raise ValueError(
            f"{where}: expected a number of seconds in (0, {MAX_TIME_LIMIT_S:g}], got {value!r}"
        )
    return seconds


def time_limit_s() -> float:
    """The per-problem time limit of this process: ``$CADSIM_PLUGIN_TIME_LIMIT_S`` or
    :data:`DEFAULT_TIME_LIMIT_S`."""
    text = os.environ.get(TIME_LIMIT_ENV, "").strip()
    return parse_time_limit(text) if text else DEFAULT_TIME_LIMIT_S


def _stop(thread: threading.Thread) -> None:
    """Ask ``thread`` to stop: :class:`_Abandoned` is raised in it at its next Python
    instruction (CPython's ``PyThreadState_SetAsyncExc``; a no-op elsewhere)."""
    try:
        set_async = ctypes.pythonapi.PyThreadState_SetAsyncExc
    except AttributeError:  # not CPython
        return
    if thread.ident is not None:
        set_async(ctypes.c_ulong(thread.ident), ctypes.py_object(_Abandoned))


def call_with_time_limit(
    label: str, fn: Callable, args: tuple, kwargs: dict, limit_s: float | None = None
) -> Any:
    """``fn(*args, **kwargs)`` on a daemon thread (with this thread's context variables), waited
    for at most ``limit_s`` seconds (None: :func:`time_limit_s`). What it raises comes back as a
    :class:`PluginError` naming ``label`` (e.g. ``"matcher 'mine'"``), the original as its
    cause; past the limit, :class:`PluginTimeout`."""
    limit = time_limit_s() if limit_s is None else parse_time_limit(limit_s, "time limit")
    outcome: dict[str, Any] = {}
    context = contextvars.copy_context()

    def target() -> None:
        try:
            outcome["value"] = context.run(fn, *args, **kwargs)
        except _Abandoned:
            pass
        except BaseException as exc:  # noqa: BLE001 - reported to the caller, whatever it is
            outcome["error"] = exc

    thread = threading.Thread(target=target, name=f"cadsim-plugin {label}", daemon=True)
    thread.start()
    thread.join(limit)
    if thread.is_alive():
        _stop(thread)
        raise PluginTimeout(
            f"{label} did not return within the time limit of {limit:g} s per problem "
            f"(${TIME_LIMIT_ENV} or --plugin-time-limit to change it)"
        )
    if "error" in outcome:
        exc = outcome["error"]
        raise PluginError(f"{label} raised {type(exc).__name__}: {exc}") from exc
    return outcome["value"]


def _shown(value: Any) -> str:
    """A short description of ``value`` for an error message."""
    if value is None:
        return "None"
    if isinstance(value, np.ndarray):
        return f"an array of shape {value.shape} and dtype {value.dtype}"
    return f"{reprlib.repr(value)} (a {type(value).__name__})"


def _as_array(label: str, what: str, value: Any) -> np.ndarray:
    try:
        arr = np.asarray(value)
    except Exception as exc:  # noqa: BLE001 - ragged lists and the like
        raise PluginError(f"{label} returned {what} that is not an array: {exc}") from None
    return arr


def _number(label: str, what: str, value: Any, *, integral: bool = False) -> None:
    """``value`` is a finite non-negative real number (an integer with ``integral``)."""
    ok = isinstance(value, int | float | np.integer | np.floating) and not isinstance(
        value, bool | np.bool_
    )
    ok = ok and math.isfinite(float(value)) and float(value) >= 0
    ok = ok and (not integral or float(value).is_integer())
    if not ok:
        kind = "a non-negative integer" if integral else "a finite number ≥ 0"
        raise PluginError(f"{label} returned {what} {_shown(value)}, expected {kind}")


def check_pairs(label: str, what: str, value: Any, n1: int, n2: int) -> np.ndarray:
    """``value`` as a (k, 2) integer array of one-to-one pairs in [0, n1) × [0, n2) (an empty
    value of any shape is no pair); :class:`PluginError` naming the first offending pair."""
    pairs = _as_array(label, what, value)
    if pairs.size == 0:
        return np.zeros((0, 2), dtype=np.int64)
    if pairs.ndim != 2 or pairs.shape[1] != 2:
        raise PluginError(f"{label} returned {what} of shape {pairs.shape}, expected (k, 2)")
    if not np.issubdtype(pairs.dtype, np.integer):
        raise PluginError(f"{label} returned {what} of dtype {pairs.dtype}, expected integers")
    outside = (pairs[:, 0] < 0) | (pairs[:, 0] >= n1) | (pairs[:, 1] < 0) | (pairs[:, 1] >= n2)
    if outside.any():
        k = int(np.flatnonzero(outside)[0])
        raise PluginError(
            f"{label} returned {what} with ({pairs[k, 0]}, {pairs[k, 1]}) at row {k}, outside "
            f"the views' {n1} x {n2} objects"
        )
    for side, column in (("i", 0), ("j", 1)):
        values, counts = np.unique(pairs[:, column], return_counts=True)
        if (counts > 1).any():
            index = int(values[np.flatnonzero(counts > 1)[0]])
            raise PluginError(
                f"{label} returned {what} that match {side} = {index} "
                f"{int(counts.max())} times, expected one-to-one pairs"
            )
    return pairs


def check_scores(label: str, what: str, value: Any, n1: int, n2: int) -> np.ndarray:
    """``value`` as an (n1, n2) real array of finite values in [0, 1]."""
    scores = _as_array(label, what, value)
    if scores.dtype.kind not in "biuf":
        raise PluginError(f"{label} returned {what} of dtype {scores.dtype}, expected numbers")
    if scores.shape != (n1, n2) and not (scores.size == 0 and n1 * n2 == 0):
        raise PluginError(f"{label} returned {what} of shape {scores.shape}, expected ({n1}, {n2})")
    if scores.size:
        finite = np.isfinite(scores)
        if not finite.all():
            nan, inf = int(np.isnan(scores).sum()), int(np.isinf(scores).sum())
            first = tuple(int(x) for x in np.argwhere(~finite)[0])
            raise PluginError(
                f"{label} returned {what} with {nan} NaN and {inf} infinite values (the first "
                f"at {first}), expected finite values in [0, 1]"
            )
        low, high = float(scores.min()), float(scores.max())
        if low < 0 or high > 1:
            raise PluginError(
                f"{label} returned {what} in [{low:g}, {high:g}], expected values in [0, 1]"
            )
    return scores


def check_matching(label: str, result: Any, n1: int, n2: int) -> None:
    """Raise :class:`PluginError` unless ``result`` keeps the matcher contract
    (docs/extending-matchers.md) on an ``n1`` × ``n2`` problem: a :class:`Matching` whose
    ``pairs`` are (k, 2) integers, one-to-one, inside the views; ``scores`` (n1, n2), finite, in
    [0, 1]; ``time_s`` finite and ≥ 0; ``iterations`` a non-negative integer."""
    if not isinstance(result, Matching):
        raise PluginError(f"{label} returned {_shown(result)}, expected a matchers.Matching")
    check_pairs(label, "pairs", result.pairs, n1, n2)
    check_scores(label, "scores", result.scores, n1, n2)
    _number(label, "time_s", result.time_s)
    _number(label, "iterations", result.iterations, integral=True)


def guard_call(
    label: str, fn: Callable, check: Callable[..., None], limit_s: float | None = None
) -> Callable:
    """``fn`` wrapped for the harness: each call runs under the time limit
    (:func:`call_with_time_limit`), then ``check(result, *args, **kwargs)`` must accept what it
    returned before it is passed on. Attributes (``requires``, ``search_space``,
    ``memory_bytes``, ...) are kept; ``plugin_label`` is ``label``."""

    @functools.wraps(fn)
    def call(*args, **kwargs):
        result = call_with_time_limit(label, fn, args, kwargs, limit_s)
        check(result, *args, **kwargs)
        return result

    call.plugin_label = label
    return call


def _check_matching_call(label: str) -> Callable[..., None]:
    def check(result, problem, *args, **options) -> None:
        check_matching(label, result, int(problem.n1), int(problem.n2))

    return check


def guard_matcher(label: str, fn: Callable, limit_s: float | None = None) -> Callable:
    """``fn`` (a matcher) wrapped by :func:`guard_call`, its result held to
    :func:`check_matching`."""
    return guard_call(label, fn, _check_matching_call(label), limit_s)
