"""A synthetic CoID benchmark shaped like the paper's Fig. 2, and the nine matchers scored on it.

Each frame pair is a scene of objects in 3-D (metres). Two views share ``covisible`` objects and
each also sees its own non-covisible distractors, placed among the covisible ones. View 1 holds
world positions plus noise; view 2 holds the positions after a random rigid transform (uniform
rotation in SO(3), translation up to 20 m) plus independent noise (``--position-noise``, metres,
per axis). Appearance is look-alike: every object's feature is one of a few non-negative prototype
vectors plus a small object-specific offset, observed in each view with independent noise, so
appearance alone cannot tell most objects apart.

Scoring (DESIGN §3): per frame pair precision, recall, F1 and accuracy (fraction of objects over
both views decided right); per-run mean over frame pairs, then mean ± std over runs with different
matcher seeds. The acceptance threshold tau is chosen per matcher on a separate validation set of
frame pairs (maximising mean F1) and then applied unchanged to the test set.
"""

from __future__ import annotations

import argparse
import logging
import time
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.spatial.transform import Rotation

from eval.core.executor import map_in_order
from eval.protocol.calibration import calibrate_ranked
from eval.protocol.metrics import (
    METRICS,
    RankedAssignments,
    average_precision,
    metrics_at_thresholds,
    pooled_pr_curve,
    summarise_runs,
)

log = logging.getLogger(__name__)

# Every matcher that needs no localisation prior (the synthetic scenes have none).
ALL_MATCHERS = (
    "none",
    "appearance",
    "sm",
    "rrwm",
    "tm",
    "hgm",
    "bcagm",
    "rrwhm",
    "mos",
    "maximin",
    "consistency",
    "cbm",
    "freealign",
    "optimal_transport",
    "v2x_reg",
)


@dataclass(frozen=True)
class SceneConfig:
    """Shape of the generated frame pairs. Counts are inclusive ranges drawn per frame pair."""

    covisible: tuple[int, int] = (4, 8)
    distractors: tuple[int, int] = (2, 6)  # per view
    extent_m: float = 30.0  # objects spread uniformly over an extent_m x extent_m area
    height_m: float = 3.0  # and over 0 .. height_m in z
    position_noise_m: float = 0.3  # per axis, independently in each view
    prototypes: int = 3  # distinct looks
    feature_dim: int = 16
    object_spread: float = 0.05  # object-specific offset from its prototype (relative)
    view_noise: float = 0.15  # per-view observation noise on features (relative)


@dataclass(frozen=True)
class FramePair:
    """One CoID problem. points*: (n, 3) metres in each view's frame; features*: (n, d) >= 0;
    truth: (k, 2) int covisible pairs (i in view 1, j in view 2); ids*: object id per row."""

    points1: np.ndarray
    points2: np.ndarray
    features1: np.ndarray
    features2: np.ndarray
    truth: np.ndarray
    ids1: np.ndarray
    ids2: np.ndarray


def make_frame_pair(rng: np.random.Generator, cfg: SceneConfig = SceneConfig()) -> FramePair:
    """Draw one frame pair (see module docstring); deterministic given ``rng``'s state."""
    n_cov = int(rng.integers(cfg.covisible[0], cfg.covisible[1] + 1))
    n_a = int(rng.integers(cfg.distractors[0], cfg.distractors[1] + 1))
    n_b = int(rng.integers(cfg.distractors[0], cfg.distractors[1] + 1))
    n_obj = n_cov + n_a + n_b
    world = np.column_stack(
        [
            rng.uniform(0.0, cfg.extent_m, (n_obj, 2)),
            rng.uniform(0.0, cfg.height_m, n_obj),
        ]
    )
    protos = rng.gamma(1.0, 1.0, (cfg.prototypes, cfg.feature_dim))
    protos /= np.linalg.norm(protos, axis=1, keepdims=True)
    look = rng.integers(0, cfg.prototypes, n_obj)
    appearance = protos[look] + cfg.object_spread * rng.standard_normal((n_obj, cfg.feature_dim))

    # object ids: 0..n_cov-1 covisible, then view-1-only, then view-2-only
    in1 = np.r_[np.arange(n_cov), n_cov + np.arange(n_a)]
    in2 = np.r_[np.arange(n_cov), n_cov + n_a + np.arange(n_b)]
    ids1 = rng.permutation(in1)
    ids2 = rng.permutation(in2)

    rot = Rotation.random(random_state=rng)
    shift = rng.uniform(-20.0, 20.0, 3)
    sigma = cfg.position_noise_m
    p1 = world[ids1] + sigma * rng.standard_normal((ids1.size, 3))
    p2 = rot.apply(world[ids2]) + shift + sigma * rng.standard_normal((ids2.size, 3))

    def observe(ids: np.ndarray) -> np.ndarray:
        f = appearance[ids] + cfg.view_noise * rng.standard_normal((ids.size, cfg.feature_dim))
        return np.clip(f, 0.0, None)

    f1, f2 = observe(ids1), observe(ids2)
    where2 = np.full(n_obj, -1)
    where2[ids2] = np.arange(ids2.size)
    cov1 = np.flatnonzero(ids1 < n_cov)
    truth = np.column_stack([cov1, where2[ids1[cov1]]]).astype(int)
    return FramePair(p1, p2, f1, f2, truth, ids1, ids2)


