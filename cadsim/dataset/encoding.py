"""Byte-exact encoders for record files: the same content always gives the same bytes.

npz: a zip of ``.npy`` members in the given key order with a fixed 1980-01-01 timestamp (numpy's
own ``savez`` stamps the current time). JSON: sorted keys, fixed separators, UTF-8, trailing
newline. PNG: OpenCV's encoder (no timestamp chunk), colour given as RGB.
"""

from __future__ import annotations

import io
import json
import math
import zipfile
import zlib
from collections.abc import Mapping

import numpy as np

_ZIP_EPOCH = (1980, 1, 1, 0, 0, 0)
MAX_NPZ_BYTES = 2**30
"""Most array data one ``.npz`` may declare (all members): twelve 4096² float32 depth maps are
0.75 GiB; a record's detections and LiDAR sweeps are far less."""


class _Refused(ValueError):
    """A member the reader refuses by its header (the message is the whole line)."""


def npz_bytes(arrays: Mapping[str, np.ndarray]) -> bytes:
    """Compressed ``.npz`` bytes of ``arrays`` (readable by ``np.load``); object arrays refused."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for key, value in arrays.items():
            arr = np.asarray(value)
            if arr.dtype == object:
                raise TypeError(
                    f"npz member {key!r}: object arrays cannot be stored without pickle"
                )
            member = io.BytesIO()
            np.lib.format.write_array(member, np.ascontiguousarray(arr), allow_pickle=False)
            info = zipfile.ZipInfo(f"{key}.npy", date_time=_ZIP_EPOCH)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, member.getvalue(), compresslevel=6)
    return buf.getvalue()


def load_npz(data: bytes | str, what: str, keys=None) -> dict[str, np.ndarray]:
    """All members of an ``.npz`` (bytes or path) as arrays, or only those named in ``keys``
    (the others are not decompressed); ``what`` names it in errors.

    Each member's ``.npy`` header is read and checked before its data is inflated: a plain
    dtype (no objects), data that the zip entry's size holds exactly, and at most
    :data:`MAX_NPZ_BYTES` declared over all members (and per member with each size counted as
    at least 1, so an empty axis cannot declare 10¹² rows) — so a header claiming 10¹² elements,
    or a stray member of gigabytes, is refused without allocating it."""
    try:
        src = io.BytesIO(data) if isinstance(data, bytes) else data
        out, declared = {}, 0
        with zipfile.ZipFile(src) as zf:
            for info in zf.infolist():
                if not info.filename.endswith(".npy"):
                    raise _Refused(f"{what}: {info.filename[:60]!r}: not an array member")
                key = info.filename[: -len(".npy")]
                if keys is not None and key not in keys:
                    continue
                with zf.open(info) as member:
                    shape, fortran, dtype = npy_header(member, what, key)
                    nbytes = math.prod(shape) * dtype.itemsize
                    declared += nbytes
                    if declared > MAX_NPZ_BYTES:
                        raise _Refused(
                            f"{what}: {key[:60]}: its header declares {shape} {dtype} "
                            f"({nbytes:,} bytes); the file may hold at most "
                            f"{MAX_NPZ_BYTES:,} bytes of arrays"
                        )
                    if info.file_size != member.tell() + nbytes:
                        raise _Refused(
                            f"{what}: {key[:60]}: its header declares {shape} {dtype} "
                            f"({nbytes:,} bytes), the member holds "
                            f"{info.file_size - member.tell():,}"
                        )
                    # allocated and shaped as np.load does (a numpy-owned array, so SIMD
                    # kernels see the same memory layout as before)
                    array = np.ndarray(math.prod(shape), dtype=dtype)
                    if member.readinto(array.view(np.uint8)) != nbytes:
                        raise _Refused(f"{what}: {key[:60]}: truncated")
                if fortran:
                    array.shape = shape[::-1]
                    array = array.transpose()
                else:
                    array.shape = shape
                out[key] = array
        missing = [] if keys is None else [k for k in keys if k not in out]
        if missing:
            raise ValueError(f"missing arrays {missing}")
        return out if keys is None else {k: out[k] for k in keys}
    except _Refused:
        raise
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
        raise ValueError(f"{what}: not a readable .npz file ({exc})") from exc


def npy_header(member, what: str, key: str) -> tuple[tuple[int, ...], bool, np.dtype]:
    """(shape, Fortran order, dtype) of an ``.npy`` member, read from its header only; a
    ValueError naming ``what`` and ``key`` for another format version or an object dtype."""
    version = np.lib.format.read_magic(member)
    if version == (1, 0):
        shape, fortran, dtype = np.lib.format.read_array_header_1_0(member)
    elif version == (2, 0):
        shape, fortran, dtype = np.lib.format.read_array_header_2_0(member)
    else:
        raise _Refused(f"{what}: {key[:60]}: npy format version {version}")
    if dtype.hasobject:
        raise _Refused(f"{what}: {key[:60]}: object arrays are not read (they need pickle)")
    shape = tuple(int(n) for n in shape)
    # an empty axis makes the data 0 bytes, not the rows a reader may walk: sizes of 0 count as 1
    cells = math.prod(max(n, 1) for n in shape)
    if cells * max(dtype.itemsize, 1) > MAX_NPZ_BYTES:
        raise _Refused(
            f"{what}: {key[:60]}: its header declares shape {str(shape)[:60]} {dtype}: more than "
            f"{MAX_NPZ_BYTES:,} bytes were each size at least 1"
        )
    return shape, bool(fortran), np.dtype(dtype)


def json_bytes(obj) -> bytes:
    """Canonical JSON: sorted keys, 1-space indent, UTF-8, trailing newline."""
    return (json.dumps(obj, sort_keys=True, indent=1, ensure_ascii=False) + "\n").encode("utf-8")


def png_bytes(rgb: np.ndarray) -> bytes:
    """PNG bytes of an (H, W, 3) uint8 RGB image."""
    import cv2

    img = np.asarray(rgb)
    if img.ndim != 3 or img.shape[2] != 3 or img.dtype != np.uint8:
        raise ValueError(f"colour image: expected (H, W, 3) uint8, got {img.shape} {img.dtype}")
    ok, buf = cv2.imencode(".png", np.ascontiguousarray(img[:, :, ::-1]))
    if not ok:
        raise ValueError("colour image: OpenCV could not encode it as PNG")
    return buf.tobytes()


def decode_png(data: bytes, what: str) -> np.ndarray:
    """(H, W, 3) uint8 RGB from PNG bytes; ``what`` names the file in errors."""
    import cv2

    img = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
    if img is None:
        raise ValueError(f"{what}: not a readable PNG image")
    return np.ascontiguousarray(img[:, :, ::-1])
