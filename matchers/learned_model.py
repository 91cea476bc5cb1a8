"""The learned matchers' model file: JSON data, never code.

A model file holds one gradient-boosted classifier per variant (``learned``: features without the
prior; ``learned_pose``: with it) as LightGBM's own text format — a list of trees, parsed, not
executed — beside what it was trained on::

    {"format": "cadsim-learned-model", "format_version": 1, "features_version": 1,
     "variants": {"learned": {"features": [...], "booster": "tree\\nversion=v4\\n..."}, ...},
     "training": {"datasets": [{"name", "checksum", "pairs", "records": [record checksums]}],
                  "rows": {...}, "positives": {...}, "params": {...}, "rounds": 200}}

The bytes are deterministic (sorted keys, no times, no paths): the same training data give the
same file on every machine. Loading checks every key before LightGBM sees the trees; anything
unexpected is refused with one line naming the file and the key.
"""

from __future__ import annotations

import hashlib
import json
import logging
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

from matchers.learned_features import FEATURES_VERSION, feature_names

log = logging.getLogger(__name__)

FORMAT = "cadsim-learned-model"
FORMAT_VERSION = 1
VARIANTS = {"learned": False, "learned_pose": True}  # variant -> uses the localisation prior
_MAX_BYTES = 64 * 2**20


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
            width = len(feature_names(VARIANTS[variant]))
            booster = self._loaded[variant] = _parse_booster(self.boosters[variant], variant, width)
        return np.asarray(booster.predict(features, num_threads=1), dtype=float)


class _LightGBMLog:
    """LightGBM's messages (its "[Fatal] ..." before an exception, included) to debug logging:
    the error a user sees is ours, in one line."""

    def info(self, msg: str) -> None:
        log.debug("lightgbm: %s", msg.strip())

    def warning(self, msg: str) -> None:
        log.debug("lightgbm: %s", msg.strip())


def _parse_booster(text: str, variant: str, width: int):
    import lightgbm

    lightgbm.register_logger(_LightGBMLog())
    try:
        booster = lightgbm.Booster(model_str=text, params={"num_threads": 1})
    except lightgbm.basic.LightGBMError as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else "unreadable"
        raise ValueError(f"variants.{variant}.booster: not a LightGBM model ({first})") from None
    if booster.num_feature() != width:
        raise ValueError(
            f"variants.{variant}.booster: {booster.num_feature()} features, expected {width}"
        )
    return booster


def save_model(model: LearnedModel, path: str | Path) -> str:
    """Write ``model`` to ``path`` (atomically: a temporary file, then a rename); its sha256."""
    path = Path(path)
    data = model.to_bytes()
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(path.name + ".partial")
    partial.write_bytes(data)
    partial.replace(path)
    return hashlib.sha256(data).hexdigest()


def load_model(path: str | Path, sha256: str | None = None) -> LearnedModel:
    """The model at ``path``; ValueError in one line naming the file and what is wrong (missing,
    not JSON, an unexpected key or value, features of another version, a ``sha256`` other than
    the expected one). Cached by the file's content."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise ValueError(f"{path}: cannot read the model file ({exc.strerror})") from None
    digest = hashlib.sha256(data).hexdigest()
    if sha256 is not None and digest != sha256:
        raise ValueError(
            f"{path}: the model file changed (sha256 {digest[:12]}, expected {sha256[:12]}); "
            "evaluate it again"
        )
    try:
        return _from_bytes(data, digest)
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None


@lru_cache(maxsize=8)
def _from_bytes(data: bytes, digest: str) -> LearnedModel:
    if len(data) > _MAX_BYTES:
        raise ValueError(f"larger than {_MAX_BYTES // 2**20} MiB; not a model file")
    try:
        document = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"not a model file (JSON expected: {exc.__class__.__name__})") from None
    if not isinstance(document, dict):
        raise ValueError("not a model file (a JSON object expected)")
    expected = {"format", "format_version", "features_version", "variants", "training"}
    if set(document) != expected:
        extra = sorted(set(document) ^ expected)
        raise ValueError(f"{extra[0]}: unexpected or missing key; expected {sorted(expected)}")
    if document["format"] != FORMAT:
        raise ValueError(f"format: expected {FORMAT!r}, got {document['format']!r}")
    if document["format_version"] != FORMAT_VERSION:
        raise ValueError(
            f"format_version: expected {FORMAT_VERSION}, got {document['format_version']!r}"
        )
    if document["features_version"] != FEATURES_VERSION:
        raise ValueError(
            f"features_version: the model was trained on features version "
            f"{document['features_version']!r}, this code computes {FEATURES_VERSION}; retrain it"
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
    if not isinstance(document["training"], dict):
        raise ValueError("training: expected an object")
    model = LearnedModel(boosters, document["training"], digest)
    for name, text in boosters.items():  # parsed now: a broken model is refused when loaded
        model._loaded[name] = _parse_booster(text, name, len(feature_names(VARIANTS[name])))
    return model
