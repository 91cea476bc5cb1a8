"""The temporal table (issue 41, ``results/table_temporal.{md,csv}``): matchers that accumulate
evidence over a window of frames, on the sequences of ``cad-v2x-seq``, under three localisation
presets.

Protocol. Each sequence (10 frames, 0.2 s apart, of the same two vehicles) becomes a
:class:`~matchers.core.sequence_problem.SequenceProblem`: its odometry drift redrawn for the run
(:func:`cadsim.dataset.sequence_odometry.redraw_odometry`), every frame's pair redrawn under the
preset (``pair.localise_preset(preset, seed=run)``) and its ``.problem()``; each agent's own
tracks from its own detections and odometry (:func:`matchers.tracking.own_tracks.with_own_tracks`,
never a true id); odometry and camera mounts from the pairs. Methods (:data:`METHODS`):
``windowed:<m>`` for the two-view matchers ``consistency`` and ``pose_refine`` at W in
{1, 3, 10} and ``temporal_pose`` at W in {1, 10}. A method that reads the localisation prior
cannot run under ``denied`` (:mod:`eval.core.abstention`, from its ``requires``): it is not
run nor tuned, its rows are kept with no number (empty CSV cells,
:data:`~eval.core.abstention.NO_NUMBER` in Markdown), and it is in no "best" and no
comparison.

Tuning (the equal budget of the two-view tables, :mod:`eval.protocol.tuning`). Per (method, W,
preset) every configuration of the method's grid
(:func:`matchers.core.temporal_registry.temporal_search_space`: 8 each, the defaults among
them; W is the table's axis, never tuned) runs on the validation split (scenario seed + 1000,
run seed 0) with ``threshold=None`` (its whole Hungarian assignment); each gets its τ by the
two-view rule (:func:`eval.protocol.calibration.calibrate_ranked`: the τ maximising the mean
per-frame F1, in the middle of the best interval) and is scored by that validation F1; the best
wins (:func:`eval.protocol.tuning.best_candidate`, exact ties to the smallest parameters JSON).
The chosen parameters (``params``) and τ go to the table and ``temporal/tuning.csv`` (every
candidate). The test split never enters the choice or τ.

Metrics. Headline: pooled F1 (``f1_pooled``: 2 ΣTP / (Σ|M| + Σ|G|) over every frame of every
test sequence, :func:`eval.protocol.pooled_bootstrap.pooled_f1`; its interval an episode-level
bootstrap, :mod:`eval.protocol.pooled_bootstrap`) — many frames of a sequence have no true pair,
where the per-frame convention gives F1 1 to declaring nothing. Secondary, per frame: F1 of the
declared pairs at τ against ``pair.gt_pairs`` (``f1_mean``);
success@(1 m, 2°) of the planar fit of those pairs (:func:`eval.core.pose_metrics.
matched_planar_error`, extrinsics ``pair.camera_extrinsics``, truth
``pair.true_relative_pose()``); the ``oracle`` row is the same fit of the true pairs. Over time
(:mod:`eval.protocol.temporal_metrics`): partner changes and the cross-agent links' CLEAR-MOT
IDSW per 100 covisible object-frames,
mean frames to the first correct association (objects never matched counted apart), HOTA and
AssA of the declared pairs named by their own track ids (mean over sequences). Intervals are
episode-level cluster t-intervals (:func:`eval.protocol.cluster_interval.t_interval`; a
sequence's episode is its simulation episode), on the per-frame values.

What accumulation buys (``table_temporal_gain.csv``): per preset, the method with the best
validation F1 at W = 10 (among those that can run there), its test pooled F1 at W = 10 minus at
W = 1 with its paired episode-level bootstrap interval (headline), and the same for the mean
per-frame F1 (paired per frame, cluster t-interval). Goals (issue 41) go through :func:`eval.protocol.goal_verdict.goal_line`.
"""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from eval.core.abstention import NO_NUMBER, cannot_run
from eval.core.pose_metrics import matched_planar_error
from eval.core.result_files import write_csv, write_text
from eval.core.tasks import MatcherSpec
from eval.protocol import pooled_bootstrap
from eval.protocol.calibration import calibrate_ranked
from eval.protocol.cluster_interval import t_interval
from eval.protocol.goal_verdict import goal_line
from eval.protocol.metrics import RankedAssignments, pair_metrics
from eval.protocol.temporal_metrics import (
    SPEED_BANDS,
    combine_sequences,
    correspondence_hota,
    cross_agent_idsw,
    frames_to_first_correct,
    partner_changes,
    track_continuity,
)
from eval.protocol.tuning import (
    Candidate,
    TuningChoice,
    best_candidate,
    check_budget,
    params_json,
    tuning_rows,
)
from matchers.core.search_spaces import TUNING_BUDGET

log = logging.getLogger(__name__)

LABEL = "CAD-V2X-Seq"
SCENARIO = "scenarios/cad-v2x-seq.toml"
TEST_SEQUENCES = 40
VAL_SEQUENCES = 20
PRESETS = ("gnss-open-sky", "gnss-urban", "denied")
METHODS: tuple[tuple[str, tuple[int, ...]], ...] = (
    ("windowed:consistency", (1, 3, 10)),
    ("windowed:pose_refine", (1, 3, 10)),
    ("temporal_pose", (1, 10)),
    ("trajectory_pose", (1, 10)),
)
RUNS = (0,)
ORACLE_ROW = "oracle"
SUCCESS_BOUNDS = (1.0, 2.0)  # metres, degrees
LONG = 10
SHORT = 1
COLUMNS = (
    "method",
    "window",
    "preset",
    "tau",
    "val_f1",
    "params",
    "f1_pooled",
    "f1_pooled_low",
    "f1_pooled_high",
    "f1_mean",
    "f1_low",
    "f1_high",
    "success_1m_2deg",
    "success_low",
    "success_high",
    "share_of_oracle",
    "partner_changes_per_100",
    "partner_changes_low",
    "partner_changes_high",
    "idsw_per_100",
    "frames_to_first",
    "never_matched",
    "hota",
    "deta",
    "assa",
    "oracle_hota",
    "oracle_assa",
    "assa_share_of_oracle",
    "frames",
    "sequences",
    "episodes",
    "ms_per_frame",
)
GAIN_COLUMNS = (
    "preset",
    "method",
    "parameters",
    "f1_pooled_w10",
    "f1_pooled_w1",
    "pooled_diff",
    "pooled_low",
    "pooled_high",
    "f1_w10",
    "f1_w1",
    "diff",
    "ci_low",
    "ci_high",
    "episodes",
)
COUNT_COLUMNS = ("never_matched", "frames", "sequences", "episodes")  # integers, or no number
TABLE, GAIN = "table_temporal", "table_temporal_gain"
TUNING_FILE = "temporal/tuning.csv"
CONTINUITY_FILE = "temporal/continuity.csv"
LIDAR_TABLE, LIDAR_LABEL = "table_temporal_lidar", "CAD-V2X-Seq-LiDAR"
LIDAR_SCENARIO = "scenarios/cad-v2x-seq-lidar.toml"


