"""Writing imported box-only frames as a dataset: the one writer of ``cadsim import v2x-seq``
and ``cadsim import opv2v``.

The same guarantee as the DMGM importer (:mod:`cadsim.importers.dmgm_dataset`): the output
folder must be new or empty (``check_output_folder``), every record is written through the
atomic record writer, and the manifest — the only thing that makes the folder a dataset — is
written last, so an interrupted or refused import leaves no dataset, only record folders that
no reader opens. Records are :class:`~cadsim.dataset.box_record.BoxRecord`; the whole import is
read and checked before the first record is written, so a malformed input leaves the folder as
it was. Must not import matchers or eval.
"""

from __future__ import annotations

import queue
import shutil
import threading
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from cadsim.dataset import layout
from cadsim.dataset.atomic_writer import write_file_atomic, write_record
from cadsim.dataset.box_record import RECORD_FILES, BoxRecord, encode_box_record, record_version
from cadsim.dataset.checksum import dataset_checksum, record_checksum
from cadsim.dataset.encoding import json_bytes
from cadsim.dataset.manifest import FORMAT_NAME
from cadsim.dataset.output_folder import OutputFolderError, check_output_folder
from cadsim.provenance import git_state, package_versions

WRITER_THREADS = 4
"""Records written at once: each file and folder is fsynced, so a lone writer mostly waits on
the disk (measured on 10,000 DAIR-V2X-C frame pairs: ``make bench``, section dair-import)."""
STOP_WAIT_S = 2.0
"""How long an interrupted import waits for each writer to finish its record (milliseconds
in practice) before clearing what was written."""


@dataclass(frozen=True)
class ImportResult:
    """What an import wrote: the dataset folder, records per episode, views, its checksum."""

    out: Path
    episodes: dict[int, int]
    views: int
    checksum: str

    @property
    def records(self) -> int:
        return sum(self.episodes.values())


def check_out(out: str | Path) -> Path:
    """The output rule: a new or empty folder, never a link, a file or inside a dataset — or a
    folder holding only what an interrupted import left (:func:`_leftovers`), which the write
    clears first."""
    try:
        return check_output_folder(out, resumable=False)
    except OutputFolderError:
        if _leftovers(Path(out)) is None:
            raise
        return Path(out)


def _leftovers(out: Path) -> Path | None:
    """``out/pairs`` when ``out`` holds nothing but an interrupted import's records (no
    manifest, no link, only record folders of record files and temporary names), else None."""
    pairs = out / layout.PAIRS_DIR
    if out.is_symlink() or not out.is_dir() or [e.name for e in out.iterdir()] != [pairs.name]:
        return None
    if pairs.is_symlink() or not pairs.is_dir():
        return None
    for entry in pairs.iterdir():
        temporary = entry.name.startswith(layout.TEMP_PREFIX)
        if entry.is_symlink() or not entry.is_dir():
            return None
        if not temporary and layout.parse_record_name(entry.name) is None:
            return None
        for file in entry.iterdir():
            own = file.name in RECORD_FILES or file.name.startswith(layout.TEMP_PREFIX)
            if file.is_symlink() or not file.is_file() or not own:
                return None
    return pairs


def write_box_dataset(
    out: str | Path, records: Sequence[BoxRecord], scenario: str, source: dict
) -> ImportResult:
    """Write ``records`` (in (episode, slot) order, one view count) as a dataset at ``out``
    (checked with :func:`check_out` first); ``source`` goes to the manifest's ``source``."""
    out = check_out(out)
    if not records:
        raise ValueError("no records to write")
    leftovers = _leftovers(out)
    if leftovers is not None:
        shutil.rmtree(leftovers)
    try:
        return _write(out, records, scenario, source)
    except BaseException:  # Ctrl-C too: no manifest was written, so nothing of this run is kept
        if not (out / layout.MANIFEST).exists() and _leftovers(out) is not None:
            shutil.rmtree(out / layout.PAIRS_DIR)
        raise


