"""On-disk cache of the temporal study's per-preset outcomes: one JSON file per
:func:`~eval.studies.temporal.preset.evaluate_preset` task, so a re-run of ``make reproduce``
reads the ``temporal`` and ``temporal_lidar`` stages instead of recomputing them.

``ROOT/<key>.json`` (``ROOT``: :data:`FOLDER` under the run cache's folder, ``cache/runs/temporal``
for ``make reproduce``) holds one :class:`~eval.studies.temporal.preset.PresetOutcome`: its
rows, gain rows, tuning candidates and continuity rows as lists of objects, its per-frame tables
as (columns, dtypes, values per column), and a SHA-256 of that payload. No pickle. Python's JSON
writes NaN as ``NaN`` and None as ``null``, so both come back as they were; numpy scalars are
stored as Python ones. Written to a temporary file in the same folder and renamed.

The key (:func:`task_key`) is a SHA-256 over the task (test and validation folders, preset,
methods and windows, run seeds, tune), both datasets' checksums, the run cache's code version
(:func:`eval.core.cache.code_version`: ``matchers/``, ``cadsim/``, the run's ``eval/core``
modules) and the sources of the study (``eval/studies/temporal/*.py``, ``eval/protocol/*.py``,
``eval/core/abstention.py``) and this format: editing any of them recomputes every outcome.

An entry is a local speed-up, not a trusted record: one that
:meth:`eval.core.digest_store.DigestStore.load` refuses (too large, unreadable, of another format
or key, not matching its digest), or whose shape contradicts its task (rows missing the table's keys, another set of (method, window) rows, a per-frame table of
unequal columns) is refused (:meth:`OutcomeCache.load` logs why and returns None) and recomputed.
A forger who rewrites an entry with a matching digest is not stopped (the run cache's boundary).
"""

from __future__ import annotations

import logging
from functools import cache
from pathlib import Path

from eval.core.digest_store import (
    DigestStore,
    frame_from_payload,
    frame_payload,
    key_of,
    sources_version,
)
from eval.studies.temporal.preset import PresetOutcome
from eval.studies.temporal.table import (
    COLUMNS,
    CONTINUITY_COLUMNS,
    GAIN_COLUMNS,
    ORACLE_ROW,
    TUNING_COLUMNS,
    abstains,
)

log = logging.getLogger("eval.reproduce")

FOLDER = "temporal"
"""The entries' folder under the run cache's folder (no clash with its two-hex-digit folders)."""

_FORMAT = 2
_MAX_BYTES = 256 << 20  # a preset of the full study is ~2 MB; a larger file is not one of ours
_DERIVED = frozenset(
    {"share_of_oracle", "oracle_hota", "oracle_assa", "assa_share_of_oracle"}
)  # table columns evaluate_temporal computes across presets
_ROOT = Path(__file__).resolve().parents[3]
_STUDY_SOURCES = ("eval/studies/temporal", "eval/protocol")


def _study_files() -> list[str]:
    """The study's sources, relative to the repository, in a fixed order."""
    found = [p for folder in _STUDY_SOURCES for p in sorted((_ROOT / folder).glob("*.py"))]
    names = [p.relative_to(_ROOT).as_posix() for p in found]
    return [*names, "eval/core/abstention.py", "eval/core/digest_store.py"]


@cache
def study_version() -> str:
    """Hex SHA-256 over this format and the names and contents of the study's sources."""
    return sources_version(f"temporal outcome format {_FORMAT}", _ROOT, _study_files())


def task_key(task: tuple) -> str:
    """Hex SHA-256 of an :func:`evaluate_preset` task (module docstring); raises what opening
    either dataset raises."""
    from cadsim.dataset import Dataset
    from eval.core.cache import code_version

    test_dir, val_dir, preset, methods, seeds, tune = task
    described = {
        "task": [str(Path(test_dir).resolve()), str(Path(val_dir).resolve()), preset],
        "methods": [[m, [int(w) for w in ws]] for m, ws in methods],
        "seeds": [int(s) for s in seeds],
        "tune": bool(tune),
        "checksums": [Dataset(test_dir).checksum, Dataset(val_dir).checksum],
        "code": [code_version(), study_version()],
    }
    return key_of(described)


