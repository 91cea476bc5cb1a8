"""A LiDAR sweep, its boxes and the detections a record stores are the same bits on every dispatch level (numpy with and without
AVX-512, one-ulp faults in its transcendental functions, another BLAS kernel): what reaches a
record does not depend on the CPU (docs/lidar.md, "Ray engine")."""

from __future__ import annotations

import pytest
from test_cpu_independence import _run_all

pytestmark = pytest.mark.slow

SCRIPT = """
import hashlib, sys
import numpy as np
from cadsim.sensing.lidar.beam_pattern import PRESETS
from cadsim.sensing.lidar.box_detector import detect_boxes
from cadsim.sensing.lidar.mount import roof_pose
from cadsim.sensing.lidar.raycast import scan
from cadsim.world import Snapshot, WorldObject

def car(i, x, y, yaw):
    return WorldObject(f"c{i}", "car", "car", (x, y, 0.75), yaw, (4.5, 1.8, 1.5), (0.2, 0.3, 0.4))

ego = car("ego", 123.4, -56.7, 0.37)
objs = [ego] + [car(i, 123.4 + 30 * np.cos(0.9 * i), -56.7 + 30 * np.sin(0.7 * i), 0.31 * i) for i in range(12)]
h = hashlib.sha256()
for seed in range(3):
    s = scan(Snapshot(0.0, objs), roof_pose(ego), PRESETS["hdl-64e"], np.random.default_rng(seed), {ego.id})
    b = detect_boxes(s.points, 1.78)
    for a in (s.ray_index, s.range_steps, s.object_index, s.points, b.centres, b.sizes, b.yaws, b.point_box):
        h.update(np.ascontiguousarray(a).tobytes())
    h.update(",".join(b.classes).encode())
    v = b.to_view_detections([f"o{k}" for k in range(len(b))], b.classes)  # what records store
    for a in (v.positions, v.features, v.headings):
        h.update(np.ascontiguousarray(a).tobytes())
open(sys.argv[1], "w").write(h.hexdigest())
"""


def test_sweeps_and_boxes_are_the_same_on_every_dispatch_level(tmp_path):
    script = tmp_path / "lidar_sweep.py"
    script.write_text(SCRIPT)
    done = _run_all(["--path", str(script), "{out}"], tmp_path)
    digests = {name: (tmp_path / name).read_text() for name in done}
    assert len(digests) >= 2 and len(set(digests.values())) == 1, digests
