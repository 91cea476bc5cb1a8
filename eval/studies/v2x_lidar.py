"""The LiDAR V2X table (``results/table_v2x_lidar.{md,csv}``): what the matchers get on boxes
that cadsim's own LiDAR detector found, beside the camera table and the label-quality box table.

Data. ``scenarios/cad-v2x-lidar.toml`` — cad-v2x's junction, traffic, observers, seeds and
localisation preset, each observer sensing with an HDL-64E on its roof instead of a camera — is
generated into ``DATA/cad-v2x-lidar`` (test, seed 11) and ``DATA/cad-v2x-lidar-val`` (validation,
seed 1011), as many pairs as the camera table's splits. Each view's detections are the LiDAR
box detector's (``cadsim.sensing.lidar.box_detector``): its misses, splits, merges, wall slivers
and centre bias (its regime card: ``cadsim info``), reported classes from box size, the box
feature vector of the *fitted* sizes, headings; no pixels.

Protocol. The camera table's (:func:`eval.studies.v2x_table.evaluate_v2x`): every matcher that
runs without pixels (:func:`eval.studies.v2x_boxes.box_matchers`), every preset, the same tuning
budget, τ and parameters on the validation split, oracle and prior rows. Files:
``table_v2x_lidar.{md,csv}``, ``table_v2x_lidar_intervals.csv``, ``v2x_lidar/<preset>/``.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from pathlib import Path

import pandas as pd

from eval.core.tasks import MatcherSpec

log = logging.getLogger(__name__)

NAME = "v2x_lidar"
LABEL = "CAD-V2X LiDAR"
SCENARIO = "scenarios/cad-v2x-lidar.toml"


def generate_lidar_splits(
    root: Path, data: Path, pairs: int, val_seed_offset: int, generate: Callable
) -> tuple[Path, Path, dict]:
    """The test and validation splits of :data:`SCENARIO` under ``data`` (``generate(path,
    folder, pairs, seed)`` makes or resumes one); (test dir, val dir, what the run record keeps)."""
    from cadsim.scenario import load_scenario

    path = root / SCENARIO
    seed = load_scenario(path).seed
    test, val = data / "cad-v2x-lidar", data / "cad-v2x-lidar-val"
    record = {}
    for split, folder, split_seed in (("test", test, None), ("val", val, seed + val_seed_offset)):
        log.info("[v2x lidar generate] %s %s: %d pairs", LABEL, split, pairs)
        made = generate(path, folder, pairs, split_seed)
        record[split] = {"dir": str(folder), "pairs": pairs, "seed": split_seed or seed}
        record[split] |= {"new_records": made.new_records}
    return test, val, record


def evaluate_lidar(
    test_dir: str | Path,
    val_dir: str | Path,
    matchers: Sequence[MatcherSpec],
    seeds: Sequence[int],
    runner,
    out_dir: str | Path,
    tune: bool = True,
) -> tuple[pd.DataFrame, dict]:
    """The full table's protocol on the LiDAR splits (module docstring); (table, record)."""
    from eval.studies.v2x_boxes import box_matchers
    from eval.studies.v2x_table import evaluate_v2x

    chosen = box_matchers(matchers)
    log.info("[v2x lidar] %s: %d matchers on %s, %s", LABEL, len(chosen), test_dir, val_dir)
    table = evaluate_v2x(test_dir, val_dir, LABEL, chosen, seeds, runner, out_dir, tune=tune, name=NAME)  # fmt: skip
    return table, {"matchers": [m.name for m in chosen]}


def _best_of_family(table: pd.DataFrame, preset: str, validation, prior: bool):
    """(name, row) of the matcher with the highest validation F1 (test F1 without it) that does
    (``prior``) or does not read the localisation prior, at ``preset``; None if there is none
    that can run there (a prior reader under ``denied`` is in no comparison)."""
    from eval.studies.v2x_table import REFERENCE_ROWS, reads_prior, runnable

    rows = table[(table["preset"] == preset) & ~table["matcher"].isin(REFERENCE_ROWS)]
    rows = rows[rows["matcher"].isin(runnable(list(rows["matcher"]), preset))]
    rows = rows[[reads_prior(m) == prior for m in rows["matcher"]]]
    if rows.empty:
        return None
    scores = (validation or {}).get(preset, {})
    key = [(-scores.get(m, -1.0), -f, m) for m, f in zip(rows["matcher"], rows["f1_mean"], strict=True)]  # fmt: skip
    best = min(key)[2]
    return best, rows[rows["matcher"] == best].iloc[0]


