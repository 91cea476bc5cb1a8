"""A complete small study, as a researcher adds one: the paper's protocol on a denser arena
(``dense-arena.toml`` beside this file: 18 look-alike robots instead of 12).

    python examples/dense_arena/study.py --pairs 4 --matchers sm,maximin --runs 1
    python examples/dense_arena/study.py --help

It is one declaration (``STUDY``) on the study engine: its data (the scenario, a test and a
validation split on disjoint seeds), its methods, its goal, the claims it emits, its report
part and its two stages. Run, it generates what ``--data`` lacks, evaluates every method with
the equal tuning budget and τ on validation (``eval.engine.protocol_run.evaluate``), writes
``table_dense_arena.csv`` into ``--out`` and the report there again with its part and claims
(``eval.run_study.run_study``). Copy this folder to start a study of your own; to make it a
built-in one, move it to ``eval/studies/<name>/`` and add its name to ``eval.studies.STUDIES``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd

from eval.core.result_files import write_csv
from eval.engine.cells import ranged
from eval.engine.episode_interval import column_interval
from eval.engine.goal import Goal
from eval.engine.protocol_run import evaluate
from eval.engine.splits import open_entry
from eval.engine.study import Data, Part, Study
from eval.engine.validation_choice import validation_f1
from eval.pipeline.sizes import ROOT
from eval.pipeline.stage import RunState, Stage, generate_splits
from eval.protocol.claims import Claim
from eval.run_study import run_study

NAME, LABEL = "dense_arena", "Dense arena"
SCENARIO = Path(__file__).resolve().with_name("dense-arena.toml").relative_to(ROOT).as_posix()
SPLITS = {"test": 20, "val": 10}  # records per split at scale 1 (--pairs caps them)
METHODS = ("sm", "maximin")  # the default; --matchers names others
F1 = ("f1_mean", "f1_low", "f1_high")  # a table row's value and its interval
GOAL = Goal("test", "F1 of the method chosen on validation ≥ 50", F1, 0.50)
TABLE = f"table_{NAME}.csv"


# --- the stages: functions of the run's state (eval.pipeline.stage.RunState) ---------------------


def generate(state: RunState) -> None:
    """The scenario's test split (its seed) and validation split (seed + 1000), or only what
    ``--data`` lacks of them."""
    sizes = {split: min(n, state.args.pairs or n) * state.sizes.scale for split, n in SPLITS.items()}  # fmt: skip
    record = state.record.setdefault(NAME, {})
    generate_splits(state, SCENARIO, (LABEL, NAME), sizes, "pairs", record)


def run(state: RunState) -> None:
    """Every method with the equal tuning budget and τ on validation, then the test split;
    ``table_dense_arena.csv``: per method its test F1 with the 95 % episode interval and its
    validation F1 (the figure every choice reads)."""
    record = state.record[NAME]
    entry = open_entry(record["test"]["dir"], record["val"]["dir"], LABEL)
    folder = state.out / NAME
    evaluate([entry], state.matchers, state.seeds, state.runner, folder, tune=state.args.tune, untuned=False)  # fmt: skip
    per_pair = pd.read_csv(folder / "metrics_per_pair.csv", keep_default_na=False, na_values=[""])
    val = validation_f1(folder / "thresholds.csv", LABEL)
    rows = [
        dict(zip(("matcher", *F1), (matcher, *column_interval(group, "f1")), strict=True))
        | {"val_f1": val.get(matcher, float("nan"))}
        for matcher, group in per_pair[per_pair["split"] == "test"].groupby("matcher", sort=False)
    ]
    write_csv(pd.DataFrame(rows), state.out / TABLE)


# --- what it states: its claims, and the report part that prints them --------------------------


def claims(results: Path) -> list[Claim]:
    """The goal on the method of highest validation F1, read off its test interval."""
    path = Path(results) / TABLE
    if not path.is_file():
        return []
    table = pd.read_csv(path)
    best = table.loc[table["val_f1"].idxmax()]
    detail = f"`{best.matcher}`, chosen on validation"
    return [GOAL.claim(best, detail, study=NAME, subject=best.matcher, source=TABLE)]


def report_part(results: Path) -> list[str]:
    """The study's section of the report: its table, then its claims' statements."""
    path = Path(results) / TABLE
    if not path.is_file():
        return []
    table = pd.read_csv(path)
    rows = [
        f"| `{r.matcher}` | {ranged(r.f1_mean, r.f1_low, r.f1_high)} | {100 * r.val_f1:.1f} |"
        for r in table.itertuples(index=False)
    ]
    said = [f"- {claim.statement}." for claim in claims(results)]
    head = ["| Method | test F1 [95 % CI] | validation F1 |", "|---|---|---|"]
    return [f"### {LABEL}", "", *head, *rows, "", *said, ""]


STUDY = Study(
    name=NAME,
    label=LABEL,
    data=(Data(NAME, SCENARIO, SPLITS),),
    methods=METHODS,
    conditions=("test",),
    goals=(GOAL,),
    claims=claims,
    parts=(Part(NAME, lambda context: report_part(context.results), LABEL),),
    stages=(
        Stage(
            NAME + "_generate",
            (SCENARIO,),
            (NAME, NAME + "-val"),
            generate,
            30,
            executor=False,
            counts_runs=False,
        ),  # fmt: skip
        Stage(NAME, (NAME, NAME + "-val"), (TABLE, NAME + "/"), run, 30),
    ),
    outputs=(TABLE, NAME + "/"),
)


if __name__ == "__main__":  # the guard that worker processes need
    argv = sys.argv[1:]
    if not any(a.startswith("--matchers") for a in argv):
        argv += ["--matchers", ",".join(METHODS)]  # the study's methods unless named
    sys.exit(run_study(STUDY, argv))
