"""One problem's tensor built once for all the hypergraph matchers run on it.

TM, HGM, BCAGM, RRWHM, MOS and maximin each build the third-order tensor of a problem from the
same inputs — the two views' positions, the tensor options and the state of the seeded generator
(the triangle sampling is its first draw) — so when several of them run on one problem with the
same seed, they build the same tensor. Inside ``with shared_tensors():`` the first build is kept
and the others reuse it::

    with shared_tensors():
        for name in ("tm", "rrwhm", "maximin"):
            get(name)(problem, seed=seed)

A reused tensor is the same tensor (same entries, same order), and the generator is left in the
state the build would have left it in, so every result is bit for bit what it is without sharing.
Its ``info`` gains ``"reused": True`` and each matcher is charged the original build time
(:func:`matchers.result.finish` adds ``info["build_s"]``), so a matcher's reported time does
not depend on which matcher happened to run first. Outside the block nothing is kept, so timing a
matcher in a loop measures its build every time. The block keeps at most ``limit`` tensors
(least recently used dropped first): several option sets may run on one problem.
"""

from __future__ import annotations

import contextlib
from collections import OrderedDict
from collections.abc import Callable, Iterator

import numpy as np

from .problem import Problem
from .sparse_tensor import SparseTensor

_MEMOS: list[tuple[OrderedDict, int]] = []


@contextlib.contextmanager
def shared_tensors(limit: int = 4) -> Iterator[None]:
    """Within the block, a tensor built for a problem is reused by later matchers that would
    build the same one (module docstring); at most ``limit`` tensors are kept."""
    if limit < 1:
        raise ValueError(f"limit: expected a positive integer, got {limit!r}")
    _MEMOS.append((OrderedDict(), int(limit)))
    try:
        yield
    finally:
        _MEMOS.pop()


def build_or_reuse(
    problem: Problem,
    rng: np.random.Generator,
    options: tuple,
    build: Callable[[], SparseTensor],
) -> SparseTensor:
    """``build()`` — or, inside :func:`shared_tensors`, the tensor an identical earlier call
    built (same positions, same ``options``, same generator state), with ``rng`` moved on as
    ``build()`` would have moved it."""
    if not _MEMOS:
        return build()
    memo, limit = _MEMOS[-1]
    key = (
        options,
        problem.points1.shape,
        problem.points2.shape,
        np.ascontiguousarray(problem.points1).tobytes(),
        np.ascontiguousarray(problem.points2).tobytes(),
        repr(rng.bit_generator.state),
    )
    kept = memo.get(key)
    if kept is None:
        tensor = build()
        memo[key] = (tensor, rng.bit_generator.state)
        while len(memo) > limit:
            memo.popitem(last=False)
        return tensor
    memo.move_to_end(key)
    tensor, state = kept
    rng.bit_generator.state = state
    return tensor.reused()
