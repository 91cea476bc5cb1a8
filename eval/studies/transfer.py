"""Does what is learned in simulation hold on data we did not make? The transfer matrix of the
learned matchers, ``results/table_transfer.{md,csv}``.

Training sets (training seeds only, never a validation or test split; :data:`TRAIN_SETS`):
cadsim's CAD training split, cadsim's CAD-V2X training split, both together ("trained on cadsim
only", the row the goals read), and the external DMGM sequence 070 (its calibration sequence).
Test sets (:data:`TEST_SETS`): cadsim's CAD test split, cadsim's CAD-V2X test split (its own
``gnss-urban`` prior, re-drawn per run) and DMGM's sequences 069 + 071. Every model × test set:
the four learned matchers (``learned``, ``learned_pose``, ``maximin_learned``,
``rrwm_learned``), τ calibrated on the test set's validation split as for every matcher (for
DMGM that is sequence 070 — the DMGM model's own training data: its τ is optimistic there, its
AP is not affected), one run (``maximin_learned`` samples triangles with seed 0; the others are
deterministic). ``maximin_learned`` and ``rrwm_learned`` take the kernel widths that maximin and
RRWM were tuned to on the same validation split by the main tables (no extra search).

Beside every row, the best hand-crafted matcher of the same kind (with the prior for
``learned_pose``, without it for the rest) on that test set, from the main tables (selected by
its test pooled F1: a reference line, not a tuned choice). A model is never scored on a record
it was trained on (:func:`eval.protocol.model_options.check_no_overlap`).
"""

from __future__ import annotations

import logging
import re
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from eval.core.result_files import write_csv, write_text
from eval.core.runner import Runner
from eval.core.tasks import MatcherSpec
from eval.protocol.model_options import with_model
from eval.report.tables import build_table
from eval.studies.evaluation import chosen_specs, evaluate, open_entry
from matchers.learned_model import load_model

log = logging.getLogger(__name__)

SUBDIR = "transfer"
LEARNED = ("learned", "learned_pose", "maximin_learned", "rrwm_learned")
HYBRID_BASES = {"maximin_learned": "maximin", "rrwm_learned": "rrwm"}
EXCLUDED = {"none", "dmgm_published", *LEARNED}
SIM_ONLY = "cadsim CAD + CAD-V2X train"  # the "trained on cadsim only" model of the goals
EXTERNAL_TRAIN = "DMGM 070"
EXTERNAL_TEST = "DMGM 069 + 071"
COLUMNS = [
    "train",
    "test",
    "matcher",
    "uses_prior",
    "f1_pooled",
    "ap",
    "tau",
    "frames",
    "handcrafted",
    "handcrafted_f1_pooled",
    "handcrafted_ap",
    "model_sha256",
]


@dataclass(frozen=True)
class TestSet:
    """A test split, its validation split, the prior preset it is scored under (None: the
    records' own), and where the main tables evaluated the hand-crafted matchers on it."""

    label: str
    test_dir: Path
    val_dir: Path
    localisation: str | None
    reference_dir: Path
    reference_label: str


def train_sets(data: Path, cad_train: Path, external_train: Path) -> dict[str, list[Path]]:
    """{training-set label: dataset folders}: labels start with ``cadsim`` (simulated) or
    ``DMGM`` (external)."""
    v2x_train = data / "cad-v2x-train"
    return {
        "cadsim CAD train": [cad_train],
        "cadsim CAD-V2X train": [v2x_train],
        SIM_ONLY: [cad_train, v2x_train],
        EXTERNAL_TRAIN: [external_train],
    }


def test_sets(data: Path, out: Path, external_test: Path, external_val: Path) -> list[TestSet]:
    """The three test sets, with the folders of the main tables' evaluations of them."""
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
        TestSet(EXTERNAL_TEST, external_test, external_val, None, out / "external", "DMGM"),
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
    from matchers.learned_training import PARAMS, ROUNDS

    if not path.is_file():
        return None
    try:
        model = load_model(path)
    except ValueError:
        return None
    recorded = [d.get("checksum") for d in model.training.get("datasets", [])]
    same = recorded == [Dataset(d).checksum for d in dirs]
    same = same and model.training.get("params") == PARAMS
    return model if same and model.training.get("rounds") == ROUNDS else None


