"""Giving the learned matchers their model: ``--model MODEL`` of the commands, and the protocol
rule that a model never scores the data it was trained on.

:func:`with_model` checks the model file once (it loads; it shares no record with any dataset
to be scored — the test datasets; a validation set may be its training data, as for a model
trained on DMGM's calibration sequence) and adds ``model`` (the path as given: results name it as the command did) and
``model_sha256`` (its content, so that the result cache never serves a run of another model
written to the same path) to every matcher that needs a model."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path

from eval.core.tasks import MatcherSpec


def overlapping_records(trained_on: set[str], dirs: Iterable[str | Path]) -> dict[str, int]:
    """{dataset folder: how many of its records are among ``trained_on``} for the folders that
    share at least one record with a model's training data: what
    :func:`cadsim.dataset.training_set.overlapping_records` says, from each verified dataset's
    manifest (the checksum of every record, as its records carry them) instead of reading every
    record."""
    from cadsim.dataset import Dataset

    shared = {}
    for folder in dirs:
        records = Dataset(folder, verify=True).manifest["records"]
        common = len({r["checksum"] for r in records} & trained_on)
        if common:
            shared[str(folder)] = common
    return shared


def check_no_overlap(model_path: str | Path, scored_dirs: Iterable[str | Path]) -> str:
    """The model's sha256 after checking that it loads and that none of ``scored_dirs`` holds a
    record it was trained on; ValueError in one line otherwise."""
    from matchers.learned.model import load_model

    model = load_model(model_path)
    shared = overlapping_records(model.training_records(), scored_dirs)
    if shared:
        folder, count = next(iter(shared.items()))
        raise ValueError(
            f"--model {model_path}: trained on {count} record(s) of {folder}, which it would "
            "score; train on a training split (cadsim train) instead"
        )
    return model.sha256


def with_model(
    specs: Sequence[MatcherSpec], model_path: str | Path | None, scored_dirs: Iterable[str | Path]
) -> dict[str, MatcherSpec]:
    """{row label: spec}: ``specs`` under their own labels, with ``model`` / ``model_sha256``
    added to each matcher that needs a model (``matchers.required_options``; its row keeps the
    plain name); ValueError when one needs it and ``model_path`` is None."""
    from matchers.core.registry import required_options

    needing = [s for s in specs if "model" in required_options(s.name)]
    if not needing:
        return {s.label: s for s in specs}
    if model_path is None:
        raise ValueError(
            f"--matchers: {needing[0].name} needs a model file: give --model MODEL "
            "(written by cadsim train)"
        )
    sha = check_no_overlap(model_path, scored_dirs)
    path = str(model_path)  # as given (relative to the working directory workers share)
    out = {}
    for spec in specs:
        if spec in needing:
            options = dict(spec.options) | {"model": path, "model_sha256": sha}
            out[spec.label] = MatcherSpec.of(spec.name, **options)
        else:
            out[spec.label] = spec
    return out
