"""Optional numba compilation for the few hot loops numpy cannot vectorise or runs slowly (the
Sinkhorn sweeps of :mod:`matchers.blocks.sinkhorn`, the tensor products, degrees and worst-case weights
of :mod:`matchers.hypergraph.tensor_product`, TM's iteration, the candidate search, and the tensor
builder's match indices and exp(-d / sigma) values, :mod:`matchers.core.portable_exp`).

``njit(fn)`` returns the compiled function when numba imports, else None — callers keep their
numpy implementation and use it whenever the compiled one is missing, so numba is an accelerator,
never a requirement. A numba that is installed but fails to import (broken against this numpy, or
a module of the same name as one it imports shadowing it, e.g. a ``timeit.py`` in the script's
directory) logs one warning saying so: the results are the same, the speed is not. Every compiled
kernel performs the same floating-point operations in the same order as its numpy twin (the exp
included: both use the portable one), tested bit for bit in ``tests/test_jit_kernels.py``, so
results do not depend on whether numba is installed.

Compiled code is cached on disk so that worker processes load it instead of compiling it again
(≈ 1.5 s per kernel). The cache lives in ``$CADSIM_CACHE_DIR/numba`` (default
``~/.cache/cadsim/numba``, or ``$XDG_CACHE_HOME/cadsim/numba``), never beside the installed
code; an explicit ``NUMBA_CACHE_DIR`` wins. ``CADSIM_NO_JIT=1`` turns compilation off.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable
from functools import cache
from pathlib import Path

log = logging.getLogger(__name__)


def cache_root() -> Path:
    """The user's cadsim cache: ``$CADSIM_CACHE_DIR``, else ``$XDG_CACHE_HOME/cadsim``, else
    ``~/.cache/cadsim`` — never the current folder."""
    root = os.environ.get("CADSIM_CACHE_DIR")
    if not root:
        base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
        root = str(Path(base) / "cadsim")
    return Path(root)


def cache_dir() -> Path:
    """Where compiled kernels are cached (see the module docstring)."""
    return cache_root() / "numba"


@cache
def _numba():
    if os.environ.get("CADSIM_NO_JIT", "").strip() not in ("", "0"):
        return None
    os.environ.setdefault("NUMBA_CACHE_DIR", str(cache_dir()))
    try:
        import numba
    except ModuleNotFoundError as exc:
        if exc.name != "numba":  # installed, but something it imports is missing or shadowed
            _fallback(exc)
        return None
    except Exception as exc:  # broken against this numpy, a shadowing module, ...
        _fallback(exc)
        return None
    return numba


def _fallback(exc: BaseException) -> None:
    """Say once per process why the compiled kernels are off."""
    if _WARNED:
        return
    _WARNED.append(exc)
    log.warning(
        "numba is installed but failed to import (%s: %s); the numpy kernels run instead — the "
        "same results, several times slower",
        type(exc).__name__,
        exc,
    )


_WARNED: list[BaseException] = []  # the failure already reported, if any


def njit(fn: Callable) -> Callable | None:
    """`fn` compiled with numba (nopython, cached on disk), or None without numba."""
    numba = _numba()
    try:
        return None if numba is None else numba.njit(cache=True, nogil=True)(fn)
    except (
        AttributeError
    ) as exc:  # numba half-imported (an import cycle through a shadowing module)
        _fallback(exc)
        return None
