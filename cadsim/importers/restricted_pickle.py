"""The project's one pickle reader: ``torch.save`` zip archives read without torch and without
executing anything from the file.

A torch zip archive holds ``<prefix>/data.pkl`` (a protocol-2 pickle of the saved object),
``<prefix>/data/<key>`` (each tensor storage's raw little-endian bytes) and ``<prefix>/version``.
``load_torch_archive(path)`` returns the unpickled object with every global replaced by a local
stand-in from ``ALLOWLIST``: tensors become numpy arrays, ``collections.OrderedDict`` a dict, and
an allowlisted class a ``PickledObject`` holding the state dict pickle gave it.

Guarantee: the only callables a pickle can reach are the stand-ins below. ``find_class`` refuses
every other global (``os.system``, ``builtins.eval``, any other torch or torch_geometric name);
each stand-in accepts only the use this format makes of it (``_rebuild_tensor_v2`` and
``OrderedDict`` via REDUCE, the two classes via NEWOBJ; calling a class or a marker is refused).
Before unpickling, every opcode is parsed with ``pickletools`` and checked against the opcodes a
protocol-2 pickler emits, so truncated length prefixes and huge memo indices are refused before
the C unpickler would allocate for them; storage sizes and tensor extents are checked against the
bytes actually present, and bounded (:data:`MAX_STORAGE_BYTES`); members are read stored or
deflated only, in chunks with a running limit, so nothing is allocated from a declared size
first and a decompression bomb stops at the limit. Every failure is one ``ImportFormatError``
line naming the file.

Must not import torch, torch_geometric, or anything outside numpy and the standard library.
"""

from __future__ import annotations

import io
import math
import os
import pickle
import pickletools
import zipfile
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np

from cadsim.importers import ImportFormatError

MAX_ARCHIVE_BYTES = 256 * 2**20
"""Largest ``.pt`` file read (bytes); the DMGM files are ≤ 80 KiB."""
MAX_PICKLE_BYTES = 2**20
"""Largest ``data.pkl`` read (bytes); the DMGM pickles are 823 bytes."""
MAX_MEMO_INDEX = 2**16
"""Largest memo index accepted: the C unpickler grows its memo table to the index it is given."""
MAX_STORAGE_BYTES = 64 * 2**20
"""Largest tensor storage read (bytes). A DMGM view holds a few hundred objects at most, each with
a 900-value float32 feature: well under 2 MiB; the largest shipped storage is 22 KiB."""
MAX_TENSOR_DIMS = 32
"""Most axes of one tensor (numpy's own limit is 64; a DMGM tensor has 1 or 2)."""
MAX_MEMBER_BYTES = 256 * 2**20
"""Largest total of decompressed bytes read from one archive."""
_COMPRESSIONS = (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED)
"""What ``torch.save`` writes (stored; deflate from other zip tools). bzip2 and lzma, whose
ratios make small bombs, are refused."""

_PROTOCOL_2_OPCODES = frozenset(
    {
        # Structure and memo.
        "PROTO", "STOP", "MARK", "POP", "POP_MARK", "DUP",
        "BINPUT", "LONG_BINPUT", "BINGET", "LONG_BINGET",
        # Plain values.
        "NONE", "NEWTRUE", "NEWFALSE", "BININT", "BININT1", "BININT2", "LONG1", "LONG4",
        "BINFLOAT", "BINUNICODE",
        # Containers.
        "EMPTY_TUPLE", "TUPLE", "TUPLE1", "TUPLE2", "TUPLE3",
        "EMPTY_LIST", "APPEND", "APPENDS", "EMPTY_DICT", "SETITEM", "SETITEMS",
        # Globals (through find_class), calls (only stand-ins are reachable), storages.
        "GLOBAL", "REDUCE", "NEWOBJ", "BUILD", "BINPERSID",
    }
)  # fmt: skip
"""Opcodes accepted in ``data.pkl``: those a protocol-2 pickler (torch's default) emits for this
kind of object. Refused, among others: INST/OBJ/EXT*/NEWOBJ_EX (other ways to reach a callable),
text-mode PERSID/GET/PUT, protocol-3+ bytes and out-of-band buffers."""


