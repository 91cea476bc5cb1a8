"""Experiment runner: computes the runs that are not cached yet, in parallel, and stores each as
it completes, so a re-run computes only what changed and an interrupted sweep resumes. A run of
the first N frame pairs is read from the cached run of the whole dataset when there is one.

Missing runs are grouped into :class:`eval.core.tasks.RunTask` s: all matchers and noise rates of one
(dataset, seed, pairs, keep level, localisation draw) share a task — the reading of every record,
its re-detection plan and the hypergraph matchers' k-NN search (``matchers.shared_tensors``) —
split into interleaved halves while there are fewer than two tasks per worker. A matcher that
ignores its seed (``matchers.deterministic``) is run with seed 0 only where nothing else it reads
uses the seed (no noise re-draw; a localisation re-draw only if it reads the prior):
its runs for other seeds are that run, read once and relabelled — same bits, a quarter of Table
I's cost. Tasks go to an :class:`eval.core.executor.Executor`; results come back to this process, which writes the cache — workers need no access to it (only to the
datasets), whichever executor runs them (local processes or a Dask cluster, docs/scale-out.md).
"""

from __future__ import annotations

import dataclasses
import hashlib
import logging
import threading
import traceback
from collections import OrderedDict
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

from tqdm import tqdm

from cadsim.user_errors import is_user_error, one_line
from eval.core.cache import ResultCache, code_version
from eval.core.cache_checks import disagreement, inconsistent_groups
from eval.core.executor import Executor
from eval.core.matcher_source import run_version
from eval.core.tasks import MatcherSpec, RunResult, RunSpec, RunTask, execute

log = logging.getLogger(__name__)

READ_MEMO = 400
"""Cached entries a runner keeps in memory once read (≈ 0.1–1 MB each)."""


@dataclass(frozen=True)
class RunRequest:
    """A run asked for: dataset (directory + checksum), matcher, seed, noise rate (None: the
    dataset's stored detections)."""

    dataset_dir: str
    dataset_checksum: str
    matcher: MatcherSpec
    seed: int
    noise_rate: float | None = None
    limit: int | None = None
    keep: float | None = None
    localisation: tuple[float, float] | str | None = None
    views: tuple[int, int] | None = None
    sensor: str | None = None

    def spec(self, version: str) -> RunSpec:
        return RunSpec(
            self.dataset_checksum,
            self.matcher,
            self.seed,
            self.noise_rate,
            version,
            self.limit,
            self.keep,
            self.localisation,
            self.views,
            self.sensor,
        )


@dataclass
class RunStats:
    """What the last :meth:`Runner.run` did: runs found in the cache, computed, failed."""

    cached: int = 0
    computed: int = 0
    failed: int = 0


class RunFailed(RuntimeError):
    """Some tasks raised; the other runs completed and are cached. ``errors``: what they raised;
    ``user_error``: all of it is bad input (a corrupt dataset, a bad option), so the CLI reports
    one line rather than a traceback (``cadsim.user_errors``)."""

    def __init__(self, message: str, errors: Sequence[BaseException] = ()) -> None:
        super().__init__(message)
        self.errors = list(errors)
        self.user_error = bool(self.errors) and all(is_user_error(e) for e in self.errors)


def requests_for(
    datasets: Iterable[tuple[str, str]],
    matchers: Iterable[MatcherSpec],
    seeds: Iterable[int],
    noise_rates: Iterable[float | None] = (None,),
    limit: int | None = None,
    keep: float | None = None,
    localisation: tuple[float, float] | str | None = None,
    views: tuple[int, int] | None = None,
    sensor: str | None = None,
) -> list[RunRequest]:
    """Every combination of (dataset dir, checksum) × matcher × seed × noise rate (first `limit`
    frame pairs of each dataset; None: all; non-covisible detections thinned to level `keep`,
    where 1 and None both mean no thinning and share the untouched runs; the localisation prior
    re-drawn at (position sigma m, yaw sigma deg) or by a GNSS-like preset (its name), None: each
    record's own; ``views``: the pair of views (i, j) of N-view snapshots, None: the records'
    pairs; ``sensor``: read a two-sensor dataset as "camera" or "lidar", None: as stored)."""
    matchers, seeds, noise_rates = list(matchers), list(seeds), list(noise_rates)
    keep = None if keep is None or float(keep) == 1.0 else float(keep)
    if localisation is not None and not isinstance(localisation, str):
        localisation = (float(localisation[0]), float(localisation[1]))
    return [
        RunRequest(d, c, m, s, r, limit, keep, localisation, views, sensor)
        for d, c in datasets
        for r in noise_rates
        for s in seeds
        for m in matchers
    ]


