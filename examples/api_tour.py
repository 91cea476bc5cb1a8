"""A tour of cadsim's Python API, on the DMGM CAD pairs shipped in eval/data (no simulation).

    python examples/api_tour.py [OUT_DIR]     # OUT_DIR default: a new temporary folder

1. load a dataset and iterate its frame pairs; 2. build a matching problem; 3. call any matcher;
4. score the matching with the suite's metrics; 5. register a matcher of your own; 6. evaluate
several matchers (yours included) on a dataset and get Table I as a pandas DataFrame.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from cadsim.dataset import Dataset
from eval.api import evaluate_matchers
from eval.protocol.metrics import pair_metrics
from matchers import Matching, Problem, get, register
from matchers.core.result import finish

ROOT = Path(__file__).resolve().parents[1]
TEST = ROOT / "eval" / "data" / "dmgm-cad" / "test-069-071"
VAL = ROOT / "eval" / "data" / "dmgm-cad" / "val-070"


def nearest_appearance(problem: Problem, seed=0, threshold=None) -> Matching:
    """A matcher of your own: cosine similarity of the appearance features, then the suite's
    shared Hungarian assignment and threshold (``finish``)."""
    started = time.perf_counter()
    f1, f2 = problem.features1, problem.features2
    if f1 is None or not len(f1) or not len(f2):
        scores = np.zeros((problem.n1, problem.n2))
    else:
        a = f1 / np.maximum(np.linalg.norm(f1, axis=1, keepdims=True), 1e-12)
        b = f2 / np.maximum(np.linalg.norm(f2, axis=1, keepdims=True), 1e-12)
        scores = np.clip(a @ b.T, 0.0, 1.0)
    return finish("nearest_appearance", scores, threshold, started)


def main(out: Path) -> None:
    # 1. A dataset: frame pairs with each view's detections and the ground truth.
    dataset = Dataset(TEST)
    print(f"{len(dataset)} frame pairs; checksum {dataset.checksum[:12]}")
    pair = dataset[0]
    print(f"pair 0: {len(pair.view1)} and {len(pair.view2)} objects, {len(pair.gt_pairs)} shared")

    # 2. The matching problem of one pair (positions, features, the localisation prior).
    problem = pair.problem()

    # 3. Any matcher, by name.
    matching = get("maximin")(problem, seed=0, threshold=0.5)

    # 4. The suite's metrics (the one implementation the tables use).
    m = pair_metrics(matching.pairs, pair.gt_pairs, problem.n1, problem.n2)
    print(f"maximin on pair 0: precision {m.precision:.2f}, recall {m.recall:.2f}, F1 {m.f1:.2f}")

    # 5. Your own matcher, registered in this process (with a memory estimate for the budget).
    register("nearest_appearance", nearest_appearance, replace=True,
             memory=lambda problem, **options: 64.0 * problem.n1 * problem.n2)  # fmt: skip

    # 6. Table I of several matchers on the dataset, τ calibrated on the validation pairs.
    table = evaluate_matchers(
        [TEST], ["sm", "maximin", "nearest_appearance"], val_dirs=[VAL], out=out, runs=1
    )
    print(table[["dataset", "matcher", "precision_mean", "recall_mean", "f1_mean"]].to_string())
    print(f"Table I and its files are in {out}")


if __name__ == "__main__":
    # never into the checkout by default: a temporary folder unless one is named
    main(
        Path(sys.argv[1])
        if len(sys.argv) > 1
        else Path(tempfile.mkdtemp(prefix="cadsim-api-tour-"))
    )
