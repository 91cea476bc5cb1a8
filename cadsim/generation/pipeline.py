"""Generation: scenario → episodes of simulation → rendered, noised, detected pairs → dataset.

Work is split into *episodes*: one simulation each, seeded by (root seed, episode index). An
episode walks its snapshots in time order, tries the source's candidate observer pairs of each
snapshot, and keeps at most one pair per snapshot (the first that passes DESIGN §5's acceptance)
until it has ``pairs_per_episode`` pairs or the simulation ends (with ``[sampling]
distinct_observers``, a pair of observer vehicles gives at most one record per episode, so a
queue waiting at a red light does not yield the same view again). Record (episode, slot) is the
slot-th pair episode ``episode`` accepted; the dataset is the first N records in (episode, slot)
order. Records therefore do not depend on the number of workers, the order episodes finish in,
or interruptions: an interrupted run is resumed by running the same command again.

Episodes are tasks of a :class:`cadsim.generation.executor.Executor`: local worker processes
(multiprocessing ``spawn``: libsumo allows one simulation per process, and a GL context must not
be forked), this process (one worker), or a Dask cluster (``scheduler``; docs/scale-out.md). In a
process whose tasks run on threads (a Dask worker), every episode runs on one dedicated thread,
one at a time: never two simulations in one process, and the renderers' GL contexts stay on the
thread that made them.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextvars
import dataclasses
import importlib
import json
import logging
import math
import os
import shutil
import signal
import socket
import threading
import time
from concurrent.futures import FIRST_COMPLETED, Future, wait
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from cadsim.dataset import layout
from cadsim.dataset.atomic_writer import (
    remove_record,
    remove_stale_temp,
    write_file_atomic,
    write_record,
)
from cadsim.dataset.checksum import record_dir_checksum
from cadsim.dataset.detections import ViewDetections, is_acceptable_pair, is_acceptable_set
from cadsim.dataset.encoding import json_bytes
from cadsim.dataset.manifest import (
    DatasetError,
    build_manifest,
    generation_config,
    read_manifest,
    write_manifest,
)
from cadsim.dataset.output_folder import check_output_folder
from cadsim.dataset.record_format import (
    FORMAT_VERSION,
    MULTI_VIEW_FORMAT,
    SEQUENCE_FORMAT,
    PairRecord,
    SnapshotRecord,
    ViewCapture,
    encode_record,
    encode_snapshot,
)
from cadsim.dataset.seeds import (
    attribute_seed,
    localisation_seed,
    noise_seed,
    odometry_seed,
    simulation_seed,
)
from cadsim.dataset.writer_lock import exclusive_writer
from cadsim.generation.executor import Executor, report_progress
from cadsim.generation.executors import make_executor
from cadsim.generation.frames_from import usable_frames
from cadsim.limits import MAX_PAIRS, MAX_SEED, MAX_WORKERS
from cadsim.observer_pose import ObserverPose
from cadsim.render.appearance import AppearanceConfig, exposed
from cadsim.scenario_views import view_count
from cadsim.sensing.odometry import Odometer, OdometryModel
from cadsim.sources.sumo.demand import DEMAND_MODEL

log = logging.getLogger(__name__)

DEFAULT_PAIRS_PER_EPISODE = 5
MIN_COVISIBLE = 3  # DESIGN §5: objects detected in both views
MIN_EXCLUSIVE = 1  # DESIGN §5: objects each view detects that the other does not


class GenerationError(RuntimeError):
    """Generation cannot produce the requested dataset (bad output folder, too few pairs)."""

    user_error = True  # reported as one line by the CLI (cadsim.user_errors)


@dataclass(frozen=True)
class Stages:
    """The pipeline's parts as ``"module:attribute"`` paths, resolved inside each worker (so the
    main process imports neither SUMO nor pyrender, and tests can substitute fakes).

    source(scenario, seed, workdir) -> TrafficSource; renderer(width, height) -> object with
    ``render(snapshot, camera, exclude_ids) -> RenderedView``; noise_config(**scenario.noise);
    apply_noise(depth, config, rng) -> noisy depth; detection_config(**scenario.detection);
    detect(view, noisy_depth, objects, camera, config, attribute_rng=rng) -> Detections.
    """

    source: str = "cadsim.sources:make_source"
    renderer: str = "cadsim.render:Renderer"
    noise_config: str = "cadsim.sensing.depth_noise:NoiseConfig"
    apply_noise: str = "cadsim.sensing.depth_noise:apply_depth_noise"
    detection_config: str = "cadsim.sensing.detection:DetectionConfig"
    detect: str = "cadsim.sensing.detection:detect"

    def resolve(self, name: str):
        module, _, attr = getattr(self, name).partition(":")
        return getattr(importlib.import_module(module), attr)


@dataclass(frozen=True)
class Criteria:
    """Episode size and acceptance. pairs_per_episode, pairs_per_snapshot, distinct_observers:
    from the scenario's ``[sampling]`` table; min_covisible, min_exclusive: DESIGN §5."""

    pairs_per_episode: int = DEFAULT_PAIRS_PER_EPISODE
    pairs_per_snapshot: int = 1
    min_covisible: int = MIN_COVISIBLE
    min_exclusive: int = MIN_EXCLUSIVE
    distinct_observers: bool = False

    @classmethod
    def from_sampling(cls, sampling: dict | None) -> Criteria:
        s = sampling or {}
        crit = cls(
            pairs_per_episode=int(s.get("pairs_per_episode", DEFAULT_PAIRS_PER_EPISODE)),
            pairs_per_snapshot=int(s.get("pairs_per_snapshot", 1)),
            distinct_observers=bool(s.get("distinct_observers", False)),
        )
        for key in ("pairs_per_episode", "pairs_per_snapshot"):
            if getattr(crit, key) < 1:
                raise GenerationError(f"sampling.{key}: expected >= 1, got {getattr(crit, key)}")
        return crit


