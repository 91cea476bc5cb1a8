"""The evaluation behind ``cadsim evaluate`` (and every study that runs matchers): datasets paired
with their validation sets, runs requested from the cached runner, τ calibrated on validation,
optional tuning, scoring, and the files of each protocol variant (per-pair metrics, AP, PR curves,
thresholds, Table I input, the qualitative-figure input). The command line is
:mod:`eval.commands.evaluate`.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from eval.core import tasks
from eval.core.pose_metrics import outcome_pose
from eval.core.result_files import recorded_path, write_csv, write_text
from eval.core.runner import Runner, requests_for
from eval.core.tasks import MatcherSpec, RunResult
from eval.protocol import calibration, tuning
from eval.protocol.cues import equal_cue_spec
from eval.protocol.metrics import (
    RankedAssignments,
    average_precision,
    pair_metrics,
    pooled_pr_curve,
)
from eval.protocol.variants import (
    EQUAL,
    MAIN,
    PAPER,
    UNTUNED,
    check_protocol,
    paper_spec,
    variant_path,
)

log = logging.getLogger(__name__)

PAPER_ORDER = ("sm", "rrwm", "hgm", "tm", "bcagm", "rrwhm", "mos", "maximin", "appearance", "none")
QUALITATIVE_MATCHERS = ("rrwhm", "mos", "maximin")
DEFAULT_CACHE = "cache/runs"  # make reproduce's, inside the repository; commands use user_cache()
# Scenario name -> table name where the first-word rule (below) does not give the right one.
DATASET_LABELS = {"cad-dense": "CAD-dense", "dmgm-cad": "DMGM"}

# A table row (the requested matcher's label) -> the spec that runs for it on one dataset (tuned
# parameters and protocol options make the two differ).
Named = dict[str, MatcherSpec]


@dataclass(frozen=True)
class DatasetEntry:
    """A test dataset and its validation dataset. label: the table's dataset name (``CAD``);
    localisation: the name of a GNSS-like preset (:mod:`cadsim.sensing.gnss_error`) that
    re-draws every record's localisation prior in every run (None: the records' own); sensor:
    the sensor a two-sensor dataset is read as ("camera", "lidar"; None: as stored,
    :mod:`cadsim.dataset.sensor_view`)."""

    label: str
    scenario: str
    test_dir: str
    test_checksum: str
    test_pairs: int
    val_dir: str | None = None
    val_checksum: str | None = None
    val_pairs: int = 0
    localisation: str | None = None  # a GNSS-like preset re-drawing every record's prior
    sensor: str | None = None


PAPER_FAMILIES = ("cad", "mrc")  # scenario-name prefixes titled like the paper's datasets


def dataset_label(scenario_name: str) -> str:
    """Table name of a scenario: :data:`DATASET_LABELS`; a scenario of the paper's families by
    its family in upper case (cad-intersection -> CAD, mrc-arena -> MRC, cad-dense ->
    CAD-dense); any other by its own name (my-busy-3lane stays my-busy-3lane)."""
    if scenario_name in DATASET_LABELS:
        return DATASET_LABELS[scenario_name]
    family = scenario_name.split("-", 1)[0]
    return family.upper() if family.lower() in PAPER_FAMILIES else scenario_name


def open_entry(
    test_dir: str | Path,
    val_dir: str | Path | None,
    label: str | None = None,
    localisation: str | None = None,
    sensor: str | None = None,
) -> DatasetEntry:
    """Open the test (and validation) dataset and describe them, titled `label` (default:
    :func:`dataset_label` of its scenario), read as ``sensor`` (a two-sensor dataset's
    "camera" or "lidar"; None: as stored). Each is verified against its
    manifest's checksums (once per process for unchanged files): the result cache is keyed by
    the manifest's checksum, so a record modified after generation would otherwise go unseen."""
    read = (lambda d: tasks.open_dataset(d)) if sensor is None else (lambda d: tasks.open_dataset(d, sensor))  # fmt: skip
    test = read(str(test_dir))
    val = read(str(val_dir)) if val_dir is not None else None
    for dataset in (test, val):
        if dataset is not None:
            dataset.verify_once()
    if val is not None and val.scenario_name != test.scenario_name:
        raise ValueError(
            f"{val_dir}: validation scenario {val.scenario_name!r} differs from "
            f"{test_dir}'s {test.scenario_name!r}"
        )
    if localisation is not None:
        from cadsim.sensing.gnss_error import model_of
        from cadsim.sensing.latency import MIN_VELOCITY_FORMAT

        latency = model_of(localisation).latency_ms  # ValueError naming the presets
        for dataset, where in ((test, test_dir), (val, val_dir)):
            version = None if dataset is None else dataset.manifest["format_version"]
            if latency and version is not None and version < MIN_VELOCITY_FORMAT:
                raise ValueError(
                    f"{where}: localisation {localisation!r} has a message latency of "
                    f"{latency:g} ms, which needs object velocities (dataset format version "
                    f"{MIN_VELOCITY_FORMAT}); this dataset is version {version} — regenerate it"
                )
    return DatasetEntry(
        label=label or dataset_label(test.scenario_name),
        scenario=test.scenario_name,
        test_dir=str(test_dir),
        test_checksum=test.checksum,
        test_pairs=len(test),
        val_dir=None if val is None else str(val_dir),
        val_checksum=None if val is None else val.checksum,
        val_pairs=0 if val is None else len(val),
        localisation=localisation,
        sensor=getattr(test, "sensor", None),
    )