def _write_one(out: Path, rec: BoxRecord, sequential: bool) -> dict:
    """Encode and write one record atomically; its manifest entry."""
    files = encode_box_record(rec)
    name = layout.record_name(rec.episode, rec.slot)
    write_record(out, name, files)
    entry = {
        "name": name,
        "episode": int(rec.episode),
        "slot": int(rec.slot),
        "sim_seed": int(rec.sim_seed),
        "checksum": record_checksum(files),
    }
    if sequential:
        entry |= {"sequence": rec.sequence["id"], "frame": int(rec.sequence["frame"])}
    return entry


def _write_all(out: Path, ordered: Sequence[BoxRecord], sequential: bool) -> list[dict]:
    """Every record written by :data:`WRITER_THREADS` daemon threads (their fsync waits overlap;
    the bytes are the same); the manifest entries in ``ordered``'s order. A worker's error is
    raised here; on any exception (Ctrl-C too) the workers stop taking records and are given
    :data:`STOP_WAIT_S` to finish the one they write, so the caller's clean-up comes after them."""
    jobs: queue.SimpleQueue = queue.SimpleQueue()
    for item in enumerate(ordered):
        jobs.put(item)
    done: queue.SimpleQueue = queue.SimpleQueue()
    stop = threading.Event()

    def work() -> None:
        while not stop.is_set():
            try:
                k, rec = jobs.get_nowait()
            except queue.Empty:
                return
            try:
                done.put((k, _write_one(out, rec, sequential), None))
            except BaseException as exc:  # handed to the main thread
                done.put((k, None, exc))
                return

    workers = [
        threading.Thread(target=work, daemon=True, name=f"cadsim-writer-{n}")
        for n in range(min(WRITER_THREADS, len(ordered)))
    ]
    entries: list[dict | None] = [None] * len(ordered)
    try:  # starting the workers is inside: a Ctrl-C while they start stops the started ones
        for worker in workers:
            worker.start()
        for _ in range(len(ordered)):
            while True:
                try:
                    k, entry, exc = done.get(timeout=0.2)  # a timeout keeps Ctrl-C prompt
                    break
                except queue.Empty:
                    continue
            if exc is not None:
                raise exc
            entries[k] = entry
    except BaseException:
        stop.set()
        for worker in workers:
            if worker.is_alive():
                worker.join(timeout=STOP_WAIT_S)
        raise
    return entries


def _write(out: Path, records: Sequence[BoxRecord], scenario: str, source: dict) -> ImportResult:
    """:func:`write_box_dataset` once ``out`` is checked and clear."""
    views = len(records[0].views)
    sequential = records[0].sequence is not None
    version = record_version(views, sequential)
    ordered = sorted(records, key=lambda r: (r.episode, r.slot))
    for rec in ordered:
        if len(rec.views) != views or (rec.sequence is not None) != sequential:
            raise ValueError("every record of a dataset has the same views and sequence kind")
    entries = _write_all(out, ordered, sequential)
    episodes: dict[int, int] = {}
    for entry in entries:
        episodes[entry["episode"]] = episodes.get(entry["episode"], 0) + 1
    checksum = dataset_checksum(e["checksum"] for e in entries)
    manifest = {
        "format": FORMAT_NAME,
        "format_version": version,
        "complete": True,
        "record_files": list(RECORD_FILES),
        **({"views": views} if views > 2 else {}),
        "scenario": {"path": None, "name": scenario, "text": ""},
        "seeds": {
            "root": None,
            "root_from": "imported",
            "derivation": "none: imported data (episode = the source's scenario or sequence)",
            "episodes": {str(e): e for e in sorted(episodes)},
        },
        "generation": {
            "format_version": version,
            "imported": True,
            "cues": "boxes",
            "noise": {},
            "detection": {},
        },
        "source": source,
        "versions": package_versions(("numpy", "PyYAML", "cadsim")),
        "git": git_state(),
        "pairs": len(entries),
        "records": entries,
        "checksum": checksum,
    }
    write_file_atomic(out / layout.MANIFEST, json_bytes(manifest))
    return ImportResult(out, dict(sorted(episodes.items())), views, checksum)


__all__ = ["ImportResult", "check_out", "write_box_dataset"]