class _Refused(pickle.UnpicklingError):
    """A stand-in was used in a way this format never uses it."""


def _refuse_setstate(self: object, state: object) -> None:
    """``__setstate__`` of the slotted stand-ins: pickle's BUILD may not alter them (a frozen
    slotted dataclass's own ``__setstate__`` would write the fields, frozen or not)."""
    raise _Refused(f"BUILD on {type(self).__name__} is not part of this format")


@dataclass(frozen=True, slots=True)
class StorageType:
    """Stand-in for a torch storage class (``torch.FloatStorage``): the dtype of its raw bytes."""

    global_name: str
    dtype: np.dtype
    __setstate__ = _refuse_setstate

    def __call__(self, *args: object, **kwargs: object) -> None:
        raise _Refused(f"call of {self.global_name} is not part of this format")


@dataclass(frozen=True, slots=True)
class ClassReference:
    """Stand-in for a class the pickle stores as a value, never instantiates
    (``torch_geometric.data.data.DataEdgeAttr``)."""

    global_name: str
    __setstate__ = _refuse_setstate

    def __call__(self, *args: object, **kwargs: object) -> None:
        raise _Refused(f"call of {self.global_name} is not part of this format")


@dataclass(frozen=True, slots=True)
class Storage:
    """One tensor storage: ``values`` (numel,) read-only, little-endian, as stored in the archive."""

    key: str
    values: np.ndarray
    __setstate__ = _refuse_setstate


class PickledObject:
    """Stand-in instance of an allowlisted class: no behaviour, only ``state``, the dict that
    pickle's BUILD gave it. Created by NEWOBJ with no arguments; a plain call (REDUCE) is refused."""

    global_name: ClassVar[str] = ""

    def __new__(cls, *args: object) -> PickledObject:
        if args:
            raise _Refused(f"{cls.global_name} created with arguments {args!r}")
        obj = super().__new__(cls)
        obj.state = {}
        return obj

    def __init__(self, *args: object, **kwargs: object) -> None:
        # NEWOBJ calls only __new__; reaching __init__ means the pickle called the class.
        raise _Refused(f"call of {self.global_name} is not part of this format")

    def __setstate__(self, state: object) -> None:
        if not isinstance(state, dict):
            raise _Refused(f"{self.global_name} state is {type(state).__name__}, not a dict")
        self.state = state

    def __repr__(self) -> str:
        return f"<{self.global_name} stand-in, keys {sorted(map(str, self.state))}>"


def _object_stand_in(global_name: str) -> type[PickledObject]:
    return type(global_name.rsplit(".", 1)[1], (PickledObject,), {"global_name": global_name})