def _hybrid_options(test: TestSet) -> dict[str, dict]:
    """The kernel widths maximin and RRWM were tuned to on ``test``'s validation split."""
    bases = [MatcherSpec(b) for b in HYBRID_BASES.values()]
    named, _ = chosen_specs(test.reference_dir, test.reference_label, bases)
    return {hybrid: dict(named[base].options) for hybrid, base in HYBRID_BASES.items()}


def evaluate_transfer(
    models: dict[str, tuple[Path, float]],
    tests: Sequence[TestSet],
    runner: Runner,
    out: Path,
    seeds: Sequence[int] = (0,),
) -> pd.DataFrame:
    """Every model on every test set (module docstring); writes ``out/transfer/<train>/<test>/``
    and ``out/table_transfer.{md,csv}``; returns the table."""
    rows = []
    for test in tests:
        entry = open_entry(test.test_dir, test.val_dir, test.reference_label, test.localisation)
        hybrid = _hybrid_options(test)
        reference = _reference(test)
        for train, (model_path, _) in models.items():
            specs = [MatcherSpec.of(n, **hybrid.get(n, {})) for n in LEARNED]
            named = with_model(specs, model_path, [test.test_dir])
            named = {spec.name: spec for spec in named.values()}
            folder = out / SUBDIR / slug(train) / slug(test.label)
            evaluate([entry], named, seeds, runner, folder, untuned=False)
            table = build_table(folder)
            for r in table.itertuples(index=False):
                prior = r.matcher == "learned_pose"
                best = reference.get(prior, {})
                rows.append(
                    {
                        "train": train,
                        "test": test.label,
                        "matcher": r.matcher,
                        "uses_prior": prior,
                        "f1_pooled": r.f1_pooled_mean,
                        "ap": r.ap_mean,
                        "tau": getattr(r, "tau", np.nan),
                        "frames": int(r.frames),
                        "handcrafted": best.get("method", ""),
                        "handcrafted_f1_pooled": best.get("f1_pooled", np.nan),
                        "handcrafted_ap": best.get("ap", np.nan),
                        "model_sha256": dict(named[r.matcher].options)["model_sha256"],
                    }
                )
    table = pd.DataFrame(rows, columns=COLUMNS)
    write_csv(table.round(6), out / "table_transfer.csv")
    write_text(out / "table_transfer.md", to_markdown(table))
    return table


def _reference(test: TestSet) -> dict[bool, dict]:
    """{uses prior: {method, f1_pooled, ap}} of the best hand-crafted matcher of each kind on
    ``test`` in the main tables (by pooled F1); empty where they have not run."""
    from eval.studies.external import prior_matchers

    try:
        table = build_table(test.reference_dir)
    except FileNotFoundError:
        return {}
    table = table[table["dataset"] == test.reference_label]
    table = table[~table["matcher"].isin(EXCLUDED)]
    priors = set(prior_matchers())
    out = {}
    for prior in (False, True):
        kind = table[table["matcher"].isin(priors) == prior]
        kind = kind.dropna(subset=["f1_pooled_mean"])
        if kind.empty:
            continue
        best = kind.loc[kind["f1_pooled_mean"].idxmax()]
        out[prior] = {
            "method": str(best["method"]),
            "f1_pooled": float(best["f1_pooled_mean"]),
            "ap": float(best.get("ap_mean", np.nan)),
        }
    return out


def _pct(value: float) -> str:
    return "–" if pd.isna(value) else f"{100 * value:.1f}"


