"""``cadsim sweep-localisation DATASET_DIR --val VAL --sigmas 0,0.5,1.2,2.5,5 --out DIR``: F1
against the observers' localisation error — the connected-driving counterpart of Fig. 4.

At each position sigma s (metres per ground axis; heading sigma s × 0.2°/1.2 m, DMGM's ratio) and
run seed, every frame pair's localisation prior is re-drawn (``FramePair.localise(s, yaw, seed)``:
nothing is re-rendered or re-detected; for one seed the error scales with s) and every matcher of
that run sees the same prior. The matcher is told the *stated* uncertainty of that level
(``Problem.world_sigma`` = the level's σ, at least 0.5 m — the detections' own position error,
:data:`cadsim.sensing.localisation.MIN_STATED_SIGMA_M`), never the error actually drawn. Because
the level changes what the best kernel is, every level is tuned again: each matcher's grid runs
on the validation dataset re-drawn at that level (:mod:`eval.protocol.tuning`, seed 0, the first
:data:`TUNE_PAIRS` pairs), then τ is calibrated on the validation dataset at that level with the
chosen configuration (``--no-tune``: the parameters ``DIR/thresholds.csv`` records, else the
defaults, at every level). Writes ``localisation_sweep.csv`` (:data:`COLUMNS`: f1_mean, f1_std
— mean and sample std over runs of the per-run mean per-pair F1; ``runs``; ``deterministic``:
every run gave the same F1, so there is no spread to report and f1_std is empty; ``params``: the
configuration used at that level, JSON) and ``fig_localisation.png/.pdf``.

Matchers that do not read the prior are run at every sigma too (their curves are flat by
construction; they are the reference a prior has to beat).
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

import pandas as pd

from eval.commands.evaluate import add_runner_arguments
from eval.core.cache import ResultCache
from eval.core.executor import make_executor
from eval.core.pose_metrics import COLUMNS as POSE_COLUMNS
from eval.core.pose_metrics import summarise_pose
from eval.core.result_files import write_csv
from eval.core.runner import Runner, requests_for
from eval.core.tasks import MatcherSpec, RunResult
from eval.engine.matcher_list import parse_matchers
from eval.engine.named_runs import as_named, calibrate_named, score_runs
from eval.engine.splits import DatasetEntry, open_entry, val_dirs
from eval.engine.validation_choice import chosen_specs
from eval.protocol import tuning

DEFAULT_SIGMAS = (0.0, 0.5, 1.2, 2.5, 5.0)
YAW_PER_METRE = 0.2 / 1.2
"""Heading sigma (degrees) per metre of position sigma: DMGM's GPS noise (1.2 m, 0.2°)."""
DEFAULT_MATCHERS = "pose,pose_refine,pose_appearance,maximin_pose,maximin,consistency"
COLUMNS = [
    "dataset",
    "position_sigma_m",
    "yaw_sigma_deg",
    "matcher",
    "f1_mean",
    "f1_std",
    "runs",
    "deterministic",
    "params",
]
TUNE_PAIRS = 25
"""Validation pairs each level's parameter search runs on (τ is then calibrated on all of them)."""


def parse_sigmas(text: str) -> list[float]:
    """Comma-separated position sigmas (metres, ≥ 0), sorted, duplicates removed."""
    try:
        sigmas = [float(s) for s in text.split(",") if s.strip()]
    except ValueError as exc:
        raise ValueError(f"--sigmas: expected comma-separated numbers, got {text!r}") from exc
    if not sigmas or any(not (s >= 0) or s == float("inf") for s in sigmas):
        raise ValueError(f"--sigmas: expected finite sigmas >= 0 (metres), got {text!r}")
    return sorted(set(sigmas))


def localisation_of(sigma: float) -> tuple[float, float]:
    """(position sigma m, yaw sigma deg) of sweep point `sigma`."""
    return float(sigma), float(sigma) * YAW_PER_METRE


