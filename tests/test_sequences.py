"""Sequences (issue 41, data layer): the ``[sequence]`` table, generation of consecutive frames of
the same observers with their odometry, ``Dataset.sequence(k)``, verification, resume, the
odometry drift model against its stated magnitudes, and a fuzz over short and empty cases.
Uses the fake stages (no SUMO, no OpenGL)."""

from __future__ import annotations

import dataclasses
import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest
import test_generate_fakes as fakes
from test_generate_fakes import FAKE_STAGES, FakeScenario

from cadsim.dataset.manifest import DatasetError
from cadsim.dataset.reader import Dataset
from cadsim.generation.pipeline import GenerationError, generate_dataset
from cadsim.observer_pose import ObserverPose
from cadsim.scenario import ScenarioError, load_scenario
from cadsim.sensing.odometry import Odometer, OdometryModel, error_sigmas, relative_pose

ROOT = Path(__file__).resolve().parents[1]


def _scenario(frames=4, interval_s=0.25, snapshots=60, min_frames=1, **traffic) -> FakeScenario:
    return FakeScenario(
        traffic={"source": "fake", "moving": True, "snapshots": snapshots, **traffic},
        sampling={"pairs_per_episode": 2, "interval": 1.0},
        sequence={"frames": frames, "interval_s": interval_s, "min_frames": min_frames},
    )


def _generate(out: Path, scenario=None, pairs=3, **kw):
    return generate_dataset(
        scenario or _scenario(), out, pairs=pairs, workers=1, stages=FAKE_STAGES, progress=False,
        **kw,
    )  # fmt: skip


def _tree(out: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(out)): p.read_bytes()
        for p in sorted((out / "pairs").rglob("*"))
        if p.is_file()
    }


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("seq") / "ds"
    _generate(out)
    return out


# --------------------------------------------------------------------------- the scenario key


def _with(tmp_path: Path, extra: str) -> Path:
    path = tmp_path / "seq.toml"
    text = (ROOT / "scenarios" / "cad-v2x.toml").read_text()
    path.write_text(text + "\n" + extra)
    shutil.copy(ROOT / "scenarios" / "cad-vtypes.add.xml", tmp_path)
    return path


@pytest.mark.parametrize(
    "extra, key, words",
    [
        ("[sequence]\nframes = 0\ninterval_s = 0.2\n", "sequence.frames", ">= 1"),
        ("[sequence]\nframes = 3\ninterval_s = 0\n", "sequence.interval_s", "> 0"),
        ("[sequence]\nframes = 3\ninterval_s = 0.25\n", "sequence.interval_s", "multiple of 0.1"),
        ("[sequence]\nframes = 3\n", "sequence.interval_s", "missing"),
        ("[sequence]\nframes = 3\ninterval_s = 0.2\nmin_frames = 4\n", "sequence.min_frames", "<="),
        ("[sequence]\nframes = 3\ninterval_s = 0.2\nfps = 4\n", "sequence.fps", "unknown"),
        ('[sequence]\nframes = "ten"\ninterval_s = 0.2\n', "sequence.frames", "wrong type"),
    ],
)
def test_a_malformed_sequence_table_names_file_key_and_expectation(tmp_path, extra, key, words):
    with pytest.raises(ScenarioError) as info:
        load_scenario(_with(tmp_path, extra))
    assert info.value.key == key and words in str(info.value) and "seq.toml" in str(info.value)


def test_the_sequence_scenario_and_no_table_without_one():
    seq = load_scenario(ROOT / "scenarios" / "cad-v2x-seq.toml")
    assert seq.sequence["frames"] >= 2 and seq.sequence["interval_s"] == pytest.approx(0.2)
    assert load_scenario(ROOT / "scenarios" / "cad-v2x.toml").sequence is None


# --------------------------------------------------------------------------- generation