@dataclass(frozen=True)
class EpisodeTask:
    """Everything a worker needs to run one episode (picklable)."""

    scenario: Any
    out: str
    root_seed: int
    episode: int
    max_slots: int
    criteria: Criteria
    stages: Stages
    frames_from: str | None = None
    """A camera-only dataset of the same frames (:mod:`cadsim.generation.frames_from`), or None."""


@dataclass
class EpisodeResult:
    """What one episode did. accepted: records of this episode now on disk (a prefix of slots);
    exhausted: the simulation ended before ``max_slots`` pairs were found. seconds,
    render_seconds: wall clock; core_seconds: the worker process's CPU time (every thread, the
    renderer's too) over the episode, of which view_core_seconds rendering + noise + detection
    (or the LiDAR) of every view tried and write_core_seconds encoding and writing records."""

    episode: int
    sim_seed: int
    max_slots: int
    accepted: int
    exhausted: bool
    new_records: int = 0
    snapshots: int = 0
    candidates: int = 0
    views: int = 0
    seconds: float = 0.0
    render_seconds: float = 0.0
    core_seconds: float = 0.0
    view_core_seconds: float = 0.0
    write_core_seconds: float = 0.0
    gl: dict | None = None  # the GL driver that drew its views (Renderer.gl); None: none drawn


@dataclass
class GenerationResult:
    """Outcome of ``generate_dataset``. views/candidates/seconds count this run's work only."""

    out: Path
    pairs: int
    checksum: str
    episodes: int
    new_records: int
    views: int
    candidates: int
    seconds: float
    render_seconds: float
    episode_results: list[EpisodeResult] = field(default_factory=list)

    @property
    def views_per_s(self) -> float:
        return self.views / self.render_seconds if self.render_seconds > 0 else 0.0

    @property
    def pairs_per_s(self) -> float:
        return self.new_records / self.seconds if self.seconds > 0 else 0.0


# --------------------------------------------------------------------------- one episode

_renderers: dict[tuple[str, int, int], Any] = {}  # per process: scenes are built once, reused
_simulation_thread: cf.ThreadPoolExecutor | None = None  # per process, made on first use
_simulation_thread_lock = threading.Lock()


def _renderer(stages: Stages, width: int, height: int):
    key = (stages.renderer, width, height)
    if key not in _renderers:
        _renderers[key] = stages.resolve("renderer")(width, height)
    return _renderers[key]


def gl_drivers(found, earlier=()) -> list[dict]:
    """The distinct GL drivers (:attr:`cadsim.render.Renderer.gl` dicts) in `earlier` and
    `found` (None entries left out), in order of first appearance: the manifest's ``gl``."""
    drivers: list[dict] = []
    for gl in [*earlier, *found]:
        if isinstance(gl, dict) and gl not in drivers:
            drivers.append(gl)
    return drivers


def _earlier_gl(out: Path) -> list[dict]:
    """The ``gl`` list an earlier (interrupted or finished) run wrote to ``out``'s manifest."""
    try:
        gl = json.loads((out / layout.MANIFEST).read_text(encoding="utf-8")).get("gl")
    except (OSError, ValueError, AttributeError):
        return []
    return [g for g in gl if isinstance(g, dict)] if isinstance(gl, list) else []


def release_renderers() -> None:
    """Close this process's cached renderers (frees their GL contexts before interpreter exit)."""
    while _renderers:
        _, renderer = _renderers.popitem()
        close = getattr(renderer, "close", None)
        if close is not None:
            close()


def _existing_prefix(out: Path, episode: int) -> tuple[int, tuple[float, int] | None]:
    """Number of consecutive slots 0.. of ``episode`` on disk, and where the last one was found:
    (snapshot time, index of the candidate pair in that snapshot), or None."""
    records = layout.existing_records(out)
    count = 0
    while (episode, count) in records:
        count += 1
    if count == 0:
        return 0, None
    record = json.loads((records[(episode, count - 1)] / layout.RECORD_JSON).read_text())
    return count, (float(record["time"]), int(record["meta"]["candidate"]))


def _observer_key(candidate) -> frozenset:
    """The observers of a candidate pair or set, unordered (``distinct_observers``)."""
    if hasattr(candidate, "observer_ids"):
        return frozenset(candidate.observer_ids)
    return frozenset((candidate.observer1_id, candidate.observer2_id))


def _views(scenario) -> int:
    """Views per record of ``scenario`` (2: frame pairs)."""
    return view_count(getattr(scenario, "observers", None) or {})


def _used_observers(out: Path, episode: int, slots: int) -> set[frozenset]:
    """Observer keys of the first ``slots`` records of ``episode`` on disk (a resumed episode
    must not repeat them)."""
    records = layout.existing_records(out)
    used = set()
    for s in range(slots):
        record = json.loads((records[(episode, s)] / layout.RECORD_JSON).read_text())
        used.add(frozenset(o["id"] for o in record["observers"]))
    return used


def _appearance(scenario) -> AppearanceConfig | None:
    """The scenario's appearance realism, or None when it has no ``[appearance]`` table."""
    table = getattr(scenario, "appearance", None)
    return AppearanceConfig(**table) if table else None


def _observe(stages, noise_cfg, det_cfg, renderer, snapshot, camera, exclude_id, seed, attr_seed, appearance):  # fmt: skip
    """Render one camera, add depth noise with ``seed``, apply the camera's exposure and white
    balance (``appearance``: an AppearanceConfig, or None for none), detect with attribute
    errors seeded by ``attr_seed``."""
    rendered = renderer.render(snapshot, camera, [exclude_id] if exclude_id else [])
    noisy = stages["apply_noise"](rendered.depth, noise_cfg, np.random.default_rng(seed))
    attribute_rng = np.random.default_rng(attr_seed)
    if appearance is not None:
        gains = appearance.camera_gains(np.random.default_rng(attr_seed))
        rendered = dataclasses.replace(rendered, color=exposed(rendered.color, gains))
    det = stages["detect"](
        rendered, noisy, snapshot.objects, camera, det_cfg, attribute_rng=attribute_rng
    )
    return rendered, ViewDetections.from_detections(det)


