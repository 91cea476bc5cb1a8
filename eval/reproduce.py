"""``make reproduce`` = ``python -m eval.reproduce``: Table I (tuned, untuned, paper protocol),
paired differences, regime cards, the regime sweep, dataset spread, Fig. 4, the PR curves, the
qualitative figure, the V2X, multi-agent, transfer and temporal tables, the external benchmark and
the run record, from nothing but the repository.

The stages, what each reads and writes, its budget and its ``--no-X`` option are declared once, in
:data:`eval.pipeline.stages.STAGES`; :func:`main` checks the options, plans every split's size
(:func:`eval.pipeline.sizes.plan_sizes`, ``--scale K``), walks the stages
(:func:`eval.pipeline.stage.walk`: each timed, its matcher runs counted, datasets and runs resumed
from ``--data`` and the result cache), then writes the run record, ``cold_run.json`` when the run
started cold, the report and, for the repository's ``results/``, README.md's results section. Ends
by printing Table I beside the paper's.

Tiny run (the test suite's): ``python -m eval.reproduce --pairs 2 --matchers sm,maximin
--rates 0,0.01 --out DIR --data DIR --cache DIR``.
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
import time
from pathlib import Path

import pandas as pd

from cadsim.limits import MAX_PAIRS, MAX_WORKERS
from cadsim.user_errors import is_user_error, one_line
from eval.commands.sweep_localisation import DEFAULT_SIGMAS, parse_sigmas
from eval.commands.sweep_noise import DEFAULT_RATES, parse_rates
from eval.commands.sweep_regime import DEFAULT_KEEP, parse_keep
from eval.core.cache import DEFAULT_CACHE, code_version
from eval.core.executor import add_scheduler_argument
from eval.engine.matcher_list import parse_matchers
from eval.engine.splits import dataset_label
from eval.pipeline.sizes import (
    DEFAULT_VAL_PAIRS,
    EXTERNAL_RUNS,
    EXTERNAL_TUNE_PAIRS,
    LOCALISATION_PAIRS,
    LOCALISATION_RUNS,
    MULTIAGENT_RUNS,
    REGIME_PAIRS,
    REGIME_RUNS,
    ROOT,
    SCENARIOS,
    SPREAD_DATASET,
    SPREAD_PAIRS,
    SPREAD_RUNS,
    SWEEP_PAIRS,
    SWEEP_RUNS,
    V2X_RUNS,
    SplitSizes,
    parse_scale,
    plan_sizes,
)
from eval.pipeline.stage import RunState, add_skip_options, walk
from eval.pipeline.stages import STAGES
from eval.protocol.cues import EQUAL_CUE_OPTIONS
from eval.protocol.variants import PAPER_OPTIONS
from eval.readme_results import update_readme, write_report
from eval.report.run_record import COLD_RECORD, StageTimer, keep_cold_record, write_run_record

log = logging.getLogger("eval.reproduce")

__all__ = ["ROOT", "SCENARIOS", "STAGES", "build_parser", "cold_start", "main", "planned_sizes"]

RECORD_SECTIONS = (
    "noise_sweep",
    "regime_sweep",
    "localisation_sweep",
    "external",
    "dataset_spread",
    "v2x",
    "multiagent",
    "transfer",
    "temporal",
)
"""The run record's sections the stages fill, in the record's order."""


PROG = "python -m eval.reproduce"


class _OneLineParser(argparse.ArgumentParser):
    """argparse, but a bad option is one line (``PROG: error: …``), exit status 2."""

    def error(self, message: str):  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    p = _OneLineParser(prog=PROG, description=__doc__.splitlines()[0])
    _dataset_options(p)
    _sweep_options(p)
    _study_options(p)
    _run_options(p)
    return p


def _dataset_options(p: argparse.ArgumentParser) -> None:
    """The Table I datasets, matchers and runs."""
    p.add_argument(
        "--scenarios",
        nargs="+",
        default=None,
        help="scenario files (default: those of SCENARIOS that exist)",
    )
    p.add_argument(
        "--pairs",
        type=int,
        default=None,
        help="test pairs per dataset (default: the scenario's, 50)",
    )
    p.add_argument(
        "--val-pairs",
        type=int,
        default=None,
        help=f"validation pairs (default: min({DEFAULT_VAL_PAIRS}, --pairs))",
    )
    p.add_argument("--matchers", default="all", help="'all' or a comma list")
    p.add_argument("--runs", type=int, default=4, help="runs (seeds 0..RUNS-1) for Table I")


def _sweep_options(p: argparse.ArgumentParser) -> None:
    """Tuning and the sweeps: noise, regime, spread, localisation."""
    p.add_argument(
        "--rates", default=",".join(map(str, DEFAULT_RATES)), help="noise rates for Fig. 4"
    )
    p.add_argument(
        "--sweep-runs",
        type=int,
        default=SWEEP_RUNS,
        help=f"runs per noise rate (default {SWEEP_RUNS})",
    )
    p.add_argument(
        "--sweep-pairs",
        type=int,
        default=SWEEP_PAIRS,
        help=f"sweep the first N test pairs (default {SWEEP_PAIRS}; 0: all)",
    )
    p.add_argument(
        "--no-tune",
        dest="tune",
        action="store_false",
        help="skip the parameter search (Table I then runs every matcher with its defaults)",
    )
    p.add_argument(
        "--keep",
        default=",".join(f"{k:g}" for k in DEFAULT_KEEP),
        help="keep levels of the regime sweep (empty: no sweep)",
    )
    p.add_argument(
        "--regime-pairs",
        type=int,
        default=REGIME_PAIRS,
        help=f"regime sweep on the first N test pairs (default {REGIME_PAIRS}; 0: all)",
    )
    p.add_argument(
        "--regime-runs",
        type=int,
        default=REGIME_RUNS,
        help=f"runs (= thinning draws) per keep level (default {REGIME_RUNS})",
    )
    p.add_argument(
        "--spread-pairs",
        type=int,
        default=SPREAD_PAIRS,
        help=f"pairs of each extra {SPREAD_DATASET} dataset (default {SPREAD_PAIRS}; 0: no spread)",
    )
    p.add_argument(
        "--spread-runs",
        type=int,
        default=SPREAD_RUNS,
        help=f"runs on each extra dataset (default {SPREAD_RUNS})",
    )
    p.add_argument(
        "--localisation-sigmas",
        default=",".join(f"{s:g}" for s in DEFAULT_SIGMAS),
        help="position errors (m) of the localisation sweep (empty: no sweep)",
    )
    p.add_argument(
        "--localisation-pairs",
        type=int,
        default=LOCALISATION_PAIRS,
        help=f"localisation sweep on the first N test pairs (default {LOCALISATION_PAIRS}; 0: all)",
    )
    p.add_argument(
        "--localisation-runs",
        type=int,
        default=LOCALISATION_RUNS,
        help=f"runs per position error (default {LOCALISATION_RUNS})",
    )


def _study_options(p: argparse.ArgumentParser) -> None:
    """The studies outside Table I, the scale and the stages' ``--no-X`` options."""
    p.add_argument(
        "--external-runs",
        type=int,
        default=EXTERNAL_RUNS,
        help=f"runs on the DMGM CAD pairs (default {EXTERNAL_RUNS}; 0: skip the external stage)",
    )
    p.add_argument(
        "--external-tune-pairs",
        type=int,
        default=EXTERNAL_TUNE_PAIRS,
        help=f"tune on the first N pairs of sequence 070 (default {EXTERNAL_TUNE_PAIRS}; 0: all)",
    )
    p.add_argument(
        "--v2x-runs",
        type=int,
        default=V2X_RUNS,
        help=f"runs per level of the cad-v2x preset sweep (default {V2X_RUNS}; 0: skip cad-v2x)",
    )
    p.add_argument(
        "--multiagent-runs",
        type=int,
        default=MULTIAGENT_RUNS,
        help=f"runs of the multi-agent table (default {MULTIAGENT_RUNS}; 0: skip cad-multi)",
    )
    p.add_argument(
        "--scale",
        type=parse_scale,
        default=1,
        help="multiply every split size (pairs, sequences, snapshots of every study) and every "
        "sweep's first-N-pairs subset by K (default 1; K > 1: datasets under DATA/scale-K)",
        metavar="K",
    )
    add_skip_options(p, STAGES)


