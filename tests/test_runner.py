"""Experiment runner: parallel, cached, resumable runs — against small in-memory fake datasets and a
fake matcher (the real pipeline is exercised by tests/test_reproduce.py)."""

from __future__ import annotations

import dataclasses
import os
import time

import numpy as np
import pytest

from eval.core import tasks
from eval.core.cache import ResultCache
from eval.core.executor import LocalProcessExecutor, SerialExecutor
from eval.core.runner import RunFailed, Runner, requests_for
from eval.core.tasks import MatcherSpec
from matchers.core.discretise import discretise
from matchers.core.matching import Matching
from matchers.core.problem import Problem


class FakePair:
    """A frame pair with the attributes the runner reads: n1 × n2 objects, the first k covisible."""

    def __init__(self, index: int, sim_seed: int, n1: int, n2: int, k: int, noise: float = 0.0):
        self.index, self.sim_seed, self.episode = index, sim_seed, index
        self.name, self.checksum = f"e{index:05d}_s00", f"{sim_seed:064x}"
        self.n1, self.n2, self.k, self.noise = n1, n2, k, noise
        self.gt_pairs = np.stack([np.arange(k), np.arange(k)[::-1] + (n2 - k)], axis=1)
        self.redetect_calls = 0  # re-detections asked for, one per rate
        self.redetect_passes = 0  # calls of redetect_rates (one per task that re-detects)

    def problem(self) -> Problem:
        rng = np.random.default_rng(self.sim_seed)
        base = rng.normal(size=(max(self.n1, self.n2) + self.k, 3))
        p1 = base[: self.n1].copy()
        p2 = rng.normal(size=(self.n2, 3))
        p2[self.gt_pairs[:, 1]] = base[self.gt_pairs[:, 0]] + self.noise
        return Problem(p1, p2)

    def redetect(self, noise_rate: float, seed: int) -> FakePair:
        self.redetect_calls += 1
        return FakePair(
            self.index, self.sim_seed, self.n1, self.n2, self.k, noise=noise_rate * (1 + seed)
        )

    def redetect_rates(self, noise_rates, seed: int) -> list[FakePair]:
        self.redetect_passes += 1
        return [self.redetect(rate, seed) for rate in noise_rates]


class FakeDataset(list):
    def __init__(self, pairs, checksum: str, scenario: str = "cad-fake"):
        super().__init__(pairs)
        self.checksum = checksum
        self.scenario_name = scenario
        self.manifest = {"scenario": {"name": scenario}}

    def verify_once(self) -> None:
        """In memory: nothing to re-hash."""


def fake_matcher(problem: Problem, seed: int = 0, threshold=None, fail_seed=None, **_) -> Matching:
    """Scores from position distances, with a little seed-dependent jitter."""
    if seed == fail_seed:
        raise RuntimeError("fake matcher failure")
    d = np.linalg.norm(problem.points1[:, None] - problem.points2[None], axis=2)
    jitter = np.random.default_rng(seed).uniform(0, 0.05, d.shape)
    scores = np.exp(-d) * (1 - jitter)
    scores = scores / scores.max() if scores.size and scores.max() > 0 else scores
    return Matching(discretise(scores, threshold), scores, "fake", time_s=1e-3)


def make_datasets(spec: dict[str, tuple[int, int]]) -> dict[str, FakeDataset]:
    """{path: (first sim seed, pairs)} -> fake datasets with 5-7 objects per view, 3 covisible."""
    out = {}
    for path, (first_seed, n) in spec.items():
        pairs = [FakePair(i, first_seed + i, 5 + i % 2, 6 + i % 2, 3) for i in range(n)]
        out[path] = FakeDataset(pairs, checksum=f"sum-{path}-{first_seed}")
    return out


@pytest.fixture
def fake_world(monkeypatch):
    """Patch the runner's dataset and matcher look-ups with fakes; returns the dataset table."""
    datasets = make_datasets({"data/cad": (100, 3), "data/cad-val": (900, 2)})
    monkeypatch.setattr(tasks, "open_dataset", lambda path: datasets[path])
    monkeypatch.setattr(tasks, "matcher_function", lambda name: fake_matcher)
    return datasets


def _runner(tmp_path, version="v1"):
    return Runner(
        ResultCache(tmp_path / "cache"), SerialExecutor(), version=version, progress=False
    )


def test_second_run_computes_nothing_and_returns_the_same(fake_world, tmp_path):
    reqs = requests_for(
        [("data/cad", "sum-data/cad-100")], [MatcherSpec("a"), MatcherSpec("b")], [0, 1]
    )
    runner = _runner(tmp_path)
    first = runner.run(reqs)
    assert (runner.stats.computed, runner.stats.cached) == (4, 0)
    again = runner.run(reqs)
    assert (runner.stats.computed, runner.stats.cached) == (0, 4)
    for a, b in zip(first, again, strict=True):
        assert a.spec == b.spec and len(a.outcomes) == 3
        for oa, ob in zip(a.outcomes, b.outcomes, strict=True):
            np.testing.assert_array_equal(oa.scores, ob.scores)
            np.testing.assert_array_equal(oa.assigned, ob.assigned)
            np.testing.assert_array_equal(oa.gt_pairs, ob.gt_pairs)