def run_episode(task: EpisodeTask, on_record=None) -> EpisodeResult:
    """Run one episode: write its records ``(episode, slot)`` for slots not yet on disk, up to
    ``task.max_slots``. ``on_record()`` is called after each record written."""
    if getattr(task.scenario, "sequence", None):
        return run_sequence_episode(task, on_record)
    if task.frames_from is not None:
        derived = _episode_from_frames(task, on_record)
        if derived is not None:
            return derived
    t0, c0 = time.perf_counter(), time.process_time()
    out = Path(task.out)
    e = task.episode
    sim_seed = simulation_seed(task.root_seed, e)
    result = EpisodeResult(e, sim_seed, task.max_slots, accepted=0, exhausted=False)
    slot, resume_after = _existing_prefix(out, e)
    result.accepted = slot
    if slot >= task.max_slots:
        return result
    crit = task.criteria
    scenario = task.scenario
    stages = {
        name: task.stages.resolve(name)
        for name in ("source", "noise_config", "apply_noise", "detection_config", "detect")
    }
    noise_cfg = stages["noise_config"](**(scenario.noise or {}))
    det_cfg = stages["detection_config"](**(scenario.detection or {}))
    used = _used_observers(out, e, slot) if crit.distinct_observers else set()
    multi = _views(scenario) != 2
    attempt, encode = (_try_set, encode_snapshot) if multi else (_try_pair, encode_record)
    # The work folder is shared by all episodes: sources cache networks there (atomically).
    with stages["source"](scenario, sim_seed, out / layout.WORK_DIR) as source:
        for snapshot in source.snapshots():
            result.snapshots += 1
            # Always asked, even when skipping, so a source's internal state evolves the same.
            candidates = (
                source.observer_sets(snapshot) if multi else source.observer_pairs(snapshot)
            )
            first, taken = 0, 0
            if resume_after is not None:  # fast-forward past what an earlier run wrote
                if snapshot.time < resume_after[0]:
                    continue
                if snapshot.time == resume_after[0]:
                    first = resume_after[1] + 1
                    taken = _taken_at(out, e, slot, snapshot.time)
                resume_after = None
            for index in range(first, len(candidates)):
                if taken >= crit.pairs_per_snapshot or slot >= task.max_slots:
                    break
                pair = candidates[index]
                if crit.distinct_observers and _observer_key(pair) in used:
                    continue
                result.candidates += 1
                record = attempt(
                    task, stages, noise_cfg, det_cfg, snapshot, pair, index, slot, result
                )
                if record is None:
                    continue
                c = time.process_time()
                if write_record(out, layout.record_name(e, slot), encode(record)):
                    result.new_records += 1
                result.write_core_seconds += time.process_time() - c
                slot += 1
                taken += 1
                used.add(_observer_key(pair))
                if on_record is not None:
                    on_record()
            if slot >= task.max_slots:
                break
        else:
            result.exhausted = True
    result.accepted = slot
    result.seconds = time.perf_counter() - t0
    result.core_seconds = time.process_time() - c0
    _write_summary(out, result)
    return result


def _write_summary(out: Path, result: EpisodeResult) -> None:
    path = out / layout.EPISODES_DIR / layout.episode_summary_name(result.episode)
    write_file_atomic(path, json_bytes(asdict(result)))


def _episode_from_frames(task: EpisodeTask, on_record=None) -> EpisodeResult | None:
    """Episode ``task.episode`` of a two-sensor scenario derived from the camera-only dataset
    ``task.frames_from`` (:mod:`cadsim.generation.frames_from`): the records a simulation would
    write are that dataset's records of the episode with each view's LiDAR added. None when
    that dataset does not settle the episode (fewer records and not exhausted there): it is
    then simulated."""
    from cadsim.generation.frames_from import lidar_added

    t0, c0 = time.perf_counter(), time.process_time()
    frames, out, e = Path(task.frames_from), Path(task.out), task.episode
    found = _episode_done_on_disk(frames, e, task.max_slots)
    if found is None:
        return None
    slots = min(found, task.max_slots)
    result = EpisodeResult(e, simulation_seed(task.root_seed, e), task.max_slots, 0, found < task.max_slots)  # fmt: skip
    on_disk, _ = _existing_prefix(out, e)
    records = layout.existing_records(frames)

    def sweep(snapshot, camera, observer, seed, view, slot):
        return _timed_lidar(task, snapshot, camera, observer, seed, slot, view, result)

    for slot in range(on_disk, slots):
        files = lidar_added(records[(e, slot)], lambda *a, slot=slot: sweep(*a, slot))
        c = time.process_time()
        if write_record(out, layout.record_name(e, slot), files):
            result.new_records += 1
        result.write_core_seconds += time.process_time() - c
        result.views += 2
        if on_record is not None:
            on_record()
    result.accepted = slots
    result.seconds = time.perf_counter() - t0
    result.core_seconds = time.process_time() - c0
    _write_summary(out, result)
    return result


# --------------------------------------------------------------------------- sequences


def _sequences_on_disk(out: Path, episode: int, remove_partial: bool = False):
    """The complete sequences of ``episode`` on disk, in slot order: a list of (first slot,
    frames, time of its last frame). A sequence is complete when its records hold frames 0 ..
    frames-1 in consecutive slots; the first one that is not (an interrupted write) ends the
    list, and with ``remove_partial`` its records and every later one of the episode are
    removed (they are rewritten, identically, by the resumed episode)."""
    records = layout.existing_records(out)
    slots = sorted(s for (e, s) in records if e == episode)
    complete, k = [], 0
    while k < len(slots) and slots[k] == k and k == (complete[-1][0] + complete[-1][1] if complete else 0):  # fmt: skip
        head = json.loads((records[(episode, k)] / layout.RECORD_JSON).read_text())
        sequence = head.get("sequence") or {}
        frames = int(sequence.get("frames", 0))
        last = k + frames - 1
        whole = (
            frames >= 1
            and sequence.get("frame") == 0
            and all((episode, s) in records for s in range(k, last + 1))
        )
        if not whole:
            break
        tail = json.loads((records[(episode, last)] / layout.RECORD_JSON).read_text())
        complete.append((k, frames, float(tail["time"])))
        k = last + 1
    if remove_partial:
        for s in slots:
            if s >= k:
                remove_record(out, layout.record_name(episode, s))
    return complete


