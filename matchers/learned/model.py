"""The learned matchers' model file: JSON data, never code.

A model file holds one gradient-boosted classifier per variant (``learned``: features without the
prior; ``learned_pose``: with it) as LightGBM's own text format — a list of trees, parsed, not
executed — beside what it was trained on::

    {"format": "cadsim-learned-model", "format_version": 1, "features_version": 1,
     "variants": {"learned": {"features": [...], "booster": "tree\\nversion=v4\\n..."}, ...},
     "training": {"datasets": [{"name", "checksum", "pairs", "records": [record checksums]}],
                  "rows": {...}, "positives": {...}, "params": {...}, "rounds": 200}}

The bytes are deterministic (sorted keys, no times, no paths): the same training data give the
same file on every machine (:meth:`LearnedModel.to_bytes`; ``cadsim train`` writes them through
the output-path rule).

Loading treats the file as hostile data, in this order, and refuses anything unexpected with one
line naming the file and the key (:class:`ModelFileError`, a ValueError: the CLI's exit 2):

1. a regular file only — ``os.stat`` first, so a FIFO, a device (``/dev/zero``) or a folder is
   never opened; then opened with ``O_NONBLOCK`` and checked again on the descriptor (a file
   swapped for a FIFO in between cannot block); at most :data:`MAX_FILE_BYTES` are read;
2. JSON nested at most :data:`MAX_JSON_DEPTH` deep (counted before parsing, so a 100,000-deep
   file is not a RecursionError), every number finite (``NaN``/``Infinity``/``1e999`` refused);
3. every key and type: the format, its version, the features' version, per variant its feature
   names and trees, and ``training`` (``datasets``: objects of name, checksum, pairs and record
   checksums; the row counts, parameters and rounds);
4. the trees as data (:mod:`matchers.learned.trees`: split features in range, child links a tree,
   counts under the caps, numbers finite), then LightGBM parses the canonical text of what was
   checked, its output captured (:mod:`matchers.learned.booster`).
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import stat
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

from matchers.learned.booster import parse_booster
from matchers.learned.booster import predict as booster_predict
from matchers.learned.features import FEATURES_VERSION, feature_names
from matchers.learned.trees import check_trees

FORMAT = "cadsim-learned-model"
FORMAT_VERSION = 1
VARIANTS = {"learned": False, "learned_pose": True}  # variant -> uses the localisation prior

MAX_FILE_BYTES = 64 * 2**20
"""Size of a model file: 5,000 rounds of 15-leaf trees for both variants are about 30 MB."""

MAX_JSON_DEPTH = 16
"""Nesting of the JSON document (a model file is 5 deep: training.datasets[i].records[j])."""

_MAX_ROUNDS = 5000  # as `cadsim train --rounds`
_STRINGS = re.compile(rb'"[^"\\]*(?:\\.[^"\\]*)*"')  # a JSON string literal (unrolled: linear)


class ModelFileError(ValueError):
    """A model file that cannot be used; the message is one line naming the file and the key."""


@dataclass(frozen=True)
class LearnedModel:
    """A loaded model file: ``boosters`` {variant: LightGBM text}, ``training`` (what it was
    trained on, as recorded), ``sha256`` of the file's bytes."""

    boosters: dict[str, str]
    training: dict
    sha256: str = ""
    _loaded: dict = field(default_factory=dict, compare=False, repr=False)

    def to_bytes(self) -> bytes:
        """The file's deterministic bytes."""
        document = {
            "format": FORMAT,
            "format_version": FORMAT_VERSION,
            "features_version": FEATURES_VERSION,
            "variants": {
                name: {"features": feature_names(VARIANTS[name]), "booster": text}
                for name, text in sorted(self.boosters.items())
            },
            "training": self.training,
        }
        return (json.dumps(document, sort_keys=True, indent=1) + "\n").encode()

    def training_records(self) -> set[str]:
        """Checksums of every record (frame pair) the model was trained on."""
        return {r for d in self.training.get("datasets", []) for r in d.get("records", [])}

    def predict(self, variant: str, features: np.ndarray) -> np.ndarray:
        """P(match) of each feature row under ``variant``'s classifier (one thread)."""
        if variant not in self.boosters:
            raise ValueError(
                f"model: this model has no {variant!r} classifier (it has "
                f"{', '.join(sorted(self.boosters))}); train it on data with a localisation prior"
            )
        if not len(features):
            return np.zeros(0)
        booster = self._loaded.get(variant)
        if booster is None:
            booster = self._loaded[variant] = checked_booster(self.boosters[variant], variant)
        return booster_predict(booster, features)


