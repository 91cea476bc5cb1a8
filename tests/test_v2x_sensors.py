"""Camera against LiDAR on the same frames: a two-sensor (``sensor = "both"``) split read as
each sensor gives the same frames and truth; the runner keeps the two readings apart; the
paired LiDAR − camera differences find a planted effect with episode-level intervals and Holm;
the report's sensor lines come from the paired rows alone."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from cadsim.cli import main
from cadsim.dataset import Dataset
from cadsim.sensing.box_features import BOX_CUES
from eval.core.tasks import MatcherSpec, RunSpec
from eval.studies.v2x.sensors import (
    CAMERA_FAVOURS,
    INCLUDES_ZERO,
    LIDAR_FAVOURS,
    NAME,
    mean_validation,
    sensor_differences,
    sensor_lines,
)

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"
BOTH = SCENARIOS / "cad-v2x-both.toml"


@pytest.fixture(scope="module")
def both_dataset(tmp_path_factory) -> Path:
    work = tmp_path_factory.mktemp("both")
    shutil.copy(SCENARIOS / "cad-vtypes.add.xml", work / "cad-vtypes.add.xml")
    scenario = work / "both.toml"
    scenario.write_text(BOTH.read_text())
    out = work / "ds"
    args = ["generate", str(scenario), "--out", str(out), "--pairs", "2", "--workers", "1"]
    assert main([*args, "--no-progress"]) == 0
    return out


@pytest.mark.render
def test_both_split_read_as_camera_and_as_lidar_gives_the_same_frames(both_dataset):
    camera, lidar = Dataset(both_dataset, verify=True), Dataset(both_dataset, sensor="lidar")
    assert Dataset(both_dataset, sensor="camera").sensor is None  # the stored detections
    assert len(camera) == len(lidar) == 2
    for c, li in zip(camera, lidar, strict=True):
        # the same record: frame, observers, time, world objects
        assert (c.path, c.name, c.episode, c.sim_seed) == (li.path, li.name, li.episode, li.sim_seed)  # fmt: skip
        assert c.time == li.time and c.observer_ids == li.observer_ids
        assert c.record["objects"] == li.record["objects"]
        # each sensor's own detections, truth from the same object ids
        assert c.cues != BOX_CUES and li.cues == BOX_CUES and li.problem().pixels1 is None
        objects = {o["id"] for o in c.record["objects"]}
        for view in (li.view1, li.view2):
            assert all(i in objects or i.startswith("clutter:lidar:") for i in view.object_ids)
        for pair in (c, li):
            i, j = pair.gt_pairs.T
            ids1 = [pair.view1.object_ids[k] for k in i]
            assert ids1 == [pair.view2.object_ids[k] for k in j] and set(ids1) <= objects
        # the LiDAR reading is the LiDAR's: its pose is the sensor's, the boxes its detector's
        sweep = c.lidar[0]
        assert np.allclose(li.cameras[0].position, sweep.pose[:3, 3])
        assert li.view1.object_ids == [str(v) for v in sweep.boxes["ids"]]
        assert li.true_relative_pose() is not None and li.prior() is not None


@pytest.mark.render
def test_the_runner_keeps_the_two_readings_apart(both_dataset, tmp_path):
    from cadsim.generation.executors import make_executor
    from eval.core.cache import ResultCache
    from eval.core.runner import Runner, requests_for

    ds = Dataset(both_dataset)
    spec = MatcherSpec("appearance")
    with make_executor(1, None) as executor:
        runner = Runner(ResultCache(tmp_path / "cache"), executor, progress=False)
        runs = {
            sensor: runner.run(
                requests_for([(str(both_dataset), ds.checksum)], [spec], [0], sensor=sensor)
            )[0]
            for sensor in ("camera", "lidar")
        }
    camera, lidar = runs["camera"], runs["lidar"]
    assert camera.spec.key() != lidar.spec.key()
    assert [o.name for o in camera.outcomes] == [o.name for o in lidar.outcomes]
    boxes = Dataset(both_dataset, sensor="lidar")
    assert [o.n1 for o in lidar.outcomes] == [len(p.view1) for p in boxes]
    assert [o.n1 for o in camera.outcomes] == [len(p.view1) for p in ds]


def test_a_sensor_the_records_lack_is_a_one_line_error(tmp_path):
    from cadsim.dataset.sensor_view import check_sensor

    with pytest.raises(ValueError, match=r"m.json: sensor 'lidar'.*camera detections only"):
        check_sensor("lidar", "camera", "m.json")
    with pytest.raises(ValueError, match=r"sensor: expected one of camera, lidar"):
        check_sensor("radar", "both", "m.json")
    assert check_sensor("lidar", "both", "m.json") == "lidar"
    assert check_sensor("lidar", "lidar", "m.json") is None


def test_run_keys_of_other_runs_do_not_depend_on_the_sensor_field():
    plain = RunSpec("c", MatcherSpec("sm"), 0, None, "v")
    assert plain.key() == RunSpec("c", MatcherSpec("sm"), 0, None, "v", sensor=None).key()
    assert plain.key() != RunSpec("c", MatcherSpec("sm"), 0, None, "v", sensor="lidar").key()


def _per_pair(effects: dict[str, float], episodes: int = 12, per_episode: int = 2, seed: int = 0):
    """Per-pair F1 rows of the same frames on two sensors: LiDAR = camera + effect + episode
    effect + noise, 2 runs, preset gnss-urban."""
    rng = np.random.default_rng(seed)
    rows = {"lidar": [], "camera": []}
    for matcher, effect in effects.items():
        for e in range(episodes):
            shift = rng.normal(scale=0.03)
            for k in range(per_episode):
                pair, base = e * per_episode + k, rng.uniform(0.3, 0.7)
                for run in (0, 1):
                    common = {"preset": "gnss-urban", "matcher": matcher, "seed": run}
                    common |= {"pair": pair, "episode": e, "sim_seed": 100 + e}
                    noise = rng.normal(scale=0.01)
                    rows["camera"].append(common | {"f1": base})
                    rows["lidar"].append(common | {"f1": base + effect + shift + noise})
    return pd.DataFrame(rows["lidar"]), pd.DataFrame(rows["camera"])


def test_paired_differences_find_a_planted_effect_with_episode_intervals_and_holm():
    lidar, camera = _per_pair({"consistency": 0.2, "sm": -0.2, "freealign": 0.0})
    validation = mean_validation(
        {"gnss-urban": {"consistency": 0.6, "sm": 0.4, "freealign": 0.5}},
        {"gnss-urban": {"consistency": 0.2, "sm": 0.5, "freealign": 0.5}},
    )
    assert validation["gnss-urban"]["consistency"] == pytest.approx(0.4)
    table = sensor_differences(lidar, camera, validation).set_index("matcher")
    assert (table["clusters"] == 12).all() and (table["pairs"] == 24).all()
    up, down, flat = table.loc["consistency"], table.loc["sm"], table.loc["freealign"]
    assert up["diff"] == pytest.approx(0.2, abs=0.03) and up.ci_low > 0
    assert down["diff"] == pytest.approx(-0.2, abs=0.03) and down.ci_high < 0
    assert (up.verdict, down.verdict) == (LIDAR_FAVOURS, CAMERA_FAVOURS)
    assert flat.ci_low < 0 < flat.ci_high and flat.verdict == INCLUDES_ZERO
    assert (table["p_holm"] >= table["p_value"]).all()
    # lidar_f1 - camera_f1 is the mean difference: the same frames on both sides
    assert (table["lidar_f1"] - table["camera_f1"]).to_numpy() == pytest.approx(table["diff"])
    # one chosen row per family: the highest mean validation F1 (freealign, 0.5 > 0.45 > 0.4)
    assert table.index[table["chosen"]].tolist() == ["freealign"]


def _planted(diffs: dict[str, list[float]]) -> tuple[pd.DataFrame, pd.DataFrame]:
    """One frame pair per episode; LiDAR F1 = camera F1 (0.5) + the given difference."""
    lidar, camera = [], []
    for matcher, values in diffs.items():
        for e, d in enumerate(values):
            common = {"preset": "gnss-urban", "matcher": matcher, "seed": 0, "pair": e}
            common |= {"episode": e, "sim_seed": e}
            camera.append(common | {"f1": 0.5})
            lidar.append(common | {"f1": 0.5 + d})
    return pd.DataFrame(lidar), pd.DataFrame(camera)


def test_holm_withholds_a_verdict_the_single_interval_would_give():
    from eval.studies.v2x.sensors import NOT_AFTER_HOLM

    effect = {"consistency": [0.1, 0.2, 0.05, 0.15]}  # t = 3.9 on 3 df: p = 0.03
    single = sensor_differences(*_planted(effect)).iloc[0]
    assert single.ci_low > 0 and single.p_holm == pytest.approx(single.p_value)
    assert single.verdict == LIDAR_FAVOURS
    nulls = {f"m{k}": [0.1, -0.1, 0.05 * (k % 3), -0.05] for k in range(20)}
    many = sensor_differences(*_planted(effect | nulls)).set_index("matcher")
    row = many.loc["consistency"]
    assert row.ci_low > 0 and row.p_holm > 0.05 and row.verdict == NOT_AFTER_HOLM


def test_frames_that_differ_between_the_sensors_are_refused():
    lidar, camera = _per_pair({"sm": 0.1})
    camera.loc[camera["pair"] == 3, "sim_seed"] = 999
    with pytest.raises(ValueError, match="not the same frames"):
        sensor_differences(lidar, camera)


def test_a_prior_matcher_is_not_compared_where_it_has_no_input():
    lidar, camera = _per_pair({"pose_refine": 0.1, "sm": 0.1})
    for frame in (lidar, camera):
        frame["preset"] = "denied"
    table = sensor_differences(lidar, camera)
    assert table["matcher"].tolist() == ["sm"]


def _sensor_rows(rows) -> pd.DataFrame:
    columns = ["preset", "matcher", "family", "chosen", "lidar_f1", "camera_f1", "diff"]
    columns += ["ci_low", "ci_high", "clusters", "pairs", "p_value", "p_holm", "verdict"]
    return pd.DataFrame(rows, columns=columns)


def test_the_report_lines_come_from_the_paired_rows_only(tmp_path):
    from eval.studies.v2x.lidar import NAME as LIDAR

    # marginal tables that would tell another story (disjoint intervals the other way)
    marginal = ["preset", "matcher", "f1_mean", "f1_low", "f1_high"]
    pd.DataFrame([("gnss-urban", "pose_refine", 0.9, 0.85, 0.95)], columns=marginal).to_csv(
        tmp_path / f"table_{LIDAR}.csv", index=False
    )
    pd.DataFrame([("gnss-urban", "pose_refine", 0.5, 0.45, 0.55)], columns=marginal).to_csv(
        tmp_path / "table_v2x.csv", index=False
    )
    assert sensor_lines(tmp_path) == []  # no paired rows: no sensor line at all
    _sensor_rows([
        ("gnss-urban", "pose_refine", "with the prior", True, 0.7, 0.8, -0.1, -0.2, -0.01, 13, 25, 0.01, 0.02, CAMERA_FAVOURS),
        ("gnss-urban", "sm", "without a prior", False, 0.5, 0.3, 0.2, 0.1, 0.3, 13, 25, 0.001, 0.001, LIDAR_FAVOURS),
        ("gnss-urban", "freealign", "without a prior", True, 0.5, 0.45, 0.05, -0.05, 0.15, 13, 25, 0.3, 0.6, INCLUDES_ZERO),
    ]).to_csv(tmp_path / f"table_{NAME}.csv", index=False)  # fmt: skip
    lines = sensor_lines(tmp_path)
    assert len(lines) == 2  # the chosen rows only
    prior, free = lines
    assert "`pose_refine`" in prior and prior.endswith(CAMERA_FAVOURS)
    assert "-10.0 [-20.0, -1.0]" in prior and "13 episodes" in prior
    assert "`freealign`" in free and free.endswith(INCLUDES_ZERO)


@pytest.mark.render
def test_the_two_sensor_scenario_has_the_camera_scenarios_frames(both_dataset, tmp_path):
    from eval.studies.v2x.sensors import same_camera_frames

    shutil.copy(SCENARIOS / "cad-vtypes.add.xml", tmp_path / "cad-vtypes.add.xml")
    scenario = tmp_path / "camera.toml"
    scenario.write_text((SCENARIOS / "cad-v2x.toml").read_text())
    camera = tmp_path / "camera"
    args = ["generate", str(scenario), "--out", str(camera), "--pairs", "2", "--workers", "1"]
    assert main([*args, "--no-progress"]) == 0
    # cad-v2x and cad-v2x-both: the same records' camera detections, byte for byte
    assert same_camera_frames(camera, both_dataset)
    # a record whose detections differ is not the same frame
    copy = tmp_path / "copy"
    shutil.copytree(both_dataset, copy)
    record = sorted((copy / "pairs").iterdir())[1] / "detections.npz"
    record.write_bytes(record.read_bytes() + b"\0")
    assert not same_camera_frames(camera, copy)


def test_the_camera_tables_runs_stand_in_only_when_they_cover_every_compared_run(tmp_path):
    from eval.studies.v2x.lidar import _camera_runs_cover
    from eval.studies.v2x.table import PRESETS

    specs = [MatcherSpec("sm"), MatcherSpec("pose_refine")]
    rows = [(m, s, p) for m in ("sm", "pose_refine", "mos") for s in (0, 1) for p in PRESETS]
    table = pd.DataFrame(rows, columns=["matcher", "seed", "preset"])
    table.to_csv(tmp_path / "metrics_per_pair.csv", index=False)
    assert _camera_runs_cover(tmp_path, specs, [0, 1])
    assert not _camera_runs_cover(tmp_path, specs, [0, 1, 2])  # a run seed missing
    assert not _camera_runs_cover(tmp_path, [*specs, MatcherSpec("freealign")], [0, 1])
    table[table["preset"] != "rtk"].to_csv(tmp_path / "metrics_per_pair.csv", index=False)
    assert not _camera_runs_cover(tmp_path, specs, [0, 1])  # a preset missing
    assert not _camera_runs_cover(tmp_path / "nothing", specs, [0, 1])


def test_the_two_sensor_scenario_is_cad_v2x_with_a_lidar():
    """cad-v2x-both must stay cad-v2x plus the LiDAR (else its frames drift away from cad-v2x's
    and the camera table's runs no longer stand for its camera side)."""
    from cadsim.scenario import load_scenario

    camera, both = load_scenario(SCENARIOS / "cad-v2x.toml"), load_scenario(BOTH)
    assert (both.sensor, camera.sensor) == ("both", "camera")
    assert both.lidar == load_scenario(SCENARIOS / "cad-v2x-lidar.toml").lidar
    for key in ("seed", "traffic", "camera", "observers", "noise", "detection", "sampling"):
        assert getattr(both, key) == getattr(camera, key), key
    for key in ("localisation", "appearance"):
        assert getattr(both, key, None) == getattr(camera, key, None), key


@pytest.mark.render
def test_the_common_readings_keep_what_lies_in_both_sensors_coverage_by_geometry(both_dataset):
    from cadsim.dataset.sensor_view import _lidar_boxes
    from eval.studies.v2x.sensors import COVERED, camera_fully_covered, coverage_counts

    stored = Dataset(both_dataset)
    lidar, common = (
        Dataset(both_dataset, sensor="lidar"),
        Dataset(both_dataset, sensor="lidar-common"),
    )
    camera_common = Dataset(both_dataset, sensor="camera-common")
    dropped = kept_false = 0
    for s, whole, shared, cam_shared in zip(stored, lidar, common, camera_common, strict=True):
        poses, boxes = _lidar_boxes(s)
        max_depth = float(s._detection["max_depth_m"])
        for k, (camera, pose, found) in enumerate(zip(s.cameras, poses, boxes, strict=True)):
            view, part = (whole.view1, shared.view1) if k == 0 else (whole.view2, shared.view2)
            # the rule recomputed by hand from the box centres: in front, in the image, in range
            world = found["centres"] @ pose[:3, :3].T + pose[:3, 3]
            c = camera.world_to_camera(world)
            uv = c[:, :2] / np.maximum(c[:, 2:], 1e-9) * camera.fx + [camera.width / 2, camera.height / 2]  # fmt: skip
            inside = (c[:, 2] > 0) & (c[:, 2] <= max_depth) & (uv >= 0).all(axis=1)
            inside &= (uv[:, 0] < camera.width) & (uv[:, 1] < camera.height)
            expect = [i for i, keep in zip(view.object_ids, inside, strict=True) if keep]
            assert part.object_ids == expect  # order kept, ids never consulted
            dropped += len(view) - len(part)
            kept_false += sum(i.startswith("clutter") for i in part.object_ids)
        # ground truth follows the kept detections; the camera side keeps its own subset
        for pair in (shared, cam_shared):
            i, j = pair.gt_pairs.T
            assert [pair.view1.object_ids[a] for a in i] == [pair.view2.object_ids[b] for b in j]
        assert set(cam_shared.view1.object_ids) <= set(s.view1.object_ids)
    assert dropped > 0  # the LiDAR sees around and beyond the camera
    counts = coverage_counts(both_dataset)
    assert counts["objects"] == COVERED
    views = 2 * len(stored)
    assert counts["lidar_per_view"] + counts["lidar_extra_per_view"] == pytest.approx(
        sum(len(p.view1) + len(p.view2) for p in lidar) / views
    )
    assert counts["lidar_extra_per_view"] == pytest.approx(dropped / views)
    assert 0 <= counts["lidar_extra_false_per_view"] <= counts["lidar_extra_per_view"]
    assert camera_fully_covered(both_dataset) == (
        counts["camera_per_view"] == sum(len(p.view1) + len(p.view2) for p in stored) / views
    )


def test_the_sensor_table_says_which_objects_it_covers(tmp_path):
    from eval.studies.v2x.sensors import COLUMNS, COVERED

    rng = np.random.default_rng(0)
    rows = [
        {"preset": "rtk", "matcher": "sm", "pair": k, "episode": k // 2, "sim_seed": 1, "f1": f}
        for k, f in enumerate(rng.uniform(0.4, 0.9, 12))
    ]
    lidar, camera = pd.DataFrame(rows), pd.DataFrame(rows).assign(f1=lambda d: d.f1 - 0.1)
    coverage = {"objects": COVERED, "camera_per_view": 9.75, "lidar_per_view": 9.5}
    coverage |= {"lidar_extra_per_view": 8.6, "lidar_extra_false_per_view": 4.6}
    table = sensor_differences(lidar, camera, coverage=coverage)
    assert list(table.columns) == list(COLUMNS)
    assert (table["objects"] == COVERED).all() and (table["lidar_extra_per_view"] == 8.6).all()
    table.assign(chosen=True).to_csv(tmp_path / f"table_{NAME}.csv", index=False)
    (line,) = sensor_lines(tmp_path)
    assert "same region (camera 9.8 and LiDAR 9.5 detections per view" in line
    assert "the LiDAR's 8.6 others, 4.6 of them false positives, left out" in line


@pytest.mark.render
def test_the_sensor_table_compares_each_familys_validation_choice_on_the_common_region(
    both_dataset, tmp_path
):
    """End to end on a 2-pair test and validation split: the LiDAR table, the camera side and
    the common-region runs of the matchers chosen on validation alone — one per family and
    preset, with the parameters and τ of each sensor's full evaluation (no re-tuning)."""
    from cadsim.generation.local_executor import SerialExecutor
    from eval.core.cache import ResultCache
    from eval.core.runner import Runner
    from eval.studies.v2x.lidar import LIDAR_COMMON, evaluate_lidar
    from eval.studies.v2x.lidar import NAME as LIDAR_NAME
    from eval.studies.v2x.table import PRESETS

    shutil.copy(SCENARIOS / "cad-vtypes.add.xml", tmp_path / "cad-vtypes.add.xml")
    scenario = tmp_path / "both.toml"
    scenario.write_text(BOTH.read_text())
    val = tmp_path / "val"
    args = ["generate", str(scenario), "--out", str(val), "--pairs", "2", "--seed", "1011"]
    assert main([*args, "--workers", "1", "--no-progress"]) == 0
    runner = Runner(ResultCache(tmp_path / "cache"), SerialExecutor(), progress=False)
    specs = [MatcherSpec("sm"), MatcherSpec("consistency"), MatcherSpec("pose_refine")]
    out = tmp_path / "out"
    evaluate_lidar(both_dataset, val, specs, [0], runner, out, tune=False)
    table = pd.read_csv(out / f"table_{NAME}.csv")
    assert len(table) and table["chosen"].all()
    for preset, rows in table.groupby("preset"):
        assert preset in PRESETS
        assert rows["family"].is_unique  # at most one matcher per family and preset
    assert "pose_refine" not in set(table.loc[table["preset"] == "denied", "matcher"])
    common = pd.read_csv(out / LIDAR_NAME / LIDAR_COMMON / "metrics_per_pair.csv")
    compared = set(zip(table["preset"], table["matcher"], strict=True))
    assert set(zip(common["preset"], common["matcher"], strict=True)) == compared
    # each sensor's own τ from its full evaluation, not one fitted on the common region
    full = pd.read_csv(out / LIDAR_NAME / "rtk" / "thresholds.csv")
    taus = dict(zip(full["matcher"], full["tau"], strict=True))
    for row in common[common["preset"] == "rtk"].itertuples():
        assert row.tau == pytest.approx(taus[row.matcher])


@pytest.mark.render
def test_the_coverage_counts_are_counted_once_per_dataset(both_dataset, tmp_path, monkeypatch):
    from eval.studies.v2x import sensors

    monkeypatch.setenv("CADSIM_CACHE_DIR", str(tmp_path / "cadsim-cache"))
    counted = sensors.coverage_counts(both_dataset)
    monkeypatch.setattr(sensors, "_coverage_counts", lambda folder: pytest.fail("counted again"))
    assert sensors.coverage_counts(both_dataset) == counted
    (entry,) = (tmp_path / "cadsim-cache" / "derived").glob("*.json")
    entry.write_text(entry.read_text().replace('"lidar_per_view":', '"lidar_per_view":1'))
    recounted = []
    monkeypatch.setattr(sensors, "_coverage_counts", lambda f: recounted.append(f) or counted)
    assert sensors.coverage_counts(both_dataset) == counted
    assert recounted == [both_dataset]  # the edited entry was refused, the counts counted again