def _sequence_source_scenario(scenario):
    """The scenario the source runs in a sequence episode: snapshots every ``interval_s``."""
    sampling = dict(scenario.sampling or {})
    sampling["interval"] = float(scenario.sequence["interval_s"])
    return dataclasses.replace(scenario, sampling=sampling)


def sequence_stride(scenario) -> int:
    """Sequence starts are tried every this many frames (``[sampling] interval`` over
    ``[sequence] interval_s``, rounded, at least 1)."""
    interval = float((scenario.sampling or {}).get("interval", 2.0))
    return max(1, round(interval / float(scenario.sequence["interval_s"])))


def _follow(source, snapshot, pair):
    """``pair``'s observers at ``snapshot`` (their cameras re-mounted), or None if one left."""
    follow = getattr(source, "follow_pair", None)
    if follow is not None:
        return follow(snapshot, pair)
    for candidate in source.observer_pairs(snapshot):
        if (candidate.observer1_id, candidate.observer2_id) == (pair.observer1_id, pair.observer2_id):  # fmt: skip
            return candidate
    return None


def run_sequence_episode(task: EpisodeTask, on_record=None) -> EpisodeResult:
    """One episode of a ``[sequence]`` scenario (docs/scenarios.md, "[sequence]"). The source
    steps every ``interval_s``; every ``sequence_stride`` frames (and after the previous
    sequence's last frame) the candidate pairs are tried as today; an accepted pair starts a
    sequence whose frames 1, 2, ... are the same two observers at the following snapshots
    (recorded whatever they see) until it has ``frames`` frames or an observer has left the
    scene. Frame k is record (episode, first slot + k); a sequence shorter than ``min_frames``
    is dropped. Every frame is kept in memory until the sequence ends, then written in order,
    so that what is on disk is whole sequences (resume: :func:`_sequences_on_disk`).
    ``task.max_slots`` and ``accepted`` count sequences."""
    t0, c0 = time.perf_counter(), time.process_time()
    out = Path(task.out)
    e = task.episode
    sim_seed = simulation_seed(task.root_seed, e)
    result = EpisodeResult(e, sim_seed, task.max_slots, accepted=0, exhausted=False)
    done = _sequences_on_disk(out, e, remove_partial=True)
    result.accepted = len(done)
    if len(done) >= task.max_slots:
        return result
    slot = done[-1][0] + done[-1][1] if done else 0
    resume_after = done[-1][2] if done else None
    crit, scenario = task.criteria, task.scenario
    seq = scenario.sequence
    frames, min_frames = int(seq["frames"]), int(seq.get("min_frames", 1))
    model = OdometryModel.from_sequence(seq)
    stride = sequence_stride(scenario)
    stages = {
        name: task.stages.resolve(name)
        for name in ("source", "noise_config", "apply_noise", "detection_config", "detect")
    }
    noise_cfg = stages["noise_config"](**(scenario.noise or {}))
    det_cfg = stages["detection_config"](**(scenario.detection or {}))
    used = _used_observers(out, e, slot) if crit.distinct_observers else set()
    active = None  # the sequence being recorded: its pair, frames, odometers
    last_frame_time = resume_after

    def finish() -> None:
        nonlocal active, slot, last_frame_time
        kept, active_now = active["frames"], active
        active = None
        last_frame_time = active_now["times"][-1]
        if len(kept) < min_frames:
            return
        first = active_now["first"]
        c = time.process_time()
        for k, rec in enumerate(kept):
            rec.sequence["frames"] = len(kept)
            if write_record(out, layout.record_name(e, first + k), encode_record(rec)):
                result.new_records += 1
        result.write_core_seconds += time.process_time() - c
        slot = first + len(kept)
        result.accepted += 1
        used.add(_observer_key(active_now["pair"]))
        if on_record is not None:
            on_record()

    def frame(rec: PairRecord, pair, k: int) -> PairRecord:
        poses = (rec.view1.pose, rec.view2.pose)
        odometry = [odo.step(p) for odo, p in zip(active["odometers"], poses, strict=True)]
        rec = dataclasses.replace(
            rec,
            sequence={
                "id": layout.record_name(e, active["first"]),
                "frame": k,
                "frames": frames,
                "interval_s": float(seq["interval_s"]),
                "start_time": active["times"][0],
                "model": model.as_record(),
                "odometry": odometry,
                "odometry_seeds": active["seeds"],
            },
        )
        active["frames"].append(rec)
        return rec

    source_scenario = _sequence_source_scenario(scenario)
    with stages["source"](source_scenario, sim_seed, out / layout.WORK_DIR) as source:
        for index, snapshot in enumerate(source.snapshots()):
            result.snapshots += 1
            if active is not None:
                k = len(active["frames"])
                pair = _follow(source, snapshot, active["pair"])
                if pair is None:
                    finish()  # an observer left the scene: the sequence ends short
                else:
                    rec = _capture_pair(
                        task, stages, noise_cfg, det_cfg, snapshot, pair, active["first"] + k,
                        result, active["meta"],
                    )  # fmt: skip
                    active["times"].append(float(snapshot.time))
                    frame(rec, pair, k)
                    if len(active["frames"]) >= frames:
                        finish()
                    if result.accepted >= task.max_slots:
                        break
                    continue
            if index % stride:
                continue
            # Always asked at a start instant, so a source's internal state evolves the same.
            candidates = source.observer_pairs(snapshot)
            if result.accepted >= task.max_slots:
                break
            if last_frame_time is not None and snapshot.time <= last_frame_time:
                continue  # inside the previous sequence, or before where an earlier run ended
            for candidate_index, pair in enumerate(candidates):
                if crit.distinct_observers and _observer_key(pair) in used:
                    continue
                result.candidates += 1
                rec = _try_pair(
                    task, stages, noise_cfg, det_cfg, snapshot, pair, candidate_index, slot,
                    result,
                )  # fmt: skip
                if rec is None:
                    continue
                seeds = tuple(odometry_seed(task.root_seed, e, slot, v) for v in (1, 2))
                active = {
                    "first": slot, "pair": pair, "frames": [], "times": [float(snapshot.time)],
                    "odometers": [Odometer(model, s, frames) for s in seeds], "seeds": seeds,
                    "meta": rec.meta,
                }  # fmt: skip
                frame(rec, pair, 0)
                if frames == 1:
                    finish()
                break
            if result.accepted >= task.max_slots:
                break
        else:
            if active is not None:
                finish()  # the simulation ended: the sequence ends short
            result.exhausted = result.accepted < task.max_slots
    result.seconds = time.perf_counter() - t0
    result.core_seconds = time.process_time() - c0
    _write_summary(out, result)
    return result


