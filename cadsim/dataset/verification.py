"""The verification of a dataset's records: one implementation, covering every view.

Every command that reads a dataset verifies it here — ``cadsim info``, ``evaluate``, ``train``,
``sweep-*`` and the studies through ``Dataset(path, verify=True)`` (every record, once per process
for unchanged files), ``cadsim show`` through ``Dataset.verify_record(k)`` (the record it draws) —
so a record one of them refuses, every one of them refuses, with the same line. A record passes
when

1. its files are exactly the manifest's ``record_files`` (none missing, no stray file beside
   them) and their checksum is the manifest's;
2. its ``record.json`` is the record the manifest describes: the manifest's format version,
   episode and slot; ``views`` (N-view formats) and one well-formed ``observers`` entry per view
   (``id``, ``kind``, camera, pose and seeds of the right types); objects that parse; a
   ``prior`` the reader knows;
3. ``detections.npz`` holds, for every view 1..N, the arrays of its format version with the
   shapes (k, 3) positions, (k, 4) boxes, (k, d) features (one d for every non-empty view), (k,)
   ids, classes and pixels, finite numbers, no object twice in one view — and nothing else: no
   array of a view the record does not have, no array the format does not define;
4. where the record has images, ``viewK.png``, ``depthK`` and ``instanceK`` for every view and no
   other, of the view's camera size and the format's types, read from the files' headers (PNG
   ``IHDR``, ``.npy`` headers) without decoding them.

What the manifest promises of every record (:func:`record_layout`: ``views``, ``record_files``,
a format version that is one of the view count's) is checked whenever a dataset is opened,
verified or not. :class:`~cadsim.dataset.multi_view.SnapshotViews` applies checks 2 and 3 to the
record it reads. Every refusal is one ``DatasetError`` line naming the file and the key.
"""

from __future__ import annotations

import io
import json
import math
import re
import struct
import zipfile
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cadsim.camera import Camera
from cadsim.dataset import layout
from cadsim.dataset.checksum import record_checksum
from cadsim.dataset.cues import cue_problem
from cadsim.dataset.detections import ViewDetections
from cadsim.dataset.encoding import load_npz, npy_header
from cadsim.dataset.manifest import DatasetError
from cadsim.dataset.record_format import (
    MULTI_VIEW_VERSIONS,
    OBSERVER_KINDS,
    SEQUENCE_FORMAT,
    TRUE_CLASS_VERSION,
)
from cadsim.limits import MAX_POSITION_M, MAX_PRIOR_SIGMA_M, MAX_SIZE_M
from cadsim.sensing.gnss_error import MAX_TIME_S
from cadsim.sensing.localisation import LocalisationConfig
from cadsim.world import WorldObject

_SEEDS = ("noise_seed", "attribute_seed", "localisation_seed")
_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@dataclass(frozen=True)
class RecordLayout:
    """What the manifest says every record is: its format version, its number of views and
    its files (``record_files``)."""

    format_version: int
    views: int
    record_files: tuple[str, ...]

    @property
    def multi_view(self) -> bool:
        """An N-view snapshot format (4, 6): ``record.json`` says ``views``."""
        return self.format_version in MULTI_VIEW_VERSIONS

    @property
    def sequential(self) -> bool:
        """A sequence format (7): ``record.json`` says ``sequence``, observers their odometry."""
        return self.format_version == SEQUENCE_FORMAT

    @property
    def class_arrays(self) -> tuple[str, ...]:
        """The class arrays of a view: ``true_classes`` and the optional ``reported_classes``
        (format 5 on), or the one ``classes`` of formats 2-4. The first is required."""
        if self.format_version >= TRUE_CLASS_VERSION:
            return ("true_classes", "reported_classes")
        return ("classes",)

    @property
    def view_arrays(self) -> tuple[str, ...]:
        """Every array name (after ``view{k}_``) a view of this format may hold."""
        return (
            "positions", "boxes", "features", "features_scale", "object_ids",
            *self.class_arrays, "pixels", "world", "headings", "sizes",
        )  # fmt: skip