def _run_options(p: argparse.ArgumentParser) -> None:
    """Folders, workers, progress."""
    p.add_argument("--out", default="results", help="output directory (default: results)")
    p.add_argument("--data", default="data", help="dataset directory (default: data)")
    p.add_argument(
        "--cache", default=DEFAULT_CACHE, help=f"result cache (default: {DEFAULT_CACHE})"
    )
    p.add_argument("--workers", type=int, default=None, help="processes (default: one per core)")
    add_scheduler_argument(p)
    p.add_argument("--no-progress", action="store_true", help="no progress bars")


def scenario_paths(args: argparse.Namespace) -> list[Path]:
    """The Table I scenario files: ``--scenarios``, else those of :data:`SCENARIOS` that exist."""
    if args.scenarios:
        return [Path(s) for s in args.scenarios]
    paths = [ROOT / s for s in SCENARIOS if (ROOT / s).is_file()]
    if not paths:
        raise FileNotFoundError(f"no scenario files found ({', '.join(SCENARIOS)})")
    return paths


def planned_sizes(args: argparse.Namespace) -> SplitSizes:
    """Every split's size for the parsed options (scenario files read, nothing generated)."""
    from cadsim.scenario import load_scenario

    scenarios = [load_scenario(path) for path in scenario_paths(args)]
    return plan_sizes(args, [(dataset_label(s.name), s.pairs) for s in scenarios])


