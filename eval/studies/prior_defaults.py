"""The prior matchers' defaults, derived from calibration data only, and how much they matter.

**Derivation** (``python -m eval.studies.prior_defaults --write``): every matcher that reads the
localisation prior (``pose``, ``pose_refine``, ``pose_appearance``, ``maximin_pose``) runs its
tuning grid (:mod:`eval.protocol.tuning`, 8 configurations around its code defaults, seed 0) on
DMGM sequence 070 — the external calibration split, all 201 pairs — and never on the test
sequences 069 + 071 or on our own test sets; τ is fitted per configuration and the configuration
with the best mean per-pair F1 at its τ is chosen (exact ties: the tuning rule). The result,
with the split's dataset checksum and sequences, is :data:`DEFAULTS_FILE`; a test requires that
the matchers' code defaults are the options recorded there, so a default cannot drift to a value
test data suggested. (They replaced defaults set from a residual analysis over all 310 pairs,
test sequences included.)

**Sensitivity** (:func:`write_sensitivity`, run by ``make reproduce`` after the external
benchmark): every grid configuration of every prior matcher scored on the external *test* pairs
at the τ its calibration run gave — ``external/prior_sensitivity.csv`` and
``fig_prior_sensitivity.png/.pdf`` — so a reader sees the spread over the grid, not one point.
"""

from __future__ import annotations

import argparse
import inspect
import json
from pathlib import Path

import pandas as pd

from eval.core.result_files import write_csv, write_text
from eval.core.runner import Runner
from eval.core.tasks import MatcherSpec
from eval.protocol import tuning

DEFAULTS_FILE = Path(__file__).resolve().parents[1] / "data" / "prior-defaults.json"
PRIOR_MATCHERS = ("pose", "pose_refine", "pose_appearance", "maximin_pose")
SENSITIVITY = "prior_sensitivity.csv"


def code_defaults(name: str) -> dict:
    """The keyword defaults of matcher `name`'s signature (``maximin_pose``: its own and the
    maximin options it forwards)."""
    from matchers import get

    fns = [get("maximin"), get(name)] if name == "maximin_pose" else [get(name)]
    return {
        p.name: p.default
        for fn in fns
        for p in inspect.signature(fn).parameters.values()
        if p.default is not inspect.Parameter.empty and p.name not in ("seed", "threshold")
    }


def derive(runner: Runner, calibration_dir: str | Path | None = None) -> dict:
    """Tune every prior matcher on the calibration split (module docstring); returns the record
    :data:`DEFAULTS_FILE` holds."""
    from eval.studies.evaluation import open_entry
    from eval.studies.external import CALIBRATION_DIR

    calibration_dir = Path(calibration_dir or CALIBRATION_DIR)
    entry = open_entry(calibration_dir, calibration_dir)  # tuning reads only the val side
    choices = tuning.tune_entry(entry, [MatcherSpec(n) for n in PRIOR_MATCHERS], runner)
    from cadsim.dataset import Dataset

    sequences = sorted({f"{p.episode:03d}" for p in Dataset(calibration_dir)})
    matchers = {}
    for name in PRIOR_MATCHERS:
        choice = choices[name]
        chosen = code_defaults(name) | choice.params
        matchers[name] = {
            "options": {k: chosen[k] for k in sorted(set().union(*tuning.grid(name)))},
            "chosen_config": choice.params,
            "val_f1": round(choice.candidates[choice.chosen].val_f1, 6),
            "grid_val_f1": {
                tuning.params_json(c.config): round(c.val_f1, 6) for c in choice.candidates
            },
        }
    return {
        "derived_from": {
            "dataset": calibration_dir.name,
            "checksum": entry.val_checksum,
            "sequences": sequences,
        },
        "rule": "each matcher's tuning grid, seed 0, mean per-pair F1 at the configuration's own "
        "tau on every pair of the calibration split; exact ties by the tuning rule",
        "matchers": matchers,
    }


def load_defaults(path: str | Path = DEFAULTS_FILE) -> dict:
    """The recorded derivation (:data:`DEFAULTS_FILE`)."""
    return json.loads(Path(path).read_text(encoding="utf-8"))