def folder_of(name: str) -> str:
    """The folder of table ``name``'s side files: ``temporal`` for the camera table,
    ``temporal_lidar`` for ``table_temporal_lidar``."""
    return "temporal" if name == TABLE else name.removeprefix("table_")


CONTINUITY_COLUMNS = (
    "preset", "band", "low_m_s", "high_m_s", "kept", "links", "continuity",
    "continuity_low", "continuity_high",
)  # fmt: skip
TUNING_COLUMNS = ("preset", "window", "matcher", "config", "params", "val_f1", "tau", "chosen")


@dataclass
class Sequenced:
    """One sequence under one preset and run: the problem, the truth per frame, the frames."""

    seq: object  # SequenceProblem
    true1: list[np.ndarray]
    true2: list[np.ndarray]
    gt: list[np.ndarray]
    extrinsics: list[np.ndarray | None]
    truth: list[np.ndarray | None]
    episode: int
    sequence: int
    speed1: list[np.ndarray] | None = None  # per frame, true speed (m/s) per detection; NaN clutter
    speed2: list[np.ndarray] | None = None


def _true_speeds(pair, object_ids: Sequence[str]) -> np.ndarray:
    """The true ground speed (m/s) of each detection's object (NaN: clutter): metrics only."""
    by_id = {
        str(o.id): float(np.hypot(*np.asarray(o.velocity, dtype=float)[:2])) for o in pair.objects
    }
    return np.array([by_id.get(str(oid), np.nan) for oid in object_ids], dtype=float)


def abstains(method: str, preset: str) -> bool:
    """Whether temporal method ``method`` cannot run under ``preset`` (it requires the prior and
    the preset gives none, :func:`eval.core.abstention.cannot_run`)."""
    return cannot_run(method, preset, temporal=True)


def _true_ids(object_ids: Sequence[str], names: dict[str, int]) -> np.ndarray:
    """Integer true id per detection (-1: clutter), consistent over one sequence via ``names``."""
    out = []
    for oid in object_ids:
        if str(oid).startswith("clutter:"):
            out.append(-1)
        else:
            out.append(names.setdefault(str(oid), len(names)))
    return np.array(out, dtype=np.int64)


def sequence_problem(frames, preset: str, seed: int, index: int = 0) -> Sequenced:
    """The :class:`Sequenced` of one sequence's ``frames`` (FramePairs in time order) under
    ``preset``, localisation drawn with ``seed``; own tracks from :func:`with_own_tracks`."""
    from matchers.tracking.own_tracks import tracked_sequence

    pairs = [f.localise_preset(preset, seed=seed) for f in frames]
    problems = [p.problem() for p in pairs]
    odometry = [p.odometry for p in pairs]
    odo = [
        np.array([[o[v].x, o[v].y, o[v].yaw] if o else [0.0, 0.0, 0.0] for o in odometry])
        for v in (0, 1)
    ]
    extrinsics = [p.camera_extrinsics for p in pairs]
    mounts = (None, None)
    if extrinsics[0] is not None and all(
        f.points1.shape[1] == 3 and f.points2.shape[1] == 3 for f in problems
    ):
        mounts = (np.asarray(extrinsics[0][0]), np.asarray(extrinsics[0][1]))
    times = np.array([float(f.time) for f in frames])
    meta = {"interval_s": round(float(np.median(np.diff(times))), 6)} if len(times) > 1 else {}
    seq = tracked_sequence(problems, odo[0], odo[1], *mounts, meta=meta)  # own tracks
    names: dict[str, int] = {}
    true1 = [_true_ids(p.view1.object_ids, names) for p in pairs]
    true2 = [_true_ids(p.view2.object_ids, names) for p in pairs]
    return Sequenced(
        seq,
        true1,
        true2,
        [np.asarray(p.gt_pairs, dtype=np.int64).reshape(-1, 2) for p in pairs],
        [None if e is None else np.stack([np.asarray(e[0]), np.asarray(e[1])]) for e in extrinsics],
        [p.true_relative_pose() for p in pairs],
        int(frames[0].episode),
        index,
        [_true_speeds(p, p.view1.object_ids) for p in pairs],
        [_true_speeds(p, p.view2.object_ids) for p in pairs],
    )


def load_split(folder: Path, preset: str, seeds: Sequence[int]) -> list[tuple[int, Sequenced]]:
    """(run seed, :class:`Sequenced`) for every sequence of the dataset at ``folder``: per run
    seed its odometry redrawn (:func:`cadsim.dataset.sequence_odometry.redraw_odometry`) and its
    prior redrawn under ``preset``, so the splits share no noise."""
    from cadsim.dataset import Dataset
    from cadsim.dataset.sequence_odometry import redraw_odometry

    ds = Dataset(str(folder))
    return [
        (seed, sequence_problem(redraw_odometry(ds.sequence(k), seed), preset, seed, k))
        for seed in seeds
        for k in range(ds.sequences)
    ]


def run_method(
    method: str,
    window: int,
    item: Sequenced,
    seed: int,
    preset: str,
    options: dict | None = None,
):
    """Per frame (assigned (k, 2), assigned scores (k,)) of ``method`` at ``window`` with its
    ``options`` (None: defaults) and no threshold; nothing declared where it cannot run (a prior
    reader under ``denied``, :func:`abstains`). Plus the seconds it took."""
    return run_windows(method, (window,), item, seed, preset, options)[window]


