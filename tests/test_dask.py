"""Generation and evaluation on a Dask cluster (a LocalCluster of 2 worker processes): the same
bytes and the same result tables as the local executors, progress messages from the workers, and
a worker killed mid-sweep costing only a retry of its task."""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

distributed = pytest.importorskip("distributed")

from cadsim.dataset import Dataset  # noqa: E402
from cadsim.generation.dask_executor import DaskExecutor  # noqa: E402
from cadsim.generation.executor import report_progress  # noqa: E402
from cadsim.generation.executors import SCHEDULER_ENV, make_executor  # noqa: E402
from cadsim.generation.local_executor import SerialExecutor  # noqa: E402
from cadsim.generation.pipeline import generate_dataset  # noqa: E402
from eval.commands.sweep_noise import sweep  # noqa: E402
from eval.core.cache import ResultCache  # noqa: E402
from eval.core.runner import Runner, requests_for  # noqa: E402
from eval.core.tasks import MatcherSpec, RunTask, execute  # noqa: E402
from eval.engine.splits import open_entry  # noqa: E402

pytestmark = [pytest.mark.slow, pytest.mark.render]

# MRC renders fastest; 7 pairs at 1 per episode = 7 episodes, so both workers simulate.
SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "mrc-arena.toml"
PAIRS = 7
MATCHERS = [MatcherSpec("sm"), MatcherSpec("rrwhm"), MatcherSpec("maximin")]
SEEDS, RATES, SWEEP_PAIRS = [0, 1], [0.0, 0.01], 3
KILL_SEED, KILL_RATE = 1, 0.01  # the sweep task (of this seed and rate) whose worker dies once


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        yield cluster


@pytest.fixture(scope="module")
def datasets(tmp_path_factory, cluster) -> tuple[Path, Path]:
    """The same dataset generated in this process and on the cluster."""
    root = tmp_path_factory.mktemp("gen")
    local, remote = root / "local", root / "dask"
    generate_dataset(SCENARIO, local, pairs=PAIRS, workers=1, progress=False)
    result = generate_dataset(
        SCENARIO, remote, pairs=PAIRS, scheduler=cluster.scheduler_address, progress=False
    )
    assert result.episodes == PAIRS and result.pairs == PAIRS
    return local, remote


def _files(out: Path) -> dict[str, bytes]:
    paths = sorted(p for p in (out / "pairs").rglob("*") if p.is_file())
    return {p.relative_to(out).as_posix(): p.read_bytes() for p in paths}


def test_cluster_generation_writes_byte_identical_records(datasets):
    local, remote = datasets
    files = _files(local)
    assert len(files) > PAIRS and files == _files(remote)
    assert Dataset(remote, verify=True).checksum == Dataset(local).checksum
    assert Dataset(remote).manifest["records"] == Dataset(local).manifest["records"]


def _reported(n: int) -> int:
    for k in range(n):
        report_progress(("record", k))
    return os.getpid()


def test_progress_messages_and_worker_processes(cluster):
    with DaskExecutor(cluster.scheduler_address) as ex:
        assert ex.workers == 2
        done = list(ex.map_unordered(_reported, [2, 3]))
        assert sorted(c.index for c in done) == [0, 1] and all(c.error is None for c in done)
        assert os.getpid() not in {c.value for c in done}  # ran in worker processes
        messages = []
        for _ in range(100):  # events arrive shortly after the results
            messages += ex.progress()
            if len(messages) >= 5:
                break
            time.sleep(0.05)
    assert sorted(map(tuple, messages)) == sorted(
        [("record", 0)] * 2 + [("record", 1)] * 2 + [("record", 2)]
    )


def test_scheduler_from_the_environment(cluster, monkeypatch):
    monkeypatch.setenv(SCHEDULER_ENV, cluster.scheduler_address)
    with make_executor(workers=4) as ex:
        assert isinstance(ex, DaskExecutor) and ex.address == cluster.scheduler_address
    monkeypatch.setenv(SCHEDULER_ENV, "")
    assert isinstance(make_executor(workers=1), SerialExecutor)


def _sweep_table(dataset: Path, runner: Runner, out: Path) -> pd.DataFrame:
    return sweep(open_entry(dataset, None), MATCHERS, SEEDS, RATES, runner, out, SWEEP_PAIRS)


def test_cluster_sweep_gives_the_local_result_table(datasets, cluster, tmp_path):
    local_ds, _ = datasets
    serial = Runner(ResultCache(tmp_path / "c1"), SerialExecutor(), progress=False)
    expected = _sweep_table(local_ds, serial, tmp_path / "r1")
    with DaskExecutor(cluster.scheduler_address) as ex:
        runner = Runner(ResultCache(tmp_path / "c2"), ex, progress=False)
        got = _sweep_table(local_ds, runner, tmp_path / "r2")
    assert runner.stats.computed == len(MATCHERS) * len(SEEDS) * len(RATES)
    pd.testing.assert_frame_equal(got, expected)
    assert (tmp_path / "r1/noise_runs.csv").read_bytes() == (
        tmp_path / "r2/noise_runs.csv"
    ).read_bytes()


