"""The dataset manifest (``manifest.json``): provenance, configuration, record list, checksums.

Written when generation starts (``"complete": false``, no records) and again, atomically, when it
ends (``"complete": true``, the first N records in (episode, slot) order with their checksums).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
import re
from pathlib import Path

from cadsim.dataset import layout
from cadsim.dataset.atomic_writer import write_file_atomic
from cadsim.dataset.checksum import dataset_checksum
from cadsim.dataset.encoding import json_bytes
from cadsim.dataset.record_format import (
    FORMAT_VERSION,
    MULTI_VIEW_FORMAT,
    READABLE_VERSIONS,
    SEQUENCE_FORMAT,
    jsonable,
)
from cadsim.object_sizes import SIZE_MODEL
from cadsim.provenance import git_state, package_versions
from cadsim.scenario_views import MULTI_VIEW_KEYS, view_count

FORMAT_NAME = "cadsim-frame-pairs"
SEED_DERIVATION = (
    "numpy SeedSequence(root, spawn_key=(0, episode)) -> simulation seed; "
    "(1, episode, slot, view) -> depth-noise seed (also FramePair.redetect's, with its seed as root); "
    "(3, episode, slot, view) -> detector-attribute seed (class confusion, size noise; stored per view); "
    "SUMO sources (object-size model 2): SeedSequence(simulation seed, spawn_key=(7, crc32(id), "
    "crc32(reversed id + '#'))) -> a vehicle's or person's size, the same under the scenario seed "
    "for signs, signal poles and roadside clutter; SeedSequence(scenario seed, spawn_key=(8,)) -> "
    "roadside clutter placement"
)
# Distributions whose versions shape the records (metadata only: nothing is imported).
_PACKAGES = (
    "numpy", "scipy", "opencv-python-headless", "pyrender-maintained", "pyrender", "PyOpenGL",
    "trimesh", "libsumo", "eclipse-sumo", "sumolib", "highway-env", "matplotlib", "cadsim",
)  # fmt: skip


class DatasetError(ValueError):
    """A dataset directory is missing, incomplete, from another generation, or corrupt."""


def _plain(value):
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return jsonable(dataclasses.asdict(value))
    return jsonable(value)


def _portable_paths(value, base: Path):
    """``value`` with absolute paths under ``base`` (the scenario's folder) or under SUMO's
    install made relative ("$SUMO_HOME/..."), so a dataset resumes from another checkout."""
    if isinstance(value, dict):
        return {k: _portable_paths(v, base) for k, v in value.items()}
    if isinstance(value, list):
        return [_portable_paths(v, base) for v in value]
    if isinstance(value, str) and value.startswith("/"):
        path = Path(value)
        if path.is_relative_to(base):
            return path.relative_to(base).as_posix()
        sumo_home = os.environ.get("SUMO_HOME")
        if sumo_home and path.is_relative_to(sumo_home):
            return "$SUMO_HOME/" + path.relative_to(sumo_home).as_posix()
    return value


def generation_config(scenario, seed: int, pairs_per_episode: int, criteria: dict) -> dict:
    """What determines the records: the scenario (contents and tables), the root seed, the
    episode size and the acceptance criteria. A resumed run must match it exactly."""
    observers = _plain(scenario.observers)
    views = view_count(observers)
    if views == 2:  # frame pairs: the configuration (and so resuming) exactly as before N views
        observers = {k: v for k, v in observers.items() if k not in MULTI_VIEW_KEYS}
    sequence = getattr(scenario, "sequence", None)
    version = FORMAT_VERSION if views == 2 else MULTI_VIEW_FORMAT
    config = {
        "format_version": SEQUENCE_FORMAT if sequence else version,
        "scenario_sha256": hashlib.sha256(scenario.text.encode("utf-8")).hexdigest(),
        "seed": int(seed),
        "pairs_per_episode": int(pairs_per_episode),
        "acceptance": dict(criteria),
        "traffic": _portable_paths(_plain(scenario.traffic), Path(scenario.path).parent),
        "camera": _plain(scenario.camera),
        "observers": observers,
        "noise": _plain(scenario.noise),
        "detection": _plain(scenario.detection),
        "sampling": _plain(scenario.sampling),
        "localisation": _plain(getattr(scenario, "localisation", {})),
        "appearance": _plain(getattr(scenario, "appearance", {})),
    }
    if _plain(scenario.traffic).get("source") == "sumo":  # per-object sizes (cadsim.object_sizes)
        config["object_sizes"] = SIZE_MODEL
    if sequence:  # only then: the configuration of a dataset without one is as before
        config["sequence"] = _plain(sequence)
    sensor = getattr(scenario, "sensor", "camera")
    if sensor != "camera":  # likewise: camera datasets' configuration is unchanged
        config["sensor"] = sensor
        config["lidar"] = _plain(getattr(scenario, "lidar", {}))
    return config


def build_manifest(
    scenario,
    config: dict,
    seed_source: str,
    records: list[dict],
    episodes: dict[int, int],
    complete: bool,
) -> dict:
    """The manifest. records: [{"name", "episode", "slot", "sim_seed", "checksum"}] in dataset
    order; episodes: {episode: simulation seed} of every episode run."""
    views = view_count(config["observers"])
    extra = {} if views == 2 else {"views": views, "record_files": list(layout.record_files(views))}
    if config.get("sensor", "camera") != "camera":
        extra["record_files"] = list(layout.record_files(views, config["sensor"]))
    if config.get("sequence"):
        extra["sequences"] = len({r["sequence"] for r in records})
    return {
        "format": FORMAT_NAME,
        "format_version": config["format_version"],
        "complete": bool(complete),
        "scenario": {"path": str(scenario.path), "name": scenario.name, "text": scenario.text},
        "seeds": {
            "root": config["seed"],
            "root_from": seed_source,
            "derivation": SEED_DERIVATION,
            "episodes": {str(e): int(s) for e, s in sorted(episodes.items())},
        },
        "generation": config,
        "versions": package_versions(_PACKAGES),
        "git": git_state(),
        "pairs": len(records),
        "records": records,
        "checksum": dataset_checksum(r["checksum"] for r in records),
    } | extra


def write_manifest(dataset_dir: Path, manifest: dict) -> None:
    write_file_atomic(Path(dataset_dir) / layout.MANIFEST, json_bytes(manifest))


def read_manifest(dataset_dir: Path, versions: tuple[int, ...] = READABLE_VERSIONS) -> dict:
    """The manifest of ``dataset_dir``; ``DatasetError`` if absent, not a cadsim manifest, or of
    a format version outside ``versions`` (reading: every readable one; resuming a generation:
    only the version it writes)."""
    path = Path(dataset_dir) / layout.MANIFEST
    if not path.is_file():
        raise DatasetError(
            f"{path}: no manifest; not a cadsim dataset (make one with `cadsim generate`)"
        )
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise DatasetError(f"{path}: unreadable manifest ({exc})") from exc
    if not isinstance(manifest, dict) or manifest.get("format") != FORMAT_NAME:
        raise DatasetError(f"{path}: 'format' is not {FORMAT_NAME!r}")
    found = manifest.get("format_version")
    if found not in versions:
        older = isinstance(found, int) and found < min(versions)
        remedy = (
            "regenerate it with `cadsim generate` (docs/dataset.md lists what changed)"
            if older
            else "use the cadsim that wrote it"
        )
        raise DatasetError(
            f"{Path(dataset_dir)}: dataset format version {found!r} is "
            f"{'older than' if older else 'not'} the version{'s' if len(versions) > 1 else ''} "
            f"{', '.join(map(str, versions[:-1])) + ' or ' if len(versions) > 1 else ''}"
            f"{versions[-1]} this cadsim {'reads' if len(versions) > 1 else 'writes'}; " + remedy
        )
    for key in ("complete", "records", "checksum", "generation", "scenario", "seeds"):
        if key not in manifest:
            raise DatasetError(f"{path}: missing key {key!r}")
    _check_fields(manifest, path)
    return manifest


_HEX64 = re.compile(r"^[0-9a-f]{64}$")


def _is_int(v) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _check_fields(manifest: dict, path: Path) -> None:
    """The types and ranges of every field a reader or the generator uses; ``DatasetError``
    naming the file and the dotted key otherwise. A record's name must be its (episode, slot)
    name, so that no entry can point outside ``pairs/``."""

    def need(ok: bool, key: str, value, expected: str) -> None:
        if not ok:
            shown = repr(value)
            shown = shown if len(shown) <= 60 else shown[:57] + "..."
            raise DatasetError(f"{path}: {key}: expected {expected}, got {shown}")

    need(isinstance(manifest["complete"], bool), "complete", manifest["complete"], "true or false")
    need(
        isinstance(manifest["checksum"], str) and bool(_HEX64.match(manifest["checksum"])),
        "checksum", manifest["checksum"], "64 hex digits",
    )  # fmt: skip
    for key in ("generation", "scenario", "seeds"):
        need(isinstance(manifest[key], dict), key, manifest[key], "an object")
    name = manifest["scenario"].get("name")
    need(isinstance(name, str), "scenario.name", name, "a string")
    root = manifest["seeds"].get("root")
    imported = manifest["seeds"].get("root_from") == "imported"  # external data: no seed
    need(
        (_is_int(root) and root >= 0) or (imported and root is None),
        "seeds.root", root, "an integer >= 0 (null only for imported data)",
    )  # fmt: skip
    gen = manifest["generation"]
    for key in ("noise", "detection"):
        value = gen.get(key, {})
        need(value is None or isinstance(value, dict), f"generation.{key}", value, "an object")
    rate = (gen.get("noise") or {}).get("noise_rate", 0.0)
    need(
        isinstance(rate, int | float) and not isinstance(rate, bool) and math.isfinite(rate)
        and rate >= 0,
        "generation.noise.noise_rate", rate, "a finite number >= 0",
    )  # fmt: skip
    records = manifest["records"]
    need(isinstance(records, list), "records", records, "a list")
    for k, r in enumerate(records):
        key = f"records[{k}]"
        need(isinstance(r, dict), key, r, "an object")
        for field in ("episode", "slot", "sim_seed"):
            value = r.get(field)
            need(_is_int(value) and value >= 0, f"{key}.{field}", value, "an integer >= 0")
        expected_name = layout.record_name(r["episode"], r["slot"])
        need(r.get("name") == expected_name, f"{key}.name", r.get("name"), repr(expected_name))
        checksum = r.get("checksum")
        need(
            isinstance(checksum, str) and bool(_HEX64.match(checksum)),
            f"{key}.checksum", checksum, "64 hex digits",
        )  # fmt: skip
    if manifest["format_version"] == SEQUENCE_FORMAT:
        _check_sequences(records, need)


def _check_sequences(records: list[dict], need) -> None:
    """A sequence dataset's records: each names its ``sequence`` (the record name of its frame
    0) and ``frame``; a sequence's frames are consecutive records, frames 0, 1, 2, ... in order."""
    previous = None
    seen = set()
    for k, r in enumerate(records):
        key = f"records[{k}]"
        sequence, frame = r.get("sequence"), r.get("frame")
        need(
            isinstance(sequence, str) and layout.parse_record_name(sequence) is not None,
            f"{key}.sequence", sequence, "the record name of the sequence's frame 0",
        )  # fmt: skip
        need(_is_int(frame) and frame >= 0, f"{key}.frame", frame, "an integer >= 0")
        if previous is not None and previous[0] == sequence:
            need(frame == previous[1] + 1, f"{key}.frame", frame, f"{previous[1] + 1} (in order)")
        else:
            need(sequence not in seen, f"{key}.sequence", sequence, "a sequence listed once")
            need(frame == 0, f"{key}.frame", frame, "0 (a sequence starts at its frame 0)")
            need(sequence == r["name"], f"{key}.sequence", sequence, repr(r["name"]))
            seen.add(sequence)
        previous = (sequence, frame)
