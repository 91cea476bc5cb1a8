"""Pure, self-describing experiment tasks and their results.

A *run* is (dataset, matcher with options, run seed, noise rate or None = the stored detections;
optionally only the dataset's first N frame pairs, optionally with its non-covisible detections
thinned to a keep level, :mod:`eval.core.thinning`, optionally with the localisation prior re-drawn at
(position sigma m, yaw sigma deg) — ``FramePair.localise(..., seed)``; None: the record's own prior).
Its identity, :class:`RunSpec`, holds everything that determines the result — dataset checksum,
matcher name and options (tuned parameters and protocol options such as ``pairwise="image"``
are options), seed, noise rate, keep level, localisation sigmas, code version — and hashes to
the cache key (the localisation draw is fixed by the sigmas, the seed and the record identity). A
:class:`RunTask` is the unit of work handed to an executor: one dataset and seed, one or more
noise rates and one or more matchers (every combination is a run). Its runs share the reading of
every frame pair and its re-detection: which objects are detected and the seeded noise field are
decided once per pair, then scaled to each rate (``FramePair.redetect_rates``). Tasks carry
only plain data (paths, names, numbers), so any executor, local or remote, gives the same result.

The run seed is passed to the matcher (random initialisation, triangle sampling) and, with a noise
rate, to ``FramePair.redetect(rate, seed)`` (which derives per-view noise seeds from it and the
record's identity), so every matcher of a run sees the same noisy detections.
"""

from __future__ import annotations

import hashlib
import json
import time
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from eval.core import snapshot_memo
from eval.core.thinning import thin_pair


@dataclass(frozen=True)
class MatcherSpec:
    """A matcher by registry name plus keyword options (sorted (key, value) pairs, JSON values)."""

    name: str
    options: tuple[tuple[str, Any], ...] = ()

    @classmethod
    def of(cls, name: str, **options: Any) -> MatcherSpec:
        return cls(name, tuple(sorted(options.items())))

    @property
    def label(self) -> str:
        """Name, with options appended when there are any: ``tm[k=5]``."""
        if not self.options:
            return self.name
        return self.name + "[" + ",".join(f"{k}={v}" for k, v in self.options) + "]"