def _capture_pair(task, stages, noise_cfg, det_cfg, snapshot, pair, slot, result, meta) -> PairRecord:  # fmt: skip
    """Both views of ``pair`` at ``snapshot`` as record (episode, ``slot``), without the
    acceptance test (a sequence's later frames are recorded whatever they see)."""
    views = [
        _capture(task, stages, noise_cfg, det_cfg, snapshot, camera, observer, v, slot, result)
        for v, camera, observer in (
            (1, pair.camera1, pair.observer1_id),
            (2, pair.camera2, pair.observer2_id),
        )  # fmt: skip
    ]
    meta = dict(meta) | {"pair": dict(pair.meta), "snapshot": dict(snapshot.meta)}
    return PairRecord(
        task.episode, slot, simulation_seed(task.root_seed, task.episode), float(snapshot.time),
        list(snapshot.objects), views[0], views[1], meta,
        dict(getattr(task.scenario, "localisation", {})),
    )  # fmt: skip


def _taken_at(out: Path, episode: int, slots: int, time_s: float) -> int:
    """How many of the first ``slots`` records of ``episode`` come from the snapshot at time_s."""
    records = layout.existing_records(out)
    times = [
        json.loads((records[(episode, s)] / layout.RECORD_JSON).read_text())["time"]
        for s in range(slots)
    ]
    return sum(t == time_s for t in times)


def _capture(task, stages, noise_cfg, det_cfg, snapshot, camera, observer, view, slot, result, lidar_now=True):  # fmt: skip
    """Render, noise and detect view ``view`` (1-based; its seeds are (episode, slot, view)'s)
    of ``camera``, carried by ``observer`` ("" for none). The view's capture. ``lidar_now``
    False (sensor "both" only): the camera alone, the LiDAR added by :func:`_with_lidar` once
    the pair is accepted."""
    seed = noise_seed(task.root_seed, task.episode, slot, view)
    attr_seed = attribute_seed(task.root_seed, task.episode, slot, view)
    sensor = getattr(task.scenario, "sensor", "camera")
    lidar = None
    if sensor == "lidar" or (sensor == "both" and lidar_now):
        lidar = _timed_lidar(task, snapshot, camera, observer, seed, slot, view, result)
    if sensor == "lidar":
        result.views += 1
        return ViewCapture(
            camera, observer, None, None, None, lidar.detections, seed, attr_seed,
            _observer_pose(snapshot, camera, observer),
            localisation_seed(task.root_seed, task.episode, slot, view), lidar,
        )  # fmt: skip
    renderer = _renderer(task.stages, camera.width, camera.height)
    result.gl = getattr(renderer, "gl", None)
    t, c = time.perf_counter(), time.process_time()
    appearance = _appearance(task.scenario)
    if hasattr(renderer, "set_lighting"):  # the episode's light (the default without a table)
        if appearance is None:
            renderer.set_lighting(*renderer.default_lighting)
        else:
            light = appearance.lighting(simulation_seed(task.root_seed, task.episode))
            renderer.set_lighting(*dataclasses.astuple(light))
    rendered, det = _observe(
        stages, noise_cfg, det_cfg, renderer, snapshot, camera, observer, seed, attr_seed,
        appearance,
    )  # fmt: skip
    result.render_seconds += time.perf_counter() - t
    result.view_core_seconds += time.process_time() - c
    result.views += 1
    return ViewCapture(
        camera, observer, rendered.color, rendered.depth, rendered.instance, det, seed,
        attr_seed, _observer_pose(snapshot, camera, observer),
        localisation_seed(task.root_seed, task.episode, slot, view), lidar,
    )  # fmt: skip


def _observer_pose(snapshot, camera, observer: str) -> ObserverPose:
    """The true pose of what carries ``camera`` (``observer`` "" for none: the camera's own)."""
    carrier = snapshot.by_id().get(observer) if observer else None
    return ObserverPose.of_carrier(carrier) if carrier else ObserverPose.of_camera(camera)


def _timed_lidar(task, snapshot, camera, observer, seed, slot, view, result):
    """:func:`_lidar_observation`, its wall and core time added to ``result``'s view times."""
    t, c = time.perf_counter(), time.process_time()
    lidar = _lidar_observation(task, snapshot, camera, observer, seed, slot, view)
    result.render_seconds += time.perf_counter() - t
    result.view_core_seconds += time.process_time() - c
    return lidar


def _with_lidar(task, snapshot, views: list[ViewCapture], slot, result) -> list[ViewCapture]:
    """Camera captures of an accepted pair (sensor "both") with their LiDAR observations, drawn
    from each view's own seed (its own stream, ``cadsim.sensing.lidar.observe``): the same
    observations as sensing both at capture time, without sweeping candidates that fail."""
    sweep = [
        _timed_lidar(task, snapshot, v.camera, v.observer_id, v.noise_seed, slot, k, result)
        for k, v in enumerate(views, start=1)
    ]
    return [dataclasses.replace(v, lidar=lidar) for v, lidar in zip(views, sweep, strict=True)]


def _lidar_observation(task, snapshot, camera, observer, seed, slot, view):
    """The view's LiDAR sweep and boxes (``cadsim.sensing.lidar.observe``), seeded by the
    view's noise seed on the LiDAR's own stream."""
    from cadsim.sensing.lidar.beam_pattern import LidarConfig
    from cadsim.sensing.lidar.observe import observe

    config = LidarConfig(**(getattr(task.scenario, "lidar", None) or {}))
    tag = f"{task.episode}-{slot}-{view}"
    return observe(snapshot, camera, observer, config, seed, tag)


