"""Does what is learned in simulation hold on data we did not make? The transfer matrix of the
learned matchers, ``results/table_transfer.{md,csv}`` (docs/learned.md, "The transfer matrix").

Training sets (:func:`train_sets`; never a test split): cadsim's CAD
training split, cadsim's CAD-V2X training split, both together (:data:`SIM_ONLY`, "trained on
cadsim only", the row the goals read), and the first :data:`EXTERNAL_TRAIN_PAIRS` frame pairs of
DMGM's calibration sequence 070 (:data:`EXTERNAL_TRAIN`). Test sets (:func:`test_sets`):
cadsim's CAD test split, cadsim's CAD-V2X test split (its own ``gnss-urban`` prior, re-drawn per
run) and DMGM's sequences 069 + 071. Every model × test set: the four learned matchers
(``learned``, ``learned_pose``, ``maximin_learned``, ``rrwm_learned``), one run
(``maximin_learned`` samples triangles with seed 0; the others are deterministic);
``maximin_learned`` and ``rrwm_learned`` take the kernel widths that maximin and RRWM were tuned
to on the same validation split by the main tables (no extra search).

τ never comes from a pair a model was trained on. On the cadsim test sets τ is calibrated on the
test set's validation split (its own scenario seeds, disjoint from every training split). On
DMGM the only non-test data is sequence 070, so it is split by frame order
(:func:`split_external`): pairs 1–100 train the DMGM model, the next :data:`EXTERNAL_GAP` are
dropped (consecutive frames are near-copies), and pairs 111–201 are the τ split of *every*
learned row on DMGM — the same τ data for every model, so the transfer gap compares models, not
calibration sets. :func:`check_tau_split` refuses a model that shares a record (by checksum) with
its τ split, and :func:`eval.protocol.model_options.check_no_overlap` one that shares a record with
a test set; both are checked for every model × test set before anything runs.

Beside every row, the best hand-crafted matcher of the same kind (with the prior for
``learned_pose``, without it for the rest) *chosen on the validation split* — the largest pooled
F1 of the main tables' matchers on the validation split they were calibrated on (on DMGM all
of 070), each at its own τ (:func:`validation_pooled_f1`, :func:`choose_reference`) — and its *test* pooled F1 and AP. The
difference learned − hand-crafted (pooled F1, the same test pairs) carries a 95 % cluster
t-interval (:func:`pooled_f1_terms`, :func:`paired_interval`): the pooled F1 2ΣTP / (Σ|M| + Σ|G|)
linearised per frame pair (delta method), then
:func:`eval.protocol.cluster_interval.t_interval` over clusters — simulation episodes on cadsim,
blocks of :data:`eval.studies.agreement.EXTERNAL_BLOCK` consecutive pairs of one sequence on
DMGM (its test pairs come from only two sequences, too few clusters). The goals
(:func:`goals`) read these intervals through :mod:`eval.protocol.goal_verdict`: "met" only when
the whole interval clears the bar.
"""

from __future__ import annotations

import json
import logging
import math
import re
import shutil
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from eval.core.result_files import write_csv, write_text
from eval.core.runner import Runner
from eval.core.tasks import MatcherSpec
from eval.engine.result_table import read_result
from eval.protocol.claims import measurement_line
from eval.protocol.cluster_interval import t_interval
from eval.protocol.goal_verdict import goal_line
from eval.protocol.metrics import summarise_pooled
from eval.protocol.model_options import with_model
from eval.protocol.variants import MAIN, variant_path
from eval.report.tables import build_table
from eval.report.threshold_format import rounded
from eval.studies.agreement import EXTERNAL_BLOCK, pair_clusters
from eval.studies.evaluation import chosen_specs, evaluate, open_entry, run_named, score_runs
from matchers.learned.model import load_model

log = logging.getLogger(__name__)