def _execute_dying_once(task: RunTask):
    """`execute`, except that the task (KILL_SEED, KILL_RATE) kills its own worker process the first
    time it runs (a marker file beside the dataset remembers)."""
    marker = Path(task.dataset_dir).parent / f"killed-{os.environ.get('PYTEST_XDIST_WORKER', '')}"
    if task.seed == KILL_SEED and KILL_RATE in task.noise_rates and not marker.exists():
        marker.write_text(str(os.getpid()))
        os.kill(os.getpid(), signal.SIGKILL)
    return execute(task)


def test_killed_worker_costs_one_retry_and_no_result(datasets, cluster, tmp_path):
    local_ds, _ = datasets
    reqs = requests_for(
        [(str(local_ds), Dataset(local_ds).checksum)], MATCHERS, SEEDS, RATES, SWEEP_PAIRS
    )
    reference = Runner(ResultCache(tmp_path / "ref"), SerialExecutor(), progress=False).run(reqs)
    cache = ResultCache(tmp_path / "cache")
    with DaskExecutor(cluster.scheduler_address) as ex:
        runner = Runner(cache, ex, progress=False, task_fn=_execute_dying_once)
        results = runner.run(reqs)
    marker = local_ds.parent / f"killed-{os.environ.get('PYTEST_XDIST_WORKER', '')}"
    assert marker.is_file()  # a worker really died
    assert (runner.stats.computed, runner.stats.failed) == (len(reqs), 0)
    entries = sorted(cache.root.rglob("*.npz"))
    assert len(entries) == len(reqs) and not list(cache.root.rglob(".tmp-*"))
    assert {cache.path(r.spec(runner.version)) for r in reqs} == set(entries)
    for got, want in zip(results, reference, strict=True):
        assert got.spec == want.spec
        for a, b in zip(got.outcomes, want.outcomes, strict=True):
            np.testing.assert_array_equal(a.scores, b.scores)
            np.testing.assert_array_equal(a.assigned, b.assigned)
    # Interrupted or not, a second run finds everything in the cache.
    with DaskExecutor(cluster.scheduler_address) as ex:
        again = Runner(cache, ex, progress=False)
        again.run(reqs)
    assert (again.stats.cached, again.stats.computed) == (len(reqs), 0)


def test_two_threads_in_one_worker_never_run_two_simulations(datasets, tmp_path):
    """One worker process with 2 threads gets both episodes at once: they take turns on the
    process's simulation thread, and the records are those of the local run."""
    local, _ = datasets
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=2, processes=True, dashboard_address=None
    ) as threaded:
        with DaskExecutor(threaded.scheduler_address) as ex:
            ex.workers = 2  # submit both episodes together, to the one worker
            generate_dataset(SCENARIO, tmp_path / "ds", pairs=PAIRS, executor=ex, progress=False)
    assert _files(tmp_path / "ds") == _files(local)


@pytest.fixture(scope="module")
def cli_cluster(tmp_path_factory):
    """A real ``dask scheduler`` and two ``dask worker`` processes, as a cluster is started by
    hand (docs/scale-out.md), the workers importing this checkout."""
    import json
    import subprocess
    import sys

    folder = tmp_path_factory.mktemp("cli-cluster")
    file = folder / "scheduler.json"
    dask = Path(sys.executable).with_name("dask")
    root = str(Path(__file__).resolve().parents[1])
    env = {**os.environ, "PYTHONPATH": root + os.pathsep + os.environ.get("PYTHONPATH", "")}
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "env": env, "cwd": root}
    scheduler = subprocess.Popen(
        [str(dask), "scheduler", "--scheduler-file", str(file), "--no-dashboard", "--port", "0"],
        **quiet,
    )
    workers = [
        subprocess.Popen(
            [
                str(dask),
                "worker",
                "--scheduler-file",
                str(file),
                "--nthreads",
                "1",
                "--no-dashboard",
                "--memory-limit",
                "0",
            ],
            **quiet,
        )  # fmt: skip
        for _ in range(2)
    ]
    try:
        deadline = time.monotonic() + 60
        while not file.is_file() and time.monotonic() < deadline:
            time.sleep(0.2)
        address = json.loads(file.read_text())["address"]
        with distributed.Client(address, timeout=60) as client:
            client.wait_for_workers(2, timeout=60)
        yield address
    finally:
        for process in [*workers, scheduler]:
            process.terminate()
        for process in [*workers, scheduler]:
            process.wait(timeout=30)


def test_a_cluster_started_by_hand_generates_the_same_dataset(datasets, cli_cluster, tmp_path):
    local, _ = datasets
    result = generate_dataset(SCENARIO, tmp_path / "cli", pairs=PAIRS, scheduler=cli_cluster, progress=False)  # fmt: skip
    assert result.pairs == PAIRS
    assert Dataset(tmp_path / "cli", verify=True).checksum == Dataset(local).checksum
