"""The fusion contract, checked at the harness boundary for plug-in fusions
(:mod:`matchers.core.plugin_guard` has the matchers' half and the time limit).

A fusion ``fusion(evidence) -> Universe`` on N views of ``evidence.sizes`` detections must return
a :class:`~matchers.fusion.universe.Universe` whose

* ``labels`` are N integer arrays, view k's of length ``sizes[k]``, each label in [0, count), no
  label twice in one view (an object holds at most one detection of a view);
* ``count`` is a non-negative integer, the number of distinct labels (every object holds a
  detection);
* ``pairs`` maps view pairs (i, j), 0 ≤ i < j < N, to (K, 2) integer pairs inside the two views,
  one to one; with ``fused`` true they are exactly the pairs of detections sharing a label (the
  cycle consistency the metrics rely on), with ``fused`` false any one-to-one pairs
  (``independent``: the input's);
* ``fused`` is a bool and ``time_s`` finite and ≥ 0.

Every breach is a :class:`~matchers.core.plugin_guard.PluginError` naming the fusion and what it
returned. The checks only read.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from matchers.core.plugin_guard import (
    PluginError,
    _as_array,
    _number,
    _shown,
    check_pairs,
    guard_call,
)
from matchers.fusion.evidence import PairwiseEvidence
from matchers.fusion.universe import Universe

__all__ = ["check_universe", "guard_fusion"]


def _labels(label: str, result: Universe, sizes: tuple[int, ...]) -> list[np.ndarray]:
    labels = result.labels
    if not isinstance(labels, tuple | list) or len(labels) != len(sizes):
        raise PluginError(
            f"{label} returned labels {_shown(labels)}, expected one array per view "
            f"({len(sizes)} views)"
        )
    out = []
    for k, (view, size) in enumerate(zip(labels, sizes, strict=True)):
        arr = _as_array(label, f"labels of view {k}", view)
        if arr.size == 0 and size == 0:
            out.append(arr.reshape(0).astype(np.int64))
            continue
        if arr.shape != (size,):
            raise PluginError(
                f"{label} returned labels of view {k} of shape {arr.shape}, expected ({size},)"
            )
        if not np.issubdtype(arr.dtype, np.integer):
            raise PluginError(
                f"{label} returned labels of view {k} of dtype {arr.dtype}, expected integers"
            )
        out.append(arr)
    return out


def check_universe(label: str, result: Any, evidence: PairwiseEvidence) -> None:
    """Raise :class:`PluginError` unless ``result`` keeps the fusion contract on ``evidence``
    (module docstring)."""
    if not isinstance(result, Universe):
        raise PluginError(f"{label} returned {_shown(result)}, expected a matchers.fusion.Universe")
    sizes = evidence.sizes
    labels = _labels(label, result, sizes)
    for k, view in enumerate(labels):
        values, counts = np.unique(view, return_counts=True)
        if (counts > 1).any():
            raise PluginError(
                f"{label} returned object {int(values[np.flatnonzero(counts > 1)[0]])} holding "
                f"{int(counts.max())} detections of view {k}, expected at most one per view"
            )
    _number(label, "count", result.count, integral=True)
    count = int(result.count)
    flat = np.concatenate(labels) if labels else np.empty(0, np.int64)
    if flat.size and (flat.min() < 0 or flat.max() >= count):
        raise PluginError(
            f"{label} returned labels in [{flat.min()}, {flat.max()}] with count {count}, "
            f"expected labels in [0, count)"
        )
    distinct = len(np.unique(flat))
    if distinct != count:
        raise PluginError(f"{label} returned count {count} but its labels name {distinct} objects")
    if not isinstance(result.fused, bool | np.bool_):
        raise PluginError(f"{label} returned fused {_shown(result.fused)}, expected a bool")
    if not isinstance(result.pairs, dict):
        raise PluginError(f"{label} returned pairs {_shown(result.pairs)}, expected a dict")
    pairs = {}
    for key, value in result.pairs.items():
        ok = isinstance(key, tuple) and len(key) == 2
        ok = ok and all(isinstance(v, int | np.integer) and not isinstance(v, bool) for v in key)
        if not ok or not 0 <= key[0] < key[1] < len(sizes):
            raise PluginError(
                f"{label} returned pairs keyed {_shown(key)}, expected views (i, j) with "
                f"0 <= i < j < {len(sizes)}"
            )
        i, j = int(key[0]), int(key[1])
        pairs[(i, j)] = check_pairs(label, f"pairs {key}", value, sizes[i], sizes[j])
    if result.fused:
        for i in range(len(sizes)):
            for j in range(i + 1, len(sizes)):
                declared = pairs.get((i, j), np.empty((0, 2), np.int64))
                same = labels[i][declared[:, 0]] == labels[j][declared[:, 1]]
                if not same.all():
                    a, b = declared[np.flatnonzero(~same)[0]]
                    raise PluginError(
                        f"{label} returned fused pairs ({i}, {j}) joining detections {a} and {b} "
                        f"of different objects, expected the pairs its labels imply"
                    )
                implied = len(np.intersect1d(labels[i], labels[j]))
                if len(declared) != implied:
                    raise PluginError(
                        f"{label} returned {len(declared)} fused pairs ({i}, {j}) where its "
                        f"labels imply {implied}, expected the pairs its labels imply"
                    )
    _number(label, "time_s", result.time_s)


def guard_fusion(label: str, fn, limit_s: float | None = None):
    """``fn`` (a fusion) wrapped for the harness: each call runs under the time limit and its
    result passes :func:`check_universe` before it is returned."""

    def check(result, evidence, *args, **options) -> None:
        check_universe(label, result, evidence)

    return guard_call(label, fn, check, limit_s)
