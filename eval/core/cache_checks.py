"""What a cached run must satisfy before the result cache serves it.

The cache (:mod:`eval.core.cache`) is a local speed-up, not a trusted record: an entry that a disk
error, a stray script or a hand edit has changed must be recomputed, never scored. Three layers,
each cheap enough for a fully cached re-run (one Hungarian assignment per frame pair of an entry,
the dataset's manifest and stored detections read once per process):

- :func:`read_bounded`: before a member's data are read, its ``.npy`` header's declared size is
  held to what its zip member holds (and that to what deflate can expand), so a forged header
  asking for 10¹² items is refused instead of allocated (the archive is read in one pass);
- :func:`check_result`: the entry against itself — view sizes and every index inside them, one-to-one
  assignments and ground truth, finite scores in [0, 1], finite non-negative times, and each
  assignment that was the Hungarian assignment of its scores when stored still being it;
- :func:`disagreement`: the entry against its dataset — as many frame pairs, in order, with the
  manifest's names and checksums, and, for runs on the stored detections, the records' own view
  sizes and ground truth; :func:`inconsistent_groups`: runs that must share their ground truth
  (same data, other matchers) do.

Imports numpy and, lazily, scipy's assignment solver and the dataset reader.
"""

from __future__ import annotations

import math
import zipfile
import zlib
from collections.abc import Sequence
from functools import lru_cache
from pathlib import Path

import numpy as np

# deflate expands at most ~1032:1; a member claiming more than this is not what it says
_MAX_RATIO = 1100
_SLACK_BYTES = 1 << 16


class StaleEntry(ValueError):
    """A cache entry that cannot be served (it contradicts itself or its dataset): recompute it."""


def read_bounded(path: Path, raw: bytes | None = None) -> dict[str, np.ndarray]:
    """Every array of the ``.npz`` at `path` ({name: array}, in one pass over the archive), each
    member held to its bounds before its data are read; :class:`StaleEntry` if a member declares
    more than deflate can expand to, its header declares more bytes than the member holds or a
    non-numeric dtype, or its data are cut short. ``raw``: the file's bytes, already read."""
    import io

    from numpy.lib import format as npy

    arrays = {}
    try:
        with zipfile.ZipFile(path if raw is None else io.BytesIO(raw)) as archive:
            for member in archive.infolist():
                if member.file_size > _MAX_RATIO * member.compress_size + _SLACK_BYTES:
                    raise StaleEntry(
                        f"{path}: {member.filename}: declares {member.file_size} bytes from "
                        f"{member.compress_size} compressed; delete it to recompute"
                    )
                with archive.open(member) as f:
                    version = npy.read_magic(f)
                    reader = (
                        npy.read_array_header_1_0
                        if version == (1, 0)
                        else npy.read_array_header_2_0
                    )
                    shape, fortran, dtype = reader(f)
                    if dtype.hasobject or any(int(s) < 0 for s in shape):
                        raise StaleEntry(
                            f"{path}: {member.filename}: dtype {dtype} or shape {shape}"
                        )
                    declared = math.prod(int(s) for s in shape) * dtype.itemsize
                    if declared > member.file_size:
                        raise StaleEntry(
                            f"{path}: {member.filename}: header declares shape {shape} "
                            f"({declared} bytes) in a member of {member.file_size}; delete it "
                            "to recompute"
                        )
                    data = bytearray(f.read(declared))  # writable, as np.load's arrays are
                if len(data) != declared:
                    raise StaleEntry(f"{path}: {member.filename}: its data are cut short")
                flat = np.frombuffer(data, dtype=dtype)
                name = member.filename.removesuffix(".npy")
                arrays[name] = flat.reshape(shape, order="F" if fortran else "C")
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
        if isinstance(exc, StaleEntry):
            raise
        raise StaleEntry(f"{path}: unreadable cache entry ({exc}); delete it to recompute") from exc
    return arrays


def _sorted_pairs(pairs: np.ndarray) -> np.ndarray:
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]


def is_hungarian(assigned: np.ndarray, scores: np.ndarray) -> bool:
    """Whether `assigned` is, in any order, the full Hungarian assignment of the canonical
    `scores` (``matchers.core.discretise.discretise(scores)``) — what every built-in matcher
    declares; a plug-in may declare its own. `scores` as the runs store them: already
    canonical, so scipy's assignment is called on them directly."""
    from scipy.optimize import linear_sum_assignment

    scores = np.asarray(scores, dtype=float)
    if scores.ndim != 2 or not np.isfinite(scores).all():
        return False
    rows, cols = linear_sum_assignment(scores, maximize=True)
    return np.array_equal(_sorted_pairs(assigned), np.stack([rows, cols], axis=1))