def _try_pair(
    task, stages, noise_cfg, det_cfg, snapshot, pair, candidate, slot, result
) -> PairRecord | None:
    """Render, noise and detect both views of a candidate; the record if it is acceptable. With
    both sensors the pair is accepted by its camera detections, so the LiDAR sweeps only the
    pairs that pass (:func:`_with_lidar`)."""
    crit = task.criteria
    later = getattr(task.scenario, "sensor", "camera") == "both"
    views = []
    for v, camera, observer in ((1, pair.camera1, pair.observer1_id), (2, pair.camera2, pair.observer2_id)):  # fmt: skip
        capture = _capture(
            task, stages, noise_cfg, det_cfg, snapshot, camera, observer, v, slot, result,
            lidar_now=not later,
        )  # fmt: skip
        if len(capture.detections) < crit.min_covisible + crit.min_exclusive:
            return None  # cannot pass, whatever the other view sees
        views.append(capture)
    if not is_acceptable_pair(
        views[0].detections, views[1].detections, crit.min_covisible, crit.min_exclusive
    ):
        return None
    if later:
        views = _with_lidar(task, snapshot, views, slot, result)
    meta = {"candidate": candidate, "pair": dict(pair.meta), "snapshot": dict(snapshot.meta)}
    return PairRecord(
        task.episode, slot, simulation_seed(task.root_seed, task.episode), float(snapshot.time),
        list(snapshot.objects), views[0], views[1], meta,
        dict(getattr(task.scenario, "localisation", {})),
    )  # fmt: skip


def _try_set(
    task, stages, noise_cfg, det_cfg, snapshot, observers, candidate, slot, result
) -> SnapshotRecord | None:
    """Render, noise and detect every view of an observer set (view k: the set's k-th camera);
    the N-view record if it meets :func:`is_acceptable_set`."""
    crit = task.criteria
    views = []
    for v, (camera, observer) in enumerate(zip(observers.cameras, observers.observer_ids, strict=True), start=1):  # fmt: skip
        capture = _capture(
            task, stages, noise_cfg, det_cfg, snapshot, camera, observer, v, slot, result
        )
        if len(capture.detections) < crit.min_covisible:
            return None  # shares too few objects with any other view, whatever they see
        views.append(capture)
    if not is_acceptable_set([v.detections for v in views], crit.min_covisible):
        return None
    meta = {"candidate": candidate, "set": dict(observers.meta), "snapshot": dict(snapshot.meta)}
    return SnapshotRecord(
        task.episode, slot, simulation_seed(task.root_seed, task.episode), float(snapshot.time),
        list(snapshot.objects), tuple(views), tuple(observers.kinds), meta,
        dict(getattr(task.scenario, "localisation", {})),
    )  # fmt: skip


def _in_simulation_thread(fn, *args):
    """Run ``fn(*args)`` on this process's one simulation thread and wait for it (so episodes
    of a multi-threaded worker run one at a time, always on the same thread)."""
    global _simulation_thread
    with _simulation_thread_lock:
        if _simulation_thread is None:
            _simulation_thread = cf.ThreadPoolExecutor(1, thread_name_prefix="cadsim-simulation")
    return _simulation_thread.submit(contextvars.copy_context().run, fn, *args).result()


def _worker_run(task: EpisodeTask) -> EpisodeResult:
    """The executor task: one episode; reports ("record", episode) after each record written."""
    if not (Path(task.out) / layout.MANIFEST).is_file():
        raise GenerationError(
            f"{task.out}: not visible on worker host {socket.gethostname()} (no {layout.MANIFEST}); "
            "the dataset folder must be on storage every worker mounts at the same path"
        )
    args = (task, lambda: report_progress(("record", task.episode)))
    if threading.current_thread() is threading.main_thread():  # a pool process, or this one
        return run_episode(*args)
    return _in_simulation_thread(run_episode, *args)


# --------------------------------------------------------------------------- orchestration


def _load_scenario(scenario):
    if isinstance(scenario, str | os.PathLike):
        from cadsim.scenario import load_scenario

        return load_scenario(scenario)
    return scenario


def _check_resume(out: Path, config: dict) -> None:
    """Refuse to mix records of another scenario/seed/configuration into ``out``. A folder that
    holds no record is free: whatever an earlier run left there (a manifest, episode summaries,
    the sources' cache; e.g. of a run that failed on a typo) is cleared for this one."""
    has_records = bool(layout.existing_records(out))
    if not (out / layout.MANIFEST).exists():
        if has_records:
            raise GenerationError(f"{out}: has frame-pair records but no manifest; use a new --out")
        return
    try:
        writes = FORMAT_VERSION if view_count(config["observers"]) == 2 else MULTI_VIEW_FORMAT
        writes = SEQUENCE_FORMAT if config.get("sequence") else writes
        previous = read_manifest(out, versions=(writes,))["generation"]
    except DatasetError as exc:
        if not has_records:
            _clear_recordless(out, f"its manifest is unusable ({exc})")
            return
        raise GenerationError(
            f"{out}: not resumable ({exc}); use a new --out (or delete it) to generate there"
        ) from exc
    differing = sorted(k for k in set(config) | set(previous) if config.get(k) != previous.get(k))
    if differing and not has_records:
        _clear_recordless(out, "an earlier run with different " + ", ".join(differing))
    elif differing:
        raise GenerationError(
            f"{out}: holds a dataset generated with different {', '.join(differing)}; "
            "use a new --out (or delete it) to generate this one"
        )


def _clear_recordless(out: Path, why: str) -> None:
    """Remove the bookkeeping of a run that wrote no record (its manifest is rewritten next)."""
    log.info("%s: holds no frame-pair record (%s); starting afresh", out, why)
    for folder in (layout.EPISODES_DIR, layout.WORK_DIR):
        shutil.rmtree(out / folder, ignore_errors=True)


