"""What a sequence's frames must agree on: the checks that need more than one record.

Each record of a format-7 dataset is verified on its own (:mod:`cadsim.dataset.verification`);
this module checks a sequence as a whole, from its records' ``record.json``:

- ``sequence.frames`` is the number of frames the manifest lists for it;
- ``interval_s``, ``start_time`` and the odometry ``model`` are the same in every frame;
- the records' ``time`` (when not null) increases strictly from frame to frame, and frame 0's
  is ``start_time``;
- every frame has the same observers in the same order — each observer's kind, odometry seed
  and the part of its id before ``:`` (imported ids carry the source frame after it).

Every refusal is one ``DatasetError`` line naming the record file and the key.
"""

from __future__ import annotations

import json
from pathlib import Path

from cadsim.dataset import layout
from cadsim.dataset.manifest import DatasetError


def _observers(record: dict) -> list[tuple]:
    """Per observer: (kind, odometry seed, id before ':')."""
    return [
        (o.get("kind", "vehicle"), o.get("odometry_seed"), str(o.get("id")).partition(":")[0])
        for o in record["observers"]
    ]


def check_sequences(dataset: Path, entries: list[dict]) -> None:
    """``DatasetError`` unless every sequence of the (individually verified) records
    ``entries`` (the manifest's, in order) is consistent (module docstring)."""
    groups: dict[str, list[dict]] = {}
    for entry in entries:
        groups.setdefault(entry["sequence"], []).append(entry)
    pairs = Path(dataset) / layout.PAIRS_DIR
    for frames in groups.values():
        first = None
        previous_time = None
        for entry in frames:
            where = pairs / entry["name"] / layout.RECORD_JSON
            record = json.loads(where.read_bytes())
            sequence = record["sequence"]
            if sequence["frames"] != len(frames):
                raise DatasetError(
                    f"{where}: sequence.frames: {sequence['frames']}, but the manifest lists "
                    f"{len(frames)} frames of sequence {entry['sequence']}"
                )
            time = record.get("time")
            if first is None:
                first = (sequence, _observers(record))
                if time is not None and time != sequence["start_time"]:
                    raise DatasetError(
                        f"{where}: time: frame 0 is at start_time {sequence['start_time']!r}, "
                        f"got {time!r}"
                    )
            else:
                for key in ("interval_s", "start_time", "model"):
                    if sequence.get(key) != first[0].get(key):
                        raise DatasetError(
                            f"{where}: sequence.{key}: {str(sequence.get(key))[:60]}, but frame 0 "
                            f"of the sequence says {str(first[0].get(key))[:60]}"
                        )
                if _observers(record) != first[1]:
                    raise DatasetError(
                        f"{where}: observers: not frame 0's observers in frame 0's order "
                        "(kind, odometry_seed, id)"
                    )
                if time is not None and previous_time is not None and not time > previous_time:
                    raise DatasetError(
                        f"{where}: time: {time!r}, not after the previous frame's {previous_time!r}"
                    )
            previous_time = time


__all__ = ["check_sequences"]