def _hungarian_one_to_one(assigned: np.ndarray, scores: np.ndarray) -> bool:
    """:func:`is_hungarian` for an `assigned` already known to be one-to-one inside the views
    and `scores` already known to be finite (what :func:`check_result` has checked by then):
    the same answer, without sorting — as many pairs as the assignment, each one of its pairs."""
    from scipy.optimize import linear_sum_assignment

    rows, cols = linear_sum_assignment(scores, maximize=True)
    pairs = assigned.reshape(-1, 2)
    if len(pairs) != len(rows):
        return False
    partner = np.full(scores.shape[0], -1, dtype=np.int64)
    partner[rows] = cols
    return bool((partner[pairs[:, 0]] == pairs[:, 1]).all())


def _plainly_valid(outcomes) -> bool:
    """Whether every outcome's counts are plain ints ≥ 0, its name and checksum text, its time a
    finite float ≥ 0 and its scores of its views' shape: the common case, checked in one pass
    (:func:`check_result` walks the outcomes one check at a time, to name what is wrong, only
    when this fails)."""
    inf = math.inf
    return all(
        type(o.n1) is int
        and type(o.n2) is int
        and type(o.index) is int
        and type(o.episode) is int
        and type(o.sim_seed) is int
        and type(o.iterations) is int
        and min(o.n1, o.n2, o.index, o.episode, o.sim_seed, o.iterations) >= 0
        and type(o.name) is str
        and type(o.checksum) is str
        and type(o.time_s) is float
        and 0.0 <= o.time_s < inf
        and o.scores.shape == (o.n1, o.n2)
        for o in outcomes
    )


def _finite_non_negative(value) -> bool:
    return isinstance(value, int | float) and math.isfinite(value) and value >= 0


def _counted(value) -> bool:
    return not isinstance(value, bool) and isinstance(value, int) and value >= 0


def check_result(result, hungarian: Sequence[bool], path: Path) -> None:
    """Raise :class:`StaleEntry` naming `path`, the frame pair and what is wrong if `result` (a
    :class:`~eval.core.tasks.RunResult` as read) contradicts itself; `hungarian`: per pair,
    whether its stored assignment was the Hungarian assignment of its scores. Vectorised over
    the frame pairs but for the one assignment per pair that `hungarian` asks to recompute."""
    if not _finite_non_negative(result.wall_s):
        raise StaleEntry(f"{path}: wall_s {result.wall_s!r}: expected finite seconds ≥ 0")
    outcomes = result.outcomes

    def refuse(k: int, why: str):
        name = str(outcomes[k].name)[:60]
        return StaleEntry(f"{path}: frame pair {k} ({name}): {why}")

    for k, o in enumerate(outcomes if not _plainly_valid(outcomes) else ()):
        for name in ("n1", "n2", "index", "episode", "sim_seed", "iterations"):
            if not _counted(getattr(o, name)):
                raise refuse(k, f"{name} {getattr(o, name)!r}: expected an integer ≥ 0")
        if not isinstance(o.name, str) or not isinstance(o.checksum, str):
            raise refuse(k, "name and checksum: expected text")
        if not _finite_non_negative(o.time_s):
            raise refuse(k, f"time_s {o.time_s!r}: expected finite seconds ≥ 0")
        if o.scores.shape != (o.n1, o.n2):
            raise refuse(k, f"scores of shape {o.scores.shape} for {o.n1} x {o.n2} objects")
    if not outcomes:
        return
    flat = np.concatenate([o.scores.reshape(-1) for o in outcomes])
    bad = ~(np.isfinite(flat) & (flat >= 0) & (flat <= 1))
    if bad.any():
        sizes = np.cumsum([o.scores.size for o in outcomes])
        k = int(np.searchsorted(sizes, int(np.argmax(bad)), side="right"))
        raise refuse(k, "scores: expected finite values in [0, 1] (NaN, infinite or out of range)")
    n1 = np.array([o.n1 for o in outcomes], dtype=np.int64)
    n2 = np.array([o.n2 for o in outcomes], dtype=np.int64)
    for what, pairs in (
        ("ground truth", [o.gt_pairs for o in outcomes]),
        ("assignment", [o.assigned for o in outcomes]),
    ):
        k, why = first_not_one_to_one(pairs, n1, n2)
        if why is not None:
            raise refuse(k, f"{what}: {why}")
    for k in np.flatnonzero(np.asarray(hungarian, dtype=bool)):
        o = outcomes[k]
        if not _hungarian_one_to_one(o.assigned, o.scores):
            raise refuse(
                int(k), "assignment differs from the Hungarian assignment of its stored scores"
            )