SUBDIR = "transfer"
LEARNED = ("learned", "learned_pose", "maximin_learned", "rrwm_learned")
HYBRID_BASES = {"maximin_learned": "maximin", "rrwm_learned": "rrwm"}
EXCLUDED = {"none", "dmgm_published", *LEARNED}
SIM_ONLY = "cadsim CAD + CAD-V2X train"  # the "trained on cadsim only" model of the goals
# DMGM's sequence 070 split by frame order: the first EXTERNAL_TRAIN_PAIRS train the DMGM model
# (as many pairs as SIM_ONLY's two 50-pair splits), EXTERNAL_GAP are dropped, the rest are the
# τ split of the learned rows on DMGM (split_external).
EXTERNAL_TRAIN_PAIRS = 100
EXTERNAL_GAP = EXTERNAL_BLOCK
EXTERNAL_SPLIT = ("dmgm-070-train", "dmgm-070-calibration")  # folders under the data folder
EXTERNAL_TRAIN = "DMGM 070 (pairs 1–100)"
EXTERNAL_TEST = "DMGM 069 + 071"
GOAL_BEATS = 0.0  # learned − hand-crafted pooled F1 ≥ 0
GOAL_PRIOR_F1 = 0.97  # learned_pose pooled F1 ≥ 97 %
GOAL_GAP = 0.05  # DMGM-trained − cadsim-trained pooled F1 ≤ 5 points
GOAL_SECONDS = 120
COLUMNS = [
    "train",
    "test",
    "matcher",
    "uses_prior",
    "f1_pooled",
    "f1_pooled_low",
    "f1_pooled_high",
    "ap",
    "tau",
    "tau_split",
    "frames",
    "handcrafted",
    "handcrafted_matcher",
    "handcrafted_val_f1_pooled",
    "handcrafted_f1_pooled",
    "handcrafted_ap",
    "diff_handcrafted",
    "diff_handcrafted_low",
    "diff_handcrafted_high",
    "diff_sim_only",
    "diff_sim_only_low",
    "diff_sim_only_high",
    "clusters",
    "cluster_unit",
    "model_sha256",
]
GAP_COLUMNS = ("diff_sim_only", "diff_sim_only_low", "diff_sim_only_high")


@dataclass(frozen=True)
class TestSet:
    """A test split, the split the learned matchers' τ is calibrated on (``val_dir``), the prior
    preset it is scored under (None: the records' own), where the main tables evaluated the
    hand-crafted matchers on it, and the cluster of its intervals (``block`` None: the
    simulation episode; N: blocks of N consecutive pairs of one sequence)."""

    label: str
    test_dir: Path
    val_dir: Path
    localisation: str | None
    reference_dir: Path
    reference_label: str
    block: int | None = None

    @property
    def cluster_unit(self) -> str:
        return "episode" if self.block is None else f"block of {self.block} pairs"


def split_external(source: Path, data: Path) -> tuple[Path, Path]:
    """(training part, τ part) of the external calibration dataset at ``source``, written once
    into ``data/``:data:`EXTERNAL_SPLIT` (copies of its records, a manifest naming the source):
    the first :data:`EXTERNAL_TRAIN_PAIRS` records in dataset (frame) order, then — after
    :data:`EXTERNAL_GAP` dropped records — the rest. Disjoint by construction; rewritten only
    when missing or not what ``source`` gives now."""
    from cadsim.dataset.reader import Dataset

    source = Path(source)
    records = Dataset(source, verify=True).manifest["records"]
    start = EXTERNAL_TRAIN_PAIRS + EXTERNAL_GAP
    if len(records) <= start:
        raise ValueError(
            f"{source}: {len(records)} frame pairs; the transfer split needs more than {start} "
            f"({EXTERNAL_TRAIN_PAIRS} to train on, {EXTERNAL_GAP} dropped, the rest for τ)"
        )
    parts = (records[:EXTERNAL_TRAIN_PAIRS], records[start:])
    roles = ("training", "tau calibration")
    out = []
    for name, part, role in zip(EXTERNAL_SPLIT, parts, roles, strict=True):
        out.append(_write_subset(source, Path(data) / name, part, role))
    return out[0], out[1]


def _write_subset(source: Path, target: Path, records: list[dict], role: str) -> Path:
    """``target``: the dataset of ``records`` of ``source`` (unchanged when already so)."""
    from cadsim.dataset import layout
    from cadsim.dataset.checksum import dataset_checksum
    from cadsim.dataset.manifest import read_manifest, write_manifest
    from cadsim.dataset.reader import Dataset

    manifest = read_manifest(source)
    checksum = dataset_checksum(r["checksum"] for r in records)
    if (target / layout.MANIFEST).is_file():
        try:
            if Dataset(target, verify=True).checksum == checksum:
                return target
        except Exception as exc:  # a stale or broken copy: rewritten below
            log.info("[transfer] rewriting %s (%s)", target, exc)
    names = [r["name"] for r in records]
    manifest |= {
        "records": records,
        "pairs": len(records),
        "checksum": checksum,
        "subset": {
            "of": source.name,
            "of_checksum": manifest["checksum"],
            "role": role,
            "first": names[0],
            "last": names[-1],
            "rule": (
                f"frame order: the first {EXTERNAL_TRAIN_PAIRS} pairs train, {EXTERNAL_GAP} "
                "dropped, the rest calibrate τ (eval.studies.transfer.split_external)"
            ),
        },
    }
    staging = target.with_name(target.name + ".tmp")
    shutil.rmtree(staging, ignore_errors=True)
    (staging / layout.PAIRS_DIR).mkdir(parents=True)
    for name in names:
        shutil.copytree(source / layout.PAIRS_DIR / name, staging / layout.PAIRS_DIR / name)
    write_manifest(staging, manifest)
    shutil.rmtree(target, ignore_errors=True)
    staging.rename(target)
    Dataset(target, verify=True)
    return target