def _shown(value, limit: int = 60) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _is_int(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _is_position(value, length: int) -> bool:
    """A list of ``length`` finite coordinates within ±:data:`MAX_POSITION_M` metres."""
    return (
        isinstance(value, list)
        and len(value) == length
        and all(_is_number(p) and abs(p) <= MAX_POSITION_M for p in value)
    )


def record_layout(manifest: dict, path: Path) -> RecordLayout:
    """The :class:`RecordLayout` of the dataset at ``path`` from its parsed ``manifest``;
    ``DatasetError`` naming the manifest and the key for ``record_files`` that are not a
    record's, a view count out of 2..``MAX_VIEWS``, or a format version that is not one of that
    view count's (N-view records are versions 4 and 6, frame pairs 2, 3 and 5)."""
    where = Path(path) / layout.MANIFEST
    files = manifest.get("record_files") or layout.RECORD_FILES
    if not (isinstance(files, list | tuple) and all(isinstance(f, str) for f in files)):
        raise DatasetError(
            f"{where}: record_files: expected a list of file names, got {str(files)[:60]}"
        )
    views = manifest.get("views", 2)
    if not _is_int(views) or not 2 <= views <= layout.MAX_VIEWS:
        raise DatasetError(
            f"{where}: views: expected an integer in 2..{layout.MAX_VIEWS}, got {str(views)[:60]}"
        )
    allowed = layout.record_files(views)
    imageless = (layout.DETECTIONS_NPZ, layout.RECORD_JSON)
    with_points = [sorted(layout.record_files(views, s)) for s in ("lidar", "both")]
    if sorted(files) not in (sorted(allowed), sorted(imageless), *with_points):
        raise DatasetError(
            f"{where}: record_files {list(files)} must include {layout.DETECTIONS_NPZ} and name "
            f"only files of {list(allowed)}: all of them, or {list(imageless)} alone (records "
            "without images)"
        )
    version = manifest["format_version"]
    if (version in MULTI_VIEW_VERSIONS) != (views > 2):
        kind = "an N-view" if version in MULTI_VIEW_VERSIONS else "a frame-pair"
        raise DatasetError(
            f"{where}: format_version: {version} is {kind} format, but views is {views} (N-view "
            f"records are versions {' and '.join(map(str, MULTI_VIEW_VERSIONS))}, frame pairs "
            "the others)"
        )
    written = manifest["generation"].get("format_version", version)
    if written != version:
        raise DatasetError(
            f"{where}: generation.format_version: expected {version} (the manifest's "
            f"format_version), got {_shown(written)}"
        )
    return RecordLayout(int(version), int(views), tuple(files))


def verify_record(record_dir: Path, entry: dict, expected: RecordLayout) -> None:
    """Verify the record at ``record_dir`` (manifest entry ``entry``): files and checksum, then
    :func:`check_record`. ``DatasetError`` (one line, naming the file and the key) otherwise."""
    record_dir = Path(record_dir)
    if not record_dir.is_dir():
        raise DatasetError(f"{record_dir}: record listed in the manifest is missing")
    missing = [n for n in expected.record_files if not (record_dir / n).is_file()]
    if missing:
        raise DatasetError(f"{record_dir}: missing record files {missing}")
    files = {name: (record_dir / name).read_bytes() for name in expected.record_files}
    if record_checksum(files) != entry["checksum"]:
        raise DatasetError(f"{record_dir}: checksum mismatch (record modified or corrupt)")
    stray = sorted(p.name for p in record_dir.iterdir() if p.name not in expected.record_files)
    if stray:
        raise DatasetError(
            f"{record_dir / stray[0]}: stray file in the record, outside its checksum (a record "
            f"of this dataset holds {list(expected.record_files)})"
        )
    check_record(record_dir, files, entry, expected)


def check_record(
    record_dir: Path, files: dict[str, bytes], entry: dict | None, expected: RecordLayout
) -> list[ViewDetections]:
    """Checks 2-4 of the module docstring on a record's files (``files``: name -> bytes);
    every view's detections."""
    where = record_dir / layout.RECORD_JSON
    try:
        record = json.loads(files[layout.RECORD_JSON].decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise DatasetError(f"{where}: unreadable record ({exc})") from None
    check_record_json(record, where, expected, entry)
    what = record_dir / layout.DETECTIONS_NPZ
    try:
        arrays = load_npz(files[layout.DETECTIONS_NPZ], str(what))
    except ValueError as exc:
        raise DatasetError(str(exc).splitlines()[0]) from None
    views = check_views(arrays, what, expected)
    prior = record.get("prior") or {}
    if prior.get("kind") == "stored":
        # "views": the views that carry one (a source whose agents do not all report a pose)
        having = prior.get("views", list(range(1, len(views) + 1)))
        if not isinstance(having, list) or not all(isinstance(v, int) for v in having):
            raise DatasetError(f"{where}: prior.views: expected a list of view numbers")
        for v, view in enumerate(views, start=1):
            if (view.world is None) == (v in having):
                state = "missing" if v in having else "present, but not in prior.views"
                raise DatasetError(f"{what}: view{v}_world: {state} (the record's prior is stored)")
    _check_images(record_dir, files, record["observers"], expected)
    if layout.LIDAR_NPZ in files:
        _check_points(record_dir, files[layout.LIDAR_NPZ], expected, len(record["objects"]))
    return views


def _check_points(record_dir: Path, data: bytes, expected: RecordLayout, objects: int) -> None:
    """``lidar.npz`` holds each view's bounded sweep (``cadsim.dataset.lidar_points``)."""
    from cadsim.dataset.lidar_points import check_lidar_arrays

    what = record_dir / layout.LIDAR_NPZ
    try:
        check_lidar_arrays(load_npz(data, str(what)), expected.views, objects, str(what))
    except ValueError as exc:
        raise DatasetError(str(exc).splitlines()[0]) from None


def check_record_json(
    record, where: Path, expected: RecordLayout, entry: dict | None = None
) -> None:
    """``record.json`` (parsed) against the layout (and the manifest entry, when given)."""
    if not isinstance(record, dict):
        raise DatasetError(f"{where}: expected a JSON object")
    version = record.get("format_version")
    if version != expected.format_version:
        raise DatasetError(
            f"{where}: format_version: expected {expected.format_version} (the manifest's), got "
            f"{_shown(version)}"
        )
    for key in ("episode", "slot") if entry is not None else ():
        if record.get(key) != entry[key]:
            raise DatasetError(
                f"{where}: {key}: expected {entry[key]} (the manifest's record {entry['name']}), "
                f"got {_shown(record.get(key))}"
            )
    n = expected.views
    if expected.multi_view and record.get("views") != n:
        raise DatasetError(
            f"{where}: views: expected {n} (the manifest's), got {str(record.get('views'))[:40]}"
        )
    if not expected.multi_view and record.get("views", 2) != 2:
        raise DatasetError(
            f"{where}: views: a frame-pair record (format {expected.format_version}) has 2 "
            f"views, got {str(record.get('views'))[:40]}"
        )
    observers = record.get("observers")
    if not isinstance(observers, list) or len(observers) != n:
        count = len(observers) if isinstance(observers, list) else type(observers).__name__
        raise DatasetError(f"{where}: observers: expected a list of {n} entries, got {count}")
    for k, observer in enumerate(observers):
        _check_observer(observer, f"{where}: observers[{k}]")
    if expected.sequential:
        _check_sequence(record, where, entry)
    elif "sequence" in record:
        raise DatasetError(
            f"{where}: sequence: a record of format {expected.format_version} is no sequence's "
            "frame (sequences are format 7)"
        )
    time = record.get("time")
    if time is not None and not (_is_number(time) and abs(time) <= MAX_TIME_S):
        raise DatasetError(
            f"{where}: time: expected seconds within ±{MAX_TIME_S:.4g} or null, got {_shown(time)}"
        )
    objects = record.get("objects")
    if not isinstance(objects, list):
        raise DatasetError(f"{where}: objects: expected a list, got {_shown(objects)}")
    for i, obj in enumerate(objects):
        try:
            WorldObject.from_dict(obj)
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise DatasetError(f"{where}: objects[{i}]: not an object entry ({exc!r})") from None
        _check_object_geometry(obj, f"{where}: objects[{i}]")
    _check_prior(record.get("prior"), where)
    if "cues" in record and (problem := cue_problem(record["cues"])) is not None:
        raise DatasetError(f"{where}: cues: {problem}")


def _check_sequence(record: dict, where: Path, entry: dict | None) -> None:
    """A sequence frame's ``sequence`` block and its observers' ``odometry`` (format 7)."""
    sequence = record.get("sequence")
    if not isinstance(sequence, dict):
        raise DatasetError(f"{where}: sequence: expected an object, got {_shown(sequence)}")
    sid, frame, frames = sequence.get("id"), sequence.get("frame"), sequence.get("frames")
    if not (isinstance(sid, str) and layout.parse_record_name(sid) is not None):
        raise DatasetError(f"{where}: sequence.id: expected a record name, got {_shown(sid)}")
    if not (_is_int(frames) and frames >= 1 and _is_int(frame) and 0 <= frame < frames):
        raise DatasetError(
            f"{where}: sequence.frame, sequence.frames: expected integers 0 <= frame < frames, "
            f"got {_shown(frame)}, {_shown(frames)}"
        )
    first = layout.parse_record_name(sid)
    if (first[0], first[1] + frame) != (record.get("episode"), record.get("slot")):
        raise DatasetError(
            f"{where}: sequence.id: {sid!r} with frame {frame} is not this record's (episode "
            f"{_shown(record.get('episode'))}, slot {_shown(record.get('slot'))})"
        )
    for key in ("interval_s", "start_time"):
        value = sequence.get(key)
        if not (_is_number(value) and abs(value) <= MAX_TIME_S) or (
            key == "interval_s" and value <= 0
        ):
            raise DatasetError(
                f"{where}: sequence.{key}: expected a number of seconds within ±{MAX_TIME_S:.4g}"
                f"{' > 0' if key == 'interval_s' else ''}, got {_shown(sequence.get(key))}"
            )
    model = sequence.get("model")
    if not isinstance(model, dict) or not all(
        _is_number(model.get(k)) and model[k] >= 0
        for k in ("scale_sigma", "heading_sigma_deg_per_m", "position_walk", "heading_walk_deg")
    ):
        raise DatasetError(
            f"{where}: sequence.model: expected the odometry model's four sigmas (finite "
            f"numbers >= 0), got {_shown(model)}"
        )
    if entry is not None and (entry.get("sequence"), entry.get("frame")) != (sid, frame):
        raise DatasetError(
            f"{where}: sequence: {sid!r} frame {frame}, the manifest's record {entry['name']} "
            f"says {_shown(entry.get('sequence'))} frame {_shown(entry.get('frame'))}"
        )
    for k, observer in enumerate(record["observers"]):
        key = f"{where}: observers[{k}]"
        odometry = observer.get("odometry")
        position = odometry.get("position") if isinstance(odometry, dict) else None
        fine = (
            _is_position(position, 2)
            and _is_number(odometry.get("yaw"))
            and _is_number(odometry.get("distance_m"))
            and 0 <= odometry["distance_m"] <= MAX_POSITION_M
        )
        if not fine:
            raise DatasetError(
                f"{key}.odometry: expected position [x, y], yaw and distance_m >= 0 (finite "
                f"numbers, metres within ±{MAX_POSITION_M:g}), got {_shown(odometry)}"
            )
        if frame == 0 and (any(position) or odometry["yaw"] or odometry["distance_m"]):
            raise DatasetError(f"{key}.odometry: frame 0 is the origin, got {_shown(odometry)}")
        seed = observer.get("odometry_seed")
        if not (_is_int(seed) and seed >= 0):
            raise DatasetError(f"{key}.odometry_seed: expected an integer >= 0, got {_shown(seed)}")


def _check_object_geometry(obj: dict, key: str) -> None:
    """An object's centre within ±MAX_POSITION_M, its sizes in (0, MAX_SIZE_M] metres, its yaw
    finite."""
    if not _is_position(obj["center"], 3):
        raise DatasetError(
            f"{key}.center: expected [x, y, z] within ±{MAX_POSITION_M:g} m, got "
            f"{_shown(obj['center'])}"
        )
    size = obj["size"]
    if not (
        isinstance(size, list)
        and len(size) == 3
        and all(_is_number(s) and 0 < s <= MAX_SIZE_M for s in size)
    ):
        raise DatasetError(
            f"{key}.size: expected [length, width, height] in (0, {MAX_SIZE_M:g}] m, got "
            f"{_shown(size)}"
        )
    if not _is_number(obj["yaw"]):
        raise DatasetError(f"{key}.yaw: expected a finite number, got {_shown(obj['yaw'])}")


def _check_observer(observer, key: str) -> None:
    if not isinstance(observer, dict):
        raise DatasetError(f"{key}: expected an object, got {_shown(observer)}")
    if not isinstance(observer.get("id"), str):
        raise DatasetError(f"{key}.id: expected a string, got {_shown(observer.get('id'))}")
    kind = observer.get("kind", "vehicle")
    if kind not in OBSERVER_KINDS:
        raise DatasetError(
            f"{key}.kind: expected one of {list(OBSERVER_KINDS)}, got {str(kind)[:40]}"
        )
    camera = observer.get("camera")
    if camera is None:
        return  # imported data: no camera, no pose, no seeds
    position = camera.get("position") if isinstance(camera, dict) else None
    fine = (
        _is_position(position, 3)
        and all(_is_number(camera.get(a, 0.0)) for a in ("yaw", "pitch", "hfov_deg"))
        and "yaw" in camera
        and all(_is_int(camera.get(a)) and camera.get(a) > 0 for a in ("width", "height"))
    )
    if not fine:
        raise DatasetError(
            f"{key}.camera: expected position [x, y, z] within ±{MAX_POSITION_M:g} m, yaw, "
            f"pitch, hfov_deg (finite numbers) and width, height (integers > 0), got "
            f"{_shown(camera)}"
        )
    hfov = camera.get("hfov_deg", 90.0)  # Camera.from_dict's default
    if not 0 < hfov < 180:
        raise DatasetError(f"{key}.camera.hfov_deg: expected degrees in (0, 180), got {hfov!r}")
    pose = observer.get("pose")
    if pose is not None:
        position = pose.get("position") if isinstance(pose, dict) else None
        fine = _is_position(position, 3) and _is_number(pose.get("yaw"))
        if not fine:
            raise DatasetError(
                f"{key}.pose: expected position [x, y, z] within ±{MAX_POSITION_M:g} m and yaw "
                f"(finite numbers), got {_shown(pose)}"
            )
    for seed in _SEEDS:
        value = observer.get(seed)
        if not (_is_int(value) and value >= 0):
            raise DatasetError(f"{key}.{seed}: expected an integer >= 0, got {_shown(value)}")


def _check_prior(prior, where: Path) -> None:
    if prior is None:
        return
    kind = prior.get("kind") if isinstance(prior, dict) else None
    if kind == "stored":
        sigma = prior.get("world_sigma_m")
        if not (_is_number(sigma) and 0 <= sigma <= MAX_PRIOR_SIGMA_M):
            raise DatasetError(
                f"{where}: prior.world_sigma_m: expected metres in [0, {MAX_PRIOR_SIGMA_M:g}], "
                f"got {_shown(sigma)}"
            )
    elif kind == "pose_error":
        fields = {
            k: prior[k] for k in ("position_sigma_m", "yaw_sigma_deg", "preset") if k in prior
        }
        try:
            LocalisationConfig(**fields)
        except (TypeError, ValueError) as exc:
            raise DatasetError(f"{where}: prior: {str(exc).splitlines()[0]}") from None
    else:
        raise DatasetError(
            f"{where}: prior.kind: expected 'pose_error' or 'stored', got {_shown(kind)}"
        )


_VIEW_ARRAY = re.compile(r"^view([1-9][0-9]*)_([a-z_]+)$")
_SHAPES = {"positions": 3, "boxes": 4, "world": 3, "sizes": 3}  # (k, columns)


def check_views(arrays: dict[str, np.ndarray], what: Path, expected: RecordLayout):
    """Every view's detections of ``detections.npz`` (``arrays``), checked (module docstring,
    point 3); ``DatasetError`` naming the file and the array otherwise."""
    n = expected.views
    allowed = expected.view_arrays
    for key in sorted(arrays):
        match = _VIEW_ARRAY.match(key)
        if match is None or not 1 <= int(match[1]) <= n or match[2] not in allowed:
            raise DatasetError(
                f"{what}: {key}: not an array of this record (a {n}-view record of format "
                f"{expected.format_version} holds view1_ … view{n}_ {', '.join(allowed)})"
            )
    views, width = [], None
    for v in range(1, n + 1):
        prefix = f"view{v}"
        required = ("positions", "boxes", "features", "object_ids", expected.class_arrays[0])
        required += ("pixels",)
        missing = [f"{prefix}_{f}" for f in required if f"{prefix}_{f}" not in arrays]
        if missing:
            raise DatasetError(f"{what}: missing arrays {missing}")
        view = _check_view(arrays, prefix, what)
        if len(view):
            columns = view.features.shape[1]
            if width is not None and columns != width[1]:
                raise DatasetError(
                    f"{what}: {prefix}_features: {columns} columns, {width[0]}_features has "
                    f"{width[1]} (one feature length per record)"
                )
            width = width or (prefix, columns)
        views.append(view)
    return views


def _check_view(arrays: dict[str, np.ndarray], prefix: str, what: Path) -> ViewDetections:
    ids = arrays[f"{prefix}_object_ids"]
    if ids.ndim != 1 or ids.dtype.kind != "U":
        raise DatasetError(
            f"{what}: {prefix}_object_ids: expected a 1-D array of strings, got shape "
            f"{ids.shape} {ids.dtype}"
        )
    k = len(ids)
    for name in ("true_classes", "reported_classes", "classes"):
        arr = arrays.get(f"{prefix}_{name}")
        if arr is not None and (arr.shape != (k,) or arr.dtype.kind != "U"):
            raise DatasetError(
                f"{what}: {prefix}_{name}: expected ({k},) strings, got {arr.shape} {arr.dtype}"
            )
    for name, columns in _SHAPES.items():
        arr = arrays.get(f"{prefix}_{name}")
        if arr is None:
            continue
        if arr.shape != (k, columns) or arr.dtype.kind != "f":
            raise DatasetError(
                f"{what}: {prefix}_{name}: expected ({k}, {columns}) floats, got {arr.shape} "
                f"{arr.dtype}"
            )
        if not np.isfinite(arr).all():
            raise DatasetError(f"{what}: {prefix}_{name}: non-finite values (NaN or inf)")
    headings = arrays.get(f"{prefix}_headings")
    if headings is not None and (
        headings.shape != (k,) or headings.dtype.kind != "f" or not np.isfinite(headings).all()
    ):
        raise DatasetError(
            f"{what}: {prefix}_headings: expected ({k},) finite floats, got {headings.shape} "
            f"{headings.dtype}"
        )
    features = arrays[f"{prefix}_features"]
    scale = arrays.get(f"{prefix}_features_scale")
    kinds = "u" if scale is not None else "f"
    if features.ndim != 2 or len(features) != k or features.dtype.kind != kinds:
        expected_type = "uint8 (with a features_scale)" if scale is not None else "floats"
        raise DatasetError(
            f"{what}: {prefix}_features: expected ({k}, d) {expected_type}, got "
            f"{features.shape} {features.dtype}"
        )
    if scale is not None and not (
        features.dtype == np.uint8
        and np.size(scale) == 1
        and np.isfinite(scale).all()
        and float(np.ravel(scale)[0]) > 0
    ):
        raise DatasetError(
            f"{what}: {prefix}_features_scale: expected one finite scale > 0 of uint8 features"
        )
    if scale is None and not np.isfinite(features).all():
        raise DatasetError(f"{what}: {prefix}_features: non-finite values (NaN or inf)")
    pixels = arrays[f"{prefix}_pixels"]
    if pixels.shape != (k,) or pixels.dtype.kind not in "iu" or (pixels < 0).any():
        raise DatasetError(
            f"{what}: {prefix}_pixels: expected ({k},) integers >= 0, got {pixels.shape} "
            f"{pixels.dtype}"
        )
    seen = set()
    for oid in ids.tolist():
        if oid in seen:
            raise DatasetError(
                f"{what}: {prefix}_object_ids: {oid!r} is detected twice in one view"
            )
        seen.add(oid)
    try:
        return ViewDetections.from_arrays(arrays, prefix, str(what))
    except ValueError as exc:  # what the checks above do not foresee
        raise DatasetError(f"{what}: {prefix}: {str(exc).splitlines()[0]}") from None


def png_size(data: bytes, what: Path) -> tuple[int, int]:
    """(height, width) of an 8-bit RGB PNG from its ``IHDR`` chunk (nothing decoded)."""
    if len(data) < 33 or data[:8] != _PNG_SIGNATURE or data[12:16] != b"IHDR":
        raise DatasetError(f"{what}: not a PNG image")
    width, height, depth, colour = struct.unpack(">IIBB", data[16:26])
    if depth != 8 or colour != 2:
        raise DatasetError(
            f"{what}: expected an 8-bit RGB PNG, got bit depth {depth}, colour type {colour}"
        )
    return height, width


def npz_headers(data: bytes, what: Path) -> dict[str, tuple[tuple[int, ...], np.dtype]]:
    """{member: (shape, dtype)} of an ``.npz`` from its members' ``.npy`` headers (only the
    first bytes of each member are decompressed)."""
    headers = {}
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as zf:
            for info in zf.infolist():
                if not info.filename.endswith(".npy"):
                    raise DatasetError(f"{what}: {info.filename}: not an array")
                key = info.filename[: -len(".npy")]
                with zf.open(info) as member:
                    shape, _, dtype = npy_header(member, str(what), key)
                headers[key] = (shape, dtype)
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
        if isinstance(exc, DatasetError):
            raise
        raise DatasetError(f"{what}: not a readable .npz file ({exc})") from None
    return headers


def _check_images(
    record_dir: Path, files: dict[str, bytes], observers: list, expected: RecordLayout
) -> None:
    sizes = {}  # view -> (height, width): its camera's, else its colour image's
    for v, observer in enumerate(observers, start=1):
        camera = observer.get("camera")
        if camera is not None:
            camera = Camera.from_dict(camera)
            sizes[v] = (camera.height, camera.width)
    for v in range(1, expected.views + 1):
        name = layout.view_png(v)
        if name not in files:
            continue
        size = png_size(files[name], record_dir / name)
        if sizes.setdefault(v, size) != size:
            raise DatasetError(
                f"{record_dir / name}: {size[1]}x{size[0]} pixels (width x height), its camera "
                f"(observers[{v - 1}].camera) {sizes[v][1]}x{sizes[v][0]}"
            )
    for name, prefix, dtype in (
        (layout.DEPTH_NPZ, "depth", np.float32),
        (layout.INSTANCE_NPZ, "instance", np.int32),
    ):
        if name not in files:
            continue
        what = record_dir / name
        headers = npz_headers(files[name], what)
        keys = [f"{prefix}{v}" for v in range(1, expected.views + 1)]
        stray = sorted(set(headers) - set(keys))
        if stray:
            raise DatasetError(
                f"{what}: {stray[0]}: not an image of this {expected.views}-view record"
            )
        for v, key in enumerate(keys, start=1):
            if key not in headers:
                raise DatasetError(f"{what}: {key}: missing")
            shape, found = headers[key]
            if len(shape) != 2 or found != dtype or sizes.setdefault(v, shape) != shape:
                want = sizes[v] if v in sizes and len(sizes[v]) == 2 else "(H, W)"
                raise DatasetError(
                    f"{what}: {key}: expected shape {want} {np.dtype(dtype)} (height, width of "
                    f"view {v}), got {shape} {found}"
                )
