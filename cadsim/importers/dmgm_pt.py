"""Reading the DMGM CAD test pairs (``proc_s/<id>/data.pt`` = view 1, ``proc_t/<id>/data.pt`` =
view 2) into numpy arrays, through ``restricted_pickle`` (no torch, nothing executed).

Each file is ``torch.save((Data, None))`` of a torch_geometric ``Data`` whose mapping holds one
view's n objects; ``read_view`` checks every field's shape, dtype and finiteness and returns a
``DmgmView``. Format and measured regime: docs/external-data.md. Must not import torch, matchers
or eval; writing our dataset format is the converter's job, not this module's.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from cadsim.importers import ImportFormatError
from cadsim.importers.restricted_pickle import PickledObject, load_torch_archive

FEATURE_DIM = 900
"""Length of the appearance descriptor ``x``."""

# Strict: ASCII digits, a 3-digit sequence and a 4-digit frame as DMGM writes them (so "69" can
# never stand for "069"), nothing after the frame (fullmatch: no trailing newline or space).
_NAME = re.compile(
    r"data/proc_(?P<side>[st])/(?P<pair>[0-9]+)/(?P<sequence>[0-9]{3})_(?P<frame>[0-9]{4})",
    re.ASCII,
)
_FLOAT_FIELDS = {"x": FEATURE_DIM, "pos": 3, "pos_world": 3, "norm": 2}


@dataclass(frozen=True)
class DmgmView:
    """One vehicle's view of a DMGM CAD pair; arrays are read-only, row k = object k.

    x: (n, 900) float32 appearance descriptors. y: (n,) int64 CARLA instance ids (same id in both
    views = same object). pos: (n, 3) float32 metres in the vehicle's camera frame (x right, y
    down, z forward). pos_world: (n, 3) float32 metres in the world frame (x, y horizontal, z up)
    through the vehicle's noisy GPS pose. norm: (n, 2) float32 image position, pixels. label:
    (n,) int64 object class. name: ``data/proc_s/<pair>/<sequence>_<frame>``.
    """

    x: np.ndarray
    y: np.ndarray
    pos: np.ndarray
    pos_world: np.ndarray
    norm: np.ndarray
    label: np.ndarray
    name: str

    @property
    def sequence(self) -> str:
        """The driving sequence, e.g. ``"069"``."""
        return _NAME.fullmatch(self.name)["sequence"]

    @property
    def frame(self) -> str:
        """The frame within the sequence, e.g. ``"0914"``."""
        return _NAME.fullmatch(self.name)["frame"]

    def __len__(self) -> int:
        return len(self.y)


class DmgmPair(NamedTuple):
    """One pair: id (folder name), view 1 (``proc_s``), view 2 (``proc_t``), sequence id."""

    pair_id: str
    view_s: DmgmView
    view_t: DmgmView
    sequence: str


def _mapping(obj: object, path: Path) -> dict:
    """The ``Data`` object's field mapping, from ``(Data, slices)``."""
    if not (isinstance(obj, tuple) and len(obj) == 2):
        raise ImportFormatError(
            path, f"top-level object is {type(obj).__name__}, not (Data, slices)"
        )
    data, slices = obj
    if slices is not None:
        raise ImportFormatError(path, "collated dataset (slices not None) is not one view")
    if not (
        isinstance(data, PickledObject) and data.global_name == "torch_geometric.data.data.Data"
    ):
        raise ImportFormatError(path, f"first element is {type(data).__name__}, not Data")
    store = data.state.get("_store")
    if not (
        isinstance(store, PickledObject)
        and store.global_name == "torch_geometric.data.storage.GlobalStorage"
    ):
        raise ImportFormatError(path, "Data has no GlobalStorage '_store'")
    mapping = store.state.get("_mapping")
    if not isinstance(mapping, dict):
        raise ImportFormatError(path, "GlobalStorage has no '_mapping' dict")
    return mapping


def _field(mapping: dict, key: str, path: Path, dtype: type, ndim: int) -> np.ndarray:
    value = mapping.get(key)
    if not isinstance(value, np.ndarray):
        raise ImportFormatError(path, f"field '{key}': missing or not a tensor")
    if value.dtype != dtype or value.ndim != ndim:
        raise ImportFormatError(
            path,
            f"field '{key}': {value.ndim}-d {value.dtype}, expected {ndim}-d {np.dtype(dtype)}",
        )
    return value