def train_sets(data: Path, cad_train: Path, external_train: Path) -> dict[str, list[Path]]:
    """{training-set label: dataset folders}: labels start with ``cadsim`` (simulated) or
    ``DMGM`` (external); the DMGM model trains on the training part of ``external_train``
    (:func:`split_external`, written into ``data``)."""
    v2x_train = Path(data) / "cad-v2x-train"
    external, _ = split_external(external_train, data)
    return {
        "cadsim CAD train": [cad_train],
        "cadsim CAD-V2X train": [v2x_train],
        SIM_ONLY: [cad_train, v2x_train],
        EXTERNAL_TRAIN: [external],
    }


def test_sets(data: Path, out: Path, external_test: Path, external_val: Path) -> list[TestSet]:
    """The three test sets, with the folders of the main tables' evaluations of them; on DMGM
    the learned matchers' τ comes from the τ part of ``external_val`` (:func:`split_external`),
    its intervals cluster blocks of :data:`EXTERNAL_BLOCK` consecutive pairs."""
    data, out = Path(data), Path(out)
    _, external_tau = split_external(external_val, data)
    return [
        TestSet("cadsim CAD test", data / "cad", data / "cad-val", None, out, "CAD"),
        TestSet(
            "cadsim CAD-V2X test",
            data / "cad-v2x",
            data / "cad-v2x-val",
            "gnss-urban",
            out / "v2x" / "gnss-urban",
            "CAD-V2X",
        ),
        TestSet(
            EXTERNAL_TEST,
            Path(external_test),
            external_tau,
            None,
            out / "external",
            "DMGM",
            EXTERNAL_BLOCK,
        ),
    ]


def slug(label: str) -> str:
    """A folder name for a label: ``cadsim CAD + CAD-V2X train`` -> ``cadsim-cad-cad-v2x-train``."""
    return re.sub(r"[^a-z0-9]+", "-", label.lower()).strip("-")


def train_models(
    sets: dict[str, list[Path]], folder: Path, progress: bool = False
) -> dict[str, tuple[Path, float]]:
    """Train one model per training set into ``folder`` (``cadsim train``'s path); {label:
    (model file, seconds)}."""
    from cadsim.commands.train import train_datasets

    models = {}
    for label, dirs in sets.items():
        started = time.perf_counter()
        path = folder / f"{slug(label)}.json"
        model = _trained_already(path, dirs)
        if model is None:
            sha, model = train_datasets([str(d) for d in dirs], path, progress=progress)
        else:
            sha = model.sha256
        seconds = time.perf_counter() - started
        log.info(
            "[transfer] %s: %s (%s candidate matches) in %.1f s, sha256 %s",
            label,
            path,
            ", ".join(f"{k} {v:,}" for k, v in model.training["rows"].items()),
            seconds,
            sha[:12],
        )
        models[label] = (path, seconds)
    return models


def _trained_already(path: Path, dirs: Sequence[Path]):
    """The model at ``path`` when it was trained, with today's features and parameters, on
    exactly the datasets at ``dirs`` (training is deterministic: training again would write the
    same bytes); else None."""
    from cadsim.dataset import Dataset
    from matchers.learned.training import PARAMS, ROUNDS

    if not path.is_file():
        return None
    try:
        model = load_model(path)
    except ValueError:
        return None
    recorded = [d.get("checksum") for d in model.training.get("datasets", [])]
    same = recorded == [Dataset(d, verify=True).checksum for d in dirs]
    same = same and model.training.get("params") == PARAMS
    return model if same and model.training.get("rounds") == ROUNDS else None