def parse_matchers(text: str) -> list[MatcherSpec]:
    """``all`` or a comma-separated list of names, case-insensitive (``SM,Maximin`` as the tables
    print them). ``all``: every registered matcher that needs nothing beyond what every dataset
    gives (``matchers.requires`` empty; the localisation-prior matchers must be named) and needs
    no option (``matchers.required_options`` empty: the learned matchers need a model), paper
    order first; an entry point that cannot be loaded is left out with a warning line. An
    unknown name is refused with the closest known ones, a named entry point that cannot be
    loaded in one line naming it (``matchers.PluginError``)."""
    from matchers.core.registry import available, get, required_options, requires, usable

    known = list(available())
    if text.strip() == "all":
        plain = [n for n in usable() if not requires(n) and not required_options(n)]
        names = [n for n in PAPER_ORDER if n in plain] + [n for n in plain if n not in PAPER_ORDER]
    else:
        by_lower = {n.lower(): n for n in known}
        given = [n.strip() for n in text.split(",") if n.strip()]
        names = [n if n in known else by_lower.get(n.lower(), n) for n in given]
        unknown = [n for n in names if n not in known and not _importable(n)]
        if unknown or not names:
            import difflib

            close = difflib.get_close_matches(unknown[0].lower(), known, n=3) if unknown else []
            hint = f" (did you mean {', '.join(close)}?)" if close else ""
            raise ValueError(
                f"--matchers: unknown {unknown or text!r}{hint}; available: {', '.join(known)}"
            )
        for name in names:
            get(name)  # a broken entry point: PluginError naming it, before anything runs
    return [MatcherSpec(n) for n in dict.fromkeys(names)]


def _importable(name: str) -> bool:
    """Whether ``name`` is a ``package.module:function`` matcher that imports."""
    if ":" not in name:
        return False
    from matchers.core.registry import get

    try:
        get(name)
    except ValueError:
        return False
    return True


def as_named(matchers: Sequence[MatcherSpec] | Mapping[str, MatcherSpec]) -> Named:
    """{row label: spec}: a mapping as given, a list of specs under their own labels."""
    if isinstance(matchers, Mapping):
        return dict(matchers)
    return {m.label: m for m in matchers}


def run_named(
    runner: Runner,
    dataset: tuple[str, str],
    named: Named,
    seeds: Sequence[int],
    desc: str,
    *,
    noise_rates: Sequence[float | None] = (None,),
    limit: int | None = None,
    keep: float | None = None,
    localisation: str | None = None,
    sensor: str | None = None,
) -> dict[str, list[RunResult]]:
    """Runs of every spec of `named` on `dataset` (dir, checksum) × seeds × noise rates, grouped
    by row label (seed order, then rate order); `localisation`: a preset re-drawing the prior;
    `sensor`: the sensor a two-sensor dataset is read as (None: as stored)."""
    specs = list(dict.fromkeys(named.values()))
    requests = requests_for(
        [dataset], specs, seeds, noise_rates, limit, keep, localisation, sensor=sensor
    )
    runs = runner.run(requests, desc=desc)
    by_spec: dict[MatcherSpec, list[RunResult]] = {}
    for run in runs:
        by_spec.setdefault(run.spec.matcher, []).append(run)
    return {label: by_spec[spec] for label, spec in named.items()}