def _episode_done_on_disk(
    out: Path, episode: int, need: int, sequences: bool = False
) -> int | None:
    """Records (``sequences``: sequences) episode ``episode`` already provides if no simulation
    is needed for ``need`` of them, else None."""
    if sequences:
        count = len(_sequences_on_disk(out, episode))
    else:
        count, _ = _existing_prefix(out, episode)
    if count >= need:
        return count
    path = out / layout.EPISODES_DIR / layout.episode_summary_name(episode)
    if path.is_file():
        summary = json.loads(path.read_text())
        if summary.get("exhausted") and summary.get("accepted") == count:
            return count
    return None


@dataclass(frozen=True)
class _Plan:
    """A generation request, fully validated before anything is written."""

    scenario: Any
    out: Path
    n_pairs: int
    root_seed: int
    seed_source: str
    criteria: Criteria
    config: dict
    max_episodes: int


def _plan(scenario, out, pairs, seed, workers, max_episodes) -> _Plan:
    """Validate every argument (the scenario is loaded and checked if given as a path); raise
    before the output folder is touched."""
    scenario = _load_scenario(scenario)
    n_pairs = _checked_int("--pairs", scenario.pairs if pairs is None else pairs, 1, MAX_PAIRS)
    root_seed = _checked_int("--seed", scenario.seed if seed is None else seed, 0, MAX_SEED)
    if workers is not None:
        _checked_int("--workers", workers, 1, MAX_WORKERS)
    crit = Criteria.from_sampling(scenario.sampling)
    acceptance = {k: v for k, v in asdict(crit).items() if k != "pairs_per_episode"}
    config = generation_config(scenario, root_seed, crit.pairs_per_episode, acceptance)
    traffic = scenario.traffic or {}
    if traffic.get("source") == "sumo" and traffic.get("demand") is not None:
        config["demand"] = DEMAND_MODEL  # drawn in process (cadsim.sources.sumo.demand)
    if max_episodes is None:
        max_episodes = 10 * math.ceil(n_pairs / crit.pairs_per_episode) + 10
    out = check_output_folder(out)  # new, empty or a cadsim dataset: never a user's folder
    return _Plan(
        scenario, Path(out).resolve(), n_pairs, root_seed,
        "scenario" if seed is None else "--seed", crit, config, int(max_episodes),
    )  # fmt: skip