def write_sensitivity(out_dir: str | Path, runner: Runner, seed: int = 0) -> pd.DataFrame:
    """Every grid configuration of the prior matchers that ``OUT/external/tuning.csv`` lists,
    run on the external test pairs (`seed`) and scored at the τ of its calibration run; writes
    ``OUT/external/prior_sensitivity.csv`` and the figure. Empty without the tuning file."""
    from eval.protocol.metrics import summarise_pooled
    from eval.studies.evaluation import run_named, score_runs
    from eval.studies.external import SUBDIR, TEST_DIR

    out_dir = Path(out_dir)
    path = out_dir / SUBDIR / "tuning.csv"
    if not path.is_file():
        return pd.DataFrame()
    grid = pd.read_csv(path)
    grid = grid[grid["matcher"].isin(PRIOR_MATCHERS)].reset_index(drop=True)
    if grid.empty:
        return grid
    from cadsim.dataset import Dataset

    test = Dataset(TEST_DIR)
    labels = [f"{r.matcher}#{r.config}" for r in grid.itertuples()]
    named = {
        label: MatcherSpec.of(r.matcher, **json.loads(r.params))
        for label, r in zip(labels, grid.itertuples(), strict=True)
    }
    runs = run_named(runner, (str(TEST_DIR), test.checksum), named, [seed], "prior sensitivity")
    per_pair = score_runs(runs, dict(zip(labels, grid["tau"], strict=True)), dataset="DMGM")
    means = per_pair.groupby("matcher", sort=False)["f1"].mean()
    pooled = summarise_pooled(per_pair, by=["matcher"]).set_index("matcher")["f1_pooled_mean"]
    table = grid.assign(
        test_f1=[means[label] for label in labels],
        test_f1_pooled=[pooled[label] for label in labels],
    )[["matcher", "config", "params", "val_f1", "tau", "chosen", "test_f1", "test_f1_pooled"]]
    write_csv(table.round(6), out_dir / SUBDIR / SENSITIVITY)
    write_figure(out_dir)
    return table


def write_figure(out_dir: str | Path) -> list[Path]:
    """``fig_prior_sensitivity.png/.pdf``: per prior matcher, pooled test F1 of every grid
    configuration (dots), the one chosen on sequence 070 ringed, the defaults marked."""
    from eval.report.figures import _colors, _figure, _save
    from eval.report.tables import method_name
    from eval.studies.external import SUBDIR

    out_dir = Path(out_dir)
    path = out_dir / SUBDIR / SENSITIVITY
    if not path.is_file():
        return []
    table = pd.read_csv(path)
    matchers = [m for m in PRIOR_MATCHERS if m in set(table["matcher"])]
    colors = _colors(matchers)
    fig, axes = _figure(7.0, 3.6)
    ax = axes[0, 0]
    for x, name in enumerate(matchers):
        rows = table[table["matcher"] == name]
        y = 100 * rows["test_f1_pooled"].to_numpy()
        offsets = (rows["config"].to_numpy() - (len(rows) - 1) / 2) * 0.06
        ax.scatter(x + offsets, y, s=22, color=colors[name], zorder=3)
        chosen = rows["chosen"].to_numpy(bool)
        ax.scatter(x + offsets[chosen], y[chosen], s=110, facecolor="none", edgecolor="black",
                   zorder=4, label="chosen on 070" if x == 0 else None)  # fmt: skip
        default = (rows["params"] == "{}").to_numpy()
        ax.scatter(x + offsets[default], y[default], marker="x", s=40, color="black", zorder=5,
                   label="defaults" if x == 0 else None)  # fmt: skip
    ax.set_xticks(range(len(matchers)), [method_name(m) for m in matchers], fontsize=8)
    ax.set_ylabel("pooled F1 on 069 + 071 (%)")
    ax.set_title("Prior matchers: test F1 over each tuning grid (8 configurations)", fontsize=9)
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=7, loc="lower left")
    return _save(fig, out_dir / "fig_prior_sensitivity")


def main(argv: list[str] | None = None) -> int:
    from eval.core.cache import ResultCache
    from eval.core.executor import make_executor
    from matchers.core.jit import cache_root

    parser = argparse.ArgumentParser(
        prog="python -m eval.studies.prior_defaults",
        description="Derive the prior matchers' defaults on DMGM sequence 070 (calibration only).",
    )
    parser.add_argument("--write", action="store_true", help=f"write {DEFAULTS_FILE.name}")
    parser.add_argument("--workers", type=int, default=None, help="processes (default: cores)")
    args = parser.parse_args(argv)
    with make_executor(args.workers, None) as executor:
        runner = Runner(ResultCache(cache_root() / "runs"), executor, progress=True)
        record = derive(runner)
    text = json.dumps(record, indent=2, sort_keys=True) + "\n"
    if args.write:
        write_text(DEFAULTS_FILE, text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