def test_only_changed_runs_are_recomputed(fake_world, tmp_path):
    runner = _runner(tmp_path)
    data = [("data/cad", "sum-data/cad-100")]
    runner.run(requests_for(data, [MatcherSpec("a")], [0, 1]))
    runner.run(requests_for(data, [MatcherSpec("a"), MatcherSpec.of("a", k=3)], [0, 1, 2]))
    assert (runner.stats.computed, runner.stats.cached) == (4, 2)
    # A new code version invalidates everything.
    other = _runner(tmp_path, version="v2")
    other.run(requests_for(data, [MatcherSpec("a")], [0]))
    assert other.stats.computed == 1


def test_noise_runs_share_one_redetection_per_pair(fake_world, tmp_path):
    runner = _runner(tmp_path)
    reqs = requests_for(
        [("data/cad", "sum-data/cad-100")],
        [MatcherSpec("a"), MatcherSpec("b"), MatcherSpec("c")],
        [0],
        [0.0, 0.1],
    )
    results = runner.run(reqs)
    assert runner.stats.computed == 6
    assert [p.redetect_calls for p in fake_world["data/cad"]] == [2, 2, 2]  # once per rate
    assert [p.redetect_passes for p in fake_world["data/cad"]] == [1, 1, 1]  # in one task
    by_rate = {r.spec.noise_rate for r in results}
    assert by_rate == {0.0, 0.1}
    # The rate reaches the detections: noisy scores differ from clean ones.
    clean = next(r for r in results if r.spec.noise_rate == 0.0 and r.spec.matcher.name == "a")
    noisy = next(r for r in results if r.spec.noise_rate == 0.1 and r.spec.matcher.name == "a")
    assert not np.allclose(clean.outcomes[0].scores, noisy.outcomes[0].scores)


def test_a_failed_task_keeps_the_others_and_a_rerun_retries_only_it(fake_world, tmp_path):
    runner = _runner(tmp_path)
    data = [("data/cad", "sum-data/cad-100")]
    failing = requests_for(data, [MatcherSpec.of("a", fail_seed=1)], [0, 1, 2])
    with pytest.raises(RunFailed, match="1 of 3 tasks failed"):
        runner.run(failing)
    assert (runner.stats.computed, runner.stats.failed) == (2, 1)
    cache = ResultCache(tmp_path / "cache")
    assert [r.spec(runner.version) in cache for r in failing] == [True, False, True]
    # The interrupted sweep resumes: the cached runs are not recomputed.
    with pytest.raises(RunFailed):
        runner.run(failing)
    assert (runner.stats.cached, runner.stats.computed) == (2, 0)


def test_dataset_changed_after_the_task_was_made_is_an_error(fake_world, tmp_path):
    runner = _runner(tmp_path)
    with pytest.raises(RunFailed, match="checksum"):
        runner.run(requests_for([("data/cad", "stale-checksum")], [MatcherSpec("a")], [0]))


def _square_or_fail(x: int) -> tuple[int, int]:
    if x == 2:
        raise ValueError("two")
    time.sleep(0.05)
    return x * x, os.getpid()


def test_local_process_pool_returns_every_outcome_and_isolates_failures():
    with LocalProcessExecutor(2) as ex:
        done = sorted(ex.map_unordered(_square_or_fail, [0, 1, 2, 3, 4, 5]), key=lambda c: c.index)
    assert [c.value[0] for c in done if c.error is None] == [0, 1, 9, 16, 25]
    assert isinstance(done[2].error, ValueError)
    assert all(pid != os.getpid() for c in done if c.error is None for pid in [c.value[1]])


def test_serial_executor_isolates_failures():
    done = list(SerialExecutor().map_unordered(_square_or_fail, [1, 2, 3]))
    assert [c.index for c in done] == [0, 1, 2]
    assert done[1].error is not None and done[2].value[0] == 9


def test_limit_runs_only_the_first_frame_pairs_and_is_its_own_run(fake_world, tmp_path):
    runner = _runner(tmp_path)
    data = [("data/cad", "sum-data/cad-100")]
    (first2,) = runner.run(requests_for(data, [MatcherSpec("a")], [0], limit=2))
    assert runner.stats.computed == 1 and first2.spec.limit == 2
    (full,) = runner.run(requests_for(data, [MatcherSpec("a")], [0]))
    assert runner.stats.computed == 1  # the first two pairs do not make the whole dataset
    assert [o.index for o in full.outcomes] == [0, 1, 2]
    assert [o.index for o in first2.outcomes] == [0, 1]
    np.testing.assert_array_equal(full.outcomes[1].scores, first2.outcomes[1].scores)


def test_a_prefix_run_is_read_from_the_cached_whole_dataset_run(fake_world, tmp_path):
    runner = _runner(tmp_path)
    data = [("data/cad", "sum-data/cad-100")]
    (full,) = runner.run(requests_for(data, [MatcherSpec("a")], [0]))
    (first1,) = runner.run(requests_for(data, [MatcherSpec("a")], [0], limit=1))
    assert (runner.stats.computed, runner.stats.cached) == (0, 1)
    assert first1.spec.limit == 1 and first1.spec == dataclasses.replace(full.spec, limit=1)
    assert [o.index for o in first1.outcomes] == [0]
    np.testing.assert_array_equal(full.outcomes[0].scores, first1.outcomes[0].scores)


