"""PCD v0.7 files as OpenCOOD reads them: header, binary and ASCII bodies, intensity in the
first colour channel of a packed rgb field."""

from __future__ import annotations

import numpy as np
import pytest

from cadsim.exporters.pcd import pcd_bytes, read_pcd


@pytest.mark.parametrize("binary", [True, False])
def test_points_and_intensity_come_back(binary):
    rng = np.random.default_rng(3)
    pts = rng.uniform(-120, 120, (257, 3))
    inten = rng.uniform(0, 1, 257)
    back, level = read_pcd(pcd_bytes(pts, inten, binary=binary))
    assert back.dtype == np.float32 and np.array_equal(back, pts.astype(np.float32))
    assert np.abs(level - inten).max() <= 0.5 / 255 + 1e-12


def test_the_header_is_pcl_v07_with_a_packed_rgb_field():
    data = pcd_bytes(np.zeros((3, 3)))
    header = data[: data.index(b"DATA binary\n") + 12].decode("ascii").splitlines()
    assert header[1:] == [
        "VERSION 0.7", "FIELDS x y z rgb", "SIZE 4 4 4 4", "TYPE F F F F", "COUNT 1 1 1 1",
        "WIDTH 3", "HEIGHT 1", "VIEWPOINT 0 0 0 1 0 0 0", "POINTS 3", "DATA binary",
    ]  # fmt: skip
    body = np.frombuffer(data[len("\n".join(header)) + 1 :], dtype="<u4").reshape(3, 4)
    # Open3D reads rgb as 0x00RRGGBB: intensity 1 → R = G = B = 255 (colors[:, 0] = 1.0)
    assert (body[:, 3] == 0x00FFFFFF).all() and len(data) == len("\n".join(header)) + 1 + 48


def test_empty_clouds_and_bad_input():
    back, level = read_pcd(pcd_bytes(np.zeros((0, 3))))
    assert back.shape == (0, 3) and level.shape == (0,)
    with pytest.raises(ValueError, match="points: non-finite"):
        pcd_bytes(np.array([[0.0, np.inf, 0.0]]))
    with pytest.raises(ValueError, match="pcd: expected FIELDS x y z rgb"):
        read_pcd(b"VERSION 0.7\nFIELDS x y z intensity\nTYPE F F F F\nPOINTS 0\nDATA binary\n")