def _seed_free(req: RunRequest) -> RunRequest:
    """`req` with seed 0 when its matcher ignores the seed and nothing else in the run uses it
    (no noise re-detection, no thinning — the run's seed is its draw — and no localisation
    re-draw unless the matcher does not read the prior)."""
    if req.seed == 0 or req.noise_rate is not None or req.keep is not None:
        return req
    from matchers.blocks.prior import PRIOR_FIELDS
    from matchers.core.registry import deterministic, requires

    try:
        free = deterministic(req.matcher.name)
        if req.localisation is not None and requires(req.matcher.name) & PRIOR_FIELDS:
            return req  # the seed re-draws the prior it reads
    except ValueError:  # unknown matcher: let the task report it
        return req
    return dataclasses.replace(req, seed=0) if free else req


def _latency_only(req: RunRequest) -> RunRequest:
    """`req` with a localisation preset spec replaced by ``exact+<latency>ms`` when its matcher
    does not read the prior: such a matcher sees only the message latency of a preset (view 2's
    positions as sent), never its pose errors, so every preset and error scale with one latency
    shares one run (a preset sweep runs the no-prior matchers once per latency)."""
    if not isinstance(req.localisation, str):
        return req
    from cadsim.sensing.gnss_error import model_of
    from matchers.blocks.prior import PRIOR_FIELDS
    from matchers.core.registry import requires

    try:
        if requires(req.matcher.name) & PRIOR_FIELDS:
            return req
        latency = model_of(req.localisation).latency_ms
    except ValueError:  # unknown matcher or spec: let the task report it
        return req
    return dataclasses.replace(req, localisation=f"exact+{latency:g}ms")


def _group(
    missing: Sequence[RunRequest],
    version: str | Callable[[RunRequest], str],
    workers: int = 1,
    plugin_time_limit_s: float | None = None,
) -> list[RunTask]:
    """Tasks for the missing runs: one per (dataset, seed, pairs, keep, localisation), holding its
    matchers × its noise rates (rates with the same missing matchers together, so that every run
    of a task was asked for). Its runs share the reading of every frame pair, its re-detection
    plan and the hypergraph matchers' k-NN search. While there are fewer than two tasks per
    worker (one worker: one task each), the task with the most runs is split in two, by rates
    when it has several, else by matchers — interleaved halves, so that they cost about the
    same. Every task carries ``plugin_time_limit_s``, the plug-ins' time limit per frame pair.
    ``version``: the code version of every run, or of each request (a plug-in's includes its
    source's hash, :mod:`eval.core.matcher_source`: its runs get tasks of their own)."""
    version_of = version if callable(version) else (lambda _req: version)
    groups: dict[tuple, dict[float | None, list[MatcherSpec]]] = {}
    for req in missing:
        key = (
            req.dataset_dir,
            req.dataset_checksum,
            req.seed,
            req.limit,
            req.keep,
            req.localisation,
            req.views,
            req.sensor,
            version_of(req),
        )
        groups.setdefault(key, {}).setdefault(req.noise_rate, []).append(req.matcher)
    blocks: list[tuple[tuple, tuple[MatcherSpec, ...], tuple[float | None, ...]]] = []
    for key, by_rate in groups.items():
        same: dict[tuple[MatcherSpec, ...], list[float | None]] = {}
        for rate, matchers in by_rate.items():
            same.setdefault(tuple(dict.fromkeys(matchers)), []).append(rate)
        blocks += [(key, matchers, tuple(rates)) for matchers, rates in same.items()]
    target = 2 * workers if workers > 1 else 1
    while blocks and len(blocks) < target:
        widest = max(range(len(blocks)), key=lambda b: len(blocks[b][1]) * len(blocks[b][2]))
        key, matchers, rates = blocks[widest]
        if len(rates) > 1:
            halves = [(key, matchers, rates[0::2]), (key, matchers, rates[1::2])]
        elif len(matchers) > 1:
            halves = [(key, matchers[0::2], rates), (key, matchers[1::2], rates)]
        else:
            break
        blocks[widest : widest + 1] = halves
    return [
        RunTask(*k[:3], rates, matchers, k[8], *k[3:7], plugin_time_limit_s, k[7])
        for k, matchers, rates in blocks
    ]


