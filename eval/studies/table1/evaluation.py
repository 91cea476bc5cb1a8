"""The evaluation behind ``cadsim evaluate`` (Table I's study): which matchers a list names
(:func:`parse_matchers`), and the study engine's evaluation under the names every study and
command imports — datasets paired with their validation sets (:mod:`eval.engine.splits`), runs
from the cached runner scored at τ (:mod:`eval.engine.named_runs`), the equal tuning budget, τ on
validation and the files of each protocol variant (:mod:`eval.engine.protocol_run`,
:mod:`eval.engine.variant_files`). The command line is :mod:`eval.commands.evaluate`.
"""

from __future__ import annotations

import logging

from eval.core.tasks import MatcherSpec
from eval.engine.named_runs import (
    as_named,
    calibrate_entry,
    calibrate_named,
    run_named,
    score_runs,
)
from eval.engine.protocol_run import evaluate, evaluate_entry
from eval.engine.ranking_quality import (
    QUALITATIVE_MATCHERS,
    qualitative_entry,
    ranking_quality,
    representative_pair,
)
from eval.engine.splits import (
    DATASET_LABELS,
    PAPER_FAMILIES,
    DatasetEntry,
    Named,
    dataset_label,
    open_entry,
    val_dirs,
)
from eval.engine.validation_choice import chosen_specs
from eval.engine.variant_files import THRESHOLD_COLUMNS, EntryResult

log = logging.getLogger(__name__)

PAPER_ORDER = ("sm", "rrwm", "hgm", "tm", "bcagm", "rrwhm", "mos", "maximin", "appearance", "none")
DEFAULT_CACHE = "cache/runs"  # make reproduce's, inside the repository; commands use user_cache()


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


__all__ = [
    "DATASET_LABELS",
    "DEFAULT_CACHE",
    "PAPER_FAMILIES",
    "PAPER_ORDER",
    "QUALITATIVE_MATCHERS",
    "THRESHOLD_COLUMNS",
    "DatasetEntry",
    "EntryResult",
    "Named",
    "as_named",
    "calibrate_entry",
    "calibrate_named",
    "chosen_specs",
    "dataset_label",
    "evaluate",
    "evaluate_entry",
    "open_entry",
    "parse_matchers",
    "qualitative_entry",
    "ranking_quality",
    "representative_pair",
    "run_named",
    "score_runs",
    "val_dirs",
]
