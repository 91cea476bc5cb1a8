"""Byte-exact encoders for record files: the same content always gives the same bytes.

npz: a zip of ``.npy`` members in the given key order with a fixed 1980-01-01 timestamp (numpy's
own ``savez`` stamps the current time). JSON: sorted keys, fixed separators, UTF-8, trailing
newline. PNG: OpenCV's encoder (no timestamp chunk), colour given as RGB.
"""

from __future__ import annotations

import io
import json
import zipfile
import zlib
from collections.abc import Mapping

import numpy as np

_ZIP_EPOCH = (1980, 1, 1, 0, 0, 0)


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
    (the others are not decompressed); ``what`` names it in errors."""
    try:
        src = io.BytesIO(data) if isinstance(data, bytes) else data
        with np.load(src, allow_pickle=False) as z:
            missing = [] if keys is None else [k for k in keys if k not in z.files]
            if missing:
                raise ValueError(f"missing arrays {missing}")
            return {k: z[k] for k in (z.files if keys is None else keys)}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
        raise ValueError(f"{what}: not a readable .npz file ({exc})") from exc


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