def check_tau_split(model_path: str | Path, val_dir: str | Path) -> None:
    """ValueError in one line when the model at ``model_path`` was trained on a record (by
    checksum) of ``val_dir``, the split its τ would be calibrated on."""
    from cadsim.dataset.training_set import overlapping_records

    trained = load_model(model_path).training_records()
    shared = overlapping_records(trained, [val_dir])
    if shared:
        raise ValueError(
            f"{model_path}: trained on {shared[str(val_dir)]} record(s) of {val_dir}, the split "
            "its τ would be calibrated on; calibrate τ on pairs the model was not trained on"
        )


def _hybrid_options(test: TestSet) -> dict[str, dict]:
    """The kernel widths maximin and RRWM were tuned to on ``test``'s validation split."""
    bases = [MatcherSpec(b) for b in HYBRID_BASES.values()]
    named, _ = chosen_specs(test.reference_dir, test.reference_label, bases)
    return {hybrid: dict(named[base].options) for hybrid, base in HYBRID_BASES.items()}


# --- intervals -----------------------------------------------------------------------------


def pooled_f1_terms(per_pair: pd.DataFrame) -> pd.DataFrame:
    """(pair, episode, value) per frame pair of one matcher's per-pair rows (columns pair,
    episode, seed, tp, n_pred, n_gt): in each run, the pooled F1 F = 2ΣTP / (Σ|M| + Σ|G|) plus
    the pair's linearised share, N · (2 tp − F (|M| + |G|)) / (Σ|M| + Σ|G|) (delta method; its
    mean over the pairs is 0), averaged over the runs. The mean of ``value`` is the mean over
    runs of the pooled F1 (the table's ``f1_pooled``); its cluster-robust variance is the
    delta-method variance. NaN values where a run has no match and no ground truth at all."""
    missing = [c for c in ("pair", "episode", "seed", "tp", "n_pred", "n_gt") if c not in per_pair]
    if missing:
        raise ValueError(f"per_pair: missing columns {missing}")
    if per_pair.empty:
        raise ValueError("per_pair: no rows")
    pairs = np.sort(per_pair["pair"].unique())
    values = []
    for seed, run in per_pair.groupby("seed", sort=True):
        run = run.sort_values("pair")
        if not np.array_equal(run["pair"].to_numpy(), pairs):
            raise ValueError(f"per_pair: run {seed} does not hold each frame pair once")
        tp = run["tp"].to_numpy(float)
        size = run["n_pred"].to_numpy(float) + run["n_gt"].to_numpy(float)
        total = size.sum()
        if total <= 0:
            values.append(np.full(len(pairs), np.nan))
            continue
        f1 = 2 * tp.sum() / total
        values.append(f1 + len(pairs) * (2 * tp - f1 * size) / total)
    episodes = per_pair.groupby("pair")["episode"].first().reindex(pairs).to_numpy()
    return pd.DataFrame({"pair": pairs, "episode": episodes, "value": np.mean(values, axis=0)})


def paired_interval(
    a: pd.DataFrame, b: pd.DataFrame | None = None, block: int | None = None
) -> tuple[float, float, float, int]:
    """(value, low, high, clusters): the pooled F1 of ``a`` (or the difference a − b on the same
    frame pairs) with its 95 % cluster t-interval; clusters are episodes, or with ``block``
    blocks of ``block`` consecutive pairs of one episode. ``a``, ``b``: :func:`pooled_f1_terms`.
    ValueError when ``b`` holds other frame pairs; NaN interval with one cluster."""
    terms = a[["pair", "episode", "value"]]
    bounds = (0.0, 1.0)
    if b is not None:
        merged = a.merge(b, on="pair", how="outer", suffixes=("_a", "_b"), indicator=True)
        same = (merged["_merge"] == "both").all()
        if not same or not (merged["episode_a"] == merged["episode_b"]).all():
            raise ValueError("paired_interval: the two matchers were scored on other frame pairs")
        terms = pd.DataFrame(
            {
                "pair": merged["pair"],
                "episode": merged["episode_a"],
                "value": merged["value_a"] - merged["value_b"],
            }
        )
        bounds = (-1.0, 1.0)
    if terms["value"].isna().any():
        return math.nan, math.nan, math.nan, 0
    clusters = pair_clusters(terms, block).reindex(terms["pair"]).to_numpy()
    return t_interval(terms["value"].to_numpy(), clusters, bounds=bounds)


def _terms_of(out_dir: Path, label: str, matcher: str) -> pd.DataFrame | None:
    """:func:`pooled_f1_terms` of ``matcher`` on dataset ``label`` in ``out_dir``'s main
    per-pair metrics (None where absent)."""
    path = variant_path(out_dir, "metrics_per_pair", MAIN, ".csv")
    if not path.is_file():
        return None
    per_pair = pd.read_csv(path, keep_default_na=False, na_values=[""])
    rows = per_pair[(per_pair["dataset"] == label) & (per_pair["matcher"] == matcher)]
    return pooled_f1_terms(rows) if len(rows) else None


