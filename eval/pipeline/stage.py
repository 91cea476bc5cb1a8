"""One stage of ``make reproduce`` as data (:class:`Stage`), what the stages share while a run
walks them (:class:`RunState`), the ``--no-X`` options derived from the declarations and the walk
itself (:func:`walk`: each stage timed, its matcher runs counted, its stale files removed, the
executor open from the first stage that needs it to the last)."""

from __future__ import annotations

import argparse
import logging
from collections.abc import Callable, Sequence
from contextlib import ExitStack
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from eval.core import pose_fit_store
from eval.core.cache import ResultCache
from eval.core.executor import make_executor
from eval.core.runner import Runner
from eval.pipeline.sizes import ROOT, SplitSizes
from eval.report.run_record import StageTimer

log = logging.getLogger("eval.reproduce")


@dataclass
class RunState:
    """What the stages of one run share: the options, every split's size, the folders, the
    runner (from the first stage that needs it), the run record's sections as the stages fill
    them, and what one stage hands to a later one (datasets, thresholds, folders)."""

    args: argparse.Namespace
    sizes: SplitSizes
    data: Path
    out: Path
    scenarios: list[Path]
    matchers: list
    seeds: list[int]
    record: dict[str, Any] = field(default_factory=dict)
    runner: Runner | None = None
    executor: Any = None
    entries: list = field(default_factory=list)
    spread_sets: list[tuple[str, str, int]] = field(default_factory=list)
    taus: dict = field(default_factory=dict)
    v2x_entry: Any = None
    multi_dirs: tuple[Path, Path] | None = None
    cad_train: Path | None = None
    temporal_dirs: tuple[Path, Path] | None = None
    temporal_lidar_dirs: tuple[Path, Path] | None = None
    table1_markdown: str = ""

    @property
    def progress(self) -> bool:
        return not self.args.no_progress

    def generate(
        self,
        scenario: Path,
        folder: Path,
        pairs: int,
        seed: int | None,
        frames_from: str | Path | None = None,
    ):
        """Generate (or resume) ``pairs`` records of ``scenario`` in ``folder`` (``seed``: the
        scenario seed, None for the scenario's own; ``frames_from``: a camera-only dataset of the
        same frames, for a two-sensor scenario, :mod:`cadsim.generation.frames_from`); the
        generation result."""
        from cadsim.generation.pipeline import generate_dataset

        result = generate_dataset(
            scenario,
            folder.resolve(),
            pairs=pairs,
            seed=seed,
            workers=self.args.workers,
            progress=self.progress,
            scheduler=self.args.scheduler,
            frames_from=frames_from,
        )
        log.info(
            "%s: %d pairs (%d new) in %.1f s",
            folder,
            result.pairs,
            result.new_records,
            result.seconds,
        )
        return result


def shown(path: Path) -> str:
    """``path`` relative to the repository when inside it (records stay machine-independent)."""
    try:
        return path.resolve().relative_to(ROOT).as_posix()
    except ValueError:
        return str(path)


@dataclass(frozen=True)
class Stage:
    """One stage. ``name``: its key in the run record's ``wall_s`` and ``runs`` and in the
    report's stage table; ``reads`` / ``writes``: datasets and result files, for the reader
    (paths under ``--data`` and ``--out``); ``run``: what it does; ``budget_s``: its cold-run
    goal, seconds on 2 cores; ``skip``: ``X`` of the ``--no-X`` option that skips it (stages of
    one study share one); ``about``: what the option skips; ``stale``: result files (under
    ``--out``) removed before it runs, run or skipped, so that no earlier run's table survives;
    ``executor``: it needs the runner; ``counts_runs``: its matcher runs (computed, cached,
    failed) go in the run record."""

    name: str
    reads: tuple[str, ...]
    writes: tuple[str, ...]
    run: Callable[[RunState], None]
    budget_s: float
    skip: str | None = None
    about: str = ""
    stale: tuple[str, ...] = ()
    executor: bool = True
    counts_runs: bool = True

    def __post_init__(self) -> None:
        if self.counts_runs and not self.executor:
            raise ValueError(f"stage {self.name}: counts_runs needs executor (the runner)")