def _die_on_three(x: int) -> int:
    if x == 3:
        os._exit(1)  # a worker process that dies mid-task
    return x


def test_a_dead_worker_fails_its_tasks_and_the_pool_recovers():
    with LocalProcessExecutor(2) as ex:
        done = list(ex.map_unordered(_die_on_three, [3]))
        assert done[0].error is not None
        again = sorted(c.value for c in ex.map_unordered(_die_on_three, [1, 2]))
    assert again == [1, 2]


def test_a_seed_free_matcher_runs_once_for_every_seed(fake_world, tmp_path, monkeypatch):
    import matchers.core.registry

    monkeypatch.setattr(matchers.core.registry, "deterministic", lambda name: name == "fixed")
    runner = _runner(tmp_path)
    data = [("data/cad", "sum-data/cad-100")]
    seeds = [0, 1, 2, 3]
    results = runner.run(requests_for(data, [MatcherSpec("fixed"), MatcherSpec("b")], seeds))
    assert runner.stats.computed == 1 + 4  # "fixed" once, "b" once per seed
    fixed = [r for r in results if r.spec.matcher.name == "fixed"]
    assert [r.spec.seed for r in fixed] == seeds  # labelled as asked
    for run in fixed[1:]:
        for a, b in zip(fixed[0].outcomes, run.outcomes, strict=True):
            np.testing.assert_array_equal(a.scores, b.scores)
    # the seed also draws the noise of a re-detection: then every seed is its own run
    runner.run(requests_for(data, [MatcherSpec("fixed")], seeds, [0.1]))
    assert runner.stats.computed == 4


def test_runs_of_a_seed_share_a_task_split_only_to_keep_every_worker_busy():
    from eval.core.runner import _group

    data = [("data/cad", "sum")]
    rates = [0.0, 0.001, 0.01, 0.1, 0.3]
    one_seed = requests_for(data, [MatcherSpec("a"), MatcherSpec("b")], [0], rates)
    assert [(t.noise_rates, t.runs) for t in _group(one_seed, "v", workers=1)] == [
        (tuple(rates), 10)
    ]
    split = _group(one_seed, "v", workers=2)  # two tasks per worker, interleaved rates
    assert [t.noise_rates for t in split] == [(0.0,), (0.3,), (0.01,), (0.001, 0.1)]
    assert sorted(r for t in split for r in t.noise_rates) == rates
    assert all(t.matchers == (MatcherSpec("a"), MatcherSpec("b")) for t in split)
    assert len(_group(one_seed, "v", workers=64)) == len(rates) * 2  # at most one run each
    four_seeds = requests_for(data, [MatcherSpec("a")], [0, 1, 2, 3], rates)
    assert [(t.seed, len(t.noise_rates)) for t in _group(four_seeds, "v", workers=2)] == [
        (s, 5) for s in range(4)
    ]
    # Every (rate, matcher) of a task is a run that was asked for: a rate with other missing
    # matchers gets its own task.
    partial = one_seed[:4] + [r for r in one_seed[4:] if r.matcher.name == "a"]
    tasks = _group(partial, "v", workers=1)
    asked = {(r.noise_rate, r.matcher) for r in partial}
    assert {(s.noise_rate, s.matcher) for t in tasks for s in t.specs()} == asked
    assert sum(t.runs for t in tasks) == len(partial) and len(tasks) == 2
    # Runs on the stored detections: the matchers of a seed together, split by matchers.
    names = [MatcherSpec(c) for c in "abcdef"]
    stored = _group(requests_for(data, names, [0]), "v", workers=2)
    assert sorted(m.name for t in stored for m in t.matchers) == list("abcdef")
    assert [t.noise_rates for t in stored] == [(None,)] * 4
    assert {len(t.matchers) for t in stored} <= {1, 2}


def test_a_task_reports_its_runs_pair_by_pair_and_the_bar_counts_each_run_once(fake_world):
    from eval.core.runner import _group, _TaskProgress

    reqs = requests_for(
        [("data/cad", "sum-data/cad-100")], [MatcherSpec("a"), MatcherSpec("b")], [0], [0.0, 0.1]
    )
    (task,) = _group(reqs, "v1", workers=1)
    executor = SerialExecutor()
    results = executor._call(tasks.execute, task)
    messages = executor.progress()
    assert len(results) == task.runs == 4
    assert messages == [("runs", task.token, 4 / 3)] * 3  # 3 frame pairs
    with _TaskProgress([task], "t", executor, show=False) as bar:
        executor._messages.extend(messages[:2] + [("record", 1)])  # two pairs reported, noise
        bar.poll()
        assert bar.done == pytest.approx(8 / 3)
        bar.finished(task)
        executor._messages.append(messages[2])  # late: its task is already counted
        bar.poll()
        assert bar.done == pytest.approx(4)
