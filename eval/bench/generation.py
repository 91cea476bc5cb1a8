"""Generation speed: views/s and pairs/s of a cold ``cadsim generate``, and its cost in
core-seconds per camera pair, per LiDAR pair and per episode (``make bench``, section
"generation"; ``python -m eval.bench.generation --cost --scenario FILE``).

``measure_generation`` generates a fresh dataset into a temporary folder (nothing reused: a new
folder, new worker processes) and reports wall-clock throughput. A "view" is one camera's render +
depth noise + detection; every candidate pair costs one or two views, accepted or not.
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

DEFAULT_SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "cad-intersection.toml"


def measure_generation(
    scenario: str | Path = DEFAULT_SCENARIO,
    pairs: int = 50,
    workers: int | None = None,
    seed: int | None = None,
    out: str | Path | None = None,
) -> dict:
    """Generate ``pairs`` frame pairs of ``scenario`` from cold and time it.

    Returns {"scenario", "pairs", "workers", "episodes", "views", "candidates", "seconds" (wall),
    "views_per_s" (views / wall s), "pairs_per_s" (pairs / wall s), "view_seconds" (summed over
    workers: render + noise + detect), "views_per_s_per_worker", "checksum"}.
    """
    from cadsim.generation.pipeline import generate_dataset

    workers = int(workers or os.cpu_count() or 1)
    with tempfile.TemporaryDirectory(prefix="cadsim-bench-") as tmp:
        target = Path(out) if out is not None else Path(tmp) / "dataset"
        if target.exists() and any(target.iterdir()):
            raise ValueError(f"out: {target} must be empty for a cold-start measurement")
        t0 = time.perf_counter()
        result = generate_dataset(
            scenario, target, pairs=pairs, seed=seed, workers=workers, progress=False
        )
        wall = time.perf_counter() - t0
    return {
        "scenario": str(scenario),
        "pairs": result.pairs,
        "workers": workers,
        "episodes": result.episodes,
        "views": result.views,
        "candidates": result.candidates,
        "seconds": wall,
        "views_per_s": result.views / wall,
        "pairs_per_s": result.pairs / wall,
        "view_seconds": result.render_seconds,
        "views_per_s_per_worker": result.views_per_s,
        "checksum": result.checksum,
    }


SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"
CAMERA_SCENARIO = SCENARIOS / "cad-v2x.toml"
LIDAR_SCENARIO = SCENARIOS / "cad-v2x-lidar.toml"
COST_PAIRS = 12  # 6 episodes of cad-v2x's 2 pairs
# Goals (core-seconds on the 2-core reference machine): a camera frame pair (two 800 x 600 views
# rendered, noised and detected), a LiDAR pair (two sweeps + box detection), an episode's overhead.
CAMERA_PAIR_GOAL_S = 0.6
LIDAR_PAIR_GOAL_S = 0.4
EPISODE_OVERHEAD_GOAL_S = 1.0


def measure_generation_cost(
    scenario: str | Path = CAMERA_SCENARIO, pairs: int = COST_PAIRS
) -> dict:
    """Core-seconds of generating ``pairs`` records of ``scenario`` in this process (one worker,
    a fresh folder; the process's CPU time over every thread, the renderer's included).

    Returns {"scenario", "pairs", "episodes", "views", "candidates", "view_pair_core_s" (two
    views of one candidate: render or sweep + noise + detection), "record_core_s" (all of an
    episode's CPU per record written: rejected candidates, writing and overhead included),
    "write_core_s" (encoding + writing one record), "episode_overhead_core_s" (median over
    episodes of what is neither a view nor a write: source set-up, demand, simulation, candidate
    search), "first_episode_overhead_core_s" (the same for the first episode, which also opens
    the renderer), "core_seconds", "seconds" (wall)}.
    """
    import numpy as np

    from cadsim.generation.pipeline import generate_dataset, release_renderers

    with tempfile.TemporaryDirectory(prefix="cadsim-bench-") as tmp:
        t0 = time.perf_counter()
        result = generate_dataset(
            scenario, Path(tmp) / "dataset", pairs=pairs, workers=1, progress=False
        )
        wall = time.perf_counter() - t0
    release_renderers()
    episodes = result.episode_results
    overhead = [e.core_seconds - e.view_core_seconds - e.write_core_seconds for e in episodes]
    core = sum(e.core_seconds for e in episodes)
    views = sum(e.views for e in episodes)
    return {
        "scenario": str(scenario),
        "pairs": result.pairs,
        "episodes": len(episodes),
        "views": views,
        "candidates": result.candidates,
        "view_pair_core_s": 2 * sum(e.view_core_seconds for e in episodes) / max(views, 1),
        "record_core_s": core / max(result.new_records, 1),
        "write_core_s": sum(e.write_core_seconds for e in episodes) / max(result.new_records, 1),
        "episode_overhead_core_s": float(
            np.median(overhead[1:] if len(overhead) > 1 else overhead)
        ),
        "first_episode_overhead_core_s": overhead[0] if overhead else float("nan"),
        "core_seconds": core,
        "seconds": wall,
    }


def format_cost(m: dict) -> str:
    """One paragraph of a ``measure_generation_cost`` result."""
    return (
        f"generate {Path(m['scenario']).name}, {m['pairs']} records in {m['episodes']} episode(s), "
        f"one worker: {m['view_pair_core_s']:.3f} core-s per view pair ({m['views']} views for "
        f"{m['candidates']} candidates), {m['write_core_s']:.3f} core-s per record write, "
        f"{m['episode_overhead_core_s']:.3f} core-s overhead per episode (first episode "
        f"{m['first_episode_overhead_core_s']:.2f}, renderer start included), "
        f"{m['record_core_s']:.3f} core-s per record all in; {m['core_seconds']:.1f} core-s, "
        f"{m['seconds']:.1f} s wall"
    )


def _cost_in_child(scenario: str) -> dict:
    return measure_generation_cost(scenario)


def generation_section(args) -> list:
    """``make bench`` section "generation": core-seconds per camera pair, per LiDAR pair and per
    episode against their goals (each scenario in a fresh process: one GL platform each)."""
    import multiprocessing as mp

    from eval.bench import Target

    found = {}
    for name, scenario in (("camera", CAMERA_SCENARIO), ("lidar", LIDAR_SCENARIO)):
        with mp.get_context("spawn").Pool(1) as pool:
            found[name] = pool.apply(_cost_in_child, (str(scenario),))
        print(format_cost(found[name]))
    overhead = max(m["episode_overhead_core_s"] for m in found.values())
    return [
        Target(
            "generation: camera frame pair (2 views 800x600 rendered + detected)",
            found["camera"]["view_pair_core_s"], CAMERA_PAIR_GOAL_S, "core-s",
        ),
        Target(
            "generation: LiDAR pair (2 sweeps + box detection)",
            found["lidar"]["view_pair_core_s"], LIDAR_PAIR_GOAL_S, "core-s",
        ),
        Target(
            "generation: per-episode overhead (median, camera and LiDAR scenarios)",
            overhead, EPISODE_OVERHEAD_GOAL_S, "core-s",
        ),
    ]  # fmt: skip


def format_report(m: dict) -> str:
    """One human-readable paragraph of a ``measure_generation`` result."""
    return (
        f"generate {Path(m['scenario']).name}: {m['pairs']} pairs in {m['seconds']:.1f} s with "
        f"{m['workers']} worker(s), {m['episodes']} episode(s): {m['pairs_per_s']:.2f} pairs/s, "
        f"{m['views_per_s']:.1f} views/s ({m['views']} views for {m['candidates']} candidate "
        f"pairs; {m['views_per_s_per_worker']:.1f} views/s per worker)"
    )


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default=str(DEFAULT_SCENARIO))
    parser.add_argument("--pairs", type=int, default=50)
    parser.add_argument("--workers", type=int)
    parser.add_argument("--cost", action="store_true", help="core-seconds, one worker")
    a = parser.parse_args()
    if a.cost:
        print(format_cost(measure_generation_cost(a.scenario, a.pairs)))
    else:
        print(format_report(measure_generation(a.scenario, a.pairs, a.workers)))