def checked_booster(text: str, variant: str):
    """LightGBM's booster of ``variant``'s trees ``text``, after they were checked as data
    (:func:`matchers.learned.trees.check_trees`); ValueError naming the key otherwise."""
    key = f"variants.{variant}.booster"
    names = feature_names(VARIANTS[variant])
    try:
        canonical, _ = check_trees(text, names)
        booster = parse_booster(canonical)
    except ValueError as exc:
        raise ModelFileError(f"{key}: {exc}") from None
    if booster.num_feature() != len(names):
        raise ModelFileError(f"{key}: {booster.num_feature()} features, expected {len(names)}")
    return booster


def load_model(path: str | Path, sha256: str | None = None) -> LearnedModel:
    """The model at ``path``; :class:`ModelFileError` in one line naming the file and what is
    wrong (not a regular file, too large, not JSON, nested too deep, a number that is not
    finite, an unexpected key or value, features of another version, trees that are not a model
    cadsim could have written, a ``sha256`` other than the expected one). Cached by content."""
    path = Path(path)
    data = read_model_bytes(path)
    digest = hashlib.sha256(data).hexdigest()
    if sha256 is not None and digest != sha256:
        raise ModelFileError(
            f"{path}: the model file changed (sha256 {digest[:12]}, expected {sha256[:12]}); "
            "evaluate it again"
        )
    try:
        return _from_bytes(data, digest)
    except ValueError as exc:
        raise ModelFileError(f"{path}: {exc}") from None


def _kind(mode: int) -> str:
    for test, name in (
        (stat.S_ISDIR, "a folder"),
        (stat.S_ISFIFO, "a FIFO"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISSOCK, "a socket"),
    ):
        if test(mode):
            return name
    return "not a regular file"


def read_model_bytes(path: Path) -> bytes:
    """The bytes of the regular file at ``path``, at most :data:`MAX_FILE_BYTES`; anything else
    (a FIFO, a device, a folder: never opened for a blocking read) is a ModelFileError."""
    try:
        info = os.stat(path)
    except OSError as exc:
        raise ModelFileError(f"{path}: cannot read the model file ({exc.strerror})") from None
    if not stat.S_ISREG(info.st_mode):
        raise ModelFileError(
            f"{path}: is {_kind(info.st_mode)}, not a model file (a file written by cadsim train)"
        )
    if info.st_size > MAX_FILE_BYTES:
        raise ModelFileError(
            f"{path}: {info.st_size:,} bytes, larger than {MAX_FILE_BYTES // 2**20} MiB; "
            "not a model file"
        )
    flags = os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0) | getattr(os, "O_NOCTTY", 0)
    try:
        fd = os.open(path, flags)
    except OSError as exc:
        raise ModelFileError(f"{path}: cannot read the model file ({exc.strerror})") from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):  # swapped after the check above
            raise ModelFileError(f"{path}: is {_kind(info.st_mode)}, not a model file")
        chunks, size = [], 0
        while size <= MAX_FILE_BYTES:
            chunk = os.read(fd, min(1 << 20, MAX_FILE_BYTES + 1 - size))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
    except OSError as exc:
        raise ModelFileError(f"{path}: cannot read the model file ({exc.strerror})") from None
    finally:
        os.close(fd)
    if size > MAX_FILE_BYTES:
        raise ModelFileError(f"{path}: larger than {MAX_FILE_BYTES // 2**20} MiB; not a model file")
    return b"".join(chunks)


def _json_depth(data: bytes) -> tuple[int, int]:
    """(deepest nesting of arrays and objects, the byte where it is first reached), strings
    left out; computed without recursion."""
    bare = np.frombuffer(_STRINGS.sub(b'""', data), dtype=np.uint8)
    step = np.isin(bare, (ord("["), ord("{"))).astype(np.int64)
    step -= np.isin(bare, (ord("]"), ord("}")))
    if not len(step):
        return 0, 0
    depth = np.cumsum(step)
    where = int(np.argmax(depth))
    return int(depth[where]), where


def _refuse_constant(name: str):
    raise ValueError(f"{name} in the JSON: every number in a model file must be finite")


def _finite_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"{text[:40]} in the JSON: every number in a model file must be finite")
    return value


