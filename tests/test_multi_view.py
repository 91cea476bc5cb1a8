"""N-view snapshots (DESIGN §12): cad-multi's records with 6 views, the acceptance rule, the
reader's pair (i, j), roadside units' exact poses, malformed records refused, `info` and `show`."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from cadsim.dataset import Dataset
from cadsim.dataset.detections import ViewDetections, is_acceptable_set
from cadsim.dataset.manifest import DatasetError

ROOT = Path(__file__).resolve().parents[1]
MULTI = ROOT / "scenarios" / "cad-multi.toml"


@pytest.fixture(scope="module")
def multi(tmp_path_factory) -> Path:
    from cadsim.generation.pipeline import generate_dataset
    from cadsim.scenario import load_scenario

    out = tmp_path_factory.mktemp("multi") / "cad-multi"
    generate_dataset(load_scenario(MULTI), out, pairs=2, workers=1, progress=False)
    return out


def _view(ids: list[str]) -> ViewDetections:
    k = len(ids)
    return ViewDetections(
        np.zeros((k, 3)), np.zeros((k, 4)), np.zeros((k, 2)), ids, ["car"] * k, np.zeros(k)
    )


def test_the_acceptance_rule_needs_every_view_linked_into_one_group():
    a, b, c = _view(list("abcd")), _view(list("abcx")), _view(list("bcdy"))
    assert is_acceptable_set([a, b, c], 3)
    lonely = _view(list("pqrs"))  # shares nothing
    assert not is_acceptable_set([a, b, c, lonely], 3)
    # two groups, each linked inside: not one scene
    assert not is_acceptable_set([a, b, _view(list("pqrs")), _view(list("pqrt"))], 3)
    assert not is_acceptable_set([a], 3)


def test_cad_multi_has_six_views_per_snapshot_that_meet_the_acceptance_rule(multi):
    ds = Dataset(multi, verify=True)
    assert len(ds) == 2 and ds.n_views == 6
    assert ds.manifest["format_version"] == 6
    for k in range(len(ds)):
        snap = ds.snapshot(k)
        assert snap.kinds == ["vehicle"] * 4 + ["roadside"] * 2
        assert all((ds.path / "pairs" / snap.name / f"view{v}.png").is_file() for v in range(1, 7))
        views = [snap.view(v) for v in range(1, 7)]
        assert is_acceptable_set(views, 3)
        record = snap.record
        assert record["views"] == 6 and len(record["counts"]["covisible"]) == 15
        ids = {o["id"] for o in record["objects"]}
        assert all(set(v.object_ids) <= ids for v in views)  # one id space for every view
        # the vehicles carrying cameras are distinct and are not seen by their own camera
        vehicles = snap.observer_ids[:4]
        assert len(set(vehicles)) == 4
        for v, vehicle in enumerate(vehicles, start=1):
            assert vehicle not in snap.view(v).object_ids


def test_pair_i_j_is_the_two_view_problem_of_those_views(multi):
    snap = Dataset(multi).snapshot(0)
    for i, j in snap.pairs():
        pair = snap.pair(i, j)
        v1, v2 = snap.view(i), snap.view(j)
        assert pair.view1.equals(v1) and pair.view2.equals(v2)
        truth = {(a, b) for a, b in pair.gt_pairs.tolist()}
        shared = {(v1.object_ids.index(o), v2.object_ids.index(o)) for o in set(v1.object_ids) & set(v2.object_ids)}  # fmt: skip
        assert truth == shared
        problem = pair.problem()
        assert (problem.n1, problem.n2) == (len(v1), len(v2))
        assert np.array_equal(problem.points1, v1.positions)
    assert Dataset(multi)[0].name == snap.pair(1, 2).name  # ds[k] reads views 1 and 2
    with pytest.raises(ValueError, match="two different views"):
        snap.pair(2, 2)
    with pytest.raises(ValueError, match=r"1\.\.6"):
        snap.pair(1, 7)


def test_view_pair_tasks_read_each_snapshot_once_per_process_and_give_the_same_bits(
    multi, monkeypatch
):
    """eval.core.snapshot_memo: the view-pair tasks of one process share each snapshot's
    reading; every outcome is the one a fresh reading gives."""
    from eval.core import snapshot_memo
    from eval.core.tasks import MatcherSpec, RunTask, execute

    checksum = Dataset(multi).checksum
    matchers = (MatcherSpec("maximin"), MatcherSpec("pose_refine"))

    def runs():
        return [
            execute(
                RunTask(
                    str(multi),
                    checksum,
                    0,
                    (None,),
                    matchers,
                    "t",
                    views=views,
                    localisation="gnss-urban",
                )
            )  # fmt: skip
            for views in ((1, 2), (2, 5), (5, 6))
        ]

    reads = []
    original = Dataset.snapshot
    monkeypatch.setattr(Dataset, "snapshot", lambda ds, k: reads.append(k) or original(ds, k))
    snapshot_memo.forget()
    shared = runs()
    assert sorted(reads) == [0, 1]  # 3 tasks, each snapshot read once
    monkeypatch.setattr(snapshot_memo, "snapshot", lambda ds, _d, _c, _s, k: ds.snapshot(k))
    fresh = runs()
    assert len(reads) == 2 + 3 * 2
    for task_a, task_b in zip(shared, fresh, strict=True):
        for a, b in zip(task_a, task_b, strict=True):
            assert a.spec == b.spec and len(a.outcomes) == 2
            for x, y in zip(a.outcomes, b.outcomes, strict=True):
                assert (x.name, x.n1, x.n2) == (y.name, y.n1, y.n2)
                for field in ("assigned", "scores", "gt_pairs", "points1", "points2", "prior_pose"):  # fmt: skip
                    assert np.array_equal(getattr(x, field), getattr(y, field)), field
    snapshot_memo.forget()


def test_a_roadside_units_pose_is_exact_and_a_vehicles_is_not(multi):
    snap = Dataset(multi).snapshot(0)
    pair = snap.pair(1, 5).localise_preset("gnss-urban", seed=0)
    assert pair.observer_kinds == ("vehicle", "roadside")
    world1, world2, _ = pair.prior()
    true1 = pair.cameras[0].camera_to_world(pair.view1.positions)
    true2 = pair.cameras[1].camera_to_world(pair._sent_view2[0]) + pair._sent_view2[1]
    assert np.allclose(world2, true2, atol=1e-9)  # the pole's surveyed pose
    assert not np.allclose(world1, true1, atol=0.05)  # the vehicle's GNSS error


def test_views_one_and_two_are_the_two_view_record_of_the_same_observers(tmp_path):
    """The N-view record's views 1 and 2 are, byte for byte, the frame pair the two-view pipeline
    makes of the same two observers at the same snapshot and slot (one rendering, one seed
    derivation): `pair(1, 2)` is today's record of those observers."""
    from cadsim.dataset.record_format import encode_record, encode_snapshot
    from cadsim.dataset.seeds import simulation_seed
    from cadsim.generation import pipeline as pl
    from cadsim.scenario import load_scenario
    from cadsim.sources.base import ObserverPair

    scenario = load_scenario(MULTI)
    crit = pl.Criteria.from_sampling(scenario.sampling)
    task = pl.EpisodeTask(scenario, str(tmp_path), scenario.seed, 0, 1, crit, pl.Stages())
    names = ("source", "noise_config", "apply_noise", "detection_config", "detect")
    stages = {name: task.stages.resolve(name) for name in names}
    noise_cfg = stages["noise_config"](**scenario.noise)
    det_cfg = stages["detection_config"](**scenario.detection)
    result = pl.EpisodeResult(0, 0, 1, 0, False)
    sim_seed = simulation_seed(scenario.seed, 0)
    try:
        with stages["source"](scenario, sim_seed, tmp_path / "work") as source:
            for snapshot in source.snapshots():
                for observers in source.observer_sets(snapshot):
                    whole = pl._try_set(task, stages, noise_cfg, det_cfg, snapshot, observers, 0, 0, result)  # fmt: skip
                    two = ObserverPair(
                        observers.cameras[0], observers.cameras[1],
                        observers.observer_ids[0], observers.observer_ids[1], observers.meta,
                    )  # fmt: skip
                    pair = pl._try_pair(task, stages, noise_cfg, det_cfg, snapshot, two, 0, 0, result)  # fmt: skip
                    if whole is not None and pair is not None:
                        break
                else:
                    continue
                break
    finally:
        pl.release_renderers()
    files6, files2 = encode_snapshot(whole), encode_record(pair)
    assert files6["view1.png"] == files2["view1.png"]
    assert files6["view2.png"] == files2["view2.png"]
    assert whole.views[0].detections.equals(pair.view1.detections)
    assert whole.views[1].detections.equals(pair.view2.detections)
    for k in (0, 1):
        assert np.array_equal(whole.views[k].depth, (pair.view1, pair.view2)[k].depth)
        assert whole.views[k].noise_seed == (pair.view1, pair.view2)[k].noise_seed
        assert whole.views[k].localisation_seed == (pair.view1, pair.view2)[k].localisation_seed