def sensor_lines(results: Path) -> list[str]:
    """Per preset and matcher family (with / without the prior): the validation-chosen matcher's
    test F1 on LiDAR boxes against on camera detections; a sensor "favours" the family only
    where the two intervals do not overlap."""
    from eval.studies.v2x_table import _ranged, _validation

    results = Path(results)
    camera_path = results / "table_v2x.csv"
    if not camera_path.is_file():
        return []
    lidar = pd.read_csv(results / f"table_{NAME}.csv", keep_default_na=False, na_values=[""])
    camera = pd.read_csv(camera_path, keep_default_na=False, na_values=[""])
    val_lidar, val_camera = _validation(results, NAME), _validation(results)
    out = []
    for preset in dict.fromkeys(lidar["preset"]):
        for prior, family in ((True, "with the prior"), (False, "without a prior")):
            a = _best_of_family(lidar, preset, val_lidar, prior)
            b = _best_of_family(camera, preset, val_camera, prior)
            if a is None or b is None or a[1].f1_mean == 0 and b[1].f1_mean == 0:
                continue
            (na, ra), (nb, rb) = a, b
            if ra.f1_low > rb.f1_high:
                verdict = "LiDAR boxes favour it"
            elif rb.f1_low > ra.f1_high:
                verdict = "cameras favour it"
            else:
                verdict = "the intervals overlap: no sensor is shown to favour it"
            out.append(
                f"`{preset}`, {family}: LiDAR `{na}` {_ranged(ra.f1_mean, ra.f1_low, ra.f1_high)} F1, "
                f"camera `{nb}` {_ranged(rb.f1_mean, rb.f1_low, rb.f1_high)} F1 — {verdict}"
            )  # fmt: skip
    return out


def goal_line(results: Path) -> list[str]:
    """Under ``gnss-urban``: the validation-chosen matcher's F1 and success@(1 m, 2°) on LiDAR
    boxes against the oracle's success, with intervals."""
    from eval.studies.v2x_table import ORACLE_ROW, _ranged, _validation, chosen_row

    table = pd.read_csv(Path(results) / f"table_{NAME}.csv", keep_default_na=False, na_values=[""])
    found = chosen_row(table, "gnss-urban", _validation(Path(results), NAME))
    oracle = table[(table["preset"] == "gnss-urban") & (table["matcher"] == ORACLE_ROW)]
    if found is None or oracle.empty:
        return []
    name, row = found
    o = oracle.iloc[0]
    return [
        f"Under `gnss-urban` on LiDAR boxes the matcher chosen on validation, `{name}`, reaches "
        f"F1 {_ranged(row.f1_mean, row.f1_low, row.f1_high)} and success@(1 m, 2°) "
        f"{_ranged(row.success_1m_2deg, row.success_low, row.success_high)}; the oracle "
        f"(true matches) {_ranged(o.success_1m_2deg, o.success_low, o.success_high)}"
    ]


def readme_part(results: Path, rel: str) -> list[str]:
    """Report lines for the LiDAR table (none without ``table_v2x_lidar.md``)."""
    from eval.studies.v2x_table import compact_markdown

    results = Path(results)
    markdown = compact_markdown(results, NAME, LABEL)
    if markdown is None:
        return []
    return [
        "### The V2X task on LiDAR boxes",
        "",
        "`cad-v2x-lidar`: the cad-v2x scenes sensed by a 64-channel roof LiDAR; the boxes are "
        "cadsim's LiDAR detector's (its misses, false positives and centre error: docs/lidar.md). "
        "Every matcher that runs without pixels, under the camera table's protocol. Per preset "
        f"the best by validation F1, the best without a prior and the reference rows; every "
        f"matcher: [{rel}/table_{NAME}.md]({rel}/table_{NAME}.md).",
        "",
        markdown,
        "",
        *[f"- {line}." for line in goal_line(results)],
        *[f"- {line}." for line in sensor_lines(results)],
        "",
        f"(`{rel}/table_{NAME}.csv`, `{rel}/table_{NAME}_intervals.csv`, `{rel}/{NAME}/`.)",
        "",
    ]


__all__ = ["LABEL", "NAME", "SCENARIO", "evaluate_lidar", "generate_lidar_splits", "readme_part"]
