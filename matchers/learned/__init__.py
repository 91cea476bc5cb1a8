"""The learned matchers (docs/learned.md): a gradient-boosted classifier's P(match) of each
candidate match as the affinity (``learned``, ``learned_pose``) or as the unary term of maximin and
RRWM (``maximin_learned``, ``rrwm_learned``).

* :mod:`~matchers.learned.matcher` — ``learned``, ``learned_pose`` (registered by those names);
* :mod:`~matchers.learned.unary` — ``maximin_learned``, ``rrwm_learned``;
* :mod:`~matchers.learned.features` — the candidate-pair features (``FEATURES_VERSION``);
* :mod:`~matchers.learned.model` — the model file as JSON data (loading checks every key);
* :mod:`~matchers.learned.trees` — LightGBM's text trees checked as data before LightGBM reads
  them (feature indices, child links, counts, finite numbers), and the caps;
* :mod:`~matchers.learned.booster` — the one place LightGBM is called for a model file, its
  output captured;
* :mod:`~matchers.learned.training` — training (LightGBM, deterministic).

The names below are importable from this package; each is loaded on first use (importing
``matchers.learned.model`` does not import maximin or RRWM).
"""

from __future__ import annotations

import importlib

_PUBLIC = {
    "learned": "matcher",
    "learned_pose": "matcher",
    "learned_probability": "matcher",
    "REQUIRED_OPTIONS": "matcher",
    "maximin_learned": "unary",
    "rrwm_learned": "unary",
    "unary_weighted": "unary",
    "FEATURES_VERSION": "features",
    "feature_names": "features",
    "pair_features": "features",
    "FORMAT": "model",
    "FORMAT_VERSION": "model",
    "VARIANTS": "model",
    "LearnedModel": "model",
    "ModelFileError": "model",
    "load_model": "model",
    "PARAMS": "training",
    "ROUNDS": "training",
    "labels": "training",
    "train_model": "training",
}

__all__ = sorted(_PUBLIC)


def __getattr__(name: str):
    if name not in _PUBLIC:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{_PUBLIC[name]}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC))
