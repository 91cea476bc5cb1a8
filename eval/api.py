"""The evaluation from Python: benchmark matchers on datasets and get Table I as a DataFrame.

    >>> from eval.api import evaluate_matchers
    >>> table = evaluate_matchers(["data/cad"], ["sm", "maximin"], val_dirs=["data/cad-val"],
    ...                           out="my-run")                        # doctest: +SKIP
    >>> table[["dataset", "matcher", "f1_mean", "f1_std"]]            # doctest: +SKIP

The same machinery as ``cadsim evaluate`` (cached runs, τ calibrated on validation, the same
metrics and files), so a row here equals the row the command writes. docs/api.md walks through
the rest of the Python API: datasets, problems, matchers, metrics.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import pandas as pd

from eval.core.cache import ResultCache
from eval.core.executor import make_executor
from eval.core.runner import Runner
from eval.engine.matcher_list import parse_matchers
from eval.engine.protocol_run import evaluate
from eval.engine.splits import open_entry
from eval.report.tables import build_table, write_tables


def evaluate_matchers(
    test_dirs: Sequence[str | Path],
    matchers: Sequence[str],
    *,
    out: str | Path,
    val_dirs: Sequence[str | Path | None] | None = None,
    runs: int = 1,
    tune: bool = False,
    cache: str | Path | None = None,
    workers: int = 1,
    progress: bool = False,
    plugin_time_limit_s: float | None = None,
) -> pd.DataFrame:
    """Run `matchers` on each test dataset and return Table I (one row per dataset and matcher,
    the columns of ``table1.csv``: rates as fractions in [0, 1], mean and std over `runs` seeds).

    matchers: registered names (case-insensitive), or ``package.module:function`` import paths.
    A matcher you ``matchers.register()``-ed in this process is seen only with ``workers=1``
    (the default: everything runs here); other processes import built-ins, entry points and
    import paths themselves. val_dirs: one validation dataset per test dataset (None: no τ, the
    full assignment). out: the folder the result files go to (created). cache: the run cache
    (default ``$CADSIM_CACHE_DIR/runs``, else ``~/.cache/cadsim/runs``). plugin_time_limit_s:
    seconds a plug-in matcher may take on one frame pair (default ``$CADSIM_PLUGIN_TIME_LIMIT_S``,
    else 600); a plug-in that breaks its contract or its limit raises ``matchers.PluginError``
    naming it (docs/extending-matchers.md).
    """
    from matchers.core.jit import cache_root

    vals = list(val_dirs) if val_dirs is not None else [None] * len(test_dirs)
    if len(vals) != len(test_dirs):
        raise ValueError(f"val_dirs: {len(vals)} for {len(test_dirs)} test datasets")
    entries = [open_entry(t, v) for t, v in zip(test_dirs, vals, strict=True)]
    specs = parse_matchers(",".join(matchers))
    cache_dir = Path(cache) if cache is not None else cache_root() / "runs"
    with make_executor(workers) as executor:
        runner = Runner(
            ResultCache(cache_dir),
            executor,
            progress=progress,
            plugin_time_limit_s=plugin_time_limit_s,
        )
        evaluate(
            entries,
            specs,
            range(runs),
            runner,
            out,
            calibrate=all(v is not None for v in vals),
            tune=tune,
        )
    write_tables(out)  # table1.md / .csv / .tex, as the command writes them
    return build_table(out)