def to_markdown(table: pd.DataFrame) -> str:
    """The transfer matrix: one block per test set, a row per (training set, learned matcher),
    the best hand-crafted matcher of the same kind beside it (percent)."""
    lines = [
        "Transfer of the learned matchers (pooled F1 and AP, percent; τ from each test set's "
        "validation split; the best hand-crafted matcher of the same kind — with or without the "
        "prior — on that test set beside each row).",
        "",
    ]
    header = ["Trained on", "Matcher", "Pooled F1", "AP", "Hand-crafted best", "its F1", "its AP"]
    for test, rows in table.groupby("test", sort=False):
        lines += [f"**Tested on {test}** ({int(rows['frames'].max())} frame pairs)", ""]
        lines += ["| " + " | ".join(header) + " |", "|:---|:---|---:|---:|:---|---:|---:|"]
        for r in rows.itertuples(index=False):
            cells = [
                r.train,
                r.matcher,
                _pct(r.f1_pooled),
                _pct(r.ap),
                r.handcrafted or "–",
                _pct(r.handcrafted_f1_pooled),
                _pct(r.handcrafted_ap),
            ]
            lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines)


def _cell(table: pd.DataFrame, train: str, matcher: str, column: str = "f1_pooled") -> float:
    rows = table[
        (table["train"] == train) & (table["test"] == EXTERNAL_TEST) & (table["matcher"] == matcher)
    ]
    return float(rows[column].iloc[0]) if len(rows) else float("nan")


def goals(
    table: pd.DataFrame, stage_s: float | None = None, computed: int | None = None
) -> list[str]:
    """The study's goals, each with its figure and whether it is met; ``stage_s`` the transfer
    stage's seconds in this run, ``computed`` how many of its runs it computed (0: all cached)."""
    out = []
    free = _cell(table, SIM_ONLY, "learned")
    best_free = _cell(table, SIM_ONLY, "learned", "handcrafted_f1_pooled")
    method = table.loc[
        (table["test"] == EXTERNAL_TEST) & (table["matcher"] == "learned"), "handcrafted"
    ]
    method = method.iloc[0] if len(method) else "the best hand-crafted matcher"
    out.append(
        f"trained on cadsim only, no prior, on DMGM 069 + 071: pooled F1 {_pct(free)} against "
        f"{method}'s {_pct(best_free)} — " + ("met" if free > best_free else "not met")
    )
    pose = _cell(table, SIM_ONLY, "learned_pose")
    out.append(
        f"trained on cadsim only, with the prior: pooled F1 {_pct(pose)} on DMGM 069 + 071 "
        "(goal ≥ 97.0) — " + ("met" if pose >= 0.97 else "not met")
    )
    for matcher in ("learned", "learned_pose"):
        gap = _cell(table, EXTERNAL_TRAIN, matcher) - _cell(table, SIM_ONLY, matcher)
        out.append(
            f"transfer gap of {matcher} (DMGM-070-trained minus cadsim-trained, on DMGM 069 + "
            f"071): {100 * gap:+.1f} F1 points (goal ≤ 5.0) — "
            + ("met" if gap <= 0.05 else "not met")
        )
    if stage_s is not None and computed:
        out.append(
            f"training and evaluation of the learned rows: {stage_s:.0f} s in this run, "
            f"{computed} runs computed (goal ≤ 120 s cold) — "
            + ("met" if stage_s <= 120 else "not met")
        )
    elif stage_s is not None:
        out.append(
            f"training and evaluation of the learned rows: {stage_s:.0f} s in this run, every "
            "run cached and the models reused (the goal, ≤ 120 s cold, is read from a cold run: "
            "the README's timing paragraph)"
        )
    return out


def readme_part(
    results: Path, rel: str, stage_s: float | None = None, computed: int | None = None
) -> list[str]:
    """README lines "Does simulation transfer?" (none without ``table_transfer.csv``)."""
    path = Path(results) / "table_transfer.csv"
    if not path.is_file():
        return []
    table = pd.read_csv(path, keep_default_na=False, na_values=[""])
    if table.empty:
        return []
    external = table[table["test"] == EXTERNAL_TEST]
    return [
        "### Does simulation transfer?",
        "",
        "Learned matchers (gradient-boosted trees on motion-invariant candidate-pair features, "
        "docs/learned.md) trained on cadsim's training splits or on DMGM's calibration sequence "
        f"070, tested on DMGM's 069 + 071 (every test set: [{rel}/table_transfer.md]"
        f"({rel}/table_transfer.md)):",
        "",
        to_markdown(external).split("\n", 2)[2].strip(),
        "",
        *[f"- {line}." for line in goals(table, stage_s, computed)],
        "",
    ]
