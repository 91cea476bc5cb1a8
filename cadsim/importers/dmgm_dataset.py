"""``cadsim import dmgm``: the DMGM CAD test pairs (``proc_s/<id>/data.pt`` + ``proc_t/<id>/
data.pt``, read by :mod:`cadsim.importers.dmgm_pt`) written as a frame-pair dataset in our format.

Mapping (docs/external-data.md has the full table):

- a driving sequence is an episode (episode = simulation seed = the sequence number, so the
  evaluation's "calibration and test share no simulation" check and the episode bootstrap see
  sequences), slot = the pair's rank in its sequence by id;
- ``pos`` (camera frame, x right, y down, z forward, metres) → detection positions, unchanged:
  DMGM's camera frame is ours (checked on the data: ``norm`` = 554.26 · (x, y)/z + (960, 540));
- ``x`` (900-d descriptor) → features (float32, or uint8 with a per-view scale when compact);
- ``label`` → class ``label<k>``; ``y`` (CARLA instance id) → object id, hence ground truth;
- ``norm`` (image position, pixels) → a zero-size box at that point (no box extent is given),
  so the box centre the reader passes to matchers is ``norm``; visible pixels unknown (0);
- ``pos_world`` → the stored localisation prior, with **y negated**: DMGM's world is CARLA's
  left-handed one; negating y makes it right-handed (x, y horizontal, z up) like ours, and the
  camera → world map a rotation. Stated uncertainty 1.2 m (the data's GPS σ).

Records have no images (``record_files`` = detections + record). Everything is written through
the atomic record writer and the manifest last, so an interrupted import leaves no dataset. Must
not import torch, matchers or eval.
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cadsim.dataset import layout
from cadsim.dataset.atomic_writer import write_file_atomic, write_record
from cadsim.dataset.checksum import dataset_checksum, record_checksum
from cadsim.dataset.detections import ViewDetections, ground_truth_pairs
from cadsim.dataset.encoding import json_bytes, npz_bytes
from cadsim.dataset.manifest import FORMAT_NAME
from cadsim.dataset.output_folder import check_output_folder
from cadsim.dataset.record_format import FORMAT_VERSION
from cadsim.importers import ImportFormatError
from cadsim.importers.dmgm_pt import DmgmPair, DmgmView, iter_pairs
from cadsim.provenance import git_state, package_versions

SCENARIO_NAME = "dmgm-cad"
WORLD_SIGMA_M = 1.2
"""The prior's stated position uncertainty: the GPS noise DMGM's data was made with (σ 1.2 m)."""
SOURCE = {
    "kind": "dmgm",
    "repository": "https://github.com/gaopeng5/DMGM",
    "commit": "5729d0e9",
    "files": "data/testdata/proc_{s,t}/<id>/data.pt",
    "licence": "MIT",
    "simulator": "CARLA + SUMO (independently simulated; not real-world recordings)",
}
RECORD_FILES = (layout.DETECTIONS_NPZ, layout.RECORD_JSON)
_WORLD_FRAME = "DMGM pos_world with y negated: right-handed, x and y horizontal, z up, metres"


@dataclass(frozen=True)
class ImportResult:
    """What an import wrote: the dataset folder, pairs per sequence, its checksum."""

    out: Path
    sequences: dict[str, int]
    checksum: str

    @property
    def pairs(self) -> int:
        return sum(self.sequences.values())


def _detections(view: DmgmView) -> ViewDetections:
    """Our detections of one DMGM view (validated by ``ViewDetections``)."""
    n = len(view)
    u, v = view.norm[:, 0].astype(np.float64), view.norm[:, 1].astype(np.float64)
    return ViewDetections(
        positions=view.pos,
        boxes=np.column_stack([u, v, u, v]),
        features=view.x,
        object_ids=[str(i) for i in view.y],
        true_classes=[f"label{k}" for k in view.label],
        # the data's own labels are all a matcher gets from it: they are its "reported" class
        reported_classes=[f"label{k}" for k in view.label],
        pixels=np.zeros(n, dtype=np.int64),
        world=view.pos_world.astype(np.float64) * [1.0, -1.0, 1.0],
    )


def _view_arrays(view: DmgmView, det: ViewDetections, prefix: str, compact: bool) -> dict:
    """npz members of one view; positions and world in the source's float32 (exact)."""
    arrays = det.to_arrays(prefix)
    arrays[f"{prefix}_positions"] = view.pos
    arrays[f"{prefix}_world"] = view.pos_world * np.float32([1.0, -1.0, 1.0])
    if compact:
        top = float(view.x.max(initial=0.0))
        scale = np.float32(top / 255.0 if top > 0 else 1.0)
        arrays[f"{prefix}_features"] = np.round(view.x / scale).astype(np.uint8)
        arrays[f"{prefix}_features_scale"] = scale
    return arrays


