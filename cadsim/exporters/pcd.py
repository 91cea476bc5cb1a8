"""Point clouds as PCD v0.7 files (the Point Cloud Library's format), as OpenCOOD reads them.

OpenCOOD loads an OPV2V agent's ``<frame>.pcd`` with Open3D's reader and takes the intensity
from the first colour channel; Open3D fills colours from a packed ``rgb`` field. So the files
have ``FIELDS x y z rgb`` (float32 each; ``rgb`` the bits of 0x00RRGGBB with R = G = B =
round(255 · intensity)), one point per return, ``WIDTH`` = points, ``HEIGHT`` 1, viewpoint the
identity, ``DATA binary`` (little-endian) or ``ascii``. The simulated LiDAR measures no
intensity: :func:`agent_point_cloud` writes 1.0 for every point.

Frames: the points are in the sensor's frame. cadsim's LiDAR frame is right-handed (x forward,
y left, z up); OPV2V's is CARLA's left-handed one (x forward, y right, z up), so
:func:`agent_point_cloud` negates y (``cadsim.importers.carla_frame``) — the frame the exported
``lidar_pose`` describes. Imports numpy only (and the dataset layout for :func:`agent_point_cloud`).
"""

from __future__ import annotations

import numpy as np

_FIELDS = ("x", "y", "z", "rgb")


def _packed_rgb(intensity: np.ndarray) -> np.ndarray:
    """(n,) float32 whose bits are 0x00RRGGBB, R = G = B = round(255 · clip(intensity, 0, 1))."""
    level = np.rint(np.clip(np.asarray(intensity, dtype=np.float64), 0.0, 1.0) * 255.0).astype(np.uint32)  # fmt: skip
    return ((level << 16) | (level << 8) | level).view(np.float32)


def pcd_bytes(points: np.ndarray, intensity: np.ndarray | None = None, binary: bool = True) -> bytes:  # fmt: skip
    """A PCD v0.7 file of ``points`` (n, 3) metres and ``intensity`` (n,) in [0, 1] (1 when None).

    >>> pcd_bytes(np.zeros((1, 3)), binary=False).decode().splitlines()[-1]
    '0 0 0 2.35098856e-38'
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if not np.isfinite(p).all():
        raise ValueError("points: non-finite coordinates")
    n = len(p)
    rgb = _packed_rgb(np.ones(n) if intensity is None else np.asarray(intensity).reshape(n))
    header = (
        "# .PCD v0.7 - Point Cloud Data file format\n"
        "VERSION 0.7\n"
        f"FIELDS {' '.join(_FIELDS)}\n"
        "SIZE 4 4 4 4\n"
        "TYPE F F F F\n"
        "COUNT 1 1 1 1\n"
        f"WIDTH {n}\n"
        "HEIGHT 1\n"
        "VIEWPOINT 0 0 0 1 0 0 0\n"
        f"POINTS {n}\n"
        f"DATA {'binary' if binary else 'ascii'}\n"
    ).encode("ascii")
    table = np.empty((n, 4), dtype="<f4")
    table[:, :3] = p
    table[:, 3] = rgb
    if binary:
        return header + table.tobytes()
    import io

    text = io.BytesIO()
    np.savetxt(text, table.astype(np.float64), fmt="%.9g")
    return header + text.getvalue()


def read_pcd(data: bytes) -> tuple[np.ndarray, np.ndarray]:
    """``(points (n, 3) float32, intensity (n,) float64)`` of a file :func:`pcd_bytes` wrote
    (``ValueError`` for another layout)."""
    head, _, body = data.partition(b"DATA ")
    kind, _, payload = body.partition(b"\n")
    fields = dict(line.split(" ", 1) for line in head.decode("ascii").splitlines() if line and not line.startswith("#"))  # fmt: skip
    if fields.get("FIELDS") != " ".join(_FIELDS) or fields.get("TYPE") != "F F F F":
        raise ValueError(f"pcd: expected FIELDS {' '.join(_FIELDS)} of TYPE F, got {fields.get('FIELDS')!r}")  # fmt: skip
    n = int(fields["POINTS"])
    if kind == b"binary":
        table = np.frombuffer(payload, dtype="<f4", count=4 * n).reshape(n, 4)
    elif kind == b"ascii":
        table = np.array(payload.split(), dtype=np.float32).reshape(n, 4)
    else:
        raise ValueError(f"pcd: DATA {kind!r} is not binary or ascii")
    level = table[:, 3].copy().view(np.uint32) & 0xFF
    return table[:, :3].copy(), level.astype(np.float64) / 255.0


def agent_point_cloud(pair, view: int) -> bytes | None:
    """The ``.pcd`` of view ``view`` (1-based record view) of a ``FramePair`` with LiDAR points,
    in OPV2V's sensor frame (y negated); None for a record without points."""
    sweeps = pair.lidar
    if sweeps is None:
        return None
    k = list(pair.view_numbers).index(int(view))
    return pcd_bytes(sweeps[k].points * np.array([1.0, -1.0, 1.0]))