def score_runs(
    runs: Mapping[str, Sequence[RunResult]], taus: Mapping[str, float | None], **columns
) -> pd.DataFrame:
    """One row per (row label, run, frame pair): metrics of the prediction at the label's τ, the
    run's matcher options (``params``, JSON), plus the given constant `columns`."""
    rows = []
    for label, label_runs in runs.items():
        tau = taus.get(label)
        for run in label_runs:
            params = tuning.params_json(dict(run.spec.matcher.options))
            for o in run.outcomes:
                predicted = calibration.predictions(o, tau)
                m = pair_metrics(predicted, o.gt_pairs, o.n1, o.n2)
                rows.append(
                    columns
                    | {
                        "matcher": label,
                        "params": params,
                        "seed": run.spec.seed,
                        "noise_rate": run.spec.noise_rate,
                        "keep": run.spec.keep,
                        "pair": o.index,
                        "episode": o.episode,
                        "sim_seed": o.sim_seed,
                        "tau": np.nan if tau is None else tau,
                        **{
                            k: getattr(m, k)
                            for k in ("n1", "n2", "n_gt", "n_pred", "tp", "correct")
                        },
                        **{
                            k: getattr(m, k)
                            for k in ("accuracy", "balanced_accuracy", "precision", "recall")
                        },
                        "f1": m.f1,
                        "time_s": o.time_s,
                    }
                    | outcome_pose(o, predicted)
                )
    return pd.DataFrame(rows)


def calibrate_named(
    runs: Mapping[str, Sequence[RunResult]],
) -> dict[str, calibration.Calibration]:
    """τ per row label, fitted on its (validation) runs only."""
    return {label: calibration.calibrate(label_runs) for label, label_runs in runs.items()}


def calibrate_entry(
    entry: DatasetEntry,
    matchers: Sequence[MatcherSpec] | Mapping[str, MatcherSpec],
    seeds: Sequence[int],
    runner: Runner,
    keep: float | None = None,
) -> tuple[dict[str, list[RunResult]], dict[str, calibration.Calibration]]:
    """Validation runs of `entry` (non-covisible detections thinned to `keep`) and τ per row
    label fitted on them (only on them)."""
    if entry.val_dir is None:
        return {}, {}
    val_runs = run_named(
        runner,
        (entry.val_dir, entry.val_checksum),
        as_named(matchers),
        seeds,
        f"{entry.label} validation",
        keep=keep,
        localisation=entry.localisation,
        sensor=entry.sensor,
    )
    return val_runs, calibrate_named(val_runs)