# --------------------------------------------------------------------------- scoring


def ranked(results: list[dict], frames: dict[int, FramePair]) -> RankedAssignments:
    """Hungarian assignments of ``results`` (one per frame pair) for threshold sweeps."""
    return RankedAssignments.from_frames(
        [
            (
                r["pairs"],
                r["scores"][r["pairs"][:, 0], r["pairs"][:, 1]],
                frames[r["frame"]].truth,
                len(frames[r["frame"]].ids1),
                len(frames[r["frame"]].ids2),
            )
            for r in results
        ]
    )


def calibrate_threshold(validation: RankedAssignments) -> tuple[float, float]:
    """Tau maximising the mean per-pair F1 over the validation frame pairs: (tau, that F1), by the
    suite's one rule (:func:`eval.protocol.calibration.calibrate_ranked`)."""
    tau, f1, _, _ = calibrate_ranked(validation)
    return tau, f1


# --------------------------------------------------------------------------- running


def _frame(seed: int, split: str, k: int, cfg: SceneConfig) -> FramePair:
    split_id = {"validation": 1, "test": 2}[split]
    return make_frame_pair(np.random.default_rng([seed, 9176, split_id, k]), cfg)


def _solve(job: tuple) -> list[dict]:
    from matchers import Problem, get

    seed, split, k, run, names, cfg, options = job
    fp = _frame(seed, split, k, cfg)
    problem = Problem(fp.points1, fp.points2, fp.features1, fp.features2)
    out = []
    for name in names:
        t0 = time.perf_counter()
        m = get(name)(problem, seed=1000 * run + k, threshold=None, **options.get(name, {}))
        out.append(
            {
                "split": split,
                "frame": k,
                "run": run,
                "matcher": name,
                "pairs": np.asarray(m.pairs, dtype=int).reshape(-1, 2),
                "scores": np.asarray(m.scores, dtype=float),
                "time_s": time.perf_counter() - t0,
            }
        )
    return out