# Count options: (name, least value). Runs of the studies that 0 skips may be 0; runs of a sweep
# that runs anyway, and the Table I runs, at least 1; a first-N-pairs subset 0 (all) or more.
_COUNTS = (
    ("runs", 1), ("sweep_runs", 1), ("regime_runs", 1), ("spread_runs", 1),
    ("localisation_runs", 1), ("external_runs", 0), ("v2x_runs", 0), ("multiagent_runs", 0),
    ("pairs", 1), ("val_pairs", 1), ("workers", 1), ("sweep_pairs", 0), ("regime_pairs", 0),
    ("spread_pairs", 0), ("localisation_pairs", 0), ("external_tune_pairs", 0),
)  # fmt: skip
MAX_RUNS = 1000  # seeds of one table: far beyond any interval's need, short of a runaway
_MOST = {"workers": MAX_WORKERS, "pairs": MAX_PAIRS, "val_pairs": MAX_PAIRS}


def _check_counts(args: argparse.Namespace) -> None:
    """Every count option within its range (None: the default), as a one-line ValueError."""
    for name, least in _COUNTS:
        value = getattr(args, name)
        if value is None:
            continue
        most = _MOST.get(name, MAX_RUNS if name.endswith("runs") else MAX_PAIRS)
        if not least <= value <= most:
            option = "--" + name.replace("_", "-")
            raise ValueError(f"{option}: expected an integer in {least}..{most}, got {value}")


def _check_sizes(sizes: SplitSizes) -> None:
    """Every planned split within what generation accepts (``--scale`` multiplies them all)."""
    record = sizes.record()
    largest = max(_counts_in(record), default=0)
    if largest > MAX_PAIRS:
        raise ValueError(
            f"--scale {sizes.scale}: a split of {largest:,} pairs or sequences, over the "
            f"{MAX_PAIRS:,} a dataset may hold; use a smaller scale"
        )


