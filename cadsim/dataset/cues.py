"""Which cues a record's detections carry for matchers: ``record.json``'s ``cues``.

Camera records (everything ``cadsim generate`` writes, and records without the key) carry
:data:`CAMERA_CUES`: positions, the reported class, an image appearance vector and the boxes'
pixel centres. Box-only records (imported 3-D labels, a LiDAR detector) carry
:data:`~cadsim.sensing.box_features.BOX_CUES`: positions, class, the box size (as the feature
vector of :mod:`cadsim.sensing.box_features`) and the heading — no pixels, so
``Problem.pixels1/2`` are None. Imports only that module.
"""

from __future__ import annotations

from cadsim.sensing.box_features import BOX_CUES

CAMERA_CUES = ("position", "class", "appearance", "pixels")
KNOWN_CUES = tuple(dict.fromkeys(CAMERA_CUES + BOX_CUES))


def record_cues(record: dict) -> tuple[str, ...]:
    """The cues of a parsed ``record.json`` (:data:`CAMERA_CUES` when it does not say)."""
    cues = record.get("cues") if isinstance(record, dict) else None
    return CAMERA_CUES if cues is None else tuple(cues)


def cue_problem(cues) -> str | None:
    """Why ``cues`` (a ``record.json`` value) is not a cue list, or None when it is one: a
    non-empty list of distinct names of :data:`KNOWN_CUES` with ``position`` among them."""
    if not isinstance(cues, list) or not cues or not all(isinstance(c, str) for c in cues):
        return f"expected a non-empty list of cue names, got {str(cues)[:60]}"
    unknown = [c for c in cues if c not in KNOWN_CUES]
    if unknown:
        return f"unknown cues {unknown[:3]} (known: {list(KNOWN_CUES)})"
    if len(set(cues)) != len(cues) or "position" not in cues:
        return f"expected distinct cues including 'position', got {cues[:8]}"
    return None


__all__ = ["BOX_CUES", "CAMERA_CUES", "KNOWN_CUES", "cue_problem", "record_cues"]
