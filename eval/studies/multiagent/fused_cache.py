"""On-disk cache of the multi-agent study's fused rows (the ``per_snapshot`` table of
:func:`~eval.studies.multiagent.evaluation.evaluate_multiagent`): a re-run of ``make reproduce``
reads it instead of loading every two-view run, calibrating τ and running every fusion on every
snapshot again (≈ 35 s of a fully cached rerun).

``ROOT/<key>.json`` (``ROOT``: :data:`FOLDER` under the run cache's folder, ``cache/runs/
multiagent`` for ``make reproduce``) in the form of :mod:`eval.core.digest_store`. The key
(:func:`fused_key`) is a SHA-256 over the result-cache keys of every two-view run the table is
made of (each names its dataset's checksum, matcher, options, seed, preset, views and code
version, a plug-in's source included), the row labels, subsets, presets, seeds and fusions, and
the sources of the study (``eval/studies/multiagent/*.py``, ``eval/protocol/*.py``,
``eval/core/abstention.py``, ``eval/core/digest_store.py``): editing any of them recomputes
the table. A fusion that is not a built-in (a plug-in, or a name re-registered) is never cached:
its code is in no key.

An entry that :meth:`~eval.core.digest_store.DigestStore.load` refuses, or whose table lacks a
column of the fused rows or holds other (split, N, preset, matcher, seed, fusion) groups than the
task's, is logged and recomputed.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from functools import cache
from pathlib import Path

import pandas as pd

from eval.core.digest_store import (
    DigestStore,
    frame_from_payload,
    frame_payload,
    key_of,
    sources_version,
)
from eval.protocol.multiway_metrics import MultiwayCounts
from matchers.fusion import get_fusion

log = logging.getLogger("eval.reproduce")

FOLDER = "multiagent"
"""The entries' folder under the run cache's folder (no clash with its two-hex-digit folders)."""

_FORMAT = 1
_MAX_BYTES = 256 << 20  # the full study's table is ~5 MB; a larger file is not one of ours
_ROOT = Path(__file__).resolve().parents[3]
_STUDY_SOURCES = ("eval/studies/multiagent", "eval/protocol")
_GROUP = ("split", "n_agents", "preset", "matcher", "seed", "fusion")
REQUIRED = (
    *_GROUP,
    "snapshot",
    "episode",
    "seconds",
    "fusion_s",
    *MultiwayCounts.__dataclass_fields__,
)
"""The columns every stored table has."""


@cache
def study_version() -> str:
    """Hex SHA-256 over this format and the names and contents of the study's sources."""
    found = [p for folder in _STUDY_SOURCES for p in sorted((_ROOT / folder).glob("*.py"))]
    names = [p.relative_to(_ROOT).as_posix() for p in found]
    names += ["eval/core/abstention.py", "eval/core/digest_store.py"]
    return sources_version(f"multiagent fused format {_FORMAT}", _ROOT, names)


def cacheable(fusions: Mapping[str, object]) -> bool:
    """Whether every fusion of {name: the callable the harness runs} is a built-in (run as it
    is, not wrapped by :func:`matchers.fusion.checked_fusion`)."""
    return all(fn is get_fusion(name) for name, fn in fusions.items())


def fused_key(
    run_keys: Sequence[str],
    labels: Sequence[str],
    subsets: Mapping[int, Sequence[int]],
    presets: Sequence[str],
    seeds: Sequence[int],
    fusions: Sequence[str],
) -> str:
    """Hex SHA-256 of the table's inputs (module docstring)."""
    described = {
        "runs": list(run_keys),
        "labels": list(labels),
        "subsets": [[int(n), [int(v) for v in views]] for n, views in subsets.items()],
        "presets": list(presets),
        "seeds": [int(s) for s in seeds],
        "fusions": list(fusions),
        "code": study_version(),
    }
    return key_of(described)


class FusedCache:
    """Fused-row tables stored under `root`, one JSON file per key."""

    def __init__(self, root: str | Path) -> None:
        self.entries = DigestStore(root, "multi-agent result cache", _FORMAT, _MAX_BYTES)
        self.root = self.entries.root

    def store(self, key: str, per_snapshot: pd.DataFrame) -> Path | None:
        """Write the table; its path, or None (a warning says why)."""
        try:
            payload = {"per_snapshot": frame_payload(per_snapshot)}
        except TypeError as exc:
            log.warning("multi-agent result cache: %s not stored (%s)", self.entries.path(key), exc)
            return None
        return self.entries.store(key, payload)

    def load(self, key: str, groups: set[tuple]) -> pd.DataFrame | None:
        """The stored table under `key` if it holds exactly the (split, N, preset, matcher,
        seed, fusion) `groups`; None otherwise (a refusal is logged)."""
        return self.entries.load(key, lambda payload: _table(payload, groups))


def _table(payload: dict, groups: set[tuple]) -> pd.DataFrame:
    table = frame_from_payload(payload["per_snapshot"], "per_snapshot")
    if missing := set(REQUIRED) - set(table.columns):
        raise ValueError(f"per_snapshot: missing {sorted(missing)}")
    found = set(table[list(_GROUP)].drop_duplicates().itertuples(index=False, name=None))
    if found != groups:
        raise ValueError("per_snapshot: not the task's (split, N, preset, matcher, seed) groups")
    return table
