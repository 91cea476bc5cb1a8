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
blocks of :data:`eval.studies.external.agreement.EXTERNAL_BLOCK` consecutive pairs of one sequence on
DMGM (its test pairs come from only two sequences, too few clusters). The goals
(:func:`eval.studies.transfer.report.goals`) read these intervals through
:mod:`eval.protocol.goal_verdict`: "met" only when the whole interval clears the bar.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from eval.core.result_files import write_csv, write_text
from eval.core.runner import Runner
from eval.core.tasks import MatcherSpec
from eval.engine.protocol_run import evaluate
from eval.engine.splits import open_entry
from eval.engine.validation_choice import chosen_specs
from eval.protocol.model_options import with_model
from eval.protocol.variants import MAIN, variant_path
from eval.report.tables import build_table
from eval.report.threshold_format import rounded
from eval.studies.transfer.gap import paired_interval, pooled_f1_terms
from eval.studies.transfer.matrix import COLUMNS, GAP_COLUMNS, to_markdown
from eval.studies.transfer.reference import LEARNED, reference_for, validation_pooled_f1
from eval.studies.transfer.sets import (
    EXTERNAL_TEST,
    EXTERNAL_TRAIN,
    EXTERNAL_TRAIN_PAIRS,
    SIM_ONLY,
    TestSet,
    slug,
    split_external,
    test_sets,
    train_sets,
)
from matchers.learned.model import load_model

log = logging.getLogger(__name__)

SUBDIR = "transfer"
HYBRID_BASES = {"maximin_learned": "maximin", "rrwm_learned": "rrwm"}
GOAL_BEATS = 0.0  # learned − hand-crafted pooled F1 ≥ 0
GOAL_PRIOR_F1 = 0.97  # learned_pose pooled F1 ≥ 97 %
GOAL_GAP = 0.05  # DMGM-trained − cadsim-trained pooled F1 ≤ 5 points
GOAL_SECONDS = 120


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
    from eval.protocol.model_options import overlapping_records

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


def _terms_of(out_dir: Path, label: str, matcher: str) -> pd.DataFrame | None:
    """:func:`pooled_f1_terms` of ``matcher`` on dataset ``label`` in ``out_dir``'s main
    per-pair metrics (None where absent)."""
    path = variant_path(out_dir, "metrics_per_pair", MAIN, ".csv")
    if not path.is_file():
        return None
    per_pair = pd.read_csv(path, keep_default_na=False, na_values=[""])
    rows = per_pair[(per_pair["dataset"] == label) & (per_pair["matcher"] == matcher)]
    return pooled_f1_terms(rows) if len(rows) else None


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


__all__ = [
    "COLUMNS",
    "EXTERNAL_TEST",
    "EXTERNAL_TRAIN",
    "EXTERNAL_TRAIN_PAIRS",
    "GAP_COLUMNS",
    "LEARNED",
    "SIM_ONLY",
    "SUBDIR",
    "TestSet",
    "check_tau_split",
    "evaluate_transfer",
    "paired_interval",
    "pooled_f1_terms",
    "reference_for",
    "split_external",
    "test_sets",
    "to_markdown",
    "train_models",
    "train_sets",
    "validation_pooled_f1",
]