def sweep_specs(
    out_dir: str | Path, entry: DatasetEntry, matchers: Sequence[MatcherSpec]
) -> dict[str, MatcherSpec]:
    """{label: spec}: the parameters ``out_dir/thresholds.csv`` records for `entry` (the
    defaults for a matcher it lacks) — what ``--no-tune`` runs at every level."""
    named, _ = chosen_specs(out_dir, entry.label, matchers)
    return named


def _runs(
    runner: Runner,
    dataset: tuple[str, str],
    named: dict[str, MatcherSpec],
    seeds: Sequence[int],
    level: float | str,
    limit: int | None,
    desc: str,
) -> dict[str, list[RunResult]]:
    """Runs of every matcher at one level: a position sigma (metres) or a preset spec."""
    specs = list(dict.fromkeys(named.values()))
    localisation = level if isinstance(level, str) else localisation_of(level)
    requests = requests_for([dataset], specs, seeds, limit=limit, localisation=localisation)
    by_spec: dict[MatcherSpec, list[RunResult]] = {}
    for run in runner.run(requests, desc=desc):
        by_spec.setdefault(run.spec.matcher, []).append(run)
    return {label: by_spec[spec] for label, spec in named.items()}


def sweep_localisation(
    entry: DatasetEntry,
    matchers: Sequence[MatcherSpec] | dict[str, MatcherSpec],
    seeds: Sequence[int],
    sigmas: Sequence[float],
    runner: Runner,
    limit: int | None = None,
    val_limit: int | None = None,
    tune: bool = False,
) -> pd.DataFrame:
    """One row per (sigma, matcher) with the columns of :data:`COLUMNS`, on the first `limit`
    test pairs (None: all); τ per sigma from the first `val_limit` validation pairs; with
    `tune`, each matcher's grid searched again at every sigma (module docstring)."""
    if entry.val_dir is None:
        raise ValueError(f"{entry.test_dir}: the localisation sweep needs a validation dataset")
    base = as_named(matchers)
    rows = []
    for sigma in sigmas:
        position, yaw = localisation_of(sigma)
        named, params = base, {label: dict(spec.options) for label, spec in base.items()}
        if tune:
            limit_tune = TUNE_PAIRS if val_limit is None else min(val_limit, TUNE_PAIRS)
            chosen = tuning.tune_entry(
                entry, list(base.values()), runner, limit_tune, localisation_of(sigma)
            )
            named = {label: chosen[label].spec for label in base}
            params = {label: chosen[label].params for label in base}
        level = {"position_sigma_m": position, "yaw_sigma_deg": yaw}
        rows += _level_rows(
            entry, named, params, seeds, sigma, level, runner, limit, val_limit, f"σ={sigma:g} m"
        )
    return pd.DataFrame(rows, columns=COLUMNS)


def _level_rows(
    entry: DatasetEntry,
    named: dict[str, MatcherSpec],
    params: dict[str, dict],
    seeds: Sequence[int],
    level: float | str,
    columns: dict,
    runner: Runner,
    limit: int | None,
    val_limit: int | None,
    desc: str,
    pose_columns: bool = False,
) -> list[dict]:
    """One row per matcher at one level (a sigma or a preset spec): τ calibrated on the
    validation dataset at that level, F1 over the runs on the test dataset; ``columns`` are
    the level's own columns; with ``pose_columns``, the pose metrics of
    :mod:`eval.core.pose_metrics` too."""
    runs = [
        _runs(runner, (d, c), named, seeds, level, lim, f"{entry.label} localisation {desc}{tag}")
        for d, c, lim, tag in (
            (entry.val_dir, entry.val_checksum, val_limit, " validation"),
            (entry.test_dir, entry.test_checksum, limit, ""),
        )
    ]
    taus = {label: fit.tau for label, fit in calibrate_named(runs[0]).items()}
    per_pair = score_runs(runs[1], taus, dataset=entry.label)
    per_run = per_pair.groupby(["matcher", "seed"], sort=False)["f1"].mean()
    stats = per_run.groupby(level=0, sort=False).agg(["mean", "std", "min", "max", "size"])
    pose = summarise_pose(per_pair, ["matcher"]).set_index("matcher") if pose_columns else None
    rows = []
    for label, row in stats.iterrows():
        same = row["min"] == row["max"]  # every run the same: nothing to report as spread
        rows.append(
            {"dataset": entry.label, **columns, "matcher": label}
            | {
                "f1_mean": float(row["mean"]),
                "f1_std": float("nan") if same else float(row["std"]),
                "runs": int(row["size"]),
                "deterministic": bool(same),
                "params": tuning.params_json(params[label]),
            }
            | ({} if pose is None or label not in pose.index else pose.loc[label].to_dict())
        )
    return rows