def run_benchmark(
    matchers: list[str],
    *,
    seed: int = 0,
    validation_frames: int = 50,
    test_frames: int = 50,
    runs: int = 4,
    cfg: SceneConfig = SceneConfig(),
    options: dict[str, dict] | None = None,
    jobs: int = 1,
    progress: bool = True,
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Calibrate tau per matcher on the validation frames (run 0), then score the test frames
    for every run (matcher seed 1000 * run + frame).

    Returns (summary, per_frame). summary: one row per matcher with tau, validation F1, test
    mean and std (over runs, ddof=1) of accuracy, precision, recall, F1 at tau; F1 with no
    threshold; pooled average precision (threshold-free, mean over runs); ms per frame pair.
    """
    options = options or {}
    work = [
        (seed, "validation", k, 0, tuple(matchers), cfg, options) for k in range(validation_frames)
    ]
    work += [
        (seed, "test", k, r, tuple(matchers), cfg, options)
        for r in range(runs)
        for k in range(test_frames)
    ]
    outputs = map_in_order(_solve, work, jobs, desc="coid", unit="frame", progress=progress)
    results = [result for out in outputs for result in out]

    val_frames = {k: _frame(seed, "validation", k, cfg) for k in range(validation_frames)}
    test_frames_ = {k: _frame(seed, "test", k, cfg) for k in range(test_frames)}
    per_frame, summary = [], []
    for name in matchers:
        mine = [r for r in results if r["matcher"] == name]
        tau, val_f1 = calibrate_threshold(
            ranked([r for r in mine if r["split"] == "validation"], val_frames)
        )
        row = {"matcher": name, "tau": tau, "val_f1": val_f1}
        ap, no_tau = [], []
        for run in range(runs):
            res = sorted(
                (r for r in mine if r["split"] == "test" and r["run"] == run),
                key=lambda r: r["frame"],
            )
            rk = ranked(res, test_frames_)
            at = metrics_at_thresholds(rk, [tau, -np.inf])
            for f, r in enumerate(res):
                per_frame.append(
                    {
                        "matcher": name,
                        "run": run,
                        "frame": r["frame"],
                        **{k: float(at[k][f, 0]) for k in METRICS},
                        "time_s": r["time_s"],
                    }
                )
            no_tau.append(float(at["f1"][:, 1].mean()))
            ap.append(average_precision(pooled_pr_curve(rk)))
        summary.append(row | {"f1_no_threshold": np.mean(no_tau), "ap": np.mean(ap)})
    per_frame_df = pd.DataFrame(per_frame)
    stats = summarise_runs(per_frame_df, by=["matcher"], run="run")
    times = per_frame_df.groupby("matcher")["time_s"].mean().rename("time_s")
    summary_df = pd.DataFrame(summary).merge(stats, on="matcher").merge(times, on="matcher")
    return summary_df, per_frame_df


def format_summary(summary: pd.DataFrame) -> str:
    """Markdown table of :func:`run_benchmark`'s summary (mean ± std over runs), best F1 first."""
    lines = [
        "| matcher | tau | val F1 | test F1 | precision | recall | accuracy | F1 no tau | AP | ms |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in summary.sort_values("f1_mean", ascending=False).itertuples():
        tau = f"{r.tau:.3g}"
        lines.append(
            f"| {r.matcher} | {tau} | {r.val_f1:.3f} | {r.f1_mean:.3f} ± {r.f1_std:.3f} | "
            f"{r.precision_mean:.3f} | {r.recall_mean:.3f} | {r.accuracy_mean:.3f} | "
            f"{r.f1_no_threshold:.3f} | {r.ap:.3f} | {r.time_s * 1e3:.1f} |"
        )
    return "\n".join(lines)


# --------------------------------------------------------------------------- CLI (via eval.validation.synthetic)


def add_arguments(group) -> None:
    """Options of ``--protocol coid`` (added to ``eval.validation.synthetic``'s parser)."""
    group.add_argument("--validation-frames", type=int, default=50, help="coid: tau calibration")
    group.add_argument("--test-frames", type=int, default=50, help="coid: test frame pairs")
    group.add_argument("--runs", type=int, default=4, help="coid: runs (matcher seeds)")
    group.add_argument(
        "--position-noise", type=float, default=SceneConfig.position_noise_m, help="coid: m"
    )
    group.add_argument(
        "--prototypes", type=int, default=SceneConfig.prototypes, help="coid: distinct looks"
    )


def run(args: argparse.Namespace) -> int:
    from eval.core.result_files import check_table_files, write_csv, write_text

    outs = check_table_files(args.out, b"matcher,")
    matchers = args.matchers or list(ALL_MATCHERS)
    cfg = SceneConfig(position_noise_m=args.position_noise, prototypes=args.prototypes)
    options = {}
    if args.tensor:
        from eval.validation.matcher_options import matcher_options

        options = {m: matcher_options(m, args.tensor) for m in matchers}
    t0 = time.perf_counter()
    summary, per_frame = run_benchmark(
        matchers,
        seed=args.seed,
        validation_frames=args.validation_frames,
        test_frames=args.test_frames,
        runs=args.runs,
        cfg=cfg,
        options=options,
        jobs=args.jobs,
        progress=not args.no_progress,
    )
    text = (
        f"## coid (seed={args.seed}, {args.validation_frames} validation / {args.test_frames} "
        f"test frame pairs, {args.runs} runs, tensor={args.tensor or 'matcher default'})\n\n"
        f"{cfg}\n\n{format_summary(summary)}\n\nran in {time.perf_counter() - t0:.0f} s\n"
    )
    print(text, flush=True)
    for path in outs:
        if path.suffix == ".csv":
            write_csv(summary, path, float_format="%.4f")
        else:
            write_text(path, text)
    return 0