def run_windows(
    method: str,
    windows: Sequence[int],
    item: Sequenced,
    seed: int,
    preset: str,
    options: dict | None = None,
) -> dict[int, tuple[list, float]]:
    """{W: :func:`run_method`'s (frames, seconds)} for every W of ``windows``: one call of the
    method's ``over_windows`` where it has one (``windowed:<m>``: the base matcher run once for
    every W; seconds then shared out evenly), else one call per W."""
    from matchers.core.temporal_registry import get_temporal

    empty = [(np.zeros((0, 2), np.int64), np.zeros(0)) for _ in item.seq.frames]
    if abstains(method, preset):
        return {w: (empty, 0.0) for w in windows}
    fn = get_temporal(method)
    options = dict(options or {})
    many = getattr(fn, "over_windows", None)
    if many is not None and len(windows) > 1:
        started = time.perf_counter()
        outs = many(item.seq, list(windows), seed=seed, threshold=None, **options)
        seconds = (time.perf_counter() - started) / len(windows)
        return {w: (_assigned(outs[w]), seconds) for w in windows}
    found = {}
    for w in windows:
        started = time.perf_counter()
        out = fn(item.seq, seed=seed, threshold=None, window=w, **options)
        found[w] = (_assigned(out), time.perf_counter() - started)
    return found


