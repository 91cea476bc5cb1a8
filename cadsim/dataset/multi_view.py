"""An N-view snapshot record read as its views and as two-view pairs (DESIGN §12).

``SnapshotViews(pair, n_views)`` wraps record k of an N-view dataset (``Dataset.snapshot(k)``):
``view(i)`` is view i's detections (1-based; positions in that observer's camera frame, metres;
ground-truth object ids shared by every view), ``pair(i, j)`` the two-view
:class:`~cadsim.dataset.reader.FramePair` of views i and j — today's ``Problem`` for every
matcher, its prior drawn with views i and j's own seeds (a roadside unit's pose is exact) and
its latency moving view j as the sender. A record that is not a well-formed N-view record is
refused with one line (``DatasetError``) before anything else is read from it.
"""

from __future__ import annotations

from functools import cached_property
from itertools import combinations
from typing import TYPE_CHECKING

from cadsim.dataset import layout
from cadsim.dataset.detections import ViewDetections
from cadsim.dataset.encoding import load_npz
from cadsim.dataset.manifest import DatasetError

if TYPE_CHECKING:  # the reader imports this module
    from cadsim.dataset.reader import FramePair

KINDS = ("vehicle", "roadside")


class SnapshotViews:
    """Record ``first.path`` as ``n_views`` views; ``first``: its pair (1, 2) as the dataset
    reads it (index, entry, noise and detection configuration are taken from it)."""

    def __init__(self, first: FramePair, n_views: int) -> None:
        self._first = first
        self.n_views = int(n_views)
        self.index = first.index
        self.name = first.name
        self.path = first.path
        self._check()

    def __repr__(self) -> str:
        sizes = ", ".join(str(len(self.view(i))) for i in range(1, self.n_views + 1))
        return f"SnapshotViews(index={self.index}, name={self.name!r}, detections=[{sizes}])"

    @property
    def record(self) -> dict:
        return self._first.record

    def _check(self) -> None:
        """One-line refusal of a record that does not hold ``n_views`` well-formed views."""
        where = self.path / layout.RECORD_JSON
        record = self.record
        if not isinstance(record, dict):
            raise DatasetError(f"{where}: expected a JSON object")
        observers = record.get("observers")
        if self.n_views > 2 and record.get("views") != self.n_views:
            raise DatasetError(
                f"{where}: views: expected {self.n_views} (the manifest's), got "
                f"{str(record.get('views'))[:40]}"
            )
        if not isinstance(observers, list) or len(observers) != self.n_views:
            count = len(observers) if isinstance(observers, list) else type(observers).__name__
            raise DatasetError(
                f"{where}: observers: expected a list of {self.n_views} entries, got {count}"
            )
        for k, entry in enumerate(observers):
            kind = entry.get("kind", "vehicle") if isinstance(entry, dict) else None
            if kind not in KINDS:
                raise DatasetError(
                    f"{where}: observers[{k}].kind: expected one of {list(KINDS)}, got "
                    f"{str(kind)[:40]}"
                )
        for i in range(1, self.n_views + 1):
            self.view(i)  # every view's arrays are present and consistent

    @cached_property
    def _arrays(self) -> dict:
        what = self.path / layout.DETECTIONS_NPZ
        if not what.is_file():
            raise DatasetError(f"{what}: missing record file")
        return load_npz(str(what), str(what))

    def view(self, i: int) -> ViewDetections:
        """View ``i``'s detections (1-based)."""
        self._check_view(i)
        what = str(self.path / layout.DETECTIONS_NPZ)
        try:
            return ViewDetections.from_arrays(self._arrays, f"view{i}", what)
        except ValueError as exc:
            raise DatasetError(str(exc).splitlines()[0]) from None

    def _check_view(self, i) -> None:
        if isinstance(i, bool) or not isinstance(i, int) or not 1 <= i <= self.n_views:
            raise ValueError(f"view: expected an integer in 1..{self.n_views}, got {i!r}")

    @property
    def kinds(self) -> list[str]:
        """Per view "vehicle" or "roadside"."""
        return [o.get("kind", "vehicle") for o in self.record["observers"]]

    @property
    def observer_ids(self) -> list[str]:
        return [o["id"] for o in self.record["observers"]]

    def pair(self, i: int, j: int) -> FramePair:
        """The two-view frame pair of views ``i`` and ``j`` (1-based, i != j; view i is the
        receiver, view j the sender)."""
        self._check_view(i)
        self._check_view(j)
        if i == j:
            raise ValueError(f"pair: expected two different views, got ({i}, {j})")
        if (i, j) == (1, 2):
            return self._first
        return self._first.of_views(i, j)

    def pairs(self, views: tuple[int, ...] | None = None) -> list[tuple[int, int]]:
        """Every pair (i, j), i < j, of ``views`` (default: all views), in order."""
        chosen = tuple(range(1, self.n_views + 1)) if views is None else tuple(views)
        return list(combinations(chosen, 2))