# --- the hand-crafted reference --------------------------------------------------------------


def validation_pooled_f1(
    reference_dir: str | Path, label: str, runner: Runner | None = None
) -> dict[str, float]:
    """{matcher: pooled F1 on the validation split at its own τ} of the hand-crafted matchers the
    main tables in ``reference_dir`` calibrated on dataset ``label``: the ``val_f1_pooled``
    column of ``thresholds.csv`` where it has one; else the main tables' own validation runs
    (the specs and τ of ``thresholds.csv``, the split, seeds and prior preset of
    ``evaluation.json``) read through ``runner`` — the result cache holds them from the
    calibration — and scored at τ. Empty without the files (or without ``runner``)."""
    reference_dir = Path(reference_dir)
    path = variant_path(reference_dir, "thresholds", MAIN, ".csv")
    if not path.is_file():
        return {}
    thresholds = pd.read_csv(path, keep_default_na=False, na_values=[""])
    thresholds = thresholds[
        (thresholds["dataset"] == label) & ~thresholds["matcher"].isin(EXCLUDED)
    ]
    if thresholds.empty:
        return {}
    if "val_f1_pooled" in thresholds.columns and thresholds["val_f1_pooled"].notna().all():
        values = thresholds["val_f1_pooled"].astype(float)
        return dict(zip(thresholds["matcher"], values, strict=True))
    record = _evaluation_record(reference_dir, label)
    if runner is None or record is None or not record[0].get("val_dir"):
        return {}
    entry, seeds = record
    specs = [MatcherSpec(m) for m in thresholds["matcher"]]
    named, taus = chosen_specs(reference_dir, label, specs)
    runs = run_named(
        runner,
        (entry["val_dir"], entry["val_checksum"]),
        named,
        seeds,
        f"{label} validation (hand-crafted reference)",
        localisation=entry.get("localisation"),
    )
    scored = score_runs(runs, taus, dataset=label, split="val")
    pooled = summarise_pooled(scored, by=["matcher"])
    return dict(zip(pooled["matcher"], pooled["f1_pooled_mean"].astype(float), strict=True))


def _evaluation_record(reference_dir: Path, label: str) -> tuple[dict, list[int]] | None:
    """(the dataset entry of ``label``, the seeds) of ``reference_dir``'s main evaluation.json."""
    path = variant_path(reference_dir, "evaluation", MAIN, ".json")
    if not path.is_file():
        return None
    record = json.loads(path.read_text(encoding="utf-8"))
    entry = next((d for d in record.get("datasets", []) if d.get("label") == label), None)
    return None if entry is None else (entry, list(record.get("seeds", [])))


def choose_reference(
    val_f1: Mapping[str, float], test_table: pd.DataFrame, priors: set[str]
) -> dict[bool, dict]:
    """{uses prior: {matcher, method, val_f1_pooled, f1_pooled, ap}}: of the hand-crafted
    matchers with a validation pooled F1 (``val_f1``) and a row in ``test_table`` (build_table
    rows of one dataset), per kind (in ``priors`` or not) the one with the largest *validation*
    pooled F1 (ties: the first in ``val_f1``'s order), with its *test* pooled F1 and AP."""
    tested = test_table.set_index("matcher")
    out = {}
    for prior in (False, True):
        kind = [
            m
            for m, f1 in val_f1.items()
            if (m in priors) == prior and m not in EXCLUDED and m in tested.index
            if math.isfinite(f1)
        ]
        if not kind:
            continue
        best = max(kind, key=lambda m: val_f1[m])  # max keeps the first of equal values
        row = tested.loc[best]
        out[prior] = {
            "matcher": best,
            "method": str(row["method"]),
            "val_f1_pooled": float(val_f1[best]),
            "f1_pooled": float(row["f1_pooled_mean"]),
            "ap": float(row["ap_mean"]) if "ap_mean" in row.index else math.nan,
        }
    return out