def _assigned(matchings) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per frame (assigned pairs (k, 2), their canonical scores (k,))."""
    from matchers.core.discretise import canonical_scores

    frames = []
    for m in matchings:
        pairs = np.asarray(m.pairs, dtype=np.int64).reshape(-1, 2)
        # canonical (grid) scores, as the two-view runner uses: τ sees the same values on every CPU
        scores = canonical_scores(np.asarray(m.scores, dtype=float))
        frames.append((pairs, scores[pairs[:, 0], pairs[:, 1]] if len(pairs) else np.zeros(0)))
    return frames


def calibrate_tau(outcomes: list[tuple[Sequenced, list]]) -> tuple[float, float]:
    """(τ, mean validation F1) of one (method, W, preset) from its validation outcomes."""
    rows = [
        (pairs, scores, item.gt[t], item.seq.frames[t].n1, item.seq.frames[t].n2)
        for item, frames in outcomes
        for t, (pairs, scores) in enumerate(frames)
    ]
    tau, f1, _, _ = calibrate_ranked(RankedAssignments.from_frames(rows))
    return tau, f1


def tune_method(
    method: str,
    window: int,
    val: list[tuple[int, Sequenced]],
    preset: str,
    tune: bool = True,
) -> TuningChoice:
    """Every configuration of ``method``'s grid (only its defaults when ``tune`` is False or a
    prior reader under ``denied``) at ``window`` on the validation items ``val``: each with its
    own τ and validation F1 (:func:`calibrate_tau`), the best chosen
    (:func:`eval.protocol.tuning.best_candidate`)."""
    return tune_windows(method, (window,), val, preset, tune)[window]


def tune_windows(
    method: str,
    windows: Sequence[int],
    val: list[tuple[int, Sequenced]],
    preset: str,
    tune: bool = True,
) -> dict[int, TuningChoice]:
    """{W: :func:`tune_method`'s choice at W} for every W of ``windows``, each configuration
    run once for all of them (:func:`run_windows`); every W chooses on its own."""
    from matchers.core.temporal_registry import temporal_search_space

    declares_nothing = abstains(method, preset)
    configs = temporal_search_space(method) if tune and not declares_nothing else [{}]
    if len(configs) > 1:
        check_budget(method, len(configs))
    candidates: dict[int, list[Candidate]] = {w: [] for w in windows}
    for config in configs:
        runs = [
            (item, run_windows(method, windows, item, seed, preset, config)) for seed, item in val
        ]
        for w in windows:
            tau, val_f1 = calibrate_tau([(item, found[w][0]) for item, found in runs])
            if declares_nothing:
                tau = float("nan")  # declares nothing: no τ to calibrate
            spec = MatcherSpec.of(method, **config)
            candidates[w].append(Candidate(spec, dict(config), val_f1, tau))
    return {
        w: TuningChoice(f"{LABEL} {preset} W={w}", method, tuple(c), best_candidate(c))
        for w, c in candidates.items()
    }


def _pose_success(item: Sequenced, t: int, pairs: np.ndarray) -> float:
    ext, truth = item.extrinsics[t], item.truth[t]
    if ext is None or truth is None:
        return float("nan")
    if len(pairs) < 2:
        return 0.0
    frame = item.seq.frames[t]
    rte, rre = matched_planar_error(frame.points1, frame.points2, pairs, ext, truth)
    if not (np.isfinite(rte) and np.isfinite(rre)):
        return 0.0
    return float(rte <= SUCCESS_BOUNDS[0] and rre <= SUCCESS_BOUNDS[1])


def score_test(item: Sequenced, frames: list, tau: float, seed: int) -> tuple[list[dict], dict]:
    """Per-frame rows and the sequence's temporal metrics of one method's test outcome at τ."""
    declared = [pairs[scores >= tau] for pairs, scores in frames]
    rows = []
    for t, pairs in enumerate(declared):
        f = item.seq.frames[t]
        rows.append(
            {
                "seed": seed,
                "sequence": item.sequence,
                "episode": item.episode,
                "frame": t,
                **_frame_counts(pair_metrics(pairs, item.gt[t], f.n1, f.n2)),
                "success": _pose_success(item, t, pairs),
            }
        )
    switches = partner_changes(declared, item.true1, item.true2)
    idsw = cross_agent_idsw(declared, item.true1, item.true2, item.seq.tracks1, item.seq.tracks2)
    first = frames_to_first_correct(declared, item.true1, item.true2)
    h = correspondence_hota(
        declared, item.true1, item.true2, item.seq.tracks1, item.seq.tracks2, arrays=True
    )
    temporal = {
        "seed": seed,
        "sequence": item.sequence,
        "episode": item.episode,
        "switches": switches["switches"],
        "object_frames": switches["object_frames"],
        "first": [v for v in first["per_object"].values() if v is not None],
        "never": first["never"],
        "objects": len(first["per_object"]),
        "idsw": idsw["idsw"],
        "hota": h,
    }
    return rows, temporal


def _frame_counts(metrics) -> dict:
    """A frame's per-frame F1 and the counts pooled F1 sums: true positives, declared pairs,
    true pairs."""
    return {"f1": metrics.f1, "tp": metrics.tp, "n_pred": metrics.n_pred, "n_gt": metrics.n_gt}


def _pooled_sums(per_frame: pd.DataFrame) -> pooled_bootstrap.Sums:
    """Per-frame counts summed per episode and run (one group) for the pooled bootstrap."""
    counts = per_frame.rename(
        columns={"tp": "true_positives", "n_pred": "declared", "n_gt": "true_pairs"}
    ).assign(_all=0)
    return pooled_bootstrap.group_sums(counts, ["_all"], pooled_bootstrap.F1_COUNTS)


def pooled_f1(per_frame: pd.DataFrame) -> tuple[float, float, float]:
    """(pooled F1, low, high): 2 ΣTP / (Σ|M| + Σ|G|) over every frame of ``per_frame`` (its
    ``tp``, ``n_pred``, ``n_gt`` columns, all runs together) with its 95 % episode-level
    bootstrap interval (NaN with one episode)."""
    if not len(per_frame):
        return (float("nan"),) * 3
    sums = _pooled_sums(per_frame)
    point = float(pooled_bootstrap.f1_of(sums)[0])
    if not pooled_bootstrap.resamplable(sums):
        return point, float("nan"), float("nan")
    resampled = pooled_bootstrap.f1_of(sums, pooled_bootstrap.weights_for(sums))
    low, high = pooled_bootstrap.interval(resampled)
    return point, float(low[0]), float(high[0])


def _interval(values, episodes, bounds=(0.0, 1.0)) -> tuple[float, float, float, int]:
    values = np.asarray(values, dtype=float)
    episodes = np.asarray(episodes)
    keep = np.isfinite(values)
    if not keep.any():
        return float("nan"), float("nan"), float("nan"), 0
    return t_interval(values[keep], episodes[keep], bounds=bounds)


def _switch_interval(temporal: list[dict]) -> tuple[float, float, float]:
    """Switches per object-frame with its episode-level interval: each covisible object-frame an
    item (1 where a switch was counted), clustered by episode."""
    values, episodes = [], []
    for s in temporal:
        n = max(s["object_frames"], s["switches"])
        values += [1.0] * s["switches"] + [0.0] * (n - s["switches"])
        episodes += [s["episode"]] * n
    if not values:
        return float("nan"), float("nan"), float("nan")
    mean, low, high, _ = t_interval(np.array(values), np.array(episodes), bounds=(0.0, 1.0))
    return mean, low, high


def summarise(per_frame: pd.DataFrame, temporal: list[dict]) -> dict:
    """One table row's metric columns from a method's per-frame rows and sequence metrics."""
    f1, f1_low, f1_high, episodes = _interval(per_frame["f1"], per_frame["episode"])
    pooled, pooled_low, pooled_high = pooled_f1(per_frame)
    success, s_low, s_high, _ = _interval(per_frame["success"], per_frame["episode"])
    sw, sw_low, sw_high = _switch_interval(temporal)
    first = [v for s in temporal for v in s["first"]]
    combined = combine_sequences([s["hota"] for s in temporal])
    object_frames = sum(s["object_frames"] for s in temporal)
    idsw = sum(s["idsw"] for s in temporal)
    return {
        "f1_pooled": pooled,
        "f1_pooled_low": pooled_low,
        "f1_pooled_high": pooled_high,
        "f1_mean": f1,
        "f1_low": f1_low,
        "f1_high": f1_high,
        "success_1m_2deg": success,
        "success_low": s_low,
        "success_high": s_high,
        "partner_changes_per_100": 100 * sw,
        "partner_changes_low": 100 * sw_low,
        "partner_changes_high": 100 * sw_high,
        "idsw_per_100": 100 * idsw / object_frames if object_frames else float("nan"),
        "frames_to_first": float(np.mean(first)) if first else float("nan"),
        "never_matched": int(sum(s["never"] for s in temporal)),
        "hota": combined["HOTA"],
        "deta": combined["DetA"],
        "assa": combined["AssA"],
        "frames": len(per_frame),
        "sequences": len({(s["seed"], s["sequence"]) for s in temporal}),
        "episodes": episodes,
    }


def continuity_rows(items: list[tuple[int, Sequenced]], preset: str) -> list[dict]:
    """The own tracker's continuity per speed band over ``items`` (both views, every run):
    :func:`~eval.protocol.temporal_metrics.track_continuity` summed, ``continuity`` = kept /
    links (NaN without a link) with its episode-level t-interval (each link an item, 1 when
    kept, clustered by episode)."""
    values: dict[str, list[float]] = {name: [] for name, _, _ in SPEED_BANDS}
    episodes: dict[str, list[int]] = {name: [] for name, _, _ in SPEED_BANDS}
    for _, item in items:
        if item.speed1 is None:
            continue
        for tracks, true, speeds in (
            (item.seq.tracks1, item.true1, item.speed1),
            (item.seq.tracks2, item.true2, item.speed2),
        ):
            for name, (kept, links) in track_continuity(tracks, true, speeds).items():
                values[name] += [1.0] * kept + [0.0] * (links - kept)
                episodes[name] += [item.episode] * links
    rows = []
    for name, low, high in SPEED_BANDS:
        kept, links = int(sum(values[name])), len(values[name])
        share, c_low, c_high = np.nan, np.nan, np.nan
        if links:
            share, c_low, c_high, _ = t_interval(
                np.array(values[name]), np.array(episodes[name]), bounds=(0.0, 1.0)
            )
        rows.append(
            {
                "preset": preset,
                "band": name,
                "low_m_s": low,
                "high_m_s": high,
                "kept": kept,
                "links": links,
                "continuity": share,
                "continuity_low": c_low,
                "continuity_high": c_high,
            }  # fmt: skip
        )
    return rows


def _oracle(items: list[tuple[int, Sequenced]], preset: str) -> tuple[dict, pd.DataFrame]:
    rows, temporal = [], []
    for seed, item in items:
        frames = [(gt, np.ones(len(gt))) for gt in item.gt]
        r, s = score_test(item, frames, 0.5, seed)
        rows += r
        temporal.append(s)
    per_frame = pd.DataFrame(rows)
    row = {"method": ORACLE_ROW, "window": 0, "preset": preset, "tau": np.nan, "val_f1": np.nan}
    row["params"] = ""
    return row | summarise(per_frame, temporal) | {"ms_per_frame": np.nan}, per_frame


@dataclass
class PresetOutcome:
    """One preset's part of the study: its table rows (the oracle's last), its gain rows (none
    without a W = 10 / W = 1 pair), its per-frame tables and its tuning candidates."""

    rows: list[dict]
    gain: list[dict]
    per_frame: list[pd.DataFrame]
    tuned: list[dict]
    continuity: list[dict]


def evaluate_preset(task: tuple) -> PresetOutcome:
    """The study under one preset: ``task`` = (test folder, validation folder, preset, methods,
    run seeds, tune). Module-level and picklable: one task of the executor per preset."""
    test_dir, val_dir, preset, methods, seeds, tune = task
    test = load_split(Path(test_dir), preset, seeds)
    val = load_split(Path(val_dir), preset, seeds)
    oracle_row, oracle_frames = _oracle(test, preset)
    continuity = continuity_rows(test, preset)
    rows, tuned = [], []
    per_frame_all = [oracle_frames.assign(method=ORACLE_ROW, window=0, preset=preset)]
    frames_by: dict[tuple[str, int], pd.DataFrame] = {}
    for method, windows in methods:
        if abstains(method, preset):  # no number: not run, not tuned, in no comparison
            rows += [
                {"method": method, "window": w, "preset": preset, "params": ""} for w in windows
            ]
            log.info("[temporal] %s %s: %s", preset, method, NO_NUMBER)
            continue
        choices = tune_windows(method, windows, val, preset, tune)
        for window in windows:
            choice = choices[window]
            chosen = choice.candidates[choice.chosen]
            tau, val_f1, options = chosen.tau, chosen.val_f1, choice.params
            tuned += [r | {"preset": preset, "window": window} for r in tuning_rows([choice])]
            per_frame, temporal, seconds = [], [], 0.0
            for seed, item in test:
                frames, took = run_method(method, window, item, seed, preset, options)
                seconds += took
                r, s = score_test(item, frames, tau, seed)
                per_frame += r
                temporal.append(s)
            table = pd.DataFrame(per_frame)
            frames_by[(method, window)] = table
            per_frame_all.append(table.assign(method=method, window=window, preset=preset))
            row = {"method": method, "window": window, "preset": preset}
            row |= {"tau": tau, "val_f1": val_f1, "params": params_json(options)}
            row |= summarise(table, temporal)
            row["ms_per_frame"] = 1000 * seconds / max(len(table), 1)
            rows.append(row)
            if window == LONG and SHORT in windows:  # W = 1 at W = 10's parameters and τ
                fixed = []
                for seed, item in test:
                    frames, _ = run_method(method, SHORT, item, seed, preset, options)
                    fixed += score_test(item, frames, tau, seed)[0]
                frames_by[(method, "fixed")] = pd.DataFrame(fixed)
            log.info(
                "[temporal] %s %s W=%d %s: τ %.3f, val F1 %.3f, test F1 %.3f",
                preset,
                method,
                window,
                row["params"],
                tau,
                val_f1,
                row["f1_mean"],
            )
    rows.append(oracle_row)
    return PresetOutcome(rows, _gains(preset, rows, frames_by), per_frame_all, tuned, continuity)


def evaluate_temporal(
    test_dir: Path,
    val_dir: Path,
    out: Path,
    methods: Sequence[tuple[str, Sequence[int]]] = METHODS,
    presets: Sequence[str] = PRESETS,
    seeds: Sequence[int] = RUNS,
    tune: bool = True,
    executor=None,
    name: str = TABLE,
    label: str = LABEL,
) -> pd.DataFrame:
    """Run the study (module docstring) and write ``out/table_temporal.{md,csv}``,
    ``out/table_temporal_gain.csv``, the per-frame scores ``out/temporal/per_frame.csv`` and
    every tuning candidate ``out/temporal/tuning.csv`` (``tune=False``: defaults only, no
    candidates). One :func:`evaluate_preset` task per preset on ``executor``
    (:class:`eval.core.executor.Executor`; None or one worker: in this process, in order);
    the outputs are assembled in preset order, whatever the completion order. ``name`` /
    ``label``: the files' stem and the caption's dataset (:func:`evaluate_temporal_lidar`: the
    LiDAR table, side files under :func:`folder_of`). Returns the table."""
    out = Path(out)
    methods = tuple((m, tuple(int(w) for w in ws)) for m, ws in methods)
    tasks = [(str(test_dir), str(val_dir), p, methods, tuple(seeds), bool(tune)) for p in presets]
    if executor is None or getattr(executor, "workers", 1) <= 1 or len(tasks) <= 1:
        outcomes = [evaluate_preset(task) for task in tasks]
    else:
        outcomes = [None] * len(tasks)
        for done in executor.map_unordered(evaluate_preset, tasks):
            if done.error is not None:
                raise done.error
            outcomes[done.index] = done.value
    rows = [r for o in outcomes for r in o.rows]
    gains = [g for o in outcomes for g in o.gain]
    per_frame_all = [f for o in outcomes for f in o.per_frame]
    tuned = [t for o in outcomes for t in o.tuned]
    continuity = pd.DataFrame(
        [c for o in outcomes for c in o.continuity], columns=list(CONTINUITY_COLUMNS)
    )
    table = pd.DataFrame(rows, columns=list(COLUMNS))
    table[list(COUNT_COLUMNS)] = table[list(COUNT_COLUMNS)].astype("Int64")  # empty: no number
    oracle = table[table["method"] == ORACLE_ROW].set_index("preset")["success_1m_2deg"]
    ceiling = table["preset"].map(oracle).to_numpy(dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        share = np.where(ceiling > 0, table["success_1m_2deg"].to_numpy(float) / ceiling, np.nan)
    table["share_of_oracle"] = share
    declared_nothing = np.array(
        [
            m != ORACLE_ROW and abstains(m, p)
            for m, p in zip(table["method"], table["preset"], strict=True)
        ],
        dtype=bool,
    )
    for column, source in (("oracle_hota", "hota"), ("oracle_assa", "assa")):
        by_preset = table[table["method"] == ORACLE_ROW].set_index("preset")[source]
        values = table["preset"].map(by_preset).to_numpy(dtype=float)
        table[column] = np.where(declared_nothing, np.nan, values)  # no number beside none
    oracle_assa = table["oracle_assa"].to_numpy(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        table["assa_share_of_oracle"] = np.where(
            oracle_assa > 0, table["assa"].to_numpy(float) / oracle_assa, np.nan
        )
    gain = pd.DataFrame([g for g in gains if g], columns=list(GAIN_COLUMNS))
    side = out / folder_of(name)
    side.mkdir(parents=True, exist_ok=True)
    write_csv(table.round(6), out / f"{name}.csv")
    write_csv(gain.round(6), out / f"{name}_gain.csv")
    write_csv(pd.DataFrame(tuned, columns=list(TUNING_COLUMNS)).round(6), side / "tuning.csv")
    write_csv(continuity.round(6), side / "continuity.csv")
    if per_frame_all:
        write_csv(pd.concat(per_frame_all, ignore_index=True).round(6), side / "per_frame.csv")
    write_text(out / f"{name}.md", to_markdown(table, gain, label) + "\n\n" + "\n".join(
        f"- {line}." for line in goals(table, out, name)
    ) + "\n")  # fmt: skip
    return table


def evaluate_temporal_lidar(
    test_dir: Path,
    val_dir: Path,
    out: Path,
    methods: Sequence[tuple[str, Sequence[int]]] = METHODS,
    presets: Sequence[str] = PRESETS,
    seeds: Sequence[int] = RUNS,
    tune: bool = True,
    executor=None,
) -> pd.DataFrame:
    """The temporal study on LiDAR boxes (``scenarios/cad-v2x-seq-lidar.toml``'s test and
    validation splits at ``test_dir`` / ``val_dir``), the same protocol as
    :func:`evaluate_temporal`: ``out/table_temporal_lidar.{md,csv}``,
    ``out/table_temporal_lidar_gain.csv`` and ``out/temporal_lidar/`` (per-frame scores, tuning
    candidates, the own tracker's continuity). Returns the table."""
    return evaluate_temporal(
        test_dir, val_dir, out, methods, presets, seeds, tune, executor, LIDAR_TABLE, LIDAR_LABEL
    )


def best_long(table: pd.DataFrame, preset: str) -> str | None:
    """The method with the best validation F1 at W = 10 under ``preset`` among those that can run
    there (None: none)."""
    rows = table[(table["preset"] == preset) & (table["window"] == LONG)]
    rows = rows[rows["method"] != ORACLE_ROW]
    rows = rows[[not abstains(m, preset) for m in rows["method"]]]
    if not len(rows):
        return None
    return str(rows.sort_values(["val_f1", "method"], ascending=[False, True]).iloc[0]["method"])


TUNED, FIXED = "tuned per W", "fixed: W = 10's"


def _gains(preset: str, rows: list[dict], frames_by: dict) -> list[dict]:
    """The preset's gain rows for the best method at W = 10: W = 10 against W = 1 each with
    its own tuned parameters and τ (``parameters`` = :data:`TUNED`), and against W = 1 run with
    W = 10's parameters and τ (:data:`FIXED`: the window's effect alone)."""
    table = pd.DataFrame([r for r in rows if r["preset"] == preset])
    method = best_long(table, preset)
    if method is None or (method, SHORT) not in frames_by:
        return []
    out = [_gain(preset, method, TUNED, frames_by[(method, LONG)], frames_by[(method, SHORT)])]
    if (method, "fixed") in frames_by:
        fixed = frames_by[(method, "fixed")]
        out.append(_gain(preset, method, FIXED, frames_by[(method, LONG)], fixed))
    return out


def _gain(preset: str, method: str, parameters: str, long, short) -> dict:
    diff = long["f1"].to_numpy(float) - short["f1"].to_numpy(float)
    mean, low, high, episodes = t_interval(diff, long["episode"].to_numpy(), bounds=(-1.0, 1.0))
    pooled = pooled_bootstrap.f1_difference(_pooled_sums(long), _pooled_sums(short))
    return {
        "preset": preset,
        "method": method,
        "parameters": parameters,
        "f1_pooled_w10": float(pooled_bootstrap.f1_of(_pooled_sums(long))[0]),
        "f1_pooled_w1": float(pooled_bootstrap.f1_of(_pooled_sums(short))[0]),
        "pooled_diff": float(pooled.point[0]),
        "pooled_low": float(pooled.low[0]),
        "pooled_high": float(pooled.high[0]),
        "f1_w10": float(long["f1"].mean()),
        "f1_w1": float(short["f1"].mean()),
        "diff": mean,
        "ci_low": low,
        "ci_high": high,
        "episodes": episodes,
    }


def _pct(value: float, digits: int = 1) -> str:
    return "–" if not np.isfinite(value) else f"{100 * value:.{digits}f}"


def _ranged(value: float, low: float, high: float) -> str:
    if not np.isfinite(value):
        return "–"
    if not (np.isfinite(low) and np.isfinite(high)):
        return _pct(value)
    return f"{_pct(value)} [{_pct(low)}, {_pct(high)}]"


def _params(params: object) -> str:
    """A ``params`` cell (canonical JSON) as ``key=value, …``; ``defaults`` for ``{}``."""
    options = json.loads(params) if isinstance(params, str) and params else {}
    if not options:
        return "defaults"
    return ", ".join(f"{k}={v}" for k, v in options.items())


def _num(value: float, digits: int = 2) -> str:
    return "–" if not np.isfinite(value) else f"{value:.{digits}f}"


def to_markdown(table: pd.DataFrame, gain: pd.DataFrame | None = None, label: str = LABEL) -> str:
    """The table as markdown: per preset every (method, W) and the oracle row."""
    lines = [
        f"**{label}** — temporal matchers × window W × localisation preset; pooled F1 (the "
        "headline: frames without a true pair are common in a sequence), mean per-frame F1 and "
        "success in percent with episode-level 95 % intervals; parameters "
        f"({TUNING_BUDGET} configurations each) and τ per "
        "(method, W, preset) from validation; "
        "partner changes and CLEAR-MOT IDSW of the cross-agent links per 100 covisible "
        "object-frames; frames to the first correct association "
        "(mean over objects matched at all; never: objects never matched correctly); HOTA/AssA "
        "of the declared pairs over the own tracks, combined over sequences as TrackEval does, "
        f"AssA also as a share of the oracle's; {NO_NUMBER}: the method reads the "
        "localisation prior, which the preset does not give (no number, in no comparison).",
        "",
        "| Preset | Method | W | τ | parameters | F1 pooled [95 % CI] | F1 per frame [95 % CI] "
        "| success@(1 m, 2°) [95 % CI] | of oracle | partner changes/100 | IDSW/100 "
        "| frames to first | never | HOTA | AssA | AssA of oracle |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for row in table.itertuples(index=False):
        oracle = row.method == ORACLE_ROW
        if not oracle and abstains(row.method, row.preset):
            lines.append(
                f"| `{row.preset}` | `{row.method}` | {row.window} | n/a | n/a | {NO_NUMBER} |"
                + " n/a |" * 10
            )
            continue
        lines.append(
            f"| `{row.preset}` | `{row.method}` | {'' if oracle else row.window} "
            f"| {'' if oracle else _num(row.tau, 3)} | {'' if oracle else _params(row.params)} "
            f"| {_ranged(row.f1_pooled, row.f1_pooled_low, row.f1_pooled_high)} "
            f"| {_ranged(row.f1_mean, row.f1_low, row.f1_high)} "
            f"| {_ranged(row.success_1m_2deg, row.success_low, row.success_high)} "
            f"| {_pct(row.share_of_oracle, 0)} | {_num(row.partner_changes_per_100)} "
            f"| {_num(row.idsw_per_100)} "
            f"| {_num(row.frames_to_first)} | {row.never_matched} | {_pct(row.hota)} "
            f"| {_pct(row.assa)} | {_pct(row.assa_share_of_oracle, 0)} |"
        )
    if gain is not None and len(gain):
        lines += [
            "",
            "What accumulation buys (best method at W = 10 by validation F1 among those that can "
            "run; test F1 at W = 10 minus W = 1: pooled, episode-level bootstrap 95 % interval; "
            "per frame, paired per frame, episode-level t-interval; parameters: each W with its "
            f"own tuned parameters and τ ({TUNED}), or W = 1 run with W = 10's ({FIXED}: the "
            "window's effect alone)):",
            "",
            "| Preset | Method | parameters | F1 pooled W = 10 | F1 pooled W = 1 "
            "| pooled difference [95 % CI] "
            "| F1 per frame W = 10 | F1 per frame W = 1 | per-frame difference [95 % CI] |",
            "|---|---|---|---|---|---|---|---|---|",
        ]
        for g in gain.itertuples(index=False):
            lines.append(
                f"| `{g.preset}` | `{g.method}` | {g.parameters} | {_pct(g.f1_pooled_w10)} "
                f"| {_pct(g.f1_pooled_w1)} "
                f"| {_ranged(g.pooled_diff, g.pooled_low, g.pooled_high)} "
                f"| {_pct(g.f1_w10)} | {_pct(g.f1_w1)} | {_ranged(g.diff, g.ci_low, g.ci_high)} |"
            )
    return "\n".join(lines)


def _per_frame(results: Path, name: str = TABLE) -> pd.DataFrame | None:
    path = Path(results) / folder_of(name) / "per_frame.csv"
    return pd.read_csv(path) if path.is_file() else None


def goals(table: pd.DataFrame, results: Path, name: str = TABLE) -> list[str]:
    """The issue's goal lines (each through :func:`goal_line`) of table ``name``."""
    per_frame = _per_frame(results, name)
    lines = []
    denied = best_long(table, "denied")
    if denied is not None:
        row = _row(table, denied, LONG, "denied")
        lines.append(
            goal_line(
                "`denied`, W = 10: best pooled F1 ≥ 80",
                row.f1_pooled,
                row.f1_pooled_low,
                row.f1_pooled_high,
                0.80,
                detail=f"`{denied}`, chosen on validation",
            )
        )
    urban = best_long(table, "gnss-urban")
    if urban is not None:
        row = _row(table, urban, LONG, "gnss-urban")
        lines.append(
            goal_line(
                "`gnss-urban`, W = 10: success@(1 m, 2°) ≥ 60",
                row.success_1m_2deg,
                row.success_low,
                row.success_high,
                0.60,
                detail=f"`{urban}`, chosen on validation",
            )
        )
        if per_frame is not None:
            mine = _frames(per_frame, urban, LONG, "gnss-urban")
            oracle = _frames(per_frame, ORACLE_ROW, 0, "gnss-urban")
            if mine is not None and oracle is not None and len(mine) == len(oracle):
                diff = mine["success"].to_numpy(float) - 0.9 * oracle["success"].to_numpy(float)
                mean, low, high, _ = _interval(diff, mine["episode"], bounds=(-1.0, 1.0))
                lines.append(
                    goal_line(
                        "`gnss-urban`, W = 10: success − 0.9 × the oracle's ≥ 0",
                        mean,
                        low,
                        high,
                        0.0,
                        detail=f"`{urban}`; share of the oracle {_pct(row.share_of_oracle, 0)} %",
                    )
                )
        lines.append(
            goal_line(
                "`gnss-urban`, W = 10: partner changes ≤ 1 per 100 object-frames",
                row.partner_changes_per_100,
                row.partner_changes_low,
                row.partner_changes_high,
                1.0,
                at_least=False,
                scale=1.0,
                digits=2,
                detail=f"`{urban}`",
            )
        )
    continuity = Path(results) / folder_of(name) / "continuity.csv"
    if continuity.is_file():
        c = pd.read_csv(continuity)
        c = c[(c["preset"] == "gnss-urban") & (c["band"] == "fast") & (c["links"] > 0)]
        if len(c):
            c = c.iloc[0]
            lines.append(
                goal_line(
                    "own tracker: ≥ 90 % of consecutive detections on one track for objects "
                    "moving ≥ 10 m/s",
                    c.continuity,
                    c.continuity_low,
                    c.continuity_high,
                    0.90,
                    detail=f"{int(c.kept)} of {int(c.links)} links, `gnss-urban` test split",
                )
            )
    gain = Path(results) / f"{name}_gain.csv"
    if gain.is_file():
        every = pd.read_csv(gain)
        fixed = every[(every["preset"] == "gnss-urban") & (every["parameters"] == FIXED)]
        if len(fixed):
            f = fixed.iloc[0]
            lines.append(
                goal_line(
                    "`gnss-urban`: W = 10 ≥ W = 1 at fixed parameters (pooled F1)",
                    f.pooled_diff,
                    f.pooled_low,
                    f.pooled_high,
                    0.0,
                    detail=f"`{f.method}`, W = 10's parameters and τ at both",
                )
            )
        g = every[(every["preset"] == "denied") & (every["parameters"] == TUNED)]
        if len(g):
            g = g.iloc[0]
            low = g.pooled_low
            above = "above 0" if np.isfinite(low) and low > 0 else "not above 0"
            lines.append(
                goal_line(
                    "`denied`: W = 10 beats W = 1 by ≥ +10 pooled F1 points",
                    g.pooled_diff,
                    g.pooled_low,
                    g.pooled_high,
                    0.10,
                    detail=f"`{g.method}`; interval {above}",
                )
            )
    return lines


def _row(table: pd.DataFrame, method: str, window: int, preset: str):
    rows = table[
        (table["method"] == method) & (table["window"] == window) & (table["preset"] == preset)
    ]
    return next(rows.itertuples(index=False))


def _frames(per_frame: pd.DataFrame, method: str, window: int, preset: str) -> pd.DataFrame | None:
    rows = per_frame[
        (per_frame["method"] == method)
        & (per_frame["window"] == window)
        & (per_frame["preset"] == preset)
    ]
    if not len(rows):
        return None
    return rows.sort_values(["seed", "sequence", "frame"]).reset_index(drop=True)


def readme_part(
    results: Path, rel: str, seconds: float | None = None, name: str = TABLE
) -> list[str]:
    """README lines for the temporal table (none without ``table_temporal.csv``): per preset
    what accumulation buys (one row each) and the issue's goal lines; ``seconds``: the last cold
    run's generation + study time (a "≤ 2 min cold" line), None: not measured cold. ``name``
    :data:`LIDAR_TABLE`: the same for the LiDAR table (:func:`readme_part_lidar`)."""
    results = Path(results)
    lidar = name == LIDAR_TABLE
    path = results / f"{name}.csv"
    if not path.is_file():
        return []
    table = pd.read_csv(path, keep_default_na=False, na_values=[""])
    gain_path = results / f"{name}_gain.csv"
    gain = pd.read_csv(gain_path) if gain_path.is_file() else pd.DataFrame(columns=GAIN_COLUMNS)
    lines = [
        "### The temporal table on LiDAR boxes" if lidar else "### The temporal table",
        "",
        f"`{LIDAR_SCENARIO if lidar else SCENARIO}`: sequences of 10 frames 0.2 s apart of the same two vehicles; each "
        "agent's own tracks from its detections and odometry (never a true id); "
        "`windowed:<m>` (a two-view matcher's scores averaged along the own tracks over W "
        "frames), `temporal_pose` (one planar motion per window from the GNSS prior and the "
        "tracks) and `trajectory_pose` (the same motion from the tracks alone), parameters "
        f"({TUNING_BUDGET} configurations each) and τ per (method, W, preset) on validation. Per preset the method with the best validation F1 "
        "at W = 10 (among those that can run there: a prior reader has no number under `denied`): "
        "test pooled F1 at W = 10 and W = 1 and their difference (episode-level bootstrap 95 % "
        "interval) with W = 1 tuned on its own or at W = 10's parameters and τ (the window "
        "alone), the per-frame mean's difference, success@(1 m, 2°) at W = 10 and the "
        f"oracle's. Every row: [{rel}/{name}.md]({rel}/{name}.md).",
        "",
        "| Preset | Method | parameters | F1 pooled W = 10 | F1 pooled W = 1 "
        "| W = 10 − W = 1 [95 % CI] "
        "| per-frame F1 W = 10 − W = 1 | success W = 10 | oracle success |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for g in gain.itertuples(index=False):
        mine = table[
            (table["method"] == g.method)
            & (table["window"] == LONG)
            & (table["preset"] == g.preset)
        ]
        oracle = table[(table["method"] == ORACLE_ROW) & (table["preset"] == g.preset)]
        success = float(mine["success_1m_2deg"].iloc[0]) if len(mine) else float("nan")
        ceiling = float(oracle["success_1m_2deg"].iloc[0]) if len(oracle) else float("nan")
        lines.append(
            f"| `{g.preset}` | `{g.method}` | {g.parameters} | {_pct(g.f1_pooled_w10)} "
            f"| {_pct(g.f1_pooled_w1)} "
            f"| {_ranged(g.pooled_diff, g.pooled_low, g.pooled_high)} "
            f"| {_ranged(g.diff, g.ci_low, g.ci_high)} | {_pct(success)} | {_pct(ceiling)} |"
        )
    findings = []
    for g in gain.itertuples(index=False):
        if not (np.isfinite(g.pooled_low) and np.isfinite(g.pooled_high)):
            verdict = "no interval (one episode)"
        elif g.pooled_low > 0:
            verdict = "a gain, interval above 0"
        elif g.pooled_high < 0:
            verdict = "a loss, interval below 0"
        else:
            verdict = "no measurable change, interval across 0"
        findings.append(
            f"`{g.preset}`: W = 10 against W = 1 ({g.parameters}) for `{g.method}`: "
            f"{100 * g.pooled_diff:+.1f} pooled F1 points — {verdict}"
        )
    abstained = table[
        [
            m != ORACLE_ROW and abstains(m, p)
            for m, p in zip(table["method"], table["preset"], strict=True)
        ]
    ]
    for preset, rows in abstained.groupby("preset", sort=False):
        names = ", ".join(f"`{m}`" for m in dict.fromkeys(rows["method"]))
        findings.append(f"`{preset}`: {names} — {NO_NUMBER}; in no comparison")
    oracle = table[(table["method"] == ORACLE_ROW) & (table["preset"] == "gnss-urban")]
    if len(oracle) and float(oracle["success_high"].iloc[0]) < 0.60:
        o = oracle.iloc[0]
        findings.append(
            "the oracle's own `gnss-urban` success@(1 m, 2°) is "
            f"{_ranged(o.success_1m_2deg, o.success_low, o.success_high)}: below the 60 bar, "
            "which no matcher can then clear (the detections' position error caps the planar fit)"
        )
    timing = (
        [f"stage time (generation + study, last cold run): {seconds:.0f} s (goal ≤ 120 s)"]
        if seconds is not None
        else []
    )
    lines += ["", *[f"- {line}." for line in findings + goals(table, results, name) + timing], ""]
    return lines


def temporal_tuning_record(table: pd.DataFrame) -> dict:
    """The run record's ``temporal.tuning``: {preset: {method: {W: {"params": chosen options,
    "tau": τ, "val_f1": validation F1}}}} of every row but the oracle; all three None for a
    method that cannot run under the preset (:func:`abstains`)."""
    record: dict = {}
    for row in table[table["method"] != ORACLE_ROW].itertuples(index=False):
        ran = not abstains(row.method, row.preset)
        record.setdefault(row.preset, {}).setdefault(row.method, {})[str(row.window)] = {
            "params": json.loads(row.params) if ran else None,
            "tau": None if not np.isfinite(row.tau) else round(float(row.tau), 6),
            "val_f1": round(float(row.val_f1), 6) if ran else None,
        }
    return record


def readme_part_lidar(results: Path, rel: str, seconds: float | None = None) -> list[str]:
    """README lines for ``table_temporal_lidar`` (none without it): :func:`readme_part`'s."""
    return readme_part(results, rel, seconds, LIDAR_TABLE)
