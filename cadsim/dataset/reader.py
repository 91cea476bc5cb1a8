"""Reading a dataset (:class:`Dataset`): the manifest, its records in dataset order as
:class:`~cadsim.dataset.frame_pair.FramePair` (views 1 and 2) or, for an N-view dataset, as
:class:`~cadsim.dataset.multi_view.SnapshotViews`, and the verification of every record
(:mod:`cadsim.dataset.verification`, once per process for unchanged files). Imports neither SUMO
nor pyrender.
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterator, Sequence
from functools import cached_property
from pathlib import Path

import numpy as np

from cadsim.dataset import layout
from cadsim.dataset.checksum import dataset_checksum
from cadsim.dataset.frame_pair import FramePair
from cadsim.dataset.manifest import DatasetError, read_manifest
from cadsim.dataset.multi_view import SnapshotViews
from cadsim.dataset.sensor_view import check_sensor, dataset_sensor, sensor_pair
from cadsim.dataset.sequence_check import check_sequences
from cadsim.dataset.verification import RecordLayout, record_layout, verify_record
from cadsim.dataset.verified_stamps import stamp, stamped

__all__ = ["Dataset", "FramePair"]  # FramePair: defined in cadsim.dataset.frame_pair

# Datasets this process has verified: resolved path -> (dataset checksum, file signature).
_VERIFIED: dict[str, tuple[str, str]] = {}


class Dataset(Sequence[FramePair]):
    """A frame-pair dataset written by ``cadsim generate`` or ``cadsim import``.

    ``len(ds)``, ``ds[k]`` (a ``FramePair``), iteration in dataset order, ``ds.manifest`` (the
    parsed manifest.json), ``ds.checksum`` (hash over the records' checksums). ``verify()``
    re-hashes and checks every record; ``verify=True`` does it on opening, once per process for unchanged
    files (:meth:`verify_once`). Raises ``DatasetError`` for a missing, incomplete or (verified)
    modified or malformed dataset (:mod:`cadsim.dataset.verification`: every view of every
    record). ``ds.n_views``: views per record (2: frame pairs); ``ds.snapshot(k)``: record k's
    views (N-view datasets). ``sensor``: read a two-sensor dataset (``sensor = "both"``) as
    "camera" (its camera detections, the default) or "lidar" (its LiDAR boxes,
    :mod:`cadsim.dataset.sensor_view`), or either one's detections where both sensors cover
    ("camera-common", "lidar-common"); None or the records' own sensor: as stored.
    """

    def __init__(self, path: str | Path, verify: bool = False, sensor: str | None = None) -> None:
        self.path = Path(path)
        self.manifest = read_manifest(self.path)
        if not self.manifest["complete"]:
            raise DatasetError(
                f"{self.path}: generation did not finish; run the same `cadsim generate` command "
                "again to resume it"
            )
        self._records: list[dict] = self.manifest["records"]
        self.checksum: str = self.manifest["checksum"]
        gen = self.manifest["generation"]
        self.noise_config: dict = dict(gen.get("noise") or {})
        self.detection_config: dict = dict(gen.get("detection") or {})
        # What every record is (views, files, format version): checked here, verified or not.
        self.record_layout: RecordLayout = record_layout(self.manifest, self.path)
        self.record_files: tuple[str, ...] = self.record_layout.record_files
        self.n_views: int = self.record_layout.views
        self.sensor: str | None = check_sensor(
            sensor, dataset_sensor(self.manifest), str(self.path / layout.MANIFEST)
        )
        if self.sensor is not None and self.n_views != 2:
            raise ValueError(
                f"{self.path / layout.MANIFEST}: sensor {sensor!r}: only frame-pair datasets "
                f"can be read by sensor, this one has {self.n_views} views per record"
            )
        if not self._records:
            raise DatasetError(
                f"{self.path / layout.MANIFEST}: records: a finished dataset with no record"
            )
        self._lidar_range_m = _lidar_range_m(gen) if self.sensor else 0.0
        if verify:
            self.verify_once()

    def __repr__(self) -> str:
        return f"Dataset({str(self.path)!r}, pairs={len(self)}, checksum={self.checksum[:12]})"

    @property
    def scenario_name(self) -> str:
        return self.manifest["scenario"]["name"]

    def __len__(self) -> int:
        return len(self._records)

    def __getitem__(self, k: int) -> FramePair:  # type: ignore[override]
        if isinstance(k, slice):
            return [self[i] for i in range(*k.indices(len(self)))]
        n = len(self)
        if not isinstance(k, int | np.integer):
            raise TypeError(f"Dataset index must be an int, got {type(k).__name__}")
        if not -n <= k < n:
            raise IndexError(f"pair {k} out of range for a dataset of {n} pairs")
        k = int(k) % n
        entry = self._records[k]
        record_dir = self.path / layout.PAIRS_DIR / entry["name"]
        if not record_dir.is_dir():
            raise DatasetError(f"{record_dir}: record listed in the manifest is missing")
        pair = FramePair(
            record_dir,
            k,
            entry,
            self.noise_config,
            self.detection_config,
            record_files=self.record_files,
        )
        return pair if self.sensor is None else sensor_pair(pair, self.sensor, self._lidar_range_m)

    def __iter__(self) -> Iterator[FramePair]:
        for k in range(len(self)):
            yield self[k]

    @property
    def is_sequential(self) -> bool:
        """Whether the records are frames of sequences (format 7, a ``[sequence]`` scenario)."""
        return self.record_layout.sequential

    @cached_property
    def _sequence_indices(self) -> list[list[int]]:
        """Per sequence, its records' dataset indices in frame order (every record its own
        sequence of one frame in a dataset without sequences)."""
        if not self.is_sequential:
            return [[k] for k in range(len(self))]
        groups: dict[str, list[int]] = {}
        for k, entry in enumerate(self._records):
            groups.setdefault(entry["sequence"], []).append(k)
        return list(groups.values())

    @property
    def sequences(self) -> int:
        """Number of sequences (of a dataset without sequences: its records, one frame each)."""
        return len(self._sequence_indices)

    def sequence(self, k: int) -> list[FramePair]:
        """Sequence ``k``'s frames as ``FramePair``s in time order (frame 0 first; each with
        ``.sequence_id``, ``.frame`` and ``.odometry``). In a dataset without sequences,
        sequence k is ``[ds[k]]``."""
        n = self.sequences
        if isinstance(k, bool) or not isinstance(k, int | np.integer):
            raise TypeError(f"sequence index must be an int, got {type(k).__name__}")
        if not -n <= k < n:
            raise IndexError(f"sequence {k} out of range for a dataset of {n} sequences")
        return [self[i] for i in self._sequence_indices[int(k) % n]]

    def iter_sequences(self) -> Iterator[list[FramePair]]:
        """Every sequence (:meth:`sequence`) in dataset order."""
        for k in range(self.sequences):
            yield self.sequence(k)

    def snapshot(self, k: int) -> SnapshotViews:
        """Record ``k`` as its ``n_views`` views (:class:`cadsim.dataset.multi_view.SnapshotViews`:
        ``pair(i, j)`` is the two-view ``FramePair`` of views i and j). ``ds[k]`` is
        ``ds.snapshot(k).pair(1, 2)``: every two-view tool reads an N-view dataset as the pairs
        of its first two views."""
        return SnapshotViews(self[k], self.n_views, self.record_layout)

    def _file_signature(self) -> str:
        """A digest of (size, mtime, inode) of the manifest and every record file: any rewrite
        changes it (except one that restores size and mtime on the same inode)."""
        h = hashlib.sha256()
        pairs = self.path / layout.PAIRS_DIR
        for path in [
            self.path / layout.MANIFEST,
            *(
                path
                for entry in self._records
                # the record's folder too: a file added beside its files changes its mtime
                for path in (
                    pairs / entry["name"],
                    *(pairs / entry["name"] / n for n in self.record_files),
                )
            ),
        ]:
            try:
                st = path.stat()
                h.update(f"{st.st_size} {st.st_mtime_ns} {st.st_ino};".encode())
            except OSError:
                h.update(b"missing;")
        return h.hexdigest()

    def verify_once(self) -> None:
        """:meth:`verify`, unless the same files were already verified — by this process or an
        earlier one (same manifest checksum, and no file rewritten or added since: see
        ``_file_signature`` and :mod:`cadsim.dataset.verified_stamps`). Costs one stat per file
        when it skips; a full read and SHA-256 of every record when it does not."""
        key = str(self.path.resolve())
        signature = (self.checksum, self._file_signature())
        if _VERIFIED.get(key) == signature:
            return
        if not stamped(self.path, signature):
            self.verify()
            stamp(self.path, signature)
        _VERIFIED[key] = signature

    def mark_verified(self) -> None:
        """Record the files as they are now as verified, without reading them: for the process
        that has just written and checksummed every record (a fresh generation)."""
        signature = (self.checksum, self._file_signature())
        stamp(self.path, signature)
        _VERIFIED[str(self.path.resolve())] = signature

    def verify_record(self, index: int) -> None:
        """Verify record ``index`` (dataset order) — its checksum and every view's contents
        (:func:`cadsim.dataset.verification.verify_record`); ``DatasetError`` naming the file
        and the key if it does not pass."""
        entry = self._records[index]
        verify_record(self.path / layout.PAIRS_DIR / entry["name"], entry, self.record_layout)

    def verify(self) -> None:
        """Verify every record and the dataset checksum; ``DatasetError`` naming the first
        record (file and key) that does not pass."""
        for index in range(len(self._records)):
            self.verify_record(index)
        if self.is_sequential:
            check_sequences(self.path, self._records)
        if dataset_checksum(r["checksum"] for r in self._records) != self.checksum:
            raise DatasetError(f"{self.path / layout.MANIFEST}: dataset checksum mismatch")


def _lidar_range_m(generation: dict) -> float:
    """The specified range (metres) of a two-sensor dataset's LiDAR (its ``[lidar]`` table)."""
    from cadsim.sensing.lidar.beam_pattern import LidarConfig

    return float(LidarConfig(**(generation.get("lidar") or {})).pattern().max_range_m)