class _TaskProgress:
    """A tqdm bar counting runs, moved as tasks report frame pairs done (``("runs", token, runs)``
    messages of :func:`eval.core.tasks.execute`, polled from the executor twice a second on a
    background thread) and set right as each task finishes."""

    POLL_S = 0.5

    def __init__(self, tasks: Sequence[RunTask], desc: str, executor: Executor, show: bool):
        self.executor = executor
        self.bar = tqdm(
            total=sum(t.runs for t in tasks),
            desc=desc,
            unit="run",
            disable=None if show else True,  # None: only on a terminal
            bar_format="{l_bar}{bar}| {n:.0f}/{total} [{elapsed}<{remaining}]",
        )
        self.reported = {t.token: 0.0 for t in tasks}  # runs reported by each unfinished task
        self.runs = {t.token: t.runs for t in tasks}
        self.finished_runs = 0  # runs of the finished tasks
        self.done = 0.0  # runs counted so far (the bar's position, also when it is hidden)
        self.lock = threading.Lock()
        self.stop = threading.Event()
        self.poller = threading.Thread(target=self._poll_loop, name="cadsim-progress", daemon=True)

    def __enter__(self) -> _TaskProgress:
        self.poller.start()
        return self

    def __exit__(self, *exc) -> None:
        self.stop.set()
        self.poller.join()
        self.bar.close()

    def _poll_loop(self) -> None:
        while not self.stop.wait(self.POLL_S):
            self.poll()

    def poll(self) -> None:
        """Move the bar by the runs that running tasks reported since the last poll."""
        with self.lock:
            for message in self.executor.progress():
                if isinstance(message, tuple) and len(message) == 3 and message[0] == "runs":
                    _, token, runs = message
                    if token in self.reported:  # a late message of a finished task: counted
                        self.reported[token] += runs
                        self._show()

    def finished(self, task: RunTask) -> None:
        """Count the rest of `task`'s runs (all of them when it reported none)."""
        with self.lock:
            self.reported.pop(task.token, None)
            self.finished_runs += task.runs
            self._show()

    def _show(self) -> None:
        # finished tasks count whole (so the bar ends exactly at its total), running ones as
        # far as they reported, each at most all of its runs
        target = self.finished_runs + sum(
            min(runs, self.runs[token]) for token, runs in self.reported.items()
        )
        self.bar.update(target - self.done)
        self.bar.n = self.done = target  # exact, not a running sum of float steps