def test_sequences_are_frames_of_the_same_observers_in_time_order(reference):
    ds = Dataset(reference, verify=True)
    assert ds.manifest["format_version"] == 7 and ds.is_sequential
    assert ds.sequences == 3 == ds.manifest["sequences"] and len(ds) == 12
    for k in range(ds.sequences):
        frames = ds.sequence(k)
        assert [f.frame for f in frames] == [0, 1, 2, 3]
        assert {f.sequence_id for f in frames} == {frames[0].name}
        times = [f.time for f in frames]
        assert np.allclose(np.diff(times), 0.25)
        ids = {tuple(o["id"] for o in f.record["observers"]) for f in frames}
        assert ids == {("obs1", "obs2")}
        # frame 0 is the origin; odometry is the true relative motion plus a small drift
        assert frames[0].odometry[0].as_dict() == {"position": [0.0, 0.0], "yaw": 0.0, "distance_m": 0.0}  # fmt: skip
        for f in frames[1:]:
            for v, pose in enumerate(f.odometry):
                true = relative_pose(frames[0].observer_poses[v], f.observer_poses[v])
                assert abs(pose.x - true[0]) < 0.2 and abs(pose.y - true[1]) < 0.2
                assert pose.distance_m == pytest.approx(math.hypot(*true[:2]))
    # object identities persist across frames (the simulator's ids; for metrics)
    frames = ds.sequence(0)
    assert set(frames[0].view1.object_ids) & set(frames[-1].view1.object_ids)
    # a later sequence starts after the previous one's last frame
    assert ds.sequence(1)[0].time > ds.sequence(0)[-1].time


def test_sequences_are_byte_identical_across_runs_and_workers(reference, tmp_path):
    _generate(tmp_path / "again")
    assert _tree(tmp_path / "again") == _tree(reference)
    assert Dataset(tmp_path / "again").checksum == Dataset(reference).checksum


def test_resume_after_an_interruption_keeps_sequences_whole(reference, tmp_path, monkeypatch):
    out = tmp_path / "resumed"
    monkeypatch.setattr(fakes, "FAIL_AT_TIME", 1.5)  # dies inside episode 0's second sequence
    with pytest.raises(RuntimeError, match="injected"):
        _generate(out)
    monkeypatch.setattr(fakes, "FAIL_AT_TIME", None)
    _generate(out)
    assert _tree(out) == _tree(reference)
    # a sequence half on disk (killed between two frames' writes) is rewritten whole
    shutil.copytree(reference, tmp_path / "cut")
    last = Dataset(reference).sequence(2)
    manifest = json.loads((tmp_path / "cut" / "manifest.json").read_text())
    (tmp_path / "cut" / "manifest.json").write_text(json.dumps(manifest | {"complete": False}))
    for f in last[-2:]:
        shutil.rmtree(tmp_path / "cut" / "pairs" / f.name)
    _generate(tmp_path / "cut")
    assert _tree(tmp_path / "cut") == _tree(reference)


def test_datasets_without_a_sequence_are_unchanged_and_read_as_one_frame_sequences(tmp_path):
    plain = FakeScenario()
    _generate(tmp_path / "plain", plain, pairs=2)
    ds = Dataset(tmp_path / "plain", verify=True)
    assert ds.manifest["format_version"] == 5 and "sequence" not in ds.manifest["generation"]
    assert ds.sequences == 2 and [f.name for f in ds.sequence(1)] == [ds[1].name]
    assert ds[0].odometry is None and ds[0].sequence_id is None and ds[0].frame == 0


# --------------------------------------------------------------------------- fuzz


@pytest.mark.parametrize(
    "case",
    ["one-frame", "cut-short", "cut-short-dropped", "sim-ends", "empty"],
)
def test_fuzz_short_one_frame_and_empty_sequences(tmp_path, case):
    out = tmp_path / case
    if case == "one-frame":
        _generate(out, _scenario(frames=1))
        ds = Dataset(out, verify=True)
        assert ds.sequences == 3 == len(ds)
        assert all(f.frame == 0 and f.odometry[1].distance_m == 0 for f in ds)
    elif case == "cut-short":  # obs2 leaves at 0.5 s: the first sequence has frames 0, 0.25
        _generate(out, _scenario(frames=4, leave_at=0.5), pairs=1)
        ds = Dataset(out, verify=True)
        assert [f.time for f in ds.sequence(0)] == [0.0, 0.25]
        assert ds.sequence(0)[0].record["sequence"]["frames"] == 2
    elif case == "cut-short-dropped":  # min_frames 3: that short sequence is dropped
        scenario = _scenario(frames=4, leave_at=0.5, min_frames=3)
        with pytest.raises(GenerationError, match="only 0 of 1"):
            _generate(out, scenario, pairs=1, max_episodes=2)
    elif case == "sim-ends":  # the simulation ends inside a sequence (3 snapshots: 0 .. 0.5 s)
        _generate(out, _scenario(frames=10, snapshots=3), pairs=2)
        ds = Dataset(out, verify=True)
        assert all(len(ds.sequence(k)) == 3 for k in range(ds.sequences))
    else:  # no snapshot at all: nothing to accept, an error naming the shortfall
        with pytest.raises(GenerationError, match="only 0 of 1"):
            _generate(out, _scenario(snapshots=0), pairs=1, max_episodes=2)