PRESET_COLUMNS = [
    "dataset",
    "axis",
    "preset",
    "scale",
    "latency_ms",
    "matcher",
    "f1_mean",
    "f1_std",
    "runs",
    "deterministic",
    "params",
    *POSE_COLUMNS,
]
DEFAULT_PRESET = "gnss-urban"
DEFAULT_SCALES = (0.0, 1.0, 2.0, 3.0)
DEFAULT_LATENCIES_MS = (0.0, 100.0, 300.0)


def preset_levels(
    preset: str, scales: Sequence[float], latencies_ms: Sequence[float]
) -> list[tuple[str, str, float, float]]:
    """(axis, spec, scale, latency ms) of the preset sweep: the scales at the preset's own
    latency ("scale" axis), then the latencies at scale 1 ("latency" axis); a level on both axes
    is listed once per axis (its runs are shared through the cache)."""
    from cadsim.sensing.gnss_error import model_of

    own = model_of(preset).latency_ms
    levels = [("scale", f"{preset}*{s:g}", float(s), own) for s in scales]
    levels += [("latency", f"{preset}+{t:g}ms", 1.0, float(t)) for t in latencies_ms]
    return levels


def sweep_presets(
    entry: DatasetEntry,
    matchers: Sequence[MatcherSpec] | dict[str, MatcherSpec],
    seeds: Sequence[int],
    levels: Sequence[tuple[str, str, float, float]],
    runner: Runner,
    limit: int | None = None,
    val_limit: int | None = None,
) -> pd.DataFrame:
    """F1 against a GNSS-like preset's error scale and message latency (:func:`preset_levels`):
    one row per (level, matcher) with :data:`PRESET_COLUMNS`; the matchers' parameters fixed
    (``matchers``), τ calibrated at every level on the validation dataset at that level."""
    if entry.val_dir is None:
        raise ValueError(f"{entry.test_dir}: the localisation sweep needs a validation dataset")
    named = as_named(matchers)
    params = {label: dict(spec.options) for label, spec in named.items()}
    rows = []
    for axis, spec, scale, latency in levels:
        columns = {"axis": axis, "preset": spec, "scale": scale, "latency_ms": latency}
        rows += _level_rows(
            entry, named, params, seeds, spec, columns, runner, limit, val_limit, spec, True
        )
    return pd.DataFrame(rows, columns=PRESET_COLUMNS)


def write_preset_sweep(out_dir: str | Path, rows: pd.DataFrame) -> Path:
    """Write ``localisation_presets.csv`` (the preset axes of the localisation sweep)."""
    path = Path(out_dir) / "localisation_presets.csv"
    path.parent.mkdir(parents=True, exist_ok=True)
    write_csv(rows.round(6), path)
    return path