def _is_int(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def rebuild_tensor(
    storage: object,
    storage_offset: object,
    size: object,
    stride: object,
    requires_grad: object,
    backward_hooks: object,
    metadata: object = None,
) -> np.ndarray:
    """Stand-in for ``torch._utils._rebuild_tensor_v2``: the tensor as a new native-endian numpy
    array of ``size``, element (i…) at ``storage.values[storage_offset + Σ i_k·stride_k]``.

    Refuses (no allocation first) an offset, size or stride that reaches beyond the storage, a
    tensor with more elements than its storage, a size whose product (each size counted as at
    least 1, so an empty axis cannot hide billions of rows) passes what
    :data:`MAX_STORAGE_BYTES` holds, gradient hooks and non-integer arguments."""
    if not isinstance(storage, Storage):
        raise _Refused(f"tensor storage is {type(storage).__name__}, not a persistent storage")
    if (
        not isinstance(size, tuple)
        or len(size) > MAX_TENSOR_DIMS
        or not all(_is_int(s) and s >= 0 for s in size)
    ):
        raise _Refused(
            f"tensor size {str(size)[:60]} is not a tuple of up to {MAX_TENSOR_DIMS} "
            "non-negative ints"
        )
    if (
        not isinstance(stride, tuple)
        or len(stride) != len(size)
        or not all(_is_int(s) and s >= 0 for s in stride)
    ):
        raise _Refused(f"tensor stride {stride!r} does not match size {size!r}")
    if not _is_int(storage_offset) or storage_offset < 0:
        raise _Refused(f"tensor storage offset {storage_offset!r} is not a non-negative int")
    hooks_empty = isinstance(backward_hooks, dict) and not backward_hooks
    metadata_empty = metadata is None or (isinstance(metadata, dict) and not metadata)
    if not isinstance(requires_grad, bool) or not hooks_empty or not metadata_empty:
        raise _Refused("tensor with gradient flag, hooks or metadata of an unexpected kind")
    numel = storage.values.size
    count = math.prod(size)
    dtype = storage.values.dtype.newbyteorder("=")
    if count == 0:  # an empty axis bounds the elements, not the rows: sizes of 0 count as 1
        cells = math.prod(max(s, 1) for s in size)
        if cells > MAX_STORAGE_BYTES // storage.values.itemsize:
            raise _Refused(
                f"empty tensor of size {str(size)[:60]}: more than a storage of "
                f"{MAX_STORAGE_BYTES} bytes holds were each size at least 1"
            )
        return np.zeros(size, dtype=dtype)
    last = storage_offset + sum((s - 1) * st for s, st in zip(size, stride, strict=True))
    if count > numel or last >= numel:
        raise _Refused(
            f"tensor of size {size} (offset {storage_offset}, stride {stride}) reaches beyond "
            f"storage {storage.key!r} of {numel} elements"
        )
    item = storage.values.itemsize
    view = np.lib.stride_tricks.as_strided(
        storage.values[storage_offset:],
        shape=size,
        strides=tuple(st * item for st in stride),
        writeable=False,
    )
    return np.array(view, dtype=dtype)


@dataclass(frozen=True, slots=True)
class StandInFunction:
    """Stand-in for an allowlisted function: immutable (no ``__dict__``, no ``__defaults__``), so
    a pickle's BUILD cannot alter it for the files read after this one."""

    global_name: str
    function: Callable[..., object]
    __setstate__ = _refuse_setstate

    def __call__(self, *args: object) -> object:
        return self.function(*args)


def _empty_ordered_dict(*args: object) -> dict:
    """Stand-in for ``collections.OrderedDict``: this format only builds empty ones (hooks)."""
    if args:
        raise _Refused("collections.OrderedDict with contents is not part of this format")
    return {}


ALLOWLIST: dict[tuple[str, str], object] = {
    ("torch._utils", "_rebuild_tensor_v2"): StandInFunction(
        "torch._utils._rebuild_tensor_v2", rebuild_tensor
    ),
    ("torch", "FloatStorage"): StorageType("torch.FloatStorage", np.dtype("<f4")),
    ("torch", "IntStorage"): StorageType("torch.IntStorage", np.dtype("<i4")),
    ("collections", "OrderedDict"): StandInFunction("collections.OrderedDict", _empty_ordered_dict),
    ("torch_geometric.data.data", "Data"): _object_stand_in("torch_geometric.data.data.Data"),
    ("torch_geometric.data.storage", "GlobalStorage"): _object_stand_in(
        "torch_geometric.data.storage.GlobalStorage"
    ),
    ("torch_geometric.data.data", "DataEdgeAttr"): ClassReference(
        "torch_geometric.data.data.DataEdgeAttr"
    ),
    ("torch_geometric.data.data", "DataTensorAttr"): ClassReference(
        "torch_geometric.data.data.DataTensorAttr"
    ),
}
"""Every global a DMGM CAD ``.pt`` pickle references (all 620 files disassembled with
``pickletools``), mapped to its stand-in; docs/external-data.md says why each is there. Every
stand-in is immutable to pickle (slotted frozen instances; classes whose ``__setstate__`` cannot be
called on the class itself), so one file cannot change how the next is read."""


def _check_opcodes(data: bytes, path: Path, entry: str) -> None:
    """Parse every opcode (pure Python, reads only bytes present) and refuse unknown ones."""
    try:
        for opcode, arg, pos in pickletools.genops(data):
            if opcode.name not in _PROTOCOL_2_OPCODES:
                raise ImportFormatError(
                    path,
                    f"{entry}: pickle opcode {opcode.name} at byte {pos} is not part of this format",
                )
            if opcode.name.endswith("PUT") and arg > MAX_MEMO_INDEX:
                raise ImportFormatError(
                    path, f"{entry}: memo index {arg} at byte {pos} is too large"
                )
    except ImportFormatError:
        raise
    except (ValueError, UnicodeDecodeError, OverflowError) as exc:
        raise ImportFormatError(path, f"{entry}: malformed pickle: {exc}") from None


class _Unpickler(pickle.Unpickler):
    """``pickle.Unpickler`` whose globals come only from ``ALLOWLIST`` and whose persistent ids
    are storages read, size-checked, from the archive."""

    def __init__(self, data: bytes, archive: zipfile.ZipFile, prefix: str, path: Path) -> None:
        super().__init__(io.BytesIO(data))
        self._budget = _ReadBudget(path)
        self._archive = archive
        self._prefix = prefix
        self._path = path
        self._storages: dict[str, Storage] = {}

    def find_class(self, module: str, name: str) -> object:
        stand_in = ALLOWLIST.get((module, name))
        if stand_in is None:
            raise ImportFormatError(
                self._path,
                f"refused global '{module}.{name}': not in the allowlist of this format "
                "(nothing from the file was run)",
            )
        return stand_in

    def persistent_load(self, pid: object) -> Storage:
        if not (
            isinstance(pid, tuple)
            and len(pid) == 5
            and pid[0] == "storage"
            and isinstance(pid[1], StorageType)
            and isinstance(pid[2], str)
            and pid[2].isdigit()
            and isinstance(pid[3], str)
            and _is_int(pid[4])
            and pid[4] >= 0
        ):
            raise _Refused(f"persistent id {pid!r} is not (storage, type, key, location, numel)")
        _, storage_type, key, _, numel = pid
        cached = self._storages.get(key)
        if cached is not None:
            if cached.values.dtype != storage_type.dtype or cached.values.size != numel:
                raise _Refused(f"storage {key!r} referenced with two different types or sizes")
            return cached
        name = f"{self._prefix}/data/{key}"
        try:
            info = self._archive.getinfo(name)
        except KeyError:
            raise _Refused(f"storage {key!r} is referenced but {name} is missing") from None
        expected = numel * storage_type.dtype.itemsize
        if expected > MAX_STORAGE_BYTES:
            raise _Refused(
                f"storage {key!r} declares {numel} elements = {expected} bytes (limit "
                f"{MAX_STORAGE_BYTES}; this format holds a few hundred objects per view)"
            )
        if info.file_size != expected:
            raise _Refused(
                f"{name} holds {info.file_size} bytes; the pickle declares {numel} elements of "
                f"{storage_type.global_name} = {expected} bytes"
            )
        raw = self._budget.read(self._archive, info, expected)
        if len(raw) != expected:
            raise _Refused(f"{name} holds {len(raw)} bytes, expected {expected}")
        storage = Storage(key, np.frombuffer(raw, dtype=storage_type.dtype))
        self._storages[key] = storage
        return storage


class _ReadBudget:
    """Reads archive members with a running limit: nothing is allocated from a declared size
    first. A member is refused unless stored or deflated; it is read in 1 MiB chunks and the read
    stops as soon as it passes the bytes it may hold or the archive's total passes
    :data:`MAX_MEMBER_BYTES`."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.total = 0

    def read(self, archive: zipfile.ZipFile, info: zipfile.ZipInfo, limit: int) -> bytes:
        if info.compress_type not in _COMPRESSIONS:
            raise ImportFormatError(
                self.path,
                f"{info.filename}: compression method {info.compress_type} refused "
                "(stored or deflate only)",
            )
        chunks, size = [], 0
        with archive.open(info) as member:
            while chunk := member.read(min(2**20, limit - size + 1)):
                size += len(chunk)
                self.total += len(chunk)
                if size > limit or self.total > MAX_MEMBER_BYTES:
                    raise ImportFormatError(
                        self.path,
                        f"{info.filename}: more than {min(limit, MAX_MEMBER_BYTES)} bytes when "
                        "decompressed (declared sizes are not trusted)",
                    )
                chunks.append(chunk)
        return b"".join(chunks)


def _archive_prefix(archive: zipfile.ZipFile, path: Path) -> str:
    pickles = [n for n in archive.namelist() if n.endswith("/data.pkl") and n.count("/") == 1]
    if len(pickles) != 1:
        raise ImportFormatError(path, "not a torch archive: expected exactly one <prefix>/data.pkl")
    prefix = pickles[0].split("/")[0]
    version = _read_small(archive, f"{prefix}/version", path)
    if version is None:
        raise ImportFormatError(path, f"not a torch archive: {prefix}/version is missing")
    if version.strip() not in (b"1", b"2", b"3"):
        raise ImportFormatError(path, f"torch archive version {version[:20]!r} is not 1, 2 or 3")
    order = _read_small(archive, f"{prefix}/byteorder", path)
    if order is not None and order.strip() != b"little":
        raise ImportFormatError(path, f"storages are {order[:20]!r}-endian, not little")
    return prefix


def _read_small(archive: zipfile.ZipFile, name: str, path: Path) -> bytes | None:
    """A short text entry (version, byte order), or None if absent."""
    try:
        info = archive.getinfo(name)
    except KeyError:
        return None
    if info.file_size > 64:
        raise ImportFormatError(path, f"{name} is {info.file_size} bytes, expected a short text")
    return _ReadBudget(path).read(archive, info, 64)


def load_torch_archive(path: str | Path) -> object:
    """Unpickle the object ``torch.save`` wrote to ``path`` with ``ALLOWLIST`` stand-ins.

    Raises ``ImportFormatError`` (message starting with ``path``) for anything outside the format,
    including a refused global; ``OSError`` only if the file cannot be opened at all.

    >>> obj = load_torch_archive("proc_s/60260/data.pt")   # doctest: +SKIP
    >>> data, slices = obj; data.state["_store"].state["_mapping"]["x"].shape
    (6, 900)
    """
    path = Path(path)
    with open(path, "rb") as f:
        size = os.fstat(f.fileno()).st_size
        if size > MAX_ARCHIVE_BYTES:
            raise ImportFormatError(path, f"{size} bytes, larger than {MAX_ARCHIVE_BYTES}")
        blob = f.read()
    try:
        with zipfile.ZipFile(io.BytesIO(blob)) as archive:
            prefix = _archive_prefix(archive, path)
            entry = f"{prefix}/data.pkl"
            size = archive.getinfo(entry).file_size
            if size > MAX_PICKLE_BYTES:
                raise ImportFormatError(path, f"{entry} is {size} bytes (limit {MAX_PICKLE_BYTES})")
            data = _ReadBudget(path).read(archive, archive.getinfo(entry), MAX_PICKLE_BYTES)
            _check_opcodes(data, path, entry)
            try:
                return _Unpickler(data, archive, prefix, path).load()
            except (ImportFormatError, zipfile.BadZipFile, zlib.error):
                raise
            except Exception as exc:  # noqa: BLE001 - untrusted bytes; only our stand-ins can run
                raise ImportFormatError(path, f"{entry}: {type(exc).__name__}: {exc}") from None
    except ImportFormatError:
        raise
    except (
        zipfile.BadZipFile,
        zipfile.LargeZipFile,
        zlib.error,
        EOFError,
        OSError,
        ValueError,
        NotImplementedError,
        RuntimeError,
    ) as exc:
        raise ImportFormatError(path, f"not a readable zip archive: {exc}") from None