def _checked_int(name: str, value, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise GenerationError(f"{name}: expected an integer, got {value!r}")
    if not low <= value <= high:
        raise GenerationError(f"{name}: expected an integer in {low}..{high}, got {value}")
    return int(value)


def generate_dataset(
    scenario,
    out: str | Path,
    pairs: int | None = None,
    seed: int | None = None,
    workers: int | None = None,
    stages: Stages | None = None,
    progress: bool = True,
    max_episodes: int | None = None,
    scheduler: str | None = None,
    executor: Executor | None = None,
    frames_from: str | Path | None = None,
) -> GenerationResult:
    """Generate (or resume) the dataset of ``scenario`` (a path or a loaded scenario) in ``out``.

    pairs: N (default: the scenario's). seed: root seed (default: the scenario's). workers:
    processes (default: one per core; 1: this process). scheduler: a Dask scheduler address
    (default: ``$CADSIM_SCHEDULER``, else local processes); ``out`` must then be on storage every
    worker mounts at the same path. executor: run episodes there instead (not closed here).
    max_episodes: give up after this many episodes without N pairs (default
    10·⌈N / pairs_per_episode⌉ + 10).
    frames_from: a camera-only dataset of the same frames for a two-sensor scenario: the episodes
    it holds take their camera captures from it (:mod:`cadsim.generation.frames_from`); ignored,
    with a log line, when it was generated otherwise.

    Every argument is checked before ``out`` is touched; ``out`` is then locked against a
    second writer (``cadsim.dataset.writer_lock``) until the final manifest is written.
    """
    t0 = time.perf_counter()
    plan = _plan(scenario, out, pairs, seed, workers, max_episodes)
    plan.out.mkdir(parents=True, exist_ok=True)
    with exclusive_writer(plan.out):
        return _generate(
            plan, stages or Stages(), workers, progress, scheduler, executor, t0, frames_from
        )  # fmt: skip


def _generate(
    plan: _Plan,
    stages: Stages,
    workers: int | None,
    progress: bool,
    scheduler: str | None,
    executor: Executor | None,
    t0: float,
    frames_from: str | Path | None = None,
) -> GenerationResult:
    """The generation itself, with ``plan.out`` locked."""
    scenario, out, n_pairs, root_seed = plan.scenario, plan.out, plan.n_pairs, plan.root_seed
    crit, config, seed_source, max_episodes = (
        plan.criteria, plan.config, plan.seed_source, plan.max_episodes,
    )  # fmt: skip
    _check_resume(out, config)
    sequential = bool(getattr(scenario, "sequence", None))
    frames = None if sequential or _views(scenario) != 2 else usable_frames(frames_from, config)
    stale = remove_stale_temp(out)
    if stale:
        log.info("removed %d unfinished record(s) of an interrupted run", len(stale))
    earlier_gl = _earlier_gl(out)  # the drivers that drew the records of a finished earlier run
    if frames is not None:  # the drivers that drew the frames' images
        earlier_gl = gl_drivers(_earlier_gl(Path(frames)), earlier_gl)
    started = build_manifest(scenario, config, seed_source, [], {}, complete=False)
    write_manifest(out, started | ({"gl": earlier_gl} if earlier_gl else {}))

    from tqdm import tqdm

    bar = tqdm(total=n_pairs, unit="pair", desc="generate", disable=not progress or None)
    done: dict[int, EpisodeResult | int] = {}  # episode -> result, or records found on disk
    results: list[EpisodeResult] = []

    def accepted(e: int) -> int:
        d = done[e]
        return d.accepted if isinstance(d, EpisodeResult) else d

    def bump(k: int = 1) -> None:
        bar.update(max(0, min(k, n_pairs - bar.n)))

    own_executor = executor is None
    if executor is None:
        executor = make_executor(workers, scheduler)
    workers = executor.workers
    in_flight: dict[Future, tuple[int, int]] = {}
    next_episode = 0
    previous_sigterm = signal.getsignal(signal.SIGTERM)
    if previous_sigterm in (signal.SIG_DFL, None):
        signal.signal(signal.SIGTERM, _raise_interrupt)
    try:
        while True:
            prefix_total, e = 0, 0
            while e in done:
                prefix_total += accepted(e)
                e += 1
            if prefix_total >= n_pairs:
                break
            while len(in_flight) < workers and next_episode < max_episodes:
                before = range(next_episode)
                known = sum(accepted(i) for i in before if i in done)
                optimistic = known + sum(m for i, m in in_flight.values() if i < next_episode)
                if optimistic >= n_pairs:
                    break
                need = min(crit.pairs_per_episode, n_pairs - known)
                on_disk = _episode_done_on_disk(out, next_episode, need, sequential)
                if on_disk is not None:
                    done[next_episode] = on_disk
                    bump(min(on_disk, need))
                else:
                    task = EpisodeTask(
                        scenario, str(out), root_seed, next_episode, need, crit, stages, frames
                    )
                    future = executor.submit(_worker_run, task, resources={"simulation": 1})
                    in_flight[future] = (next_episode, need)
                next_episode += 1
            if not in_flight:
                if next_episode >= max_episodes:
                    raise GenerationError(
                        f"{scenario.path}: only {prefix_total} of {n_pairs} acceptable pairs in "
                        f"{max_episodes} episodes (each needs >= {crit.min_covisible} covisible "
                        f"and >= {crit.min_exclusive} non-covisible objects per view); "
                        "check the scenario's traffic and observer settings"
                    )
                continue
            finished, _ = wait(list(in_flight), timeout=0.2, return_when=FIRST_COMPLETED)
            bump(sum(1 for message in executor.progress() if message[0] == "record"))
            for fut in finished:
                e_done, _ = in_flight.pop(fut)
                res = fut.result()
                done[e_done] = res
                results.append(res)
                bump(res.accepted - res.new_records)
        # Nothing is in flight here: an episode starts only if the ones before it cannot fill N.
        if own_executor:
            executor.close()
    except BaseException:
        for future in in_flight:
            future.cancel()
        if own_executor:
            executor.terminate()  # running episodes' partial records: removed on resume
        raise
    finally:
        signal.signal(signal.SIGTERM, previous_sigterm)
        bar.close()
        release_renderers()  # those episodes run in this process made (one worker)

    files = layout.record_files(_views(scenario), getattr(scenario, "sensor", "camera"))
    records = _finalise_records(out, n_pairs, files, sequential)
    shutil.rmtree(out / layout.WORK_DIR, ignore_errors=True)
    # The episodes that define the dataset: 0 .. the last one contributing a record.
    episodes = {e: simulation_seed(root_seed, e) for e in range(records[-1]["episode"] + 1)}
    manifest = build_manifest(scenario, config, seed_source, records, episodes, complete=True)
    drivers = gl_drivers([r.gl for r in results if r.new_records], earlier_gl)
    if drivers:  # the GL drivers that drew the records (none for a LiDAR-only dataset)
        manifest["gl"] = drivers
    write_manifest(out, manifest)
    res = GenerationResult(
        out=out,
        pairs=len(records),
        checksum=manifest["checksum"],
        episodes=len(results),
        new_records=sum(r.new_records for r in results),
        views=sum(r.views for r in results),
        candidates=sum(r.candidates for r in results),
        seconds=time.perf_counter() - t0,
        render_seconds=sum(r.render_seconds for r in results),
        episode_results=sorted(results, key=lambda r: r.episode),
    )
    if res.new_records == res.pairs:  # every record written and checksummed just now
        from cadsim.dataset import Dataset

        Dataset(out).mark_verified()
    log.debug(  # the caller reports the result (the CLI prints it once)
        "%s: %d pairs (%d new) from %d episode(s) in %.1f s; checksum %s",
        out, res.pairs, res.new_records, res.episodes, res.seconds, res.checksum[:12],
    )  # fmt: skip
    return res


def _raise_interrupt(signum, frame) -> None:
    raise KeyboardInterrupt(f"signal {signum}")


def _finalise_records(
    out: Path, n_pairs: int, files: tuple[str, ...], sequences: bool = False
) -> list[dict]:
    """The first ``n_pairs`` records (``sequences``: the records of the first ``n_pairs``
    sequences) in (episode, slot) order, with checksums. Records beyond them (an episode asked
    for more pairs than turned out to be missing, or an earlier run with a larger N) are
    removed so that the folder holds exactly the dataset."""
    on_disk = layout.existing_records(out)
    if sequences:
        frames_of = {}  # (episode, first slot) -> frames, in dataset order
        for episode in sorted({e for e, _ in on_disk}):
            for first, frames, _ in _sequences_on_disk(out, episode):
                frames_of[(episode, first)] = frames
        chosen = list(frames_of.items())[:n_pairs]
        if len(chosen) < n_pairs:
            raise GenerationError(f"{out}: expected {n_pairs} sequences on disk, found {len(chosen)}")  # fmt: skip
        keep = [(e, first + k) for (e, first), n in chosen for k in range(n)]
        n_pairs = len(keep)
    else:
        keep = list(on_disk)[:n_pairs]
    if len(keep) < n_pairs:
        raise GenerationError(f"{out}: expected {n_pairs} records on disk, found {len(keep)}")
    kept = set(keep)
    for ident in on_disk:
        if ident not in kept:
            remove_record(out, layout.record_name(*ident))
    entries = []
    for episode, slot in keep:
        path = on_disk[(episode, slot)]
        record = json.loads((path / layout.RECORD_JSON).read_text())
        entry = {
            "name": path.name,
            "episode": episode,
            "slot": slot,
            "sim_seed": int(record["sim_seed"]),
            "checksum": record_dir_checksum(path, files),
        }
        if sequences:
            entry |= {"sequence": record["sequence"]["id"], "frame": record["sequence"]["frame"]}
        entries.append(entry)
    return entries