def _counts_in(tree) -> list[int]:
    if isinstance(tree, dict):
        return [n for key, v in tree.items() if key != "scale" for n in _counts_in(v)]
    if isinstance(tree, list | tuple):
        return [n for v in tree for n in _counts_in(v)]
    return [tree] if isinstance(tree, int) and not isinstance(tree, bool) else []


def _check_options(args: argparse.Namespace) -> None:
    """Parse every list option once before anything is generated (a bad one stops the run with
    its one-line message, nothing written)."""
    _check_counts(args)
    parse_rates(args.rates)
    if args.keep.strip():
        parse_keep(args.keep)
    if args.localisation_sigmas.strip():
        try:
            parse_sigmas(args.localisation_sigmas)
        except ValueError as exc:  # the sweep command's option is --sigmas
            raise ValueError(str(exc).replace("--sigmas", "--localisation-sigmas", 1)) from None
    for option, path in (("--data", args.data), ("--cache", args.cache)):
        if not str(path).strip():
            raise ValueError(f"{option}: expected a folder path, got an empty one")
        if Path(path).exists() and not Path(path).is_dir():
            raise ValueError(f"{option} {path}: exists and is not a folder")


def _check_scenarios(paths: list[Path]) -> None:
    """Each scenario file exists (its contents are checked as it is read)."""
    for path in paths:
        if not path.is_file():
            raise FileNotFoundError(f"--scenarios {path}: no such scenario file")


def _start(args: argparse.Namespace) -> tuple[RunState, dict[str, bool]]:
    """The run's state before its first stage, and whether it starts cold. Every option is
    checked before anything is created."""
    from eval.core.result_files import check_outputs

    _check_options(args)
    paths = scenario_paths(args)
    _check_scenarios(paths)
    matchers = parse_matchers(args.matchers)
    sizes = planned_sizes(args)
    _check_sizes(sizes)
    data, out = sizes.data_root(Path(args.data)), check_outputs(args.out, args.cache)
    cold = cold_start(data, Path(args.cache))
    out.mkdir(parents=True, exist_ok=True)
    if sizes.scale != 1:
        log.info("scale %d: every split × %d, datasets under %s", sizes.scale, sizes.scale, data)
    state = RunState(args, sizes, data, out, paths, matchers, list(range(args.runs)))
    state.record = {key: {} for key in RECORD_SECTIONS}
    return state, cold


def _record(
    state: RunState, timer: StageTimer, runs: dict, cold: dict, argv: list[str] | None
) -> Path:
    """Write ``run_record.json``: the options, every stage's sections, times and runs."""
    args = state.args
    command = ["python -m eval.reproduce", *(argv if argv is not None else sys.argv[1:])]
    return write_run_record(
        state.out / "run_record.json",
        timer,
        command=" ".join(command),
        scale=state.sizes.scale,
        executor=executor_record(args.workers, args.scheduler),
        datasets=state.record.get("datasets", []),
        matchers=[m.label for m in state.matchers],
        seeds=state.seeds,
        tuning=_tuning_record(state.out) if args.tune else {},
        paper_protocol={"options": PAPER_OPTIONS, "threshold": None, "tuned": False},
        equal_cues={
            "options": {k: dict(v) for k, v in EQUAL_CUE_OPTIONS.items()},
            "tuned": bool(args.tune),
        },
        **{key: state.record[key] for key in RECORD_SECTIONS},
        thresholds=state.taus,
        runs=runs,
        cold_start=cold,
        code_version=code_version(),
        gl=gl_record(state.data),
        cache=str(args.cache),
        budget_s={stage.name: stage.budget_s for stage in STAGES},
    )


def gl_record(data: Path) -> dict:
    """The GL drivers that drew the run's datasets (each manifest's ``gl`` under ``data``,
    distinct) and the backend variables of this process, for the run record."""
    import os

    from cadsim.generation.pipeline import gl_drivers

    found = []
    for manifest in sorted(Path(data).glob("**/manifest.json")):
        try:
            gl = json.loads(manifest.read_text(encoding="utf-8")).get("gl")
        except (OSError, ValueError, AttributeError):
            continue
        found += gl if isinstance(gl, list) else []
    return {
        "drivers": gl_drivers(found),
        "env": {k: os.environ.get(k) for k in ("CADSIM_GL_BACKEND", "PYOPENGL_PLATFORM")},
    }


