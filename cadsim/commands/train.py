"""``cadsim train DATASET_DIR... --out MODEL``: train the learned matchers' classifiers
(``learned``, ``learned_pose``; also the unary of ``maximin_learned`` / ``rrwm_learned``) on the
candidate matches of every record of the given datasets, and write the model file (JSON data:
LightGBM's text trees, the features' version, the training data's checksums;
:mod:`matchers.learned_model`). Deterministic: the same datasets give the same bytes.

Train on training splits only — never on the data a table scores: ``cadsim evaluate --model``
refuses a model that shares a record with an evaluated dataset. ``make reproduce`` generates
training splits on their own scenario seeds (docs/learned.md).
"""

from __future__ import annotations

import argparse
import logging
import time

from cadsim.cli import int_in

log = logging.getLogger(__name__)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from matchers.learned_model import VARIANTS

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


def train_datasets(dirs, out, variants: str = "auto", rounds: int | None = None, progress=False):
    """Train on the datasets at ``dirs`` and write the model to ``out``; (sha256, model)."""
    from cadsim.dataset.training_set import training_examples
    from matchers.learned_model import VARIANTS, save_model
    from matchers.learned_training import ROUNDS, train_model

    examples, record = training_examples(dirs, progress)
    if not examples:
        raise ValueError(f"{dirs[0]}: no frame pairs to train on")
    if variants == "auto":
        with_prior = all(p.world1 is not None and p.world_sigma is not None for p, _ in examples)
        chosen = list(VARIANTS) if with_prior else ["learned"]
    else:
        chosen = [v.strip() for v in variants.split(",") if v.strip()]
        unknown = [v for v in chosen if v not in VARIANTS]
        if unknown or not chosen:
            raise ValueError(
                f"--variants: unknown {unknown or variants!r}; choose from {list(VARIANTS)}"
            )
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
