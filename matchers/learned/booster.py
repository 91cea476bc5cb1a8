"""The one place LightGBM reads a model file's trees and predicts with them.

LightGBM reports a fatal error by printing ``[LightGBM] [Fatal] ...`` to the process's stderr
(``fprintf``, before it throws) and other messages to stdout when no logger is registered; a user
would see those lines before, or instead of, cadsim's one-line error. So every call goes through
:func:`captured_output`, which points file descriptors 1 and 2 at a temporary file for the call
(under a process-wide lock: two threads never swap them at once) and sends what LightGBM wrote to
debug logging (``cadsim -v`` shows it). The trees LightGBM is given were checked first
(:mod:`matchers.learned.trees`); the error a user sees names the file and the key.
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import logging
import os
import sys
import tempfile
import threading

import numpy as np

log = logging.getLogger(__name__)

_LOCK = threading.RLock()
_KEEP = 1 << 16  # bytes of captured output kept for the debug log


class _LightGBMLog:
    """LightGBM's messages through its Python logger, to debug logging."""

    def info(self, msg: str) -> None:
        log.debug("lightgbm: %s", msg.strip())

    def warning(self, msg: str) -> None:
        log.debug("lightgbm: %s", msg.strip())


@functools.cache
def _libc():
    try:
        return ctypes.CDLL(None)
    except OSError:  # pragma: no cover - no C library to flush
        return None


def _flush_c_streams() -> None:
    """C's stdio buffers out (``fflush(NULL)``), so that nothing written before the swap lands
    in the capture, nor anything LightGBM wrote after it."""
    libc = _libc()
    if libc is not None:
        with contextlib.suppress(Exception):
            libc.fflush(None)


@contextlib.contextmanager
def captured_output():
    """File descriptors 1 and 2 go to a temporary file while the block runs; what was written
    there goes to debug logging. A descriptor that is not open is left alone."""
    with _LOCK:
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(Exception):
                stream.flush()
        _flush_c_streams()
        with tempfile.TemporaryFile() as sink:
            saved = {}
            for fd in (1, 2):
                try:
                    saved[fd] = os.dup(fd)
                except OSError:
                    continue
                os.dup2(sink.fileno(), fd)
            try:
                yield
            finally:
                _flush_c_streams()
                for fd, copy in saved.items():
                    os.dup2(copy, fd)
                    os.close(copy)
                sink.seek(0)
                text = sink.read(_KEEP).decode("utf-8", "replace").strip()
                if text:
                    log.debug("lightgbm output: %s", text)


def parse_booster(text: str):
    """A LightGBM booster of the checked, canonical ``text``; ValueError with LightGBM's first
    line when it still refuses it."""
    import lightgbm

    lightgbm.register_logger(_LightGBMLog())
    try:
        with captured_output():
            return lightgbm.Booster(model_str=text, params={"num_threads": 1, "verbosity": -1})
    except lightgbm.basic.LightGBMError as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else "unreadable"
        raise ValueError(f"not a LightGBM model ({first[:200]})") from None


def predict(booster, features: np.ndarray) -> np.ndarray:
    """P(match) of each row of ``features`` (one thread)."""
    with captured_output():
        return np.asarray(booster.predict(features, num_threads=1), dtype=float)