def executor_record(workers: int | None, scheduler: str | None) -> dict:
    """Where the run's tasks ran, for the run record: a Dask scheduler's address (``--scheduler``
    or ``$CADSIM_SCHEDULER``; the cluster decides the workers) or local processes and how many."""
    from cadsim.generation.executors import scheduler_address
    from cadsim.generation.local_executor import default_workers

    address = scheduler_address(scheduler)
    if address is not None:
        return {"kind": "dask", "scheduler": address}
    return {"kind": "local processes", "workers": default_workers() if workers is None else workers}


def _report(out: Path, record: Path) -> None:
    """``cold_run.json`` (a cold run only), the report and the README's results section."""
    log.info("run record: %s", record)
    if keep_cold_record(out, json.loads(record.read_text())):
        log.info("cold stage times: %s", out / COLD_RECORD)
    for path in write_report(out):  # the report: out/README.md, out/index.html
        log.info("report written: %s", path)
    if out.resolve() == (ROOT / "results").resolve() and update_readme(ROOT / "README.md", out):
        log.info("README.md results section rewritten from %s", out)


def main(argv: list[str] | None = None) -> int:
    """Run every stage; a user error (a bad option, a missing or bad file) is one line on
    stderr, exit status 2, and — found by the checks of :func:`_start` — nothing created."""
    args = build_parser().parse_args(argv)
    logging.basicConfig(
        level=logging.INFO, format="%(asctime)s %(name)s: %(message)s", datefmt="%H:%M:%S"
    )
    try:
        return _reproduce(args, argv)
    except Exception as exc:
        if not is_user_error(exc):
            raise  # a bug: its traceback is what a report needs
        print(f"{PROG}: error: {one_line(exc)}", file=sys.stderr)
        return 2


def _reproduce(args: argparse.Namespace, argv: list[str] | None) -> int:
    started = time.perf_counter()
    state, cold = _start(args)
    timer = StageTimer()
    runs = walk(STAGES, state, timer)
    _report(state.out, _record(state, timer, runs, cold, argv))
    print()
    print("Table I — ours beside the paper's (results/table1.md)")
    print()
    print(state.table1_markdown)
    print(
        f"wall time: {time.perf_counter() - started:.1f} s "
        + ", ".join(f"{k} {v:.1f} s" for k, v in timer.seconds.items())
    )
    return 0


def cold_start(data: Path, cache: Path) -> dict[str, bool]:
    """Whether this run starts cold: no dataset (nor trained model) under ``data`` and no cached
    run under ``cache``. Stage times are quoted as cold only from a run where ``cold`` is true
    (the README's stage table and every "≤ N min cold" goal line)."""

    def empty(path: Path) -> bool:
        return not path.is_dir() or not any(path.iterdir())

    out = {"data_empty": empty(data), "cache_empty": empty(cache)}
    return out | {"cold": out["data_empty"] and out["cache_empty"]}


def _tuning_record(out: Path) -> dict:
    """{dataset: {matcher: {"params": chosen options, "val_f1": its validation F1}}} from
    ``tuning.csv`` (empty without it)."""
    path = out / "tuning.csv"
    if not path.is_file():
        return {}
    table = pd.read_csv(path, keep_default_na=False, na_values=[""])
    chosen = table[table["chosen"].astype(str) == "True"]
    record: dict = {}
    for row in chosen.itertuples(index=False):
        record.setdefault(row.dataset, {})[row.matcher] = {
            "params": json.loads(row.params),
            "val_f1": float(row.val_f1),
            "configs": int(
                (table["dataset"].eq(row.dataset) & table["matcher"].eq(row.matcher)).sum()
            ),
        }
    return record


if __name__ == "__main__":
    sys.exit(main())
