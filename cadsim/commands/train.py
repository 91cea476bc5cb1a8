"""``cadsim train DATASET_DIR... --out MODEL``: train the learned matchers' classifiers
(``learned``, ``learned_pose``; also the unary of ``maximin_learned`` / ``rrwm_learned``) on the
candidate matches of every record of the given datasets, and write the model file (JSON data:
LightGBM's text trees, the features' version, the training data's checksums;
:mod:`matchers.learned.model`). Deterministic: the same datasets give the same bytes.

``--out`` follows the output-path rule (:mod:`cadsim.dataset.output_folder`), checked before
anything is read: a new file, or a model file written before — never a folder, a symbolic link,
a file inside a dataset (its manifest included) or a file of another kind; written under a new
temporary name in the same folder and renamed into place at the end.

Train on training splits only — never on the data a table scores: ``cadsim evaluate --model``
refuses a model that shares a record with an evaluated dataset. ``make reproduce`` generates
training splits on their own scenario seeds (docs/learned.md).
"""

from __future__ import annotations

import argparse
import hashlib
import logging
import time
from pathlib import Path

from cadsim.cli import int_in

log = logging.getLogger(__name__)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from matchers.learned.model import VARIANTS

    parser.add_argument("datasets", nargs="+", metavar="DATASET_DIR", help="training datasets")
    parser.add_argument("--out", required=True, metavar="MODEL", help="model file to write")
    parser.add_argument(
        "--variants",
        default="auto",
        help="comma list of "
        + ", ".join(VARIANTS)
        + " (default auto: both when every record has a localisation prior, else learned)",
    )
    parser.add_argument(
        "--rounds", type=int_in(1, 5000), default=None, help="boosting rounds (default 200)"
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")


MODEL_MARKER = b'"format": "cadsim-learned-model"'  # near the start of every model file


def check_model_out(out) -> Path:
    """``out`` as a Path when a model file may be written there (the output-path rule,
    :func:`cadsim.dataset.output_folder.check_output_file`): a new file outside any dataset, or a
    model file written before; never a folder, a link, a dataset's manifest or a user's file."""
    from cadsim.dataset.output_folder import check_output_file, file_holds

    return check_output_file(out, "a cadsim model file", file_holds(MODEL_MARKER, 4096))


def save_model(model, path) -> str:
    """Write ``model`` (a :class:`matchers.learned.model.LearnedModel`) to ``path`` through the
    output-path rule (checked, then a new temporary file renamed into place); its sha256."""
    from cadsim.dataset.atomic_writer import write_file_atomic

    path = check_model_out(path)
    data = model.to_bytes()
    write_file_atomic(path, data)
    return hashlib.sha256(data).hexdigest()


def _chosen_variants(variants: str) -> list[str] | None:
    from matchers.learned.model import VARIANTS

    if variants == "auto":
        return None
    chosen = [v.strip() for v in variants.split(",") if v.strip()]
    unknown = [v for v in chosen if v not in VARIANTS]
    if unknown or not chosen:
        raise ValueError(
            f"--variants: unknown {unknown or variants!r}; choose from {list(VARIANTS)}"
        )
    return chosen


def train_datasets(dirs, out, variants: str = "auto", rounds: int | None = None, progress=False):
    """Train on the datasets at ``dirs`` and write the model to ``out``; (sha256, model).
    ``out`` and ``variants`` are checked before anything is read."""
    from cadsim.dataset.training_set import training_examples
    from matchers.learned.model import VARIANTS
    from matchers.learned.training import ROUNDS, train_model

    out = check_model_out(out)
    chosen = _chosen_variants(variants)
    examples, record = training_examples(dirs, progress)
    if not examples:
        raise ValueError(f"{dirs[0]}: no frame pairs to train on")
    if chosen is None:
        with_prior = all(p.world1 is not None and p.world_sigma is not None for p, _ in examples)
        chosen = list(VARIANTS) if with_prior else ["learned"]
    model = train_model(examples, record, chosen, rounds or ROUNDS)
    return save_model(model, out), model


def run(args: argparse.Namespace) -> int:
    started = time.perf_counter()
    sha, model = train_datasets(
        args.datasets, args.out, args.variants, args.rounds, not args.no_progress
    )
    training = model.training
    print(
        f"{args.out}: {', '.join(sorted(model.boosters))} trained on "
        f"{sum(d['pairs'] for d in training['datasets'])} frame pairs "
        f"({', '.join(f'{v} {n:,} candidate matches' for v, n in training['rows'].items())}) "
        f"in {time.perf_counter() - started:.1f} s; sha256 {sha[:12]}"
    )
    return 0