def reference_for(test: TestSet, test_checksum: str, runner: Runner | None) -> dict[bool, dict]:
    """:func:`choose_reference` on ``test``'s main tables; empty where they have not run, or
    ran on another test dataset than the one at ``test_checksum``."""
    from eval.studies.external import prior_matchers

    record = _evaluation_record(Path(test.reference_dir), test.reference_label)
    if record is None:
        return {}
    if record[0].get("test_checksum") != test_checksum:
        log.warning(
            "[transfer] %s: the main tables in %s scored another dataset; no hand-crafted "
            "reference",
            test.label,
            test.reference_dir,
        )
        return {}
    try:
        table = build_table(test.reference_dir)
    except FileNotFoundError:
        return {}
    table = table[table["dataset"] == test.reference_label].dropna(subset=["f1_pooled_mean"])
    val_f1 = validation_pooled_f1(test.reference_dir, test.reference_label, runner)
    return choose_reference(val_f1, table, set(prior_matchers()))


# --- the matrix -------------------------------------------------------------------------------


def evaluate_transfer(
    models: dict[str, tuple[Path, float]],
    tests: Sequence[TestSet],
    runner: Runner,
    out: Path,
    seeds: Sequence[int] = (0,),
) -> pd.DataFrame:
    """Every model on every test set (module docstring); writes ``out/transfer/<train>/<test>/``
    and ``out/table_transfer.{md,csv}``; returns the table. Every model is checked against every
    test set and τ split first (ValueError before anything runs)."""
    specs = {}
    for test in tests:
        for train, (model_path, _) in models.items():
            check_tau_split(model_path, test.val_dir)
            specs[train, test.label] = with_model(
                [MatcherSpec(n) for n in LEARNED], model_path, [test.test_dir]
            )
    rows = []
    for test in tests:
        entry = open_entry(test.test_dir, test.val_dir, test.reference_label, test.localisation)
        hybrid = _hybrid_options(test)
        reference = reference_for(test, entry.test_checksum, runner)
        reference_terms = {
            prior: _terms_of(Path(test.reference_dir), test.reference_label, ref["matcher"])
            for prior, ref in reference.items()
        }
        terms = {}
        for train in models:
            named = {
                name: MatcherSpec.of(name, **dict(spec.options) | hybrid.get(name, {}))
                for name, spec in specs[train, test.label].items()
            }
            folder = out / SUBDIR / slug(train) / slug(test.label)
            evaluate([entry], named, seeds, runner, folder, untuned=False)
            table = build_table(folder)
            for r in table.itertuples(index=False):
                prior = r.matcher == "learned_pose"
                best = reference.get(prior, {})
                mine = _terms_of(folder, test.reference_label, r.matcher)
                terms[train, r.matcher] = mine
                _, low, high, clusters = paired_interval(mine, block=test.block)
                diff = (math.nan,) * 3
                theirs = reference_terms.get(prior)
                if theirs is not None:
                    diff = paired_interval(mine, theirs, test.block)[:3]
                rows.append(
                    {
                        "train": train,
                        "test": test.label,
                        "matcher": r.matcher,
                        "uses_prior": prior,
                        "f1_pooled": r.f1_pooled_mean,
                        "f1_pooled_low": low,
                        "f1_pooled_high": high,
                        "ap": r.ap_mean,
                        "tau": getattr(r, "tau", np.nan),
                        "tau_split": Path(test.val_dir).name,
                        "frames": int(r.frames),
                        "handcrafted": best.get("method", ""),
                        "handcrafted_matcher": best.get("matcher", ""),
                        "handcrafted_val_f1_pooled": best.get("val_f1_pooled", np.nan),
                        "handcrafted_f1_pooled": best.get("f1_pooled", np.nan),
                        "handcrafted_ap": best.get("ap", np.nan),
                        "diff_handcrafted": diff[0],
                        "diff_handcrafted_low": diff[1],
                        "diff_handcrafted_high": diff[2],
                        "clusters": clusters,
                        "cluster_unit": test.cluster_unit,
                        "model_sha256": dict(named[r.matcher].options)["model_sha256"],
                    }
                )
        for row in rows:
            if row["test"] != test.label or row["train"] == SIM_ONLY:
                continue
            base = terms.get((SIM_ONLY, row["matcher"]))
            if base is not None:
                gap = paired_interval(terms[row["train"], row["matcher"]], base, test.block)[:3]
                row |= dict(zip(GAP_COLUMNS, gap, strict=True))
    table = pd.DataFrame(rows, columns=COLUMNS)
    write_csv(rounded(table), out / "table_transfer.csv")
    write_text(out / "table_transfer.md", to_markdown(table))
    return table


def _pct(value: float) -> str:
    return "–" if pd.isna(value) else f"{100 * value:.1f}"