def test_verification_refuses_tampered_sequence_fields(reference, tmp_path):
    from cadsim.dataset.checksum import record_dir_checksum

    def tamper(edit, what):
        out = tmp_path / what
        shutil.copytree(reference, out)
        manifest = json.loads((out / "manifest.json").read_text())
        entry = manifest["records"][1]
        path = out / "pairs" / entry["name"] / "record.json"
        record = json.loads(path.read_text())
        edit(record, manifest)
        path.write_text(json.dumps(record))
        entry["checksum"] = record_dir_checksum(path.parent, Dataset(reference).record_files)
        from cadsim.dataset.checksum import dataset_checksum

        manifest["checksum"] = dataset_checksum(r["checksum"] for r in manifest["records"])
        (out / "manifest.json").write_text(json.dumps(manifest))
        with pytest.raises(DatasetError) as info:
            Dataset(out, verify=True)
        return str(info.value)

    assert "sequence.id" in tamper(lambda r, m: r["sequence"].update(id="e00009_s00"), "id")
    assert "odometry" in tamper(lambda r, m: r["observers"][0].pop("odometry"), "odo")
    assert "records[1].frame" in tamper(lambda r, m: m["records"][1].update(frame=2), "frame")
    assert "sequence.frame" in tamper(lambda r, m: r["sequence"].update(frame=9), "frames")


# --------------------------------------------------------------------------- the drift model


def test_odometry_drift_matches_its_stated_model():
    """Over 4000 drawn sequences of a straight 40 m drive in 10 frames, the along-track and
    heading errors have mean 0 and the spreads of :func:`error_sigmas` (at a fixed seed the
    draw is fixed; the tolerances are > 6 standard errors, so a correct model cannot fail)."""
    model = OdometryModel()
    n, frames, step = 4000, 10, 40.0 / 9
    along, heading = np.empty(n), np.empty(n)
    for i in range(n):
        odo = Odometer(model, 1000 + i, frames)
        for k in range(frames):
            pose = odo.step(ObserverPose((10.0 + k * step, 5.0, 0.75), 0.0))
        along[i], heading[i] = pose.x - pose.distance_m, pose.yaw
    sigma_along, sigma_heading = error_sigmas(model, 40.0)
    assert sigma_along == pytest.approx(math.hypot(0.4, 0.02 * math.sqrt(40)))
    for values, sigma in ((along, sigma_along), (heading, sigma_heading)):
        assert abs(values.mean()) < 6 * sigma / math.sqrt(n)
        assert values.std() == pytest.approx(sigma, rel=0.1)
    # ~1 % of distance: the along-track spread is 1.0-1.1 % of the distance driven
    assert 0.01 <= sigma_along / 40.0 <= 0.011
    # a standing vehicle reports no motion at all
    odo = Odometer(model, 7, 3)
    poses = [odo.step(ObserverPose((1.0, 2.0, 0.0), 0.3)) for _ in range(3)]
    assert all(
        p.as_dict() == {"position": [0.0, 0.0], "yaw": 0.0, "distance_m": 0.0} for p in poses
    )


def test_odometry_is_relative_to_frame_0_in_its_body_frame():
    model = dataclasses.replace(OdometryModel(), scale_sigma=0, heading_sigma_deg_per_m=0)
    model = dataclasses.replace(model, position_walk=0, heading_walk_deg=0)
    odo = Odometer(model, 0, 3)
    odo.step(ObserverPose((5.0, 5.0, 0.0), math.pi / 2))
    odo.step(ObserverPose((5.0, 8.0, 0.0), math.pi / 2))
    pose = odo.step(ObserverPose((3.0, 8.0, 0.0), math.pi))
    assert (pose.x, pose.y, pose.yaw, pose.distance_m) == pytest.approx(
        (3.0, 2.0, math.pi / 2, 5.0)
    )


