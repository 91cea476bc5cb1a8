"""Scale-out benchmark: the same noise sweep on the local process pool and on a Dask LocalCluster
with as many single-threaded worker processes, on this machine (for ``make bench``).

``measure_scaleout`` generates a small CAD dataset (or uses ``dataset``), then runs
matchers × seeds × rates on its first `pairs` frame pairs (default 9 × 4 × 5 = 180 runs of 2 pairs
each, in 20 tasks: all matchers of a (seed, rate) share a task) once per executor — in this process
(the baseline of the speed-ups), on the pool, on the cluster — each into a fresh result cache, and
checks that all give the same results. It also times a batch of empty tasks on each executor: their wall time per
task is the executor's own cost (submission, transport, result collection). Startup (spawning the
pool, starting the cluster) is timed separately. Times are wall-clock seconds.

Wire-up: ``eval.bench.register(Section("scaleout", "...", scaleout_section))``.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
DEFAULT_SCENARIO = ROOT / "scenarios" / "cad-intersection.toml"
DEFAULT_RATES = (0.0, 0.001, 0.003, 0.01, 0.03)
EMPTY_TASKS = 200


def _empty(item: int) -> int:
    return item


def _timed_sweep(executor, requests, cache_dir: Path):
    from eval.core.cache import ResultCache
    from eval.core.runner import Runner

    runner = Runner(ResultCache(cache_dir), executor, progress=False)
    t0 = time.perf_counter()
    results = runner.run(requests, desc="sweep")
    return time.perf_counter() - t0, results, runner.stats.computed


def _timed_empty(executor, count: int) -> float:
    t0 = time.perf_counter()
    done = list(executor.map_unordered(_empty, list(range(count))))
    wall = time.perf_counter() - t0
    if sorted(c.value for c in done) != list(range(count)):
        raise RuntimeError("empty tasks: lost or duplicated outcomes")
    return wall


def _on_cluster(workers: int, requests, cache_dir: Path, profile: bool):
    """(start s, sweep s, results, empty-task batch s) on a fresh LocalCluster; `profile`: the
    workers' statistical profiler (Dask's default: on, sampling every 10 ms)."""
    import dask
    from distributed import LocalCluster

    from cadsim.generation.dask_executor import DaskExecutor

    t0 = time.perf_counter()
    with (
        dask.config.set({"distributed.worker.profile.enabled": profile}),
        LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        DaskExecutor(cluster.scheduler_address) as executor,
    ):
        start = time.perf_counter() - t0
        sweep, results, _ = _timed_sweep(executor, requests, cache_dir)
        empty = _timed_empty(executor, EMPTY_TASKS)
    return start, sweep, results, empty


def _same(a, b) -> bool:
    return all(
        x.spec == y.spec
        and all(
            np.array_equal(o.scores, p.scores) and np.array_equal(o.assigned, p.assigned)
            for o, p in zip(x.outcomes, y.outcomes, strict=True)
        )
        for x, y in zip(a, b, strict=True)
    )


def measure_scaleout(
    dataset: str | Path | None = None,
    pairs: int = 2,
    matchers: str = "all",
    seeds: int = 4,
    rates: tuple[float, ...] = DEFAULT_RATES,
    workers: int = 2,
    scenario: str | Path = DEFAULT_SCENARIO,
) -> dict:
    """Time the sweep (first `pairs` frame pairs of `dataset`, or of a fresh `pairs`-pair dataset
    of `scenario`) on ``LocalProcessExecutor(workers)`` and on a ``LocalCluster`` of `workers`
    processes × 1 thread, and in this process. Returns {"runs", "tasks", "workers",
    "serial_sweep_s", "local_start_s", "local_sweep_s", "dask_start_s", "dask_sweep_s",
    "local_speedup", "dask_speedup" (serial / sweep), "dask_noprofile_sweep_s" (the cluster with
    the workers' profiler off), "overhead_per_task_s" ((dask − local
    sweep) / tasks), "local_empty_task_s", "dask_empty_task_s" (wall per empty task),
    "identical"}."""
    from cadsim.dataset import Dataset
    from cadsim.generation.local_executor import LocalProcessExecutor, SerialExecutor
    from cadsim.generation.pipeline import generate_dataset
    from eval.core.runner import requests_for
    from eval.engine.matcher_list import parse_matchers

    with tempfile.TemporaryDirectory(prefix="cadsim-scaleout-") as tmp:
        tmp = Path(tmp)
        if dataset is None:
            dataset = tmp / "dataset"
            generate_dataset(scenario, dataset, pairs=pairs, workers=1, progress=False)
        specs = parse_matchers(matchers)
        requests = requests_for(
            [(str(dataset), Dataset(dataset).checksum)], specs, range(seeds), rates, pairs
        )
        tasks = seeds * len(rates)

        serial_sweep, serial_results, _ = _timed_sweep(SerialExecutor(), requests, tmp / "c-1")
        t0 = time.perf_counter()
        with LocalProcessExecutor(workers) as local:
            local._started()  # spawn the pool outside the timed sweep
            local_start = time.perf_counter() - t0
            local_sweep, local_results, computed = _timed_sweep(local, requests, tmp / "c-local")
            local_empty = _timed_empty(local, EMPTY_TASKS)

        dask_start, dask_sweep, dask_results, dask_empty = _on_cluster(
            workers, requests, tmp / "c-dask", profile=True
        )
        _, quiet_sweep, quiet_results, _ = _on_cluster(
            workers, requests, tmp / "c-quiet", profile=False
        )

    return {
        "runs": computed,
        "tasks": tasks,
        "workers": workers,
        "serial_sweep_s": serial_sweep,
        "local_start_s": local_start,
        "local_sweep_s": local_sweep,
        "dask_start_s": dask_start,
        "dask_sweep_s": dask_sweep,
        "local_speedup": serial_sweep / local_sweep,
        "dask_speedup": serial_sweep / dask_sweep,
        "dask_noprofile_sweep_s": quiet_sweep,
        "overhead_per_task_s": (dask_sweep - local_sweep) / tasks,
        "local_empty_task_s": local_empty / EMPTY_TASKS,
        "dask_empty_task_s": dask_empty / EMPTY_TASKS,
        "identical": all(
            _same(serial_results, other) for other in (local_results, dask_results, quiet_results)
        ),
    }


def format_report(m: dict) -> str:
    """A markdown table of a ``measure_scaleout`` result."""
    rows = [
        "| executor | start (s) | sweep (s) | speed-up | empty task (ms) |",
        "|---|---:|---:|---:|---:|",
        f"| this process (serial) | – | {m['serial_sweep_s']:.1f} | 1.00 | – |",
        f"| local pool, {m['workers']} processes | {m['local_start_s']:.2f} | "
        f"{m['local_sweep_s']:.1f} | {m['local_speedup']:.2f} | "
        f"{1e3 * m['local_empty_task_s']:.2f} |",
        f"| Dask LocalCluster, {m['workers']} × 1 thread | {m['dask_start_s']:.2f} | "
        f"{m['dask_sweep_s']:.1f} | {m['dask_speedup']:.2f} | "
        f"{1e3 * m['dask_empty_task_s']:.2f} |",
        f"| same, worker profiler off | | {m['dask_noprofile_sweep_s']:.1f} | "
        f"{m['serial_sweep_s'] / m['dask_noprofile_sweep_s']:.2f} | |",
    ]
    return "\n".join(rows) + (
        f"\n\n{m['runs']} runs in {m['tasks']} tasks; Dask overhead per sweep task "
        f"{1e3 * m['overhead_per_task_s']:+.0f} ms; results identical: {m['identical']}"
    )


def scaleout_section(args: argparse.Namespace) -> list:
    """``eval.bench`` section: prints the table; checks no speed target (returns [])."""
    print(format_report(measure_scaleout()), flush=True)
    return []


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dataset", default=None, help="dataset (default: generate CAD pairs)")
    parser.add_argument("--pairs", type=int, default=2)
    parser.add_argument("--matchers", default="all")
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("--workers", type=int, default=2)
    a = parser.parse_args()
    print(
        format_report(measure_scaleout(a.dataset, a.pairs, a.matchers, a.seeds, workers=a.workers))
    )