def _points(value: float, low: float, high: float) -> str:
    """``+1.2 [−3.4, 5.6]`` (percentage points), ``–`` without a value."""
    if pd.isna(value):
        return "–"
    shown = f"{100 * value:+.1f}"
    if pd.isna(low) or pd.isna(high):
        return shown + " (no interval)"
    return shown + f" [{100 * low:+.1f}, {100 * high:+.1f}]"


def to_markdown(table: pd.DataFrame) -> str:
    """The transfer matrix: one block per test set, a row per (training set, learned matcher),
    the hand-crafted matcher of the same kind chosen on validation beside it (percent), and the
    difference with its interval (percentage points)."""
    lines = [
        "Transfer of the learned matchers (pooled F1 and AP, percent). τ of every learned row "
        "from pairs its model was not trained on: each cadsim test set's validation split; on "
        "DMGM pairs 111–201 of sequence 070 (pairs 1–100 train the DMGM model). Beside each "
        "row, the hand-crafted matcher of the same kind (with or without the prior) with the "
        "best pooled F1 on the *validation* split, and its *test* figures. Δ: learned − "
        "hand-crafted pooled F1 on the same test pairs, percentage points, with its 95 % "
        "cluster t-interval (episodes; on DMGM blocks of 10 consecutive pairs).",
        "",
    ]
    header = ["Trained on", "Matcher", "Pooled F1", "AP", "Hand-crafted (chosen on val.)"]
    header += ["its F1", "its AP", "Δ F1 [95 % CI]"]
    table = table.reindex(columns=list(dict.fromkeys([*COLUMNS, *table.columns])))
    for test, rows in table.groupby("test", sort=False):
        frames = rows["frames"].max()
        shown = [] if pd.isna(frames) else [f"{int(frames)} frame pairs"]
        shown += [_clusters_text(rows.iloc[0], "in")] if pd.notna(rows["clusters"].max()) else []
        lines += [f"**Tested on {test}**" + (f" ({' '.join(shown)})" if shown else ""), ""]
        lines += ["| " + " | ".join(header) + " |", "|:---|:---|---:|---:|:---|---:|---:|---:|"]
        for r in rows.itertuples(index=False):
            cells = [
                r.train,
                r.matcher,
                _pct(r.f1_pooled),
                _pct(r.ap),
                r.handcrafted if isinstance(r.handcrafted, str) and r.handcrafted else "–",
                _pct(r.handcrafted_f1_pooled),
                _pct(r.handcrafted_ap),
                _points(r.diff_handcrafted, r.diff_handcrafted_low, r.diff_handcrafted_high),
            ]
            lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines)


# --- goals ------------------------------------------------------------------------------------


def _row(table: pd.DataFrame, train: str, matcher: str) -> pd.Series | None:
    rows = table[
        (table["train"] == train) & (table["test"] == EXTERNAL_TEST) & (table["matcher"] == matcher)
    ]
    return rows.iloc[0] if len(rows) else None


def _get(row: pd.Series | None, column: str) -> float:
    if row is None or column not in row.index:
        return math.nan
    try:
        return float(row[column])
    except (TypeError, ValueError):
        return math.nan


def _chosen(row: pd.Series | None, method: str) -> str:
    """How the reference was chosen: ``X chosen on the validation split (its pooled F1 there
    70.2)``; a table without validation figures (an older file) says so."""
    val = _get(row, "handcrafted_val_f1_pooled")
    if math.isfinite(val):
        return f"{method} chosen on the validation split (its pooled F1 there {_pct(val)})"
    return f"{method} not chosen on validation (a table without validation figures)"


def _clusters_text(row: pd.Series | None, lead: str = "95 % cluster t-interval over") -> str:
    """``95 % cluster t-interval over 12 blocks of 10 pairs`` (``lead`` first)."""
    count = _get(row, "clusters")
    unit = row.get("cluster_unit") if row is not None else None
    if not math.isfinite(count) or not isinstance(unit, str):
        return "95 % cluster t-interval"
    plural = unit.replace("block", "blocks", 1) if unit.startswith("block") else unit + "s"
    text = f"{lead} {int(count)} {plural if int(count) != 1 else unit}"
    if unit.startswith("block") and lead != "in":  # DMGM's test pairs: two sequences
        text += " from 2 sequences (blocks of one sequence are not independent clusters)"
    return text