def add_skip_options(parser: argparse.ArgumentParser, stages: Sequence[Stage]) -> None:
    """One ``--no-X`` option per distinct ``skip`` of ``stages``, its help naming the stages."""
    named: dict[str, list[Stage]] = {}
    for stage in stages:
        if stage.skip is not None:
            named.setdefault(stage.skip, []).append(stage)
    for skip, group in named.items():
        about = next((s.about for s in group if s.about), "")
        parser.add_argument(
            f"--no-{skip}",
            action="store_true",
            help=f"skip {' and '.join(s.name for s in group)}" + (f": {about}" if about else ""),
        )


def skipped(args: argparse.Namespace, stage: Stage) -> bool:
    """Whether ``stage``'s ``--no-X`` option was given."""
    return stage.skip is not None and bool(getattr(args, f"no_{stage.skip}".replace("-", "_")))


def walk(stages: Sequence[Stage], state: RunState, timer: StageTimer) -> dict[str, dict]:
    """Run ``stages`` in order, each timed under its name (a skipped stage too, with only its
    stale files removed); the runner is made before the first stage that needs it and its
    executor closed after the last. Returns each counting stage's matcher runs."""
    runs: dict[str, dict] = {}
    last = max((i for i, s in enumerate(stages) if s.executor), default=-1)
    with ExitStack() as open_executor:
        for i, stage in enumerate(stages):
            if stage.executor and state.runner is None:
                args = state.args
                state.executor = open_executor.enter_context(
                    make_executor(args.workers, args.scheduler)
                )
                state.runner = Runner(
                    ResultCache(args.cache), state.executor, progress=state.progress
                )
                pose_fit_store.load(args.cache)  # the fits earlier runs made (speed-up only)
            before = asdict(state.runner.totals) if stage.counts_runs else {}
            with timer.stage(stage.name):
                for name in stage.stale:
                    (state.out / name).unlink(missing_ok=True)
                if not skipped(state.args, stage):
                    stage.run(state)
            if state.runner is not None:
                pose_fit_store.save(state.args.cache)
            if stage.counts_runs:
                now = asdict(state.runner.totals)
                runs[stage.name] = {k: v - before.get(k, 0) for k, v in now.items()}
            if i == last:
                open_executor.close()
    return runs


def generate_splits(
    state: RunState,
    scenario: str,
    names: tuple[str, str],
    sizes: dict[str, int],
    unit: str,
    record: dict,
) -> tuple[Path, Path] | None:
    """Generate (or resume) ``scenario``'s test split (the scenario's seed) and validation split
    (seed + VAL_SEED_OFFSET), ``sizes[split]`` records each, as ``data/<name>`` and
    ``data/<name>-val`` (``names`` = (label for the log, folder name)), filling ``record`` (the
    run record's section: per split its folder, size in ``unit``, seed and new records; the
    scenario); the two folders, or None without the scenario file."""
    from cadsim.scenario import load_scenario
    from eval.pipeline.sizes import ROOT, VAL_SEED_OFFSET
    from eval.report.run_record import scenario_file

    label, name = names
    path = ROOT / scenario
    if not path.is_file():
        log.warning("[%s] skipped: no %s", label, scenario)
        return None
    seed = load_scenario(path).seed
    splits = {"test": (state.data / name, seed), "val": (state.data / f"{name}-val", seed + VAL_SEED_OFFSET)}  # fmt: skip
    for split, (folder, split_seed) in splits.items():
        n = sizes[split]
        log.info("[generate] %s %s: %d %s (seed %d)", label, split, n, unit, split_seed)
        made = state.generate(path, folder, n, None if split == "test" else split_seed)
        record[split] = {"dir": str(folder), unit: n, "seed": split_seed}
        record[split] |= {"new_records": made.new_records}
    record["scenario"] = scenario_file(path) | {"path": shown(path)}
    return splits["test"][0], splits["val"][0]