def first_not_one_to_one(pairs: list[np.ndarray], n1: np.ndarray, n2: np.ndarray):
    """(frame pair, why) of the first (k, 2) array of `pairs` that is not a one-to-one matching
    inside its views' n1 x n2 objects; (-1, None) when every one is."""
    counts = np.array([len(p) for p in pairs], dtype=np.int64)
    if not counts.sum():
        return -1, None
    flat = np.concatenate(pairs).reshape(-1, 2)
    frame = np.repeat(np.arange(len(pairs)), counts)
    outside = (flat < 0).any(axis=1) | (flat[:, 0] >= n1[frame]) | (flat[:, 1] >= n2[frame])
    if outside.any():
        k = int(frame[np.argmax(outside)])
        return k, f"an index outside the views' {n1[k]} x {n2[k]} objects"
    for column in (0, 1):
        key = frame * (int(flat[:, column].max()) + 1) + flat[:, column]
        unique, first = np.unique(key, return_index=True)
        if len(unique) != len(key):
            repeated = np.setdiff1d(np.arange(len(key)), first)[0]
            return int(frame[repeated]), "an object matched twice"
    return -1, None


# ----------------------------------------------------------------------------------------------
# Against the dataset


@lru_cache(maxsize=32)
def _manifest_records(dataset_dir: str, checksum: str) -> tuple[dict, ...] | None:
    """The manifest's record entries of the dataset at `dataset_dir` if its checksum is
    `checksum` (None otherwise, or when it cannot be read)."""
    from cadsim.dataset.manifest import read_manifest

    try:
        manifest = read_manifest(Path(dataset_dir))
    except (OSError, ValueError):
        return None
    if manifest.get("checksum") != checksum:
        return None
    return tuple(manifest.get("records") or ())


@lru_cache(maxsize=32)
def _stored_detections(dataset_dir: str, checksum: str) -> tuple | None:
    """Per record of the dataset: (n1, n2, ground truth (g, 2) sorted) of its stored detections,
    read once per process; None when the dataset cannot be read."""
    from cadsim.dataset import Dataset

    try:
        dataset = Dataset(dataset_dir)
        if dataset.checksum != checksum:
            return None
        return tuple((len(p.view1), len(p.view2), _sorted_pairs(p.gt_pairs)) for p in dataset)
    except (OSError, ValueError):
        return None


def _reads_stored_detections(spec) -> bool:
    """Whether the run's views, sizes and ground truth are its records' own (no re-detection,
    thinning, re-localisation, other views or sensor)."""
    return (
        spec.noise_rate is None
        and spec.keep is None
        and spec.localisation is None
        and spec.views in (None, (1, 2))
        and spec.sensor is None
    )


def disagreement(result, dataset_dir: str) -> str | None:
    """Why cached `result` disagrees with the dataset at `dataset_dir` (its frame pairs, their
    identities, and — on the stored detections — view sizes and ground truth); None when it
    agrees or the dataset cannot be read here (the run's task then reports that)."""
    spec = result.spec
    records = _manifest_records(str(dataset_dir), spec.dataset_checksum)
    if records is None:
        return None
    count = len(records) if spec.limit is None else min(spec.limit, len(records))
    if len(result.outcomes) != count:
        return f"{len(result.outcomes)} frame pairs where the dataset has {count}"
    suffix = "" if spec.views in (None, (1, 2)) else f":{spec.views[0]}-{spec.views[1]}"
    for k, (o, entry) in enumerate(zip(result.outcomes, records, strict=False)):
        expected = (k, f"{entry.get('name')}{suffix}", entry.get("checksum"))
        if (o.index, o.name, o.checksum) != expected or (o.episode, o.sim_seed) != (
            entry.get("episode"),
            entry.get("sim_seed"),
        ):
            return f"frame pair {k} is not the dataset's {expected[1]}"
    if not _reads_stored_detections(spec):
        return None
    stored = _stored_detections(str(dataset_dir), spec.dataset_checksum)
    if stored is None:
        return None
    for k, o in enumerate(result.outcomes):
        n1, n2, gt = stored[k]
        if (o.n1, o.n2) != (n1, n2):
            return f"frame pair {k}: {o.n1} x {o.n2} objects where the dataset has {n1} x {n2}"
        if not np.array_equal(_sorted_pairs(o.gt_pairs), gt):
            return f"frame pair {k}: ground truth differs from the dataset's"
    return None


def inconsistent_groups(results: Sequence) -> set[int]:
    """Indices of `results` in a group of runs on the same data (every spec field but the
    matcher, code version and frame-pair limit) whose view sizes or ground truth differ on some
    frame pair: none of them can be trusted over the others."""
    groups: dict[tuple, list[int]] = {}
    for i, r in enumerate(results):
        s = r.spec
        key = (s.dataset_checksum, s.seed, s.noise_rate, s.keep, s.localisation, s.views, s.sensor)
        groups.setdefault(key, []).append(i)
    bad: set[int] = set()
    for members in groups.values():
        reference: dict[int, tuple] = {}
        for i in members:
            for k, o in enumerate(results[i].outcomes):
                facts = (o.n1, o.n2, _sorted_pairs(o.gt_pairs).tobytes())
                if reference.setdefault(k, facts) != facts:
                    bad.update(members)
                    break
            if bad.issuperset(members):
                break
    return bad