@dataclass(frozen=True)
class RunSpec:
    """Everything that determines one run's result; :meth:`key` is its cache key."""

    dataset_checksum: str
    matcher: MatcherSpec
    seed: int
    noise_rate: float | None
    code_version: str
    limit: int | None = None  # only the first `limit` frame pairs (None: all)
    keep: float | None = None  # thinning level of non-covisible detections (None: no thinning)
    # a re-drawn localisation prior: (position sigma m, yaw sigma deg) of the i.i.d. model, or a
    # GNSS-like preset's name (cadsim.sensing.gnss_error); None: the record's own
    localisation: tuple[float, float] | str | None = None
    # the pair of views (i, j) of each N-view snapshot (view i receives); None: the record's pair
    views: tuple[int, int] | None = None
    # the sensor a two-sensor dataset is read as (cadsim.dataset.sensor_view); None: as stored
    sensor: str | None = None

    def key(self) -> str:
        """Hex SHA-256 of the canonical JSON of the fields (``views`` and ``sensor`` only when
        set, so that the keys of other runs do not depend on them)."""
        fields = asdict(self)
        for optional in ("views", "sensor"):
            if fields[optional] is None:
                del fields[optional]
        text = json.dumps(fields, sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()


@dataclass(frozen=True)
class RunTask:
    """One dataset × seed, for one or more noise rates (``(None,)``: the stored detections) and
    one or more matchers: one run per (rate, matcher), rate-major."""

    dataset_dir: str
    dataset_checksum: str
    seed: int
    noise_rates: tuple[float | None, ...]
    matchers: tuple[MatcherSpec, ...]
    code_version: str
    limit: int | None = None
    keep: float | None = None
    localisation: tuple[float, float] | str | None = None
    views: tuple[int, int] | None = None
    # seconds a plug-in matcher may take on one frame pair (None: the worker's
    # $CADSIM_PLUGIN_TIME_LIMIT_S or 600); not part of any result, so not of the specs' keys
    plugin_time_limit_s: float | None = None
    sensor: str | None = None  # a two-sensor dataset read as "camera" or "lidar"; None: as stored

    def __post_init__(self) -> None:
        if not self.noise_rates or (None in self.noise_rates and len(self.noise_rates) > 1):
            raise ValueError(
                f"noise_rates: expected (None,) or one or more rates, got {self.noise_rates!r}"
            )

    @property
    def runs(self) -> int:
        """How many runs the task computes: rates × matchers."""
        return len(self.noise_rates) * len(self.matchers)

    @property
    def token(self) -> str:
        """A short name of this task for its progress messages (its first run's cache key)."""
        return self.specs()[0].key()[:16]

    def specs(self) -> list[RunSpec]:
        """One spec per run, rate-major (the order of :func:`execute`'s results)."""
        return [
            RunSpec(
                self.dataset_checksum,
                m,
                self.seed,
                rate,
                self.code_version,
                self.limit,
                self.keep,
                self.localisation,
                self.views,
                self.sensor,
            )
            for rate in self.noise_rates
            for m in self.matchers
        ]


@dataclass
class PairOutcome:
    """A matcher's output on one frame pair, with the ground truth needed to score it.

    index, name, episode, sim_seed, checksum: the frame pair's identity in its dataset. n1, n2:
    objects per view. gt_pairs (g, 2) and assigned (k, 2): int (i, j) pairs — ground truth and the
    matcher's full Hungarian assignment (threshold None). scores: (n1, n2) soft scores in [0, 1].
    time_s: the matcher's wall time on this pair, seconds; iterations: as the matcher reports.
    points1 (n1, D), points2 (n2, D): the positions the matcher saw (metres, each camera's frame;
    view 2's as its message reports them), true_pose: the 4x4 transform from view 2's frame into
    view 1's (None when unknown: imported data), prior_pose: the 4x4 transform the two observers'
    noisy broadcast poses imply (``FramePair.broadcast_relative_pose``; None without a prior),
    extrinsics: (2, 4, 4) each view's camera → body transform (None when unknown) — for the pose
    metrics of :mod:`eval.core.pose_metrics`.
    """

    index: int
    name: str
    episode: int
    sim_seed: int
    checksum: str
    n1: int
    n2: int
    gt_pairs: np.ndarray
    assigned: np.ndarray
    scores: np.ndarray
    time_s: float
    iterations: int
    points1: np.ndarray | None = None
    points2: np.ndarray | None = None
    true_pose: np.ndarray | None = None
    prior_pose: np.ndarray | None = None
    extrinsics: np.ndarray | None = None

    @property
    def assigned_scores(self) -> np.ndarray:
        return self.scores[self.assigned[:, 0], self.assigned[:, 1]]


@dataclass
class RunResult:
    """One run: its spec, one :class:`PairOutcome` per frame pair (dataset order), wall time."""

    spec: RunSpec
    dataset_dir: str
    outcomes: list[PairOutcome] = field(default_factory=list)
    wall_s: float = 0.0

    def ranking_frames(self) -> list[tuple]:
        """Input for :meth:`eval.protocol.metrics.RankedAssignments.from_frames`."""
        return [(o.assigned, o.assigned_scores, o.gt_pairs, o.n1, o.n2) for o in self.outcomes]


def open_dataset(path: str, sensor: str | None = None):
    """The dataset at `path` (``cadsim.dataset.Dataset``), read as ``sensor`` (None: as stored;
    "camera" or "lidar": one sensor of a two-sensor dataset)."""
    from cadsim.dataset import Dataset

    return Dataset(path, sensor=sensor)


def matcher_function(name: str):
    """The registered matcher `name` (``matchers.get``)."""
    from matchers.core.registry import get

    return get(name)


def harness_function(name: str, limit_s: float | None):
    """What a task runs for matcher `name`: a built-in as it is, a plug-in under the time limit
    `limit_s` with its results checked (``matchers.core.registry.checked``)."""
    from matchers.core.registry import checked

    return checked(name, matcher_function(name), limit_s)


def _has_what_it_needs(fn, problem) -> bool:
    """Whether ``problem`` has every optional field matcher ``fn`` requires (``requires``; the
    rule of :mod:`eval.core.abstention`)."""
    from eval.core.abstention import problem_lacks

    return not problem_lacks(getattr(fn, "requires", ()), problem)


def _declares_nothing(name: str, problem):
    """The matching of a matcher whose input is not there (a prior under the ``denied``
    localisation preset): no pair declared, all scores 0 — its run is kept, and the tables give
    it no number (:mod:`eval.core.abstention`)."""
    from matchers.core.matching import Matching

    return Matching(
        np.empty((0, 2), dtype=np.int64), np.zeros((problem.n1, problem.n2)), name, time_s=0.0
    )


def _pair_outcomes(pair, task: RunTask, functions: list) -> list[PairOutcome]:
    """Every matcher of `task` (``functions``: theirs, in order) on one frame pair, already
    re-detected at the run's noise rate; thinned and re-localised as the task says."""
    from matchers.core.discretise import canonical_scores
    from matchers.core.plugin_guard import PluginError
    from matchers.hypergraph.tensor_sharing import shared_tensors

    if task.keep is not None:
        pair = thin_pair(pair, task.keep, draw=task.seed)  # each run: its own thinning draw
    if isinstance(task.localisation, str):
        pair = pair.localise_preset(task.localisation, seed=task.seed)
    elif task.localisation is not None:
        pair = pair.localise(*task.localisation, seed=task.seed)
    problem = pair.problem()
    gt = np.asarray(pair.gt_pairs, dtype=np.int64).reshape(-1, 2)
    true_pose = pair.true_relative_pose() if hasattr(pair, "true_relative_pose") else None
    prior_pose = extrinsics = None
    if true_pose is not None:
        prior_pose = pair.broadcast_relative_pose()  # the poses alone: no detection enters
        mounts = pair.camera_extrinsics
        extrinsics = None if mounts is None else np.stack(mounts).astype(float)
    matchings = []
    with shared_tensors():  # the hypergraph matchers of a pair share its k-NN search
        for spec, fn in zip(task.matchers, functions, strict=True):
            if not _has_what_it_needs(fn, problem):
                matchings.append(_declares_nothing(spec.name, problem))
                continue
            try:
                matchings.append(fn(problem, seed=task.seed, threshold=None, **dict(spec.options)))
            except PluginError as exc:  # a plug-in broke its contract: say where
                raise type(exc)(
                    f"{exc} (frame pair {pair.name} of {task.dataset_dir}, seed {task.seed})"
                ) from exc
    outcomes = []
    for matching in matchings:
        # canonical (grid) scores: τ and the ranking see the same values on every CPU, whatever
        # the matcher (a third-party one may not use matchers.core.discretise)
        scores = canonical_scores(
            np.asarray(matching.scores, dtype=float).reshape(problem.n1, problem.n2)
        )
        outcomes.append(
            PairOutcome(
                index=pair.index,
                name=pair.name,
                episode=pair.episode,
                sim_seed=pair.sim_seed,
                checksum=pair.checksum,
                n1=problem.n1,
                n2=problem.n2,
                gt_pairs=gt,
                assigned=np.asarray(matching.pairs, dtype=np.int64).reshape(-1, 2),
                scores=scores,
                time_s=float(matching.time_s),
                iterations=int(matching.iterations),
                points1=np.asarray(problem.points1, dtype=float),
                points2=np.asarray(problem.points2, dtype=float),
                true_pose=true_pose,
                prior_pose=prior_pose,
                extrinsics=extrinsics,
            )
        )
    return outcomes


def execute(task: RunTask) -> list[RunResult]:
    """Run every matcher of `task` at each of its noise rates on every frame pair of its dataset;
    one result per run, in :meth:`RunTask.specs` order. After each frame pair it reports
    ``("runs", task.token, runs)`` (``report_progress``): the share of its runs now done."""
    from cadsim.generation.executor import report_progress

    dataset = (
        open_dataset(task.dataset_dir)
        if task.sensor is None
        else open_dataset(task.dataset_dir, task.sensor)
    )
    if dataset.checksum != task.dataset_checksum:
        raise ValueError(
            f"{task.dataset_dir}: dataset checksum {dataset.checksum[:12]} differs from the task's "
            f"{task.dataset_checksum[:12]} (the dataset changed after the task was made)"
        )
    functions = [harness_function(m.name, task.plugin_time_limit_s) for m in task.matchers]
    results = [RunResult(spec, task.dataset_dir) for spec in task.specs()]
    started = time.perf_counter()
    count = len(dataset) if task.limit is None else min(task.limit, len(dataset))
    token = task.token
    for k in range(count):
        if task.views is None:
            pair = dataset[k]
        else:  # read once per process for every view-pair task (eval.core.snapshot_memo)
            views = snapshot_memo.snapshot(
                dataset, task.dataset_dir, task.dataset_checksum, task.sensor, k
            )
            pair = views.pair(*task.views)
        if task.noise_rates == (None,):
            variants = [pair]
        else:  # the pair re-detected at every rate: one plan and one noise field per view
            variants = pair.redetect_rates(task.noise_rates, seed=task.seed)
        for r, variant in enumerate(variants):
            runs = results[r * len(functions) : (r + 1) * len(functions)]
            for result, outcome in zip(runs, _pair_outcomes(variant, task, functions), strict=True):
                result.outcomes.append(outcome)
        report_progress(("runs", token, task.runs / count))
    wall = time.perf_counter() - started
    for result in results:
        result.wall_s = wall / len(results)
    return results
