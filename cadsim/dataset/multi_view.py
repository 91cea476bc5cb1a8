"""An N-view snapshot record read as its views and as two-view pairs (DESIGN §12).

``SnapshotViews(pair, n_views)`` wraps record k of an N-view dataset (``Dataset.snapshot(k)``):
``view(i)`` is view i's detections (1-based; positions in that observer's camera frame, metres;
ground-truth object ids shared by every view), ``pair(i, j)`` the two-view
:class:`~cadsim.dataset.frame_pair.FramePair` of views i and j — today's ``Problem`` for every
matcher, its prior drawn with views i and j's own seeds (a roadside unit's pose is exact) and
its latency moving view j as the sender. A record that is not a well-formed N-view record is
refused with one line (``DatasetError``) before anything else is read from it, by the checks
verification makes (:mod:`cadsim.dataset.verification`).
"""

from __future__ import annotations

from functools import cached_property
from itertools import combinations
from typing import TYPE_CHECKING

from cadsim.dataset import layout
from cadsim.dataset.detections import ViewDetections
from cadsim.dataset.encoding import load_npz
from cadsim.dataset.manifest import DatasetError
from cadsim.dataset.record_format import OBSERVER_KINDS as KINDS  # noqa: F401  (its old name)
from cadsim.dataset.verification import RecordLayout, check_record_json, check_views

if TYPE_CHECKING:  # annotations only (frame_pair imports nothing of this module either)
    from cadsim.dataset.frame_pair import FramePair


class SnapshotViews:
    """Record ``first.path`` as ``n_views`` views; ``first``: its pair (1, 2) as the dataset
    reads it (index, entry, noise and detection configuration are taken from it). ``expected``:
    what the manifest says the record is (``Dataset.snapshot`` gives it; default: ``n_views``
    views of the record's own format version and ``first``'s record files)."""

    def __init__(
        self, first: FramePair, n_views: int, expected: RecordLayout | None = None
    ) -> None:
        self._first = first
        self.n_views = int(n_views)
        self.index = first.index
        self.name = first.name
        self.path = first.path
        if expected is None:  # the record's own format version
            record = first.record
            version = record.get("format_version") if isinstance(record, dict) else None
            if isinstance(version, bool) or not isinstance(version, int):
                raise DatasetError(
                    f"{self.path / layout.RECORD_JSON}: format_version: expected an integer, "
                    f"got {str(version)[:40]}"
                )
            expected = RecordLayout(version, self.n_views, tuple(first._record_files))
        self._expected = expected
        self._check()

    def __repr__(self) -> str:
        sizes = ", ".join(str(len(self.view(i))) for i in range(1, self.n_views + 1))
        return f"SnapshotViews(index={self.index}, name={self.name!r}, detections=[{sizes}])"

    @property
    def record(self) -> dict:
        return self._first.record

    def _check(self) -> None:
        """One-line refusal of a record that does not hold ``n_views`` well-formed views: the
        checks of ``record.json`` and ``detections.npz`` that verification makes
        (:mod:`cadsim.dataset.verification`), on the record as read."""
        check_record_json(self.record, self.path / layout.RECORD_JSON, self._expected)
        _ = self._views  # every view's arrays are present and well-formed

    @cached_property
    def _arrays(self) -> dict:
        what = self.path / layout.DETECTIONS_NPZ
        if not what.is_file():
            raise DatasetError(f"{what}: missing record file")
        try:
            return load_npz(str(what), str(what))
        except ValueError as exc:
            raise DatasetError(str(exc).splitlines()[0]) from None

    def view(self, i: int) -> ViewDetections:
        """View ``i``'s detections (1-based)."""
        self._check_view(i)
        return self._views[i - 1]

    @cached_property
    def _views(self) -> list[ViewDetections]:
        return check_views(self._arrays, self.path / layout.DETECTIONS_NPZ, self._expected)

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
