"""One problem's k-NN tensor search done once for all the hypergraph matchers run on it.

TM, HGM, BCAGM, RRWHM, MOS and maximin each build the third-order tensor of a problem. Its costly
part, the triangle sampling and k-NN candidate search (:func:`matchers.hypergraph.tensor_build.build_tensor`),
depends only on the two views' positions, the recipe, the triangle/neighbour counts, the cap and
the state of the seeded generator (the sampling is its only draw) — not on the bandwidth
``sigma``, which matchers tune separately. Inside ``with shared_tensors():`` the first search is
kept and later matchers with the same inputs reuse it, computing only their own values::

    with shared_tensors():
        for name in ("tm", "rrwhm", "maximin"):
            get(name)(problem, seed=seed, sigma=tuned[name])

A reused search is the same search (same entries, same order), and the generator is left in the
state the search would have left it in, so every result is bit for bit what it is without
sharing. The tensor's ``info`` gains ``"reused": True`` and ``reused_s`` (the search's seconds),
and :func:`matchers.core.result.finish` charges ``reused_s`` to the matcher, so a matcher's reported
time does not depend on which matcher happened to run first. Outside the block nothing is kept,
so timing a matcher in a loop measures its search every time. The block keeps at most ``limit``
searches (least recently used dropped first).
"""

from __future__ import annotations

import contextlib
from collections import OrderedDict
from collections.abc import Callable, Iterator
from typing import TypeVar

import numpy as np

from matchers.core.problem import Problem

T = TypeVar("T")

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
    build: Callable[[], T],
) -> tuple[T, bool]:
    """(``build()``, False) — or, inside :func:`shared_tensors`, (what an identical earlier call
    built, True): same positions, same ``options``, same generator state, with ``rng`` moved on
    as ``build()`` would have moved it. ``build()`` must draw from ``rng`` and nothing else
    random, and its result must not be modified by its users."""
    if not _MEMOS:
        return build(), False
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
        built = build()
        memo[key] = (built, rng.bit_generator.state)
        while len(memo) > limit:
            memo.popitem(last=False)
        return built, False
    memo.move_to_end(key)
    built, state = kept
    rng.bit_generator.state = state
    return built, True
