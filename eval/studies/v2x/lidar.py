"""The LiDAR V2X table (``results/table_v2x_lidar.{md,csv}``): what the matchers get on boxes
that cadsim's own LiDAR detector found, beside the camera table and the label-quality box table.

Data. ``scenarios/cad-v2x-both.toml`` — cad-v2x's junction, traffic, observers, seeds and
localisation preset, each observer sensing with its camera *and* an HDL-64E on its roof — is
generated into ``DATA/cad-v2x-both`` (test, seed 11) and ``DATA/cad-v2x-both-val`` (validation,
seed 1011), as many pairs as the camera table's splits. Pairs are accepted by their camera
detections, so the frames are cad-v2x's. Read as LiDAR (``sensor="lidar"``,
:mod:`cadsim.dataset.sensor_view`), each view's detections are the LiDAR box detector's
(``cadsim.sensing.lidar.box_detector``): its misses, splits, merges, wall slivers and centre bias
(its regime card: ``cadsim info``), reported classes from box size, the box feature vector of
the *fitted* sizes, headings; no pixels. Read as camera, the same records give cad-v2x's camera
detections.

Protocol. The camera table's (:func:`eval.studies.v2x.table.evaluate_v2x`): every matcher that
runs without pixels (:func:`eval.studies.v2x.boxes.box_matchers`), every preset, the same tuning
budget, τ and parameters on the validation split, oracle and prior rows — on the LiDAR boxes
(the LiDAR table) and on the camera detections of the same records, whose per-pair F1 the
paired sensor comparison (:mod:`eval.studies.v2x.sensors`) takes: the camera V2X table's runs
where its splits hold these very camera records (checked record by record), else an evaluation
of the two-sensor split as camera. Files: ``table_v2x_lidar.{md,csv}``,
``table_v2x_lidar_intervals.csv``, ``v2x_lidar/<preset>/``; ``table_v2x_sensors.csv``, from the
two sensors' detections in the region both cover (``sensor="lidar-common"`` and
``"camera-common"``): per preset the matcher of each family chosen on the two sensors' full
validation F1, run on the test split's common region with each sensor's own parameters and τ
(under ``v2x_lidar/``: ``lidar_common/metrics_per_pair.csv`` and ``camera_common/…``, the
latter the camera runs themselves when no camera detection lies outside the region); only when
the camera side is evaluated here, under ``v2x_lidar/``: ``table_camera.{md,csv}``,
``table_camera_intervals.csv``, ``camera/<preset>/``.
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
CAMERA_LABEL = "CAD-V2X camera (two-sensor split)"
CAMERA_NAME = "camera"  # the camera side's table and folder under ``v2x_lidar/``
LIDAR_COMMON, CAMERA_COMMON = "lidar_common", "camera_common"  # both sensors' shared region
SCENARIO = "scenarios/cad-v2x-both.toml"


def generate_lidar_splits(
    root: Path,
    data: Path,
    pairs: dict[str, int],
    val_seed_offset: int,
    generate: Callable,
    frames: tuple[str | Path, str | Path] | None = None,
) -> tuple[Path, Path, dict]:
    """The test and validation splits of :data:`SCENARIO` under ``data``, ``pairs[split]`` frame
    pairs each (``generate(path, folder, n, seed, frames_from)`` makes or resumes one); (test
    dir, val dir, what the run record keeps). ``frames``: cad-v2x's (test, validation) folders,
    the camera splits of the same frames, from which the records take their camera captures
    (only the LiDAR is swept; :mod:`cadsim.generation.frames_from`)."""
    from cadsim.scenario import load_scenario

    path = root / SCENARIO
    seed = load_scenario(path).seed
    test, val = data / "cad-v2x-both", data / "cad-v2x-both-val"
    record = {}
    splits = (("test", test, None), ("val", val, seed + val_seed_offset))
    for (split, folder, split_seed), frames_from in zip(splits, frames or (None, None), strict=True):  # fmt: skip
        n = pairs[split]
        log.info("[v2x lidar generate] %s %s: %d pairs", LABEL, split, n)
        made = generate(path, folder, n, split_seed, frames_from)
        record[split] = {"dir": str(folder), "pairs": n, "seed": split_seed or seed}
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
    camera_table: tuple[str | Path, str | Path] | None = None,
) -> tuple[pd.DataFrame, dict]:
    """The full table's protocol on the two-sensor splits read as LiDAR, then as camera, and
    the paired sensor comparison (module docstring); (LiDAR table, record). ``camera_table``:
    the (test, validation) folders the camera V2X table was evaluated on in ``out_dir`` (same
    seeds and tuning); where they hold the very camera records of the two-sensor splits
    (:func:`eval.studies.v2x.sensors.same_camera_frames`), that table's runs are the camera
    side and nothing is evaluated twice."""
    from eval.core.result_files import write_csv
    from eval.engine.validation_choice import recorded_validation
    from eval.studies.v2x.boxes import box_matchers
    from eval.studies.v2x.sensors import (
        camera_fully_covered,
        chosen_per_family,
        coverage_counts,
        mean_validation,
        same_camera_frames,
        write_sensor_table,
    )
    from eval.studies.v2x.table import SUBDIR, evaluate_v2x

    out_dir = Path(out_dir)
    chosen = box_matchers(matchers)
    log.info("[v2x lidar] %s: %d matchers on %s, %s", LABEL, len(chosen), test_dir, val_dir)
    table = evaluate_v2x(
        test_dir, val_dir, LABEL, chosen, seeds, runner, out_dir, tune=tune, name=NAME,
        sensor="lidar",
    )  # fmt: skip
    camera_dir = out_dir / SUBDIR
    if not _camera_runs_cover(camera_dir, chosen, seeds) or not (
        camera_table is not None
        and same_camera_frames(camera_table[0], test_dir)
        and same_camera_frames(camera_table[1], val_dir)
    ):
        log.info("[v2x lidar] %s: the same records' camera detections", CAMERA_LABEL)
        camera_dir = out_dir / NAME / CAMERA_NAME
        evaluate_v2x(
            test_dir, val_dir, CAMERA_LABEL, chosen, seeds, runner, out_dir / NAME, tune=tune,
            name=CAMERA_NAME, sensor="camera",
        )  # fmt: skip
    else:
        log.info("[v2x lidar] camera side: the camera table's runs (the same camera records)")
    # The sensor comparison: both sensors on the objects both cover (eval.studies.v2x.sensors),
    # each family's validation-chosen matcher with each sensor's own parameters and τ.
    validation = mean_validation(
        recorded_validation(out_dir, NAME), recorded_validation(camera_dir.parent, camera_dir.name)
    )
    compared = chosen_per_family(validation, [m.label for m in chosen])
    common = {}
    for sensor, folder, source in (
        ("lidar-common", LIDAR_COMMON, out_dir / NAME),
        ("camera-common", CAMERA_COMMON, camera_dir),
    ):
        where = out_dir / NAME / folder
        if sensor == "camera-common" and camera_fully_covered(test_dir):
            per_pair = pd.read_csv(
                camera_dir / "metrics_per_pair.csv", keep_default_na=False, na_values=[""]
            )  # no camera detection lies outside the region: the camera runs are its runs
        else:
            log.info("[v2x lidar] %s: the detections both sensors cover (%s)", LABEL, sensor)
            per_pair = common_region_runs(
                test_dir, val_dir, sensor, source, chosen, compared, seeds, runner
            )
        where.mkdir(parents=True, exist_ok=True)
        write_csv(per_pair, where / "metrics_per_pair.csv")
        common[sensor] = per_pair
    write_sensor_table(
        common["lidar-common"], common["camera-common"], validation, out_dir,
        coverage_counts(test_dir),
    )  # fmt: skip
    camera_side = str(camera_dir.relative_to(out_dir))
    return table, {"matchers": [m.name for m in chosen], "camera_side": camera_side}


def common_region_runs(
    test_dir: str | Path,
    val_dir: str | Path,
    sensor: str,
    source: Path,
    matchers: Sequence[MatcherSpec],
    compared: dict[str, list[str]],
    seeds: Sequence[int],
    runner,
) -> pd.DataFrame:
    """Per-pair test metrics (with a ``preset`` column) of the matchers ``compared[preset]``
    on the test split read as ``sensor`` ("lidar-common" / "camera-common") under each preset,
    each with the parameters and τ its sensor's full evaluation chose on validation
    (``source/<preset>/thresholds.csv``): the common region restricts what is scored, not
    how a matcher was tuned, so no tuning or calibration is repeated on it."""
    from eval.engine.named_runs import run_named, score_runs
    from eval.engine.splits import open_entry
    from eval.engine.validation_choice import chosen_specs

    frames = []
    for preset, labels in compared.items():
        if not labels:
            continue
        thresholds = pd.read_csv(source / preset / "thresholds.csv", keep_default_na=False)
        (label,) = set(thresholds["dataset"])
        named, taus = chosen_specs(source / preset, label, matchers)
        named = {m: named[m] for m in labels}
        entry = open_entry(test_dir, val_dir, f"{LABEL} ({sensor})", preset, sensor)
        runs = run_named(
            runner, (entry.test_dir, entry.test_checksum), named, seeds,
            f"{entry.label} {preset} test", localisation=preset, sensor=sensor,
        )  # fmt: skip
        scored = score_runs(runs, {m: taus[m] for m in labels}, dataset=entry.label, split="test")
        frames.append(scored.assign(preset=preset))
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()


def _camera_runs_cover(folder: Path, matchers: Sequence[MatcherSpec], seeds: Sequence[int]) -> bool:
    """Whether ``folder/metrics_per_pair.csv`` (a V2X-protocol evaluation) has test runs of
    every one of ``matchers`` that can run under a preset, under every preset, for exactly
    ``seeds``."""
    from eval.studies.v2x.table import PRESETS, runnable

    path = folder / "metrics_per_pair.csv"
    if not path.is_file():
        return False
    runs = pd.read_csv(path, usecols=["matcher", "seed", "preset"])
    names = {m.label for m in matchers}
    have = runs[runs["matcher"].isin(names)]
    return set(have["seed"]) == set(seeds) and all(
        set(runnable(sorted(names), p)) <= set(have.loc[have["preset"] == p, "matcher"])
        for p in PRESETS
    )


def goal_line(results: Path) -> list[str]:
    """Under ``gnss-urban``: the validation-chosen matcher's F1 and success@(1 m, 2°) on LiDAR
    boxes against the oracle's success, with intervals."""
    from eval.engine.cells import ranged
    from eval.engine.validation_choice import recorded_validation
    from eval.studies.v2x.report import chosen_row
    from eval.studies.v2x.table import ORACLE_ROW

    table = pd.read_csv(Path(results) / f"table_{NAME}.csv", keep_default_na=False, na_values=[""])
    found = chosen_row(table, "gnss-urban", recorded_validation(Path(results), NAME))
    oracle = table[(table["preset"] == "gnss-urban") & (table["matcher"] == ORACLE_ROW)]
    if found is None or oracle.empty:
        return []
    name, row = found
    o = oracle.iloc[0]
    return [
        f"Under `gnss-urban` on LiDAR boxes the matcher chosen on validation, `{name}`, reaches "
        f"F1 {ranged(row.f1_mean, row.f1_low, row.f1_high)} and success@(1 m, 2°) "
        f"{ranged(row.success_1m_2deg, row.success_low, row.success_high)}; the oracle "
        f"(true matches) {ranged(o.success_1m_2deg, o.success_low, o.success_high)}"
    ]