class Runner:
    """Cache-aware execution of runs through an executor. `task_fn` computes one task (a
    picklable module-level function; default :func:`eval.core.tasks.execute`).
    `plugin_time_limit_s`: seconds a plug-in matcher (or fusion) may take on one problem
    (None: ``$CADSIM_PLUGIN_TIME_LIMIT_S`` of this process, else 600); it travels in every task,
    so every executor's workers apply this value (:mod:`matchers.core.plugin_guard`)."""

    def __init__(
        self,
        cache: ResultCache,
        executor: Executor,
        version: str | None = None,
        progress: bool = True,
        task_fn: Callable[[RunTask], list[RunResult]] = execute,
        plugin_time_limit_s: float | None = None,
    ) -> None:
        from matchers.core.plugin_guard import parse_time_limit, time_limit_s

        self.plugin_time_limit_s = (
            time_limit_s()
            if plugin_time_limit_s is None
            else parse_time_limit(plugin_time_limit_s, "plugin_time_limit_s")
        )
        self.cache = cache
        self.executor = executor
        self.task_fn = task_fn
        self.version = code_version() if version is None else version
        self.progress = progress
        self.stats = RunStats()  # of the last run() call
        self.totals = RunStats()  # of every call so far
        self._versions: dict[str, str] = {}  # matcher name -> its runs' code version (per call)
        self._memo: OrderedDict[tuple, RunResult] = OrderedDict()  # recent reads (:meth:`_read`)

    def run(self, requests: Sequence[RunRequest], desc: str = "runs") -> list[RunResult]:
        """Results of `requests`, in order; computes the missing ones. Raises :class:`RunFailed`
        after every other task has finished if some task raised."""
        try:
            return self._run(requests, desc)
        finally:
            for name in ("cached", "computed", "failed"):
                setattr(self.totals, name, getattr(self.totals, name) + getattr(self.stats, name))

    def spec_keys(self, requests: Sequence[RunRequest]) -> list[str]:
        """The result-cache key of each request's run (:meth:`RunSpec.key`, the run's code
        version included): what a table derived from these runs alone can be keyed by."""
        return [req.spec(self._version(req)).key() for req in requests]

    def _source(self, spec: RunSpec) -> RunSpec | None:
        """The cached run `spec` can be read from: itself, or — for a run of the first N frame
        pairs — the cached run of the whole dataset (frame pairs are computed independently and in
        dataset order, so the first N outcomes are the same); None when neither is cached."""
        if spec in self.cache:
            return spec
        if spec.limit is not None:
            full = dataclasses.replace(spec, limit=None)
            if full in self.cache:
                return full
        return None

    def _load(self, spec: RunSpec, checked: bool = True) -> RunResult:
        source = self._source(spec)
        result = self._read(spec if source is None else source, checked)
        if source is not None and source != spec:
            outcomes = result.outcomes[: spec.limit]
            share = len(outcomes) / max(len(result.outcomes), 1)
            result = RunResult(spec, result.dataset_dir, outcomes, result.wall_s * share)
        return result

    def _read(self, spec: RunSpec, checked: bool) -> RunResult:
        """``cache.load(spec)``, remembered for the rest of this process (the last
        :data:`READ_MEMO` entries): the studies read the same validation and test runs several
        times, and each read would decompress and check the entry again. A digest of the
        entry's bytes is part of the key, so a rewritten entry is read and checked afresh."""
        try:
            raw = self.cache.path(spec).read_bytes()  # read once: digested, then parsed
            key = (spec, hashlib.blake2b(raw, digest_size=16).digest(), checked)
        except OSError:
            raw = key = None
        if key is not None and key in self._memo:
            self._memo.move_to_end(key)
            return self._memo[key]
        result = self.cache.load(spec, checked=checked, raw=raw)
        if key is not None:
            self._memo[key] = result
            while len(self._memo) > READ_MEMO:
                self._memo.popitem(last=False)
        return result

    def _version(self, req: RunRequest) -> str:
        """The code version of `req`'s run (a plug-in's includes its source file's hash)."""
        name = req.matcher.name
        if name not in self._versions:
            self._versions[name] = run_version(self.version, name)
        return self._versions[name]

    def _servable(self, specs: dict[RunSpec, RunRequest]) -> dict[RunSpec, RunResult]:
        """The cached results of `specs` that can be served: readable, consistent with
        themselves, with their dataset and with the other runs on the same data
        (:mod:`eval.core.cache_checks`). An entry refused is logged and recomputed."""
        found: dict[RunSpec, RunResult] = {}
        for spec, req in specs.items():
            if self._source(spec) is None:
                continue
            try:
                result = self._load(spec)
                why = disagreement(result, req.dataset_dir)
            except ValueError as exc:
                why = one_line(exc)
            if why is None:
                found[spec] = result
            else:
                log.warning("result cache: refused %s (%s); recomputing it", spec.key()[:16], why)
        loaded = list(found.values())
        for i in sorted(inconsistent_groups(loaded)):
            spec = loaded[i].spec
            log.warning(
                "result cache: refused %s (its ground truth or view sizes differ from another "
                "run's on the same data); recomputing it",
                spec.key()[:16],
            )
            found.pop(spec, None)
        return found

    def _run(self, requests: Sequence[RunRequest], desc: str) -> list[RunResult]:
        self._versions = {}  # a plug-in's file may have changed since the last call
        wanted = [req.spec(self._version(req)) for req in requests]
        requests = [_seed_free(_latency_only(req)) for req in requests]
        specs = [req.spec(self._version(req)) for req in requests]
        by_spec = dict(zip(specs, requests, strict=True))
        loaded = self._servable(by_spec)
        missing = [r for s, r in by_spec.items() if s not in loaded]
        if loaded:
            log.info(
                "%s: %d of %d runs read from the result cache %s (delete it to recompute them)",
                desc,
                len(loaded),
                len(by_spec),
                self.cache.root,
            )
        self.stats = RunStats(cached=len(loaded))
        if missing:
            tasks = _group(missing, self._version, self.executor.workers, self.plugin_time_limit_s)
            log.info(
                "%s: %d cached, %d to compute in %d tasks",
                desc,
                self.stats.cached,
                len(missing),
                len(tasks),
            )
            failures, errors = [], []
            fresh: dict[RunSpec, RunResult] = {}
            with _TaskProgress(tasks, desc, self.executor, self.progress) as bar:
                for done in self.executor.map_unordered(self.task_fn, tasks):
                    task = tasks[done.index]
                    if done.error is not None:
                        self.stats.failed += task.runs
                        detail = "".join(traceback.format_exception(done.error)).rstrip()
                        failures.append(f"{task}: {done.error!r}")
                        errors.append(done.error)
                        if is_user_error(done.error):  # bad input: RunFailed's one line says it
                            log.debug("task failed: %s: %s\n%s", task, one_line(done.error), detail)
                        else:
                            log.error("task failed: %s\n%s", task, detail)
                    else:
                        for result in done.value:
                            self.cache.store(result)
                            fresh[result.spec] = result
                        self.stats.computed += len(done.value)
                    bar.finished(task)
            if failures:
                raise RunFailed(
                    f"{len(failures)} of {len(tasks)} tasks failed (the rest are cached; re-run "
                    f"to retry only the failed ones); the first: {one_line(errors[0])}",
                    errors,
                )
        for spec in dict.fromkeys(specs):  # each computed run read back as stored
            if spec not in loaded:  # (stored by this process a moment ago: not re-checked)
                try:
                    loaded[spec] = self._load(spec, checked=False)
                except ValueError as exc:  # stored but not servable: use it this once
                    log.warning("result cache: %s; not served again", one_line(exc))
                    loaded[spec] = fresh[spec]
        return [
            loaded[spec] if spec == want else dataclasses.replace(loaded[spec], spec=want)
            for spec, want in zip(specs, wanted, strict=True)
        ]