def _frozen(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a


def read_view(path: str | Path) -> DmgmView:
    """Read one DMGM CAD ``data.pt``; ``ImportFormatError`` (one line: file, field) if malformed.

    >>> view = read_view("proc_s/60260/data.pt")   # doctest: +SKIP
    >>> view.sequence, len(view), view.pos_world.shape
    ('069', 6, (6, 3))
    """
    path = Path(path)
    mapping = _mapping(load_torch_archive(path), path)
    name = mapping.get("name")
    if not isinstance(name, str) or _NAME.fullmatch(name) is None:
        shown = f"{name[:80]!r}" if isinstance(name, str) else f"a {type(name).__name__}"
        raise ImportFormatError(
            path,
            f"field 'name': {shown} is not data/proc_<s|t>/<id>/<sequence: 3 digits>_"
            "<frame: 4 digits>",
        )
    label = _field(mapping, "label", path, np.int32, 1)
    ids = _field(mapping, "y", path, np.float32, 1)
    n = len(ids)
    arrays = {}
    for key, width in _FLOAT_FIELDS.items():
        a = _field(mapping, key, path, np.float32, 2)
        if a.shape != (n, width):
            raise ImportFormatError(
                path, f"field '{key}': shape {a.shape}, expected ({n}, {width})"
            )
        arrays[key] = a
    if label.shape != (n,):
        raise ImportFormatError(path, f"field 'label': shape {label.shape}, expected ({n},)")
    for key, a in {"y": ids, **arrays}.items():
        if not np.isfinite(a).all():
            raise ImportFormatError(path, f"field '{key}': non-finite values")
    if not (np.all(ids == np.round(ids)) and np.all(np.abs(ids) < 2**24)):
        raise ImportFormatError(path, "field 'y': instance ids are not exact integers")
    y = ids.astype(np.int64)
    if len(np.unique(y)) != n:
        raise ImportFormatError(path, "field 'y': an instance id appears twice in one view")
    return DmgmView(
        x=_frozen(arrays["x"]),
        y=_frozen(y),
        pos=_frozen(arrays["pos"]),
        pos_world=_frozen(arrays["pos_world"]),
        norm=_frozen(arrays["norm"]),
        label=_frozen(label.astype(np.int64)),
        name=name,
    )


def iter_pairs(src_dir: str | Path) -> Iterator[DmgmPair]:
    """Yield every pair of a folder laid out as ``proc_s/<id>/data.pt`` + ``proc_t/<id>/data.pt``,
    sorted by numeric id. Both folders must hold the same ids, and both views of a pair the same
    sequence and frame; otherwise ``ImportFormatError`` naming the folder or file.

    >>> for pair_id, view_s, view_t, sequence in iter_pairs("dmgm-cad"):   # doctest: +SKIP
    ...     print(pair_id, sequence, len(view_s), len(view_t))
    """
    src_dir = Path(src_dir)
    ids = {}
    for side in ("proc_s", "proc_t"):
        folder = src_dir / side
        if not folder.is_dir():
            raise ImportFormatError(folder, "missing folder (expected proc_s/<id>/data.pt layout)")
        ids[side] = {p.name for p in folder.iterdir() if p.is_dir()}
        bad = sorted(i for i in ids[side] if not i.isdigit())[:3]
        if bad:
            raise ImportFormatError(folder, f"pair folders {bad} are not numeric ids")
    only = sorted(ids["proc_s"] ^ ids["proc_t"], key=int)[:5]
    if only:
        raise ImportFormatError(src_dir, f"pairs {only} are in only one of proc_s/ and proc_t/")
    seen: dict[tuple[str, str], str] = {}
    for pair_id in sorted(ids["proc_s"], key=int):
        path_s = src_dir / "proc_s" / pair_id / "data.pt"
        path_t = src_dir / "proc_t" / pair_id / "data.pt"
        view_s, view_t = read_view(path_s), read_view(path_t)
        for path, view, side in ((path_s, view_s, "s"), (path_t, view_t, "t")):
            claimed = _NAME.fullmatch(view.name)
            if (claimed["side"], claimed["pair"]) != (side, pair_id):
                raise ImportFormatError(
                    path,
                    f"its name {view.name!r} claims another pair or side than proc_{side}/{pair_id}",
                )
            if len(view) == 0:
                raise ImportFormatError(path, "a view with no objects (nothing to match)")
        if (view_s.sequence, view_s.frame) != (view_t.sequence, view_t.frame):
            raise ImportFormatError(
                path_t, f"frame {view_t.name!r} differs from view 1's {view_s.name!r}"
            )
        frame = (view_s.sequence, view_s.frame)
        if frame in seen:
            raise ImportFormatError(
                path_s, f"pairs {seen[frame]} and {pair_id} are the same frame {'_'.join(frame)}"
            )
        seen[frame] = pair_id
        yield DmgmPair(pair_id, view_s, view_t, view_s.sequence)