def _copy(multi: Path, tmp_path: Path) -> Path:
    out = tmp_path / "copy"
    shutil.copytree(multi, out)
    return out


@pytest.mark.parametrize(
    ("edit", "words"),
    [
        (lambda r: r.update(views=5), "views: expected 6"),
        (lambda r: r["observers"].pop(), "observers: expected a list of 6"),
        (lambda r: r["observers"][5].update(kind="drone"), r"observers\[5\]\.kind"),
    ],
)
def test_malformed_n_view_records_are_refused_with_one_line(multi, tmp_path, edit, words):
    out = _copy(multi, tmp_path)
    path = next((out / "pairs").iterdir()) / "record.json"
    record = json.loads(path.read_text())
    edit(record)
    path.write_text(json.dumps(record))
    ds = Dataset(out)  # not verified: the reader's own checks refuse it
    index = [e["name"] for e in ds.manifest["records"]].index(path.parent.name)
    with pytest.raises(DatasetError, match=words) as info:
        ds.snapshot(index)
    assert "\n" not in str(info.value) and str(path) in str(info.value)


def test_missing_view_arrays_and_a_bad_view_count_are_refused(multi, tmp_path):
    out = _copy(multi, tmp_path)
    record_dir = (
        out / "pairs" / json.loads((out / "manifest.json").read_text())["records"][0]["name"]
    )
    arrays = dict(np.load(record_dir / "detections.npz"))
    arrays = {k: v for k, v in arrays.items() if not k.startswith("view6_")}
    np.savez(record_dir / "detections.npz", **arrays)
    with pytest.raises(DatasetError, match="view6_") as info:
        Dataset(out).snapshot(0)
    assert "\n" not in str(info.value)
    manifest = json.loads((out / "manifest.json").read_text())
    manifest["views"] = 1
    (out / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(DatasetError, match=r"views: expected an integer in 2\.\.12"):
        Dataset(out)


def test_info_reports_views_and_view_pairs_and_show_draws_all_views(multi, tmp_path, capsys):
    from cadsim.cli import main

    assert main(["info", str(multi), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    multi_view = summary["multi_view"]
    assert [v["view"] for v in multi_view["views"]] == [1, 2, 3, 4, 5, 6]
    assert [v["kind"] for v in multi_view["views"]][-2:] == ["roadside", "roadside"]
    assert len(multi_view["view_pairs"]) == 15
    first = multi_view["view_pairs"][0]
    assert first["views"] == "1-2" and "covisible" in first and "regime" in first
    assert main(["info", str(multi)]) == 0
    assert "view pair" in capsys.readouterr().out
    assert main(["show", str(multi), "--pair", "1", "--out", str(tmp_path / "s.png")]) == 0
    assert "6 views" in capsys.readouterr().out
    assert (tmp_path / "s.png").stat().st_size > 10_000


def test_multi_view_keys_need_the_sumo_source(tmp_path):
    from cadsim.scenario import ScenarioError, load_scenario

    path = tmp_path / "arena.toml"
    text = (ROOT / "scenarios" / "mrc-arena.toml").read_text()
    assert "[observers]" not in text
    path.write_text(text + "\n[observers]\ncount = 3\n")
    with pytest.raises(ScenarioError, match="observers.count") as info:
        load_scenario(path)
    assert "sumo" in str(info.value)