def representative_pair(runs: Sequence[RunResult]) -> int:
    """Index of the frame pair with the median number of covisible objects (lowest index on
    ties): a deterministic, not cherry-picked, pair for the qualitative figure."""
    counts = np.array([len(o.gt_pairs) for o in runs[0].outcomes])
    median = np.sort(counts)[(len(counts) - 1) // 2]
    return int(runs[0].outcomes[int(np.flatnonzero(counts == median)[0])].index)


def qualitative_entry(
    entry: DatasetEntry,
    test_runs: Mapping[str, Sequence[RunResult]],
    taus: Mapping[str, float | None],
) -> dict:
    """Predictions of the Fig. 3 matchers (first seed) on the representative test pair."""
    all_runs = [r for runs in test_runs.values() for r in runs]
    first_seed = min(r.spec.seed for r in all_runs)
    index = representative_pair([r for r in all_runs if r.spec.seed == first_seed])
    methods, gt = {}, []
    for label, runs in test_runs.items():
        run = next(r for r in runs if r.spec.seed == first_seed)
        if run.spec.matcher.name not in QUALITATIVE_MATCHERS:
            continue
        outcome = next(o for o in run.outcomes if o.index == index)
        methods[label] = calibration.predictions(outcome, taus.get(label)).tolist()
        gt = outcome.gt_pairs.tolist()
    if not methods:
        return {}
    return {
        "dataset_dir": recorded_path(entry.test_dir),
        "pair": index,
        "seed": first_seed,
        "gt_pairs": gt,
        "methods": methods,
    }


def ranking_quality(
    label: str, test_runs: Mapping[str, Sequence[RunResult]]
) -> tuple[list[dict], pd.DataFrame]:
    """Threshold-free view of dataset `label`: AP rows per (matcher, run), and the PR curves of
    every matcher with its runs pooled."""
    ap_rows, curves = [], []
    for matcher, runs in test_runs.items():
        for run in runs:
            curve = pooled_pr_curve(RankedAssignments.from_frames(run.ranking_frames()))
            ap = average_precision(curve)
            ap_rows.append({"dataset": label, "matcher": matcher, "seed": run.spec.seed, "ap": ap})
        pooled = pooled_pr_curve(
            RankedAssignments.from_frames([f for r in runs for f in r.ranking_frames()])
        )
        curves.append(
            pd.DataFrame(
                {"dataset": label, "matcher": matcher, "threshold": pooled.thresholds}
                | {"precision": pooled.precision, "recall": pooled.recall}
            )
        )
    return ap_rows, pd.concat(curves, ignore_index=True)


@dataclass
class EntryResult:
    """One dataset evaluated under one variant: τ and options per row label and the tables."""

    entry: DatasetEntry
    named: Named
    taus: dict[str, float | None]
    fits: dict[str, calibration.Calibration]
    per_pair: pd.DataFrame
    ap_rows: list[dict]
    pr: pd.DataFrame
    qualitative: dict = field(default_factory=dict)


def evaluate_entry(
    entry: DatasetEntry, named: Named, seeds: Sequence[int], runner: Runner, calibrate: bool
) -> EntryResult:
    """Validation runs and τ (when `calibrate`), then the test runs scored at τ."""
    val_runs, fits = calibrate_entry(entry, named, seeds, runner) if calibrate else ({}, {})
    test_runs = run_named(
        runner,
        (entry.test_dir, entry.test_checksum),
        named,
        seeds,
        f"{entry.label} test",
        localisation=entry.localisation,
        sensor=entry.sensor,
    )
    if val_runs:
        calibration.check_disjoint(
            [r for runs in val_runs.values() for r in runs],
            [r for runs in test_runs.values() for r in runs],
        )
    taus = {label: (fits[label].tau if label in fits else None) for label in named}
    ap_rows, pr = ranking_quality(entry.label, test_runs)
    return EntryResult(
        entry=entry,
        named=named,
        taus=taus,
        fits=fits,
        per_pair=score_runs(test_runs, taus, dataset=entry.label, split="test"),
        ap_rows=ap_rows,
        pr=pr,
        qualitative=qualitative_entry(entry, test_runs, taus),
    )


THRESHOLD_COLUMNS = (
    "dataset",
    "matcher",
    "params",
    "tau",
    "val_f1",
    "val_frames",
    "val_runs",
    "val_dir",
)


def _write_variant(
    out_dir: Path,
    variant: str,
    results: Sequence[EntryResult],
    seeds: Sequence[int],
    runner: Runner,
    settings: dict,
) -> None:
    """The files of one variant (:func:`eval.protocol.variants.variant_path`); the PR curves and the
    qualitative-figure input only for the main variant."""
    tau_rows = [
        {
            "dataset": r.entry.label,
            "matcher": label,
            "params": tuning.params_json(dict(r.named[label].options)),
            "tau": fit.tau,
            "val_f1": fit.val_f1,
            "val_frames": fit.frames,
            "val_runs": fit.runs,
            "val_dir": recorded_path(r.entry.val_dir),
        }
        for r in results
        for label, fit in r.fits.items()
    ]
    if variant != PAPER:
        write_csv(
            pd.DataFrame(tau_rows, columns=list(THRESHOLD_COLUMNS)),
            variant_path(out_dir, "thresholds", variant, ".csv"),
        )
    write_csv(
        pd.concat([r.per_pair for r in results], ignore_index=True),
        variant_path(out_dir, "metrics_per_pair", variant, ".csv"),
    )
    write_csv(
        pd.DataFrame([a for r in results for a in r.ap_rows]),
        variant_path(out_dir, "average_precision", variant, ".csv"),
    )
    if variant == MAIN:
        write_csv(
            pd.concat([r.pr for r in results], ignore_index=True).round(6),
            out_dir / "pr_curves.csv",
        )
        qualitative = {r.entry.label: r.qualitative for r in results if r.qualitative}
        write_text(out_dir / "qualitative.json", json.dumps(qualitative, indent=1))
    record = {
        "datasets": [
            asdict(r.entry)
            | {
                "test_dir": recorded_path(r.entry.test_dir),
                "val_dir": recorded_path(r.entry.val_dir),
            }
            for r in results
        ],
        "matchers": list(results[0].named) if results else [],
        "seeds": list(seeds),
        **settings,
        "thresholds": {r.entry.label: r.taus for r in results},
        "params": {
            r.entry.label: {label: dict(spec.options) for label, spec in r.named.items()}
            for r in results
        },
        "code_version": runner.version,
        "cache": str(runner.cache.root),
    }
    write_text(variant_path(out_dir, "evaluation", variant, ".json"), json.dumps(record, indent=1))


def evaluate(
    entries: Sequence[DatasetEntry],
    matchers: Sequence[MatcherSpec],
    seeds: Sequence[int],
    runner: Runner,
    out_dir: str | Path,
    calibrate: bool = True,
    tune: bool = False,
    protocol: str = "calibrated",
    tune_limit: int | None = None,
    untuned: bool = True,
) -> dict:
    """The whole evaluation of one protocol; writes into `out_dir` the variant files of
    :mod:`eval.protocol.variants` (thresholds, metrics_per_pair, average_precision, evaluation.json; the
    main variant also pr_curves.csv and qualitative.json; with `tune` also ``tuning.csv`` and the
    untuned variant, unless `untuned` is False; `tune_limit`: tune on the first N validation
    pairs only). Returns the τ table of the main (or paper) variant as
    {dataset label: {matcher label: τ or None}}."""
    protocol = check_protocol(protocol)
    if protocol == "paper" and tune:
        raise ValueError("--tune: the paper protocol runs every matcher untuned")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    labels = [e.label for e in entries]
    if len(set(labels)) != len(labels):
        raise ValueError(f"datasets: two test datasets of the same scenario kind {labels}")
    base = as_named(matchers)
    main_variant = MAIN
    if protocol == "equal_cues":
        base = {label: equal_cue_spec(spec) for label, spec in base.items()}
        main_variant, untuned, protocol = EQUAL, False, "calibrated"
    calibrate = calibrate and protocol == "calibrated"
    results: dict[str, list[EntryResult]] = {}
    choices: list[tuning.TuningChoice] = []
    for entry in entries:
        if (calibrate or tune) and entry.val_dir is None:
            raise ValueError(
                f"{entry.test_dir}: no validation dataset (give --val DIR or create "
                f"{entry.test_dir}-val), or pass --no-calibration"
            )
        if protocol == "paper":
            named = {label: paper_spec(spec) for label, spec in base.items()}
            results.setdefault(PAPER, []).append(
                evaluate_entry(entry, named, seeds, runner, calibrate=False)
            )
            continue
        if tune:
            chosen = tuning.tune_entry(entry, base, runner, tune_limit, entry.localisation)
            choices += chosen.values()
            named = {label: chosen[label].spec for label in base}
            if untuned:
                results.setdefault(UNTUNED, []).append(
                    evaluate_entry(entry, base, seeds, runner, calibrate)
                )
            results.setdefault(main_variant, []).append(
                evaluate_entry(entry, named, seeds, runner, calibrate)
            )
        else:
            results.setdefault(main_variant, []).append(
                evaluate_entry(entry, base, seeds, runner, calibrate)
            )
    for variant, variant_results in results.items():
        settings = {
            "protocol": protocol,
            "calibrated": calibrate,
            "tuned": tune and variant == main_variant,
        }
        if variant == EQUAL:
            settings["protocol"] = "equal_cues"
        _write_variant(out_dir, variant, variant_results, seeds, runner, settings)
    if tune:
        write_csv(
            pd.DataFrame(tuning.tuning_rows(choices)),
            variant_path(out_dir, "tuning", main_variant, ".csv"),
        )
    main = results.get(PAPER if protocol == "paper" else main_variant, [])
    return {r.entry.label: r.taus for r in main}


def chosen_specs(
    out_dir: str | Path, label: str, matchers: Sequence[MatcherSpec]
) -> tuple[Named, dict[str, float | None]]:
    """The spec (tuned parameters included) and τ of each matcher on dataset `label`, as the
    main variant's ``thresholds.csv`` in `out_dir` records them; a matcher it lacks runs as
    requested with no τ (None)."""
    named, taus = as_named(matchers), {}
    path = Path(out_dir) / "thresholds.csv"
    if not path.is_file():
        return named, {m: None for m in named}
    table = pd.read_csv(path, keep_default_na=False, na_values=[""])
    table = table[table["dataset"] == label]
    for row in table.itertuples(index=False):
        if row.matcher not in named:
            continue
        params = json.loads(row.params) if "params" in table.columns and row.params else {}
        named[row.matcher] = MatcherSpec.of(named[row.matcher].name, **params)
        taus[row.matcher] = None if pd.isna(row.tau) else float(row.tau)
    return named, {m: taus.get(m) for m in named}


def val_dirs(datasets: Sequence[str], given: Sequence[str] | None) -> list[str | None]:
    """Validation dataset per test dataset: `given` in order, else ``DIR-val`` if it exists."""
    if given:
        if len(given) != len(datasets):
            raise ValueError(f"--val: {len(given)} directories for {len(datasets)} datasets")
        return list(given)
    candidates = [str(Path(d).with_name(Path(d).name + "-val")) for d in datasets]
    return [c if (Path(c) / "manifest.json").is_file() else None for c in candidates]
