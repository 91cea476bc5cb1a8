"""Record times of imported data, decided in one place for every importer.

A record's ``time`` is what a localisation preset's GNSS walk is drawn at (it counts from t = 0,
the recording's start; docs/localisation.md), so an importer never keeps a source's clock as it
is: each sequence's (or scene's) times count from its first frame, the source's own time kept in
the record's ``meta.source_time_s``. A group whose frames have no time gets 0 for a snapshot and
``k × interval_s`` for frame k of a sequence; the manifest's ``source.time`` counts both kinds
(:class:`TimeNote`). Refused, one line naming the file: a group where some frames have a time
and others not, a time that is not finite, a sequence whose times do not increase, mixed units
(seconds beside milli- or microseconds) and a group spanning more than :data:`MAX_SPAN_S`.

The one exception is cadsim's own clock (``cadsim export opv2v``'s ``start_time``): already
counted from its simulation's start, it is kept when the group lies within a day of 0, so a
round trip keeps every drawn prior. Must not import matchers or eval.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from cadsim.importers import ImportFormatError
from cadsim.importers.box_sequence import DEFAULT_INTERVAL_S, ImportedFrame

MAX_SPAN_S = 86_400.0  # one day: no cooperative recording is longer; 51 years is mixed units


@dataclass
class TimeNote:
    """What the importer did with its records' times, for the manifest's ``source.time``."""

    relative: int = 0  # records whose time counts from their group's first frame
    kept: int = 0  # records on cadsim's own clock, kept
    missing: int = 0  # records whose source gave no time (0, or k × interval_s in a sequence)

    def as_manifest(self) -> dict:
        """``source.time`` of the manifest: the rule and the counts."""
        return {
            "counted_from": "the first frame of each sequence or scene (source time in "
            "meta.source_time_s); cadsim's own clock kept",
            "relative": self.relative,
            "kept": self.kept,
            "missing": self.missing,
            "missing_as": "0 s for a snapshot, k x interval_s for frame k of a sequence",
        }


def relative_times(
    frames: Sequence[ImportedFrame],
    path: str | Path,
    what: str,
    *,
    ordered: bool,
    interval_s: float | None = None,
    own_clock: bool = False,
    note: TimeNote | None = None,
) -> list[ImportedFrame]:
    """``frames`` (one sequence when ``ordered``, else one scene of snapshots) with times counted
    from the group's first frame (seconds; module docstring). ``path`` and ``what`` name the file
    and group in a refusal (``ImportFormatError``); ``interval_s``: a timeless sequence's step
    (default :data:`DEFAULT_INTERVAL_S`); ``own_clock``: the times are cadsim's own, kept when
    within a day of 0; ``note`` counts what was done.

    >>> f = [ImportedFrame(1.6e9 + k * 0.1, ()) for k in range(3)]
    >>> [round(x.time, 3) for x in relative_times(f, "info.json", "sequence 1", ordered=True)]
    [0.0, 0.1, 0.2]
    """
    note = TimeNote() if note is None else note
    if not frames:
        return []
    given = [f.time is not None for f in frames]
    if not any(given):
        note.missing += len(frames)
        step = interval_s or DEFAULT_INTERVAL_S
        return [replace(f, time=k * step if ordered else 0.0) for k, f in enumerate(frames)]
    if not all(given):
        raise ImportFormatError(
            path,
            f"{what}: {given.count(False)} of {len(frames)} frames have no time "
            "(expected a time for every frame or for none)",
        )
    times = np.array([float(f.time) for f in frames])
    if not np.isfinite(times).all():
        bad = int(np.flatnonzero(~np.isfinite(times))[0])
        raise ImportFormatError(path, f"{what}: frame {bad}: time {times[bad]!r} is not finite")
    if ordered and times.size > 1 and not (np.diff(times) > 0).all():
        k = int(np.flatnonzero(np.diff(times) <= 0)[0])
        raise ImportFormatError(
            path,
            f"{what}: frame {k + 1}'s time {times[k + 1]:.6g} s is not after frame {k}'s "
            f"{times[k]:.6g} s (expected increasing times)",
        )
    _check_span(times, path, what)
    if own_clock and times.min() >= 0 and times.max() <= MAX_SPAN_S:
        note.kept += len(frames)
        return list(frames)
    origin = float(times[0] if ordered else times.min())
    note.relative += len(frames)
    return [
        replace(f, time=float(t - origin), meta=f.meta | {"source_time_s": float(t)})
        for f, t in zip(frames, times, strict=True)
    ]


def _check_span(times: np.ndarray, path: str | Path, what: str) -> None:
    """Refuse mixed units and a group longer than a day."""
    span = float(times.max() - times.min())
    if span <= MAX_SPAN_S:
        return
    sizes = np.abs(times[times != 0])
    if math.floor(math.log10(sizes.max())) - math.floor(math.log10(sizes.min())) >= 2:
        raise ImportFormatError(
            path,
            f"{what}: times from {times.min():.6g} to {times.max():.6g} mix units (seconds "
            "beside milli- or microseconds; expected one unit)",
        )
    raise ImportFormatError(
        path,
        f"{what}: times span {span:.6g} s (expected a sequence or scene within "
        f"{MAX_SPAN_S:.0f} s, one day)",
    )


__all__ = ["MAX_SPAN_S", "TimeNote", "relative_times"]