def write_sweep(out_dir: str | Path, rows: pd.DataFrame) -> Path:
    """Write (or, for other datasets already in it, extend) ``localisation_sweep.csv``."""
    path = Path(out_dir) / "localisation_sweep.csv"
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.is_file():
        old = pd.read_csv(path)
        rows = pd.concat([old[~old["dataset"].isin(rows["dataset"])], rows], ignore_index=True)
    write_csv(rows.round(6), path)
    return path


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("dataset", metavar="DATASET_DIR", help="test dataset (simulated, CAD)")
    parser.add_argument(
        "--val", default=None, metavar="DIR", help="validation dataset (default: DATASET_DIR-val)"
    )
    parser.add_argument(
        "--sigmas",
        default=",".join(f"{s:g}" for s in DEFAULT_SIGMAS),
        help="comma-separated position sigmas, metres (yaw sigma = 0.2° per 1.2 m)",
    )
    parser.add_argument(
        "--preset",
        default=None,
        metavar="PRESET",
        help="sweep a GNSS-like preset's error scale and message latency instead of the i.i.d. "
        "sigmas (e.g. gnss-urban; writes localisation_presets.csv)",
    )
    parser.add_argument(
        "--scales",
        default=",".join(f"{s:g}" for s in DEFAULT_SCALES),
        help="with --preset: comma-separated error scales",
    )
    parser.add_argument(
        "--latencies",
        default=",".join(f"{t:g}" for t in DEFAULT_LATENCIES_MS),
        help="with --preset: comma-separated message latencies, milliseconds",
    )
    parser.add_argument("--pairs", type=int, default=None, help="only the first N test pairs")
    parser.add_argument(
        "--no-tune",
        dest="tune",
        action="store_false",
        help="no parameter search per level: the parameters DIR/thresholds.csv records, else "
        "the defaults, at every level",
    )
    add_runner_arguments(parser)
    for action in parser._actions:
        if action.dest == "matchers":
            action.default = DEFAULT_MATCHERS
            action.help = f"comma list or 'all' (default: {DEFAULT_MATCHERS})"


def run(args: argparse.Namespace) -> int:
    from eval.core.result_files import check_outputs

    check_outputs(args.out, args.cache)
    (val,) = val_dirs([args.dataset], [args.val] if args.val else None)
    entry = open_entry(args.dataset, val)
    matchers = parse_matchers(args.matchers)
    if args.preset is not None:
        return _run_presets(args, entry, matchers)
    sigmas = parse_sigmas(args.sigmas)
    with make_executor(args.workers, args.scheduler) as executor:
        runner = Runner(
            ResultCache(args.cache),
            executor,
            progress=not args.no_progress,
            plugin_time_limit_s=args.plugin_time_limit,
        )
        named = matchers if args.tune else sweep_specs(args.out, entry, matchers)
        rows = sweep_localisation(
            entry, named, range(args.runs), sigmas, runner, args.pairs, tune=args.tune
        )
    write_sweep(args.out, rows)
    from eval.report.figures import write_fig_localisation

    for path in write_fig_localisation(args.out):
        print(path)
    return 0


def _run_presets(args: argparse.Namespace, entry: DatasetEntry, matchers) -> int:
    """``--preset``: the preset's scale and latency axes, parameters as ``--no-tune`` runs them."""
    from cadsim.sensing.gnss_error import parse_spec

    parse_spec(args.preset)  # ValueError naming the presets
    levels = preset_levels(args.preset, parse_sigmas(args.scales), parse_sigmas(args.latencies))
    for _, spec, _, _ in levels:
        open_entry(args.dataset, None, localisation=spec)  # refuses a dataset without velocities
    with make_executor(args.workers, args.scheduler) as executor:
        runner = Runner(
            ResultCache(args.cache),
            executor,
            progress=not args.no_progress,
            plugin_time_limit_s=args.plugin_time_limit,
        )
        named = sweep_specs(args.out, entry, matchers)
        rows = sweep_presets(entry, named, range(args.runs), levels, runner, args.pairs)
    write_preset_sweep(args.out, rows)
    from eval.report.figures import write_fig_localisation_presets

    for path in write_fig_localisation_presets(args.out):
        print(path)
    return 0