def test_cad_v2x_seq_makes_sequences_of_the_same_sumo_vehicles(tmp_path):
    """The real pipeline (SUMO, pyrender) on cad-v2x-seq cut to 3 frames: one sequence, frames
    0.2 s apart of the same two vehicles, odometry close to their true motion (~8 s)."""
    text = (ROOT / "scenarios" / "cad-v2x-seq.toml").read_text()
    path = tmp_path / "seq.toml"
    path.write_text(text.replace("frames = 10 ", "frames = 3  "))
    shutil.copy(ROOT / "scenarios" / "cad-vtypes.add.xml", tmp_path)
    generate_dataset(load_scenario(path), tmp_path / "ds", pairs=1, workers=1, progress=False)
    ds = Dataset(tmp_path / "ds", verify=True)
    (frames,) = list(ds.iter_sequences())
    assert [f.frame for f in frames] == [0, 1, 2]
    assert np.allclose(np.diff([f.time for f in frames]), 0.2)
    assert len({tuple(o["id"] for o in f.record["observers"]) for f in frames}) == 1
    for v in range(2):
        true = relative_pose(frames[0].observer_poses[v], frames[-1].observer_poses[v])
        pose = frames[-1].odometry[v]
        assert abs(pose.x - true[0]) < 0.3 and abs(pose.y - true[1]) < 0.3


# --------------------------------------------------------------------------- a run's odometry


def _odometry(frames) -> list[tuple]:
    return [tuple(p.as_dict()["position"] + [p.yaw]) for f in frames for p in f.odometry]


def test_a_run_redraws_the_odometry_drift_and_none_keeps_the_records_own(reference, tmp_path):
    from cadsim.dataset.sequence_odometry import (
        odometry_redraw_seeds,
        redraw_odometry,
        replay_odometry,
    )

    ds = Dataset(reference)
    frames = ds.sequence(0)
    # replaying generation with the stored seeds gives the stored odometry bit for bit: the
    # redraw is the generation's model along the same true poses, only the seeds differ
    stored = [int(o["odometry_seed"]) for o in frames[0].record["observers"]]
    assert _odometry(replay_odometry(frames, stored)) == _odometry(frames)
    assert _odometry(redraw_odometry(frames, None)) == _odometry(frames)
    run0, run1 = redraw_odometry(frames, 0), redraw_odometry(frames, 1)
    assert _odometry(run0) == _odometry(redraw_odometry(ds.sequence(0), 0))  # same seed, same
    assert _odometry(run0) != _odometry(frames) and _odometry(run0) != _odometry(run1)
    assert run0[0].odometry[0].as_dict() == frames[0].odometry[0].as_dict()  # the origin
    for f, g in zip(frames, run0, strict=True):  # only the odometry changes
        assert g.name == f.name and np.array_equal(g.view1.positions, f.view1.positions)
        assert [p.distance_m for p in g.odometry] == [p.distance_m for p in f.odometry]
        # and it survives the other redraws of a run
        assert g.localise_preset("gnss-urban", seed=0).odometry == g.odometry
    # another split (another root seed, the same episode and slot numbers): other noise in run 0
    _generate(tmp_path / "other", seed=99)
    other = Dataset(tmp_path / "other").sequence(0)
    assert (other[0].episode, other[0].slot) == (frames[0].episode, frames[0].slot)
    assert odometry_redraw_seeds(other, 0) != odometry_redraw_seeds(frames, 0)
    assert odometry_redraw_seeds(frames, 0) != odometry_redraw_seeds(frames, 1)
    assert odometry_redraw_seeds(frames, 0) != tuple(stored)


def test_a_redraw_refuses_frames_that_are_not_one_whole_sequence(reference):
    from cadsim.dataset.sequence_odometry import redraw_odometry

    ds = Dataset(reference)
    with pytest.raises(ValueError, match="one sequence"):
        redraw_odometry(ds.sequence(0)[1:], 0)
    with pytest.raises(ValueError, match="one sequence"):
        redraw_odometry(ds.sequence(0)[:2] + ds.sequence(1)[2:], 0)
