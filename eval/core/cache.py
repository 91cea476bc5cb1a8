"""On-disk result cache: one ``.npz`` per run, keyed by :meth:`eval.core.tasks.RunSpec.key`.

``ROOT/ab/abcdef….npz`` holds one :class:`eval.core.tasks.RunResult`: its spec and per-pair metadata
as JSON, and the ragged per-pair arrays (ground truth, Hungarian assignment, soft score matrix)
concatenated with offsets. Written to a temporary file in the same directory and renamed, so a
reader never sees half a file and an interrupted sweep leaves only complete entries. No pickle.

The code version in every key is a SHA-256 over the source of everything that shapes a run's
result: the ``matchers`` and ``cadsim`` packages (matchers, dataset reading, depth noise,
detection), ``eval/core/tasks.py`` and ``eval/core/thinning.py`` — any edit there invalidates the cache;
a plug-in matcher's runs also carry its own module file's hash (:mod:`eval.core.matcher_source`).

An entry is a local speed-up, not a trusted record: :meth:`ResultCache.load` bounds every array a
``.npy`` header declares and refuses (:class:`StaleEntry`) one whose contents contradict themselves
(:mod:`eval.core.cache_checks`); the runner also holds it against the dataset and recomputes it.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
import zipfile
import zlib
from dataclasses import asdict
from functools import cache
from pathlib import Path

import numpy as np

from eval.core.cache_checks import StaleEntry, check_result, is_hungarian, read_bounded
from eval.core.tasks import MatcherSpec, PairOutcome, RunResult, RunSpec

DEFAULT_CACHE = "cache/runs"  # make reproduce's, inside the repository; commands use user_cache()
# 4: the positions, true pose, broadcast prior pose and camera mounts of every pair;
# 5: whether each pair's assignment is the Hungarian of its scores ("hungarian")
_FORMAT = 5

# Sources that cannot change a run's result (how tasks are dispatched, the CLI, drawing, benches):
# left out of the code version so editing them does not invalidate the cache. Everything else
# under matchers/ and cadsim/ counts (erring towards re-computation).
_NOT_RESULT_SHAPING = (
    "cadsim/generation/executor.py",
    "cadsim/generation/executors.py",
    "cadsim/generation/local_executor.py",
    "cadsim/generation/dask_executor.py",
    "cadsim/__main__.py",
    "cadsim/cli.py",
    "cadsim/commands/",
    "cadsim/pair_drawing.py",
    "cadsim/dataset/regime.py",  # a dataset's summary card, never read by a run
)


def _source_files() -> list[tuple[str, Path]]:
    """(name relative to the source root, path) of every result-shaping source file."""
    import cadsim
    import matchers

    files = []
    for package in (matchers, cadsim):
        root = Path(list(package.__path__)[0])
        for p in sorted(root.rglob("*.py")):
            name = p.relative_to(root.parent).as_posix()
            if not name.startswith(_NOT_RESULT_SHAPING):
                files.append((name, p))
    for name in ("tasks.py", "thinning.py", "pose_metrics.py"):
        files.append((f"eval/core/{name}", Path(__file__).with_name(name)))
    return files


@cache
def code_version() -> str:
    """Hex SHA-256 (first 16 digits) over the cache's format and the names and contents of the
    result-shaping sources (a new format never meets an entry of an older one)."""
    h = hashlib.sha256(f"cache format {_FORMAT}\0".encode())
    for name, path in _source_files():
        h.update(name.encode() + b"\0")
        h.update(hashlib.sha256(path.read_bytes()).digest())
    return h.hexdigest()[:16]


def _ragged(arrays: list[np.ndarray], name: str, dtype) -> dict[str, np.ndarray]:
    flat = np.concatenate([a.reshape(-1) for a in arrays]) if arrays else np.zeros(0, dtype)
    counts = np.array([a.size for a in arrays], dtype=np.int64)
    return {name: flat.astype(dtype), f"{name}_offsets": np.concatenate([[0], np.cumsum(counts)])}


def _unragged(data, name: str) -> list[np.ndarray]:
    """The per-pair arrays of `name`; ValueError unless its offsets run from 0 to its length,
    never decreasing."""
    flat, offsets = data[name], data[f"{name}_offsets"]
    if (
        flat.ndim != 1
        or offsets.ndim != 1
        or offsets.dtype.kind not in "iu"
        or len(offsets) == 0
        or offsets[0] != 0
        or offsets[-1] != len(flat)
        or (np.diff(offsets) < 0).any()
    ):
        raise ValueError(f"{name}: offsets do not partition its {flat.size} values")
    return [flat[a:b] for a, b in zip(offsets[:-1], offsets[1:], strict=True)]


def _size(value) -> int:
    """A stored view size: an int ≥ 0 (ValueError otherwise, before it shapes any reshape)."""
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise ValueError(f"view size: expected an integer ≥ 0, got {value!r}")
    return value


def _spec_from_dict(d: dict) -> RunSpec:
    m = d["matcher"]
    options = tuple((k, v) for k, v in m["options"])
    return RunSpec(
        dataset_checksum=d["dataset_checksum"],
        matcher=MatcherSpec(m["name"], options),
        seed=int(d["seed"]),
        noise_rate=None if d["noise_rate"] is None else float(d["noise_rate"]),
        code_version=d["code_version"],
        limit=None if d.get("limit") is None else int(d["limit"]),
        keep=None if d.get("keep") is None else float(d["keep"]),
        localisation=_localisation(d.get("localisation")),
        views=None if d.get("views") is None else (int(d["views"][0]), int(d["views"][1])),
        sensor=d.get("sensor"),
    )


class ResultCache:
    """Runs stored under `root`, one file per :class:`RunSpec` key."""

    def __init__(self, root: str | Path) -> None:
        self.root = Path(root)

    def path(self, spec: RunSpec) -> Path:
        key = spec.key()
        return self.root / key[:2] / f"{key}.npz"

    def __contains__(self, spec: RunSpec) -> bool:
        """Whether a complete entry exists. A truncated one (a disk filled up, a copy cut short:
        no zip directory at its end) counts as absent, so the runner recomputes and replaces it."""
        path = self.path(spec)
        return path.is_file() and zipfile.is_zipfile(path)

    def store(self, result: RunResult) -> Path:
        """Write `result` atomically (temporary file + rename); returns its path."""
        path = self.path(result.spec)
        path.parent.mkdir(parents=True, exist_ok=True)
        outcomes = result.outcomes
        meta = {
            "format": _FORMAT,
            "spec": asdict(result.spec),
            "dataset_dir": result.dataset_dir,
            "wall_s": result.wall_s,
            "pairs": [
                {
                    k: getattr(o, k)
                    for k in ("index", "name", "episode", "sim_seed", "checksum", "n1", "n2")
                }
                | {
                    "time_s": o.time_s,
                    "iterations": o.iterations,
                    "hungarian": is_hungarian(o.assigned, o.scores),
                }
                for o in outcomes
            ],
        }
        arrays = {
            "meta": np.array(json.dumps(meta)),
            **_ragged([o.gt_pairs for o in outcomes], "gt_pairs", np.int64),
            **_ragged([o.assigned for o in outcomes], "assigned", np.int64),
            **_ragged([o.scores for o in outcomes], "scores", np.float64),
            **_ragged([_points(o.points1, o.n1) for o in outcomes], "points1", np.float64),
            **_ragged([_points(o.points2, o.n2) for o in outcomes], "points2", np.float64),
            "pose": np.array([_pose_row(o) for o in outcomes], dtype=np.float64).reshape(
                -1, _POSE_ROW
            ),
        }
        fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix=".npz", dir=path.parent)
        try:
            with os.fdopen(fd, "wb") as f:
                np.savez_compressed(f, **arrays)
            os.replace(tmp, path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
        return path

    def load(self, spec: RunSpec, checked: bool = True, raw: bytes | None = None) -> RunResult:
        """The cached result of `spec`; ``KeyError`` if absent, ``ValueError`` if unreadable,
        :class:`StaleEntry` (a ValueError) if its contents contradict themselves.
        ``checked=False``: the read-time checks of an untrusted entry are skipped — only for
        an entry this process has just stored (the runner's read-back of what it computed).
        ``raw``: the entry file's bytes, when the caller has read them already."""
        path = self.path(spec)
        if raw is None and not path.is_file():
            raise KeyError(f"{path}: no cached result for {spec}")
        try:
            data = read_bounded(path, raw)  # the bounds hold whether or not `checked`: one pass
            meta = json.loads(str(data["meta"]))
            gts = _unragged(data, "gt_pairs")
            assigned = _unragged(data, "assigned")
            scores = _unragged(data, "scores")
            points1 = _unragged(data, "points1")
            points2 = _unragged(data, "points2")
            pose = data["pose"]
        except StaleEntry:
            raise
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
            raise ValueError(
                f"{path}: unreadable cache entry ({exc}); delete it to recompute"
            ) from exc
        try:
            belongs = meta.get("format") == _FORMAT and _spec_from_dict(meta["spec"]) == spec
        except (AttributeError, KeyError, TypeError, ValueError, IndexError):
            belongs = False
        if not belongs:
            raise ValueError(f"{path}: cache entry does not belong to {spec}; delete it")
        try:
            result = _result(spec, meta, gts, assigned, scores, points1, points2, pose)
        except (AttributeError, KeyError, TypeError, ValueError, IndexError) as exc:
            raise StaleEntry(f"{path}: malformed cache entry ({exc})") from exc
        if checked:
            check_result(result, [bool(p.get("hungarian")) for p in meta["pairs"]], path)
        return result


def _result(spec, meta, gts, assigned, scores, points1, points2, pose) -> RunResult:
    """The :class:`RunResult` of a read entry (shapes as stored; :func:`check_result` judges)."""
    pairs = meta["pairs"]
    if not (len(pairs) == len(gts) == len(assigned) == len(scores) == len(pose)):
        raise ValueError(f"{len(pairs)} pairs but {len(scores)} score matrices, {len(pose)} poses")
    outcomes = [
        PairOutcome(
            **{k: p[k] for k in ("index", "name", "episode", "sim_seed", "checksum", "n1", "n2")},
            gt_pairs=g.reshape(-1, 2),
            assigned=a.reshape(-1, 2),
            scores=s.reshape(_size(p["n1"]), _size(p["n2"])),
            time_s=float(p["time_s"]),
            iterations=int(p["iterations"]),
            **_pose_fields(q1, _size(p["n1"]), q2, _size(p["n2"]), row),
        )
        for p, g, a, s, q1, q2, row in zip(
            pairs, gts, assigned, scores, points1, points2, pose, strict=True
        )
    ]
    return RunResult(spec, str(meta["dataset_dir"]), outcomes, float(meta["wall_s"]))


def _points(points: np.ndarray | None, n: int) -> np.ndarray:
    """A pair's positions for storage: (n, D) as given, or an empty array when not kept."""
    return np.zeros(0) if points is None else np.asarray(points, dtype=np.float64).reshape(-1)


_POSE_ROW = 16 + 16 + 32 + 1
"""Stored pose fields of one outcome: true pose (16), prior pose (16), the two camera mounts
(32), each NaN when unknown, and whether the positions were kept (1/0)."""


def _pose_row(outcome: PairOutcome) -> np.ndarray:
    """(:data:`_POSE_ROW`,) true pose, broadcast prior pose, camera → body mounts (NaN where
    unknown), whether the positions were kept (1/0)."""
    row = np.full(_POSE_ROW, np.nan)
    for start, value, size in ((0, outcome.true_pose, 16), (16, outcome.prior_pose, 16), (32, outcome.extrinsics, 32)):  # fmt: skip
        if value is not None:
            row[start : start + size] = np.asarray(value, dtype=np.float64).reshape(size)
    row[64] = outcome.points1 is not None and outcome.points2 is not None
    return row


def _pose_fields(q1: np.ndarray, n1: int, q2: np.ndarray, n2: int, row: np.ndarray) -> dict:
    """The pose fields of a stored pair (:func:`_points`, :func:`_pose_row` reversed)."""
    kept = row[64] == 1
    return {
        "points1": _shaped(q1, n1) if kept else None,
        "points2": _shaped(q2, n2) if kept else None,
        "true_pose": None if np.isnan(row[0]) else row[:16].reshape(4, 4),
        "prior_pose": None if np.isnan(row[16]) else row[16:32].reshape(4, 4),
        "extrinsics": None if np.isnan(row[32]) else row[32:64].reshape(2, 4, 4),
    }


def _shaped(flat: np.ndarray, n: int) -> np.ndarray:
    """(n, D) positions from their stored flat form (an empty view: (0, 3))."""
    return flat.reshape(n, -1) if n else np.zeros((0, 3))


def _localisation(value) -> tuple[float, float] | str | None:
    """A stored run's localisation: None, a preset's name, or (position sigma, yaw sigma)."""
    if value is None or isinstance(value, str):
        return value
    return tuple(float(v) for v in value)