def _count(value, key: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise ValueError(f"{key}: expected a whole number >= 0, got {_shown(value)}")
    return value


def _shown(value) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _check_training(training) -> None:
    """``training`` as ``cadsim train`` writes it (module docstring); ValueError naming the key."""
    if not isinstance(training, dict):
        raise ValueError("training: expected an object")
    allowed = {"datasets", "rows", "positives", "params", "rounds"}
    extra = sorted(set(training) - allowed)
    if extra:
        raise ValueError(f"training.{extra[0]}: unexpected key; expected {sorted(allowed)}")
    datasets = training.get("datasets")
    if not isinstance(datasets, list):
        raise ValueError(f"training.datasets: expected a list, got {_shown(datasets)}")
    keys = {"name", "checksum", "pairs", "records"}
    for i, entry in enumerate(datasets):
        where = f"training.datasets[{i}]"
        if not isinstance(entry, dict):
            raise ValueError(f"{where}: expected an object, got {_shown(entry)}")
        if set(entry) != keys:
            odd = sorted(set(entry) ^ keys)[0]
            raise ValueError(f"{where}.{odd}: unexpected or missing key; expected {sorted(keys)}")
        for key in ("name", "checksum"):
            if not isinstance(entry[key], str):
                raise ValueError(f"{where}.{key}: expected a string, got {_shown(entry[key])}")
        _count(entry["pairs"], f"{where}.pairs")
        records = entry["records"]
        if not isinstance(records, list):
            raise ValueError(f"{where}.records: expected a list, got {_shown(records)}")
        for j, record in enumerate(records):
            if not isinstance(record, str):
                raise ValueError(f"{where}.records[{j}]: expected a checksum, got {_shown(record)}")
    for key in ("rows", "positives"):
        if key in training:
            counts = training[key]
            if not isinstance(counts, dict) or not set(counts) <= set(VARIANTS):
                raise ValueError(
                    f"training.{key}: expected an object with keys from {list(VARIANTS)}"
                )
            for variant, value in counts.items():
                _count(value, f"training.{key}.{variant}")
    if "params" in training:
        params = training["params"]
        if not isinstance(params, dict):
            raise ValueError(f"training.params: expected an object, got {_shown(params)}")
        for key, value in params.items():
            if not isinstance(value, str | int | float | bool):
                raise ValueError(f"training.params.{key}: expected a number, word or flag")
    if "rounds" in training:
        rounds = _count(training["rounds"], "training.rounds")
        if not 1 <= rounds <= _MAX_ROUNDS:
            raise ValueError(f"training.rounds: {rounds}, expected 1..{_MAX_ROUNDS}")


@lru_cache(maxsize=8)
def _from_bytes(data: bytes, digest: str) -> LearnedModel:
    if len(data) > MAX_FILE_BYTES:
        raise ValueError(f"larger than {MAX_FILE_BYTES // 2**20} MiB; not a model file")
    depth, where = _json_depth(data)
    if depth > MAX_JSON_DEPTH:
        raise ValueError(
            f"JSON nested {depth} deep at byte {where:,} (a model file is at most "
            f"{MAX_JSON_DEPTH}); not a model file"
        )
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ValueError(f"not a model file (JSON expected: {exc.__class__.__name__})") from None
    try:
        document = json.loads(text, parse_constant=_refuse_constant, parse_float=_finite_float)
    except json.JSONDecodeError as exc:
        raise ValueError(f"not a model file (JSON expected: {exc.__class__.__name__})") from None
    except RecursionError:  # not reached after the depth check; kept as a last line of defence
        raise ValueError("not a model file (JSON nested too deep)") from None
    if not isinstance(document, dict):
        raise ValueError("not a model file (a JSON object expected)")
    expected = {"format", "format_version", "features_version", "variants", "training"}
    if set(document) != expected:
        extra = sorted(set(document) ^ expected)
        raise ValueError(f"{extra[0]}: unexpected or missing key; expected {sorted(expected)}")
    if document["format"] != FORMAT:
        raise ValueError(f"format: expected {FORMAT!r}, got {_shown(document['format'])}")
    if type(document["format_version"]) is not int or document["format_version"] != FORMAT_VERSION:
        raise ValueError(
            f"format_version: expected {FORMAT_VERSION}, got {_shown(document['format_version'])}"
        )
    version = document["features_version"]
    if type(version) is not int or version != FEATURES_VERSION:
        raise ValueError(
            f"features_version: the model was trained on features version "
            f"{_shown(version)}, this code computes {FEATURES_VERSION}; retrain it"
        )
    variants = document["variants"]
    if not isinstance(variants, dict) or not variants or not set(variants) <= set(VARIANTS):
        raise ValueError(f"variants: expected a non-empty object with keys from {list(VARIANTS)}")
    boosters = {}
    for name, entry in variants.items():
        if not isinstance(entry, dict) or set(entry) != {"features", "booster"}:
            raise ValueError(f"variants.{name}: expected the keys 'booster' and 'features'")
        if entry["features"] != feature_names(VARIANTS[name]):
            raise ValueError(f"variants.{name}.features: not the features this code computes")
        text = entry["booster"]
        if not isinstance(text, str) or not text.startswith("tree\n"):
            raise ValueError(f"variants.{name}.booster: expected LightGBM's text model format")
        boosters[name] = text
    _check_training(document["training"])
    model = LearnedModel(boosters, document["training"], digest)
    for name, text in boosters.items():  # parsed now: a broken model is refused when loaded
        model._loaded[name] = checked_booster(text, name)
    return model