def goals(
    table: pd.DataFrame, stage_s: float | None = None, computed: int | None = None
) -> list[str]:
    """The study's goals, each with its figure, its 95 % interval and its verdict
    (:func:`eval.protocol.goal_verdict.goal_line`: met only when the whole interval clears the
    bar); ``stage_s`` the transfer stage's seconds in the last cold run, ``computed`` how many of its runs
    it computed (0: all cached)."""
    out = []
    free = _row(table, SIM_ONLY, "learned")
    method = free.get("handcrafted") if free is not None else None
    method = method if isinstance(method, str) and method else "the best hand-crafted matcher"
    out.append(
        goal_line(
            "trained on cadsim only, no prior, beats the best hand-crafted matcher on DMGM "
            "069 + 071 (learned − hand-crafted pooled F1 ≥ 0)",
            _get(free, "diff_handcrafted"),
            _get(free, "diff_handcrafted_low"),
            _get(free, "diff_handcrafted_high"),
            GOAL_BEATS,
            unit=" points",
            detail=f"pooled F1 {_pct(_get(free, 'f1_pooled'))} against {method}'s "
            f"{_pct(_get(free, 'handcrafted_f1_pooled'))}, {_chosen(free, method)}; "
            f"{_clusters_text(free)}",
        )
    )
    pose = _row(table, SIM_ONLY, "learned_pose")
    pose_method = pose.get("handcrafted") if pose is not None else None
    pose_method = pose_method if isinstance(pose_method, str) and pose_method else "–"
    out.append(
        goal_line(
            "trained on cadsim only, with the prior: pooled F1 on DMGM 069 + 071 ≥ 97.0",
            _get(pose, "f1_pooled"),
            _get(pose, "f1_pooled_low"),
            _get(pose, "f1_pooled_high"),
            GOAL_PRIOR_F1,
            detail=f"learned − {pose_method} ({_chosen(pose, pose_method)}): "
            + _points(
                _get(pose, "diff_handcrafted"),
                _get(pose, "diff_handcrafted_low"),
                _get(pose, "diff_handcrafted_high"),
            )
            + f" points; {_clusters_text(pose)}",
        )
    )
    for matcher in ("learned", "learned_pose"):
        external = _row(table, EXTERNAL_TRAIN, matcher)
        base = _row(table, SIM_ONLY, matcher)
        out.append(
            goal_line(
                f"transfer gap of {matcher} (DMGM-070-trained minus cadsim-trained pooled F1, "
                "on DMGM 069 + 071, ≤ 5.0 points)",
                _get(external, "diff_sim_only"),
                _get(external, "diff_sim_only_low"),
                _get(external, "diff_sim_only_high"),
                GOAL_GAP,
                at_least=False,
                unit=" points",
                detail="against the hand-crafted reference: DMGM-trained "
                + _points(
                    _get(external, "diff_handcrafted"),
                    _get(external, "diff_handcrafted_low"),
                    _get(external, "diff_handcrafted_high"),
                )
                + ", cadsim-trained "
                + _points(
                    _get(base, "diff_handcrafted"),
                    _get(base, "diff_handcrafted_low"),
                    _get(base, "diff_handcrafted_high"),
                )
                + f"; {_clusters_text(external)}",
            )
        )
    if stage_s is not None and computed:
        out.append(
            measurement_line(
                "training and evaluation of the learned rows",
                stage_s,
                GOAL_SECONDS,
                f"last cold run, results/cold_run.json; {computed} runs computed",
            )
        )
    elif stage_s is not None:
        out.append(
            f"training and evaluation of the learned rows: {stage_s:.0f} s in this run, every "
            f"run cached and the models reused (the goal, ≤ {GOAL_SECONDS} s cold, is read from a "
            "cold run: the README's timing paragraph)"
        )
    return out


def readme_part(
    results: Path, rel: str, stage_s: float | None = None, computed: int | None = None
) -> list[str]:
    """README lines "Does simulation transfer?" (none without ``table_transfer.csv``)."""
    table = read_result(results, "table_transfer.csv")
    if table is None:
        return []
    table = table.reindex(columns=list(dict.fromkeys([*COLUMNS, *table.columns])))  # older files
    external = table[table["test"] == EXTERNAL_TEST]
    return [
        "### Does simulation transfer?",
        "",
        "Learned matchers (gradient-boosted trees on motion-invariant candidate-pair features, "
        "docs/learned.md) trained on cadsim's training splits or on the first 100 pairs of "
        "DMGM's calibration sequence 070, τ from pairs 111–201 of 070, tested on DMGM's 069 + "
        f"071 (every test set: [{rel}/table_transfer.md]({rel}/table_transfer.md)):",
        "",
        to_markdown(external).split("\n", 2)[2].strip(),
        "",
        *[f"- {line}." for line in goals(table, stage_s, computed)],
        "",
    ]