class OutcomeCache:
    """Preset outcomes stored under `root`, one JSON file per task key."""

    def __init__(self, root: str | Path) -> None:
        self.entries = DigestStore(root, "temporal result cache", _FORMAT, _MAX_BYTES)
        self.root = self.entries.root

    def path(self, key: str) -> Path:
        return self.entries.path(key)

    def store(self, key: str, outcome: PresetOutcome) -> Path | None:
        """Write `outcome` (:meth:`DigestStore.store`); its path, or None (a warning says why)
        when it holds what this format does not restore (a per-frame dtype, a cell that is no
        number or text) or the write fails: the study goes on uncached."""
        try:
            frames = [frame_payload(f) for f in outcome.per_frame]
        except TypeError as exc:
            log.warning("temporal result cache: %s not stored (%s)", self.path(key), exc)
            return None
        payload = {
            "rows": outcome.rows,
            "gain": outcome.gain,
            "tuned": outcome.tuned,
            "continuity": outcome.continuity,
            "per_frame": frames,
        }
        return self.entries.store(key, payload)

    def load(self, key: str, task: tuple) -> PresetOutcome | None:
        """The stored outcome of `task` (whose key is `key`); None when there is none, or when
        the entry is refused (a warning names it and why)."""
        return self.entries.load(key, lambda payload: _outcome(payload, task))


def _records(payload: dict, name: str, required) -> list[dict]:
    """``payload[name]``: objects of scalar values, each with every key of `required`."""
    records = payload[name]
    if not isinstance(records, list) or not all(isinstance(r, dict) for r in records):
        raise ValueError(f"{name}: expected a list of objects")
    for k, record in enumerate(records):
        if any(isinstance(v, list | dict) for v in record.values()):
            raise ValueError(f"{name} {k}: a value that is not a table cell")
        if missing := set(required) - set(record):
            raise ValueError(f"{name} {k}: missing {sorted(missing)}")
    return records


def _outcome(payload: dict, task: tuple) -> PresetOutcome:
    """The :class:`PresetOutcome` of a read payload; ValueError if its shape contradicts `task`."""
    _, _, preset, methods, _, _ = task
    rows = _records(payload, "rows", ("method", "window", "preset"))
    expected = [(m, int(w)) for m, ws in methods for w in ws]
    if [(r["method"], r["window"]) for r in rows[:-1]] != expected or (
        not rows or rows[-1]["method"] != ORACLE_ROW
    ):
        raise ValueError("rows: not one per (method, window) of the task and the oracle's last")
    for k, row in enumerate(rows):
        scored = row["method"] == ORACLE_ROW or not abstains(row["method"], preset)
        if scored and (missing := set(COLUMNS) - _DERIVED - set(row)):
            raise ValueError(f"rows {k}: missing {sorted(missing)}")
        if row["preset"] != preset:
            raise ValueError(f"rows {k}: preset {row['preset']!r}, not {preset!r}")
    gain = _records(payload, "gain", ())
    if any(g and set(GAIN_COLUMNS) - set(g) for g in gain):
        raise ValueError("gain: a row without the gain table's columns")
    frames = payload["per_frame"]
    if not isinstance(frames, list):
        raise ValueError("per_frame: expected a list")
    return PresetOutcome(
        rows=rows,
        gain=gain,
        per_frame=[frame_from_payload(f, f"per_frame {k}") for k, f in enumerate(frames)],
        tuned=_records(payload, "tuned", TUNING_COLUMNS),
        continuity=_records(payload, "continuity", CONTINUITY_COLUMNS),
    )
