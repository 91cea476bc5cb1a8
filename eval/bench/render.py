"""Speed of the view pipeline on a synthetic street scene: render, depth noise, detection.

``python -m eval.bench.render [--views N] [--objects K]`` prints views/s of each stage; ``measure``
returns the same figures for ``make bench``. The scene: a road, four building blocks and K
vehicles/persons/signals placed at random (seeded), the camera driving down the road.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from cadsim.camera import Camera
from cadsim.world import Snapshot, WorldObject

_KINDS = [
    ("car", (4.5, 1.8, 1.5)),
    ("car", (4.5, 1.8, 1.5)),
    ("van", (5.0, 2.0, 2.2)),
    ("bus", (12.0, 2.5, 3.2)),
    ("truck", (9.0, 2.5, 3.4)),
    ("bicycle", (1.7, 0.65, 1.7)),
    ("person", (0.3, 0.5, 1.75)),
]
_PALETTE = [(0.8, 0.1, 0.1), (0.1, 0.2, 0.8), (0.92, 0.92, 0.92), (0.1, 0.1, 0.1), (0.9, 0.8, 0.1)]


def street_snapshot(n_objects: int = 30, seed: int = 0, time_s: float = 0.0) -> Snapshot:
    """A seeded synthetic street: road, building blocks, ``n_objects`` targets (metres, world)."""
    rng = np.random.default_rng(seed)
    objs = [
        WorldObject(
            "road",
            "road",
            "road",
            (60.0, 0.0, -0.05),
            0.0,
            (200.0, 14.0, 0.1),
            (0.25, 0.25, 0.27),
            target=False,
        )
    ]
    for k, (x, y) in enumerate([(30, 22), (30, -22), (90, 22), (90, -22)]):
        size = (40.0, 28.0, 10.0 + 4 * k)
        objs.append(
            WorldObject(
                f"bldg{k}",
                "building",
                "building",
                (x, y, size[2] / 2),
                0.0,
                size,
                (0.65, 0.6, 0.55),
                target=False,
            )
        )
    for i in range(n_objects):
        shape, size = _KINDS[i % len(_KINDS)]
        x, y = rng.uniform(8, 110), rng.uniform(-6, 6)
        yaw = rng.choice([0.0, np.pi]) + rng.normal(0, 0.1)
        objs.append(
            WorldObject(
                f"obj{i}", shape, shape, (x, y, size[2] / 2), yaw, size, _PALETTE[i % len(_PALETTE)]
            )
        )
    for j, x in enumerate((20.0, 70.0)):
        objs.append(
            WorldObject(
                f"tl{j}",
                "traffic_light",
                "traffic_light",
                (x, -7.5, 2.0),
                np.pi,
                (0.4, 0.4, 4.0),
                (0.1, 0.9, 0.2),
                state="G",
            )
        )
        objs.append(
            WorldObject(
                f"sign{j}",
                "sign",
                "sign",
                (x + 5, 7.5, 1.25),
                np.pi,
                (0.05, 0.8, 2.5),
                (0.9, 0.1, 0.1),
                variant="stop",
            )
        )
    return Snapshot(time_s, objs)


def measure(n_views: int = 40, n_objects: int = 30, width: int = 640, height: int = 480) -> dict:
    """Views/s (wall clock) of render (colour + depth + instances), noise and detection, the
    process CPU time per rendered view (all llvmpipe threads; insensitive to other load), and the
    backend used."""
    from cadsim.render import Renderer
    from cadsim.sensing.depth_noise import NoiseConfig, apply_depth_noise
    from cadsim.sensing.detection import DetectionConfig, detect

    snap = street_snapshot(n_objects)
    renderer = Renderer(width, height)
    cameras = [
        Camera((2.0 * k, -1.5, 1.6), 0.02 * np.sin(k), width=width, height=height)
        for k in range(n_views)
    ]
    renderer.render(snap, cameras[0])  # builds the meshes
    t0, cpu0 = time.perf_counter(), time.process_time()
    views = [renderer.render(snap, c) for c in cameras]
    t1, cpu1 = time.perf_counter(), time.process_time()
    noisy = [
        apply_depth_noise(v.depth, NoiseConfig(), np.random.default_rng(k))
        for k, v in enumerate(views)
    ]
    t2 = time.perf_counter()
    dets = [
        detect(v, d, snap.objects, c, DetectionConfig())
        for v, d, c in zip(views, noisy, cameras, strict=True)
    ]
    t3 = time.perf_counter()
    renderer.close()
    return {
        "backend": renderer.backend,
        "objects": len(snap.objects),
        "render_views_per_s": n_views / (t1 - t0),
        "render_cpu_ms_per_view": 1000.0 * (cpu1 - cpu0) / n_views,
        "noise_views_per_s": n_views / (t2 - t1),
        "detect_views_per_s": n_views / (t3 - t2),
        "pipeline_views_per_s": n_views / (t3 - t0),
        "detections_per_view": float(np.mean([len(d) for d in dets])),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--views", type=int, default=40)
    parser.add_argument("--objects", type=int, default=30)
    args = parser.parse_args()
    for key, value in measure(args.views, args.objects).items():
        print(f"{key:>22}: {value:.1f}" if isinstance(value, float) else f"{key:>22}: {value}")


if __name__ == "__main__":
    main()
