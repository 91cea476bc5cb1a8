"""Speed of the LiDAR: rays/s of one sweep, a 64 × 1024 sweep's time, and a LiDAR view pair
(sweep + box detector, two sensors) against a camera view pair (render + depth noise + detection)
on the same synthetic street (``eval.bench.render.street_snapshot``).

``python -m eval.bench.lidar`` prints the figures; ``lidar_section`` is ``make bench``'s
``lidar`` section. Goals: ≥ 1 M rays/s (a 64 × 1024 sweep in ≤ 70 ms) and a LiDAR pair in
≤ 2 × a camera pair's time.
"""

from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np

from eval.bench import Target, _row, timed
from eval.bench.render import street_snapshot

SWEEP = (64, 1024)


def measure(repeat: int = 5, camera_views: int = 10) -> dict:
    """Figures of the module docstring (wall-clock seconds, best of ``repeat`` after a warm-up)."""
    from cadsim.sensing.lidar.beam_pattern import PRESETS
    from cadsim.sensing.lidar.box_detector import detect_boxes
    from cadsim.sensing.lidar.mount import level_pose
    from cadsim.sensing.lidar.ray_engine import first_hits
    from cadsim.sensing.lidar.raycast import scan
    from cadsim.sensing.lidar.scene_triangles import scene_triangles

    snap = street_snapshot(30)
    pose = level_pose((2.0, -1.5, 1.8), 0.0)
    hdl64 = PRESETS["hdl-64e"]
    low, high = hdl64.elevations_deg[0], hdl64.elevations_deg[-1]
    sweep = replace(
        hdl64,
        name="64x1024",
        elevations_deg=tuple(low + (high - low) * i / (SWEEP[0] - 1) for i in range(SWEEP[0])),
        azimuth_steps=SWEEP[1],
        _directions=None,
    )
    triangles, _ = scene_triangles(snap, pose, sweep.max_range_m)
    dirs = sweep.directions()
    engine_s, _ = timed(lambda: first_hits(triangles, dirs), repeat)
    sweep_s, s = timed(lambda: scan(snap, pose, sweep, np.random.default_rng(0)), repeat)
    full_s, full = timed(lambda: scan(snap, pose, hdl64, np.random.default_rng(0)), repeat)
    detect_s, boxes = timed(lambda: detect_boxes(full.points, 1.8), repeat)
    out = {
        "triangles": len(triangles),
        "rays": sweep.ray_count,
        "engine_rays_per_s": sweep.ray_count / engine_s,
        "sweep_ms": 1000.0 * sweep_s,
        "sweep_rays_per_s": sweep.ray_count / sweep_s,
        "sweep_points": len(s),
        "hdl64e_sweep_ms": 1000.0 * full_s,
        "hdl64e_points": len(full),
        "detect_ms": 1000.0 * detect_s,
        "boxes": len(boxes),
        "lidar_pair_ms": 2000.0 * (full_s + detect_s),
    }
    try:
        from eval.bench.render import measure as camera_measure

        cam = camera_measure(n_views=camera_views, n_objects=30, width=800, height=600)
        out["camera_pair_ms"] = 2000.0 / cam["pipeline_views_per_s"]
        out["camera_backend"] = cam["backend"]
    except Exception as exc:  # no off-screen OpenGL here: the LiDAR figures still stand
        out["camera_error"] = f"{type(exc).__name__}: {exc}"
    return out


def lidar_section(args: argparse.Namespace) -> list[Target]:
    m = measure(repeat=max(1, args.repeat))
    print(_row(["figure", "value"]))
    print(_row(["---", "---"]))
    for key, value in m.items():
        print(_row([key, f"{value:.4g}" if isinstance(value, float) else str(value)]))
    targets = [
        Target("LiDAR 64 x 1024 sweep (scene + rays + noise)", m["sweep_ms"], 70.0, "ms"),
        Target("LiDAR seconds per million rays (>= 1 M rays/s)", 1e6 / m["sweep_rays_per_s"], 1.0),
    ]
    if "camera_pair_ms" in m:
        ratio = m["lidar_pair_ms"] / m["camera_pair_ms"]
        targets.append(Target("LiDAR pair / camera pair time", ratio, 2.0, "x"))
    return targets


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    for key, value in measure(parser.parse_args().repeat).items():
        print(f"{key:>20}: {value:.4g}" if isinstance(value, float) else f"{key:>20}: {value}")


if __name__ == "__main__":
    main()