def readme_part(results: Path, rel: str) -> list[str]:
    """Report lines for the LiDAR table (none without ``table_v2x_lidar.md``)."""
    from eval.engine.power import power_line
    from eval.engine.result_table import bullets
    from eval.studies.v2x.report import compact_markdown
    from eval.studies.v2x.sensors import NAME as SENSORS
    from eval.studies.v2x.sensors import sensor_lines

    markdown = compact_markdown(Path(results), NAME, LABEL)
    if markdown is None:
        return []
    lines = [
        "### The V2X task on LiDAR boxes",
        "",
        "`cad-v2x-both`: the cad-v2x frames sensed by each vehicle's camera and a 64-channel roof "
        "LiDAR; the boxes are cadsim's LiDAR detector's (its misses, false positives and centre "
        "error: docs/lidar.md). Every matcher that runs without pixels, under the camera table's "
        "protocol, on the LiDAR boxes and on the camera detections of the same records. Per preset "
        f"the best by validation F1, the best without a prior and the reference rows; every "
        f"matcher: [{rel}/table_{NAME}.md]({rel}/table_{NAME}.md).",
        "",
        markdown,
        "",
        *bullets(goal_line(results) + [line for line in (power_line(results, NAME),) if line]),
        "",
        "LiDAR against camera on the same frames and the same region — the detections of each "
        "sensor inside the camera's field of view and range, decided by geometry, false "
        "positives included — per preset and matcher family (the matcher "
        "chosen on validation, the same on both sensors): mean per-frame-pair difference of F1 "
        "with its 95 % interval over episodes; a sensor favours the family only where the "
        "difference stays beyond 0 after Holm's adjustment over every comparison of "
        f"[{rel}/table_{SENSORS}.csv]({rel}/table_{SENSORS}.csv):",
        "",
        *bullets(sensor_lines(results)),
        "",
        f"(`{rel}/table_{NAME}.csv`, `{rel}/table_{NAME}_intervals.csv`, `{rel}/{NAME}/`, "
        f"`{rel}/table_{SENSORS}.csv`.)",
        "",
    ]
    return lines


__all__ = ["LABEL", "NAME", "SCENARIO", "evaluate_lidar", "generate_lidar_splits", "readme_part"]
