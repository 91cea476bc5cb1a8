"""eval.core.snapshot_memo: a snapshot is read once per process and key; the least recently used
is dropped beyond the bound. (Same bits as a fresh reading: tests/test_multi_view.py.)"""

from __future__ import annotations

from eval.core import snapshot_memo


class Reads:
    """A stand-in dataset that counts its snapshot reads."""

    def __init__(self) -> None:
        self.reads: list[int] = []

    def snapshot(self, k: int) -> tuple[str, int]:
        self.reads.append(k)
        return ("snapshot", k)


def test_a_snapshot_is_read_once_per_dataset_checksum_sensor_and_index():
    snapshot_memo.forget()
    ds = Reads()
    first = snapshot_memo.snapshot(ds, "d", "c1", None, 3)
    assert snapshot_memo.snapshot(ds, "d", "c1", None, 3) is first
    snapshot_memo.snapshot(ds, "d", "c2", None, 3)  # the dataset changed: read again
    snapshot_memo.snapshot(ds, "d", "c1", "lidar", 3)
    snapshot_memo.snapshot(ds, "e", "c1", None, 3)
    assert ds.reads == [3, 3, 3, 3]
    snapshot_memo.forget()


def test_the_least_recently_used_snapshot_is_dropped_beyond_the_bound(monkeypatch):
    snapshot_memo.forget()
    monkeypatch.setattr(snapshot_memo, "SNAPSHOTS", 2)
    ds = Reads()
    for k in (0, 1, 0, 2):  # 1 is the least recently used when 2 arrives
        snapshot_memo.snapshot(ds, "d", "c", None, k)
    snapshot_memo.snapshot(ds, "d", "c", None, 0)
    snapshot_memo.snapshot(ds, "d", "c", None, 1)
    assert ds.reads == [0, 1, 2, 1]
    snapshot_memo.forget()