def encode_pair(pair: DmgmPair, slot: int, compact: bool = False) -> dict[str, bytes]:
    """{file name: bytes} of one imported record (deterministic)."""
    episode = int(pair.sequence)
    det1, det2 = _detections(pair.view_s), _detections(pair.view_t)
    gt = ground_truth_pairs(det1, det2)
    record = {
        "format_version": FORMAT_VERSION,
        "episode": episode,
        "slot": int(slot),
        "sim_seed": episode,
        "time": None,
        "observers": [{"id": "", "camera": None}, {"id": "", "camera": None}],
        "objects": [],
        "ground_truth": [
            {"object_id": det1.object_ids[i], "i": int(i), "j": int(j)} for i, j in gt
        ],
        "counts": {"n1": len(det1), "n2": len(det2), "covisible": len(gt)},
        "prior": {"kind": "stored", "world_sigma_m": WORLD_SIGMA_M, "frame": _WORLD_FRAME},
        "meta": {
            "source": SOURCE["kind"],
            "pair_id": pair.pair_id,
            "sequence": pair.sequence,
            "frame": pair.view_s.frame,
            "name": pair.view_s.name,
        },
    }
    arrays = _view_arrays(pair.view_s, det1, "view1", compact) | _view_arrays(
        pair.view_t, det2, "view2", compact
    )
    return {layout.DETECTIONS_NPZ: npz_bytes(arrays), layout.RECORD_JSON: json_bytes(record)}


def _source_digest(src: Path, pair_ids: Iterable[str]) -> str:
    """SHA-256 over the imported files' names and contents, in pair order."""
    h = hashlib.sha256()
    for pair_id in pair_ids:
        for side in ("proc_s", "proc_t"):
            path = src / side / pair_id / "data.pt"
            h.update(f"{side}/{pair_id}/data.pt".encode() + b"\0")
            h.update(hashlib.sha256(path.read_bytes()).digest())
    return h.hexdigest()


def _check_out(out: str | Path) -> Path:
    """``out`` as a Path under the output-path rule for a dataset folder that must be new or
    empty (never empty itself, a link, a file, a user's folder, or inside another dataset)."""
    return check_output_folder(out, resumable=False)


def _pair_count(src: Path) -> int:
    folder = src / "proc_s"
    return sum(1 for p in folder.iterdir() if p.is_dir()) if folder.is_dir() else 0


def import_dmgm(
    src: str | Path,
    out: str | Path,
    sequences: Iterable[str] | None = None,
    compact: bool = False,
    progress: bool = True,
) -> ImportResult:
    """Convert the DMGM CAD pairs under ``src`` (only ``sequences``, e.g. ``["069", "071"]``, if
    given) into a dataset at ``out`` (a new or empty folder). ``compact`` stores features as uint8
    with a per-view scale (≈ 4× smaller; cosine similarities change by < 1e-3). Raises
    ``ImportFormatError`` (one line naming the file) for malformed input.

    >>> import_dmgm("../shared/data/dmgm-cad", "data/dmgm-test", ["069", "071"])  # doctest: +SKIP
    ImportResult(out=PosixPath('data/dmgm-test'), sequences={'069': 61, '071': 48}, ...)
    """
    from tqdm import tqdm

    src, out = Path(src), _check_out(out)  # checked before Path("") could become "."
    wanted = None if sequences is None else {str(s) for s in sequences}
    records, counts, ids = [], {}, []
    with tqdm(
        total=_pair_count(src),
        unit="pair",
        desc="import dmgm",
        disable=not progress or None,
        leave=False,
    ) as bar:
        for pair in iter_pairs(src):
            bar.update(1)
            if wanted is not None and pair.sequence not in wanted:
                continue
            slot = counts.get(pair.sequence, 0)
            counts[pair.sequence] = slot + 1
            files = encode_pair(pair, slot, compact)
            name = layout.record_name(int(pair.sequence), slot)
            write_record(out, name, files)
            ids.append(pair.pair_id)
            records.append(
                {
                    "name": name,
                    "episode": int(pair.sequence),
                    "slot": slot,
                    "sim_seed": int(pair.sequence),
                    "checksum": record_checksum(files),
                }
            )
    if not records:
        found = "no pairs" if wanted is None else f"no pairs of sequences {sorted(wanted)}"
        raise ImportFormatError(src, f"{found} to import")
    missing = sorted(wanted - set(counts)) if wanted is not None else []
    if missing:
        raise ImportFormatError(src, f"sequences {missing} not found (have {sorted(counts)})")
    records.sort(key=lambda r: (r["episode"], r["slot"]))
    checksum = dataset_checksum(r["checksum"] for r in records)
    manifest = {
        "format": FORMAT_NAME,
        "format_version": FORMAT_VERSION,
        "complete": True,
        "record_files": list(RECORD_FILES),
        "scenario": {"path": None, "name": SCENARIO_NAME, "text": ""},
        "seeds": {
            "root": None,
            "root_from": "imported",
            "derivation": "none: imported data (episode = driving sequence)",
            "episodes": {str(int(s)): int(s) for s in sorted(counts)},
        },
        "generation": {
            "format_version": FORMAT_VERSION,
            "imported": True,
            "compact_features": bool(compact),
            "noise": {},
            "detection": {},
        },
        "source": SOURCE
        | {
            "folder": src.name,
            "sequences": dict(sorted(counts.items())),
            "sha256": _source_digest(src, ids),
        },
        "versions": package_versions(("numpy", "cadsim")),
        "git": git_state(),
        "pairs": len(records),
        "records": records,
        "checksum": checksum,
    }
    write_file_atomic(out / layout.MANIFEST, json_bytes(manifest))
    return ImportResult(out, dict(sorted(counts.items())), checksum)
