"""Stable ids for highway-env vehicles, which carry no id of their own.

A vehicle is the same vehicle for as long as the same Python object is on the road. The tracker
keeps a strong reference to every object it has seen in the latest update, so the object's
``id()`` cannot be reused by a newly created vehicle while the tracker still maps it; an object
that leaves the road is forgotten at the next update and a later vehicle never inherits its id.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass


@dataclass(frozen=True)
class TrackUpdate:
    """Result of one update: ``ids`` in the order of the objects given, the ids seen for the first
    time (same order), and the ids that left since the previous update (sorted)."""

    ids: list[str]
    new: list[str]
    gone: list[str]


class VehicleTracker:
    """Maps live objects to ids ``f"{prefix}{n}"``, n = 0, 1, 2, … in order of first sight."""

    def __init__(self, prefix: str = "hw") -> None:
        self.prefix = prefix
        self._next = 0
        # id(obj) -> (obj, stable id); the stored obj pins the address while it is mapped.
        self._live: dict[int, tuple[object, str]] = {}

    def __len__(self) -> int:
        return len(self._live)

    def update(self, objects: Iterable[object]) -> TrackUpdate:
        """Register the objects present now; returns their ids and which ids are new or gone."""
        objects = list(objects)
        current: dict[int, tuple[object, str]] = {}
        ids: list[str] = []
        new: list[str] = []
        for obj in objects:
            key = id(obj)
            if key in current:
                raise ValueError(
                    f"VehicleTracker.update: the same object is listed twice ({obj!r})"
                )
            entry = self._live.get(key)
            if entry is None or entry[0] is not obj:
                entry = (obj, f"{self.prefix}{self._next}")
                self._next += 1
                new.append(entry[1])
            current[key] = entry
            ids.append(entry[1])
        gone = sorted(
            (sid for key, (_, sid) in self._live.items() if key not in current),
            key=lambda s: int(s[len(self.prefix) :]),
        )
        self._live = current
        return TrackUpdate(ids=ids, new=new, gone=gone)
