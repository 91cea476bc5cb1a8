"""Generation speed: views/s and pairs/s of a cold ``cadsim generate`` (for ``make bench``).

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
    a = parser.parse_args()
    print(format_report(measure_generation(a.scenario, a.pairs, a.workers)))
