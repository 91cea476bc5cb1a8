"""The field's public real files, imported and evaluated as a new user would: ``pytest -m
real_files`` with ``CADSIM_REAL_FILES`` naming a folder; every test here skips without it (CI
never has the files, and nothing of them is committed: their licences forbid it).

The folder holds what it has of (each test skips what is missing):

- ``v2xset/2021_08_21_17_30_41/`` — the V2XSet frame of ucla-mobility/OpenCDA,
  ``opencood/dummy_v2xset/validate/2021_08_21_17_30_41/`` (agents 4279, 4288, 4297, frame
  000069; only the ``.yaml`` files are read);
- ``DAIR-V2X/`` — the DAIR-V2X-C pair of MassimoQu/v2i-calib at commit c472e33,
  ``data/DAIR-V2X/`` (vehicle 017314, roadside 001366; labels and ``cooperative/``).

What is checked is what a person found by hand on these files: counts, links and places, and
that every localisation preset draws a prior of its own size on them (docs/real-data.md).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest

import matchers
from cadsim.cli import main
from cadsim.dataset import Dataset
from cadsim.dataset.box_record import read_box_sizes
from cadsim.sensing.gnss_error import PRESETS, draw_error

pytestmark = pytest.mark.real_files

ROOT = Path(os.environ["CADSIM_REAL_FILES"]) if os.environ.get("CADSIM_REAL_FILES") else None
V2XSET = "v2xset"
DAIR = "DAIR-V2X"
DRAWS = 200


def _source(name: str) -> Path:
    if ROOT is None or not ROOT.is_dir():
        pytest.skip("CADSIM_REAL_FILES names no folder (the real files are not redistributable)")
    if not (ROOT / name).is_dir():
        pytest.skip(f"{ROOT / name}: not there")
    return ROOT / name


def _import(tmp_path: Path, fmt: str, src: Path, *extra: str) -> Dataset:
    out = tmp_path / f"{fmt}-data"
    assert main(["import", fmt, str(src), "--out", str(out), *extra]) == 0
    return Dataset(out, verify=True)


def _drawn_priors_have_their_presets_size(pairs) -> None:
    """Over DRAWS runs, view 1's median position error is within ±30 % of the preset's own
    model's at the same elapsed time, and above 0 for every preset but exact."""
    for preset, model in PRESETS.items():
        if not model.given:
            continue
        drawn, own = [], []
        for seed in range(DRAWS):
            pair = pairs[seed % len(pairs)]
            error = pair.localise_preset(preset, seed=seed).pose_errors()[0]
            drawn.append(math.hypot(error.dx, error.dy))
            ref = draw_error(model, 10_000 + seed, pair.observer_ids[0], pair.time, 20_000 + seed)
            own.append(math.hypot(ref.dx, ref.dy))
        drawn_m, own_m = float(np.median(drawn)), float(np.median(own))
        if preset == "exact":
            assert drawn_m == own_m == 0.0
        else:
            assert drawn_m > 0 and 0.7 * own_m <= drawn_m <= 1.3 * own_m, (preset, drawn_m, own_m)


def _evaluates(data: Path, tmp_path: Path) -> None:
    for preset in ("gnss-urban", "exact"):
        args = ["evaluate", str(data), "--matchers", "pose,maximin_pose,cbm,v2x_reg"]
        args += ["--localisation", preset, "--no-calibration", "--runs", "1", "--workers", "1"]
        args += [
            "--no-progress",
            "--cache",
            str(tmp_path / "cache"),
            "--out",
            str(tmp_path / preset),
        ]
        assert main([*args, "--pose-metrics", "v2x-reg"]) == 0


def test_the_v2xset_frame_imports_as_found_by_hand(tmp_path):
    data = _import(tmp_path, "opv2v", _source(V2XSET))
    snapshot = data.snapshot(0)
    assert data.n_views == 3 and snapshot.record["meta"]["agents"] == [4279, 4288, 4297]
    pairs = {(i, j): snapshot.pair(i, j) for i, j in snapshot.pairs()}
    assert [len(pairs[(1, 2)].view1.object_ids), len(pairs[(1, 2)].view2.object_ids),
            len(pairs[(1, 3)].view2.object_ids)] == [21, 22, 15]  # fmt: skip
    shared = {key: len(p.gt_pairs) for key, p in pairs.items() if key[0] < key[1]}
    assert shared == {(1, 2): 17, (1, 3): 14, (2, 3): 11}
    for p in pairs.values():  # every link is the same actor
        ids1, ids2 = p.view1.object_ids, p.view2.object_ids
        assert all(ids1[i] == ids2[j] for i, j in p.gt_pairs)
    in_4288 = pairs[(2, 3)]  # agent 4288 receives
    k = in_4288.view1.object_ids.index("4279")
    np.testing.assert_allclose(in_4288.view1.positions[k], [-9.962, 1.182, 45.394], atol=1e-3)
    assert in_4288.view1.headings[k] == pytest.approx(3.1365, abs=1e-4)
    assert in_4288.view1.true_classes[k] == "car"
    sizes = read_box_sizes(in_4288.path, 2)
    np.testing.assert_allclose(sizes[k], [4.90, 2.13, 1.51], atol=0.01)
    objects = {o["id"]: o for o in snapshot.record["objects"]}
    for (i, _), p in pairs.items():  # the stored per-agent prior: centimetres off
        truth = np.array([objects[o]["center"][:2] for o in p.view1.object_ids])
        off = np.hypot(*(p.problem().world1[:, :2] - truth).T)
        assert 0.02 < off.min() < 0.07 and off.max() < 0.25, (i, off.min(), off.max())


def test_the_v2xset_frame_draws_every_preset_and_evaluates(tmp_path):
    data = _import(tmp_path, "opv2v", _source(V2XSET), "--no-prior")
    assert data.snapshot(0).pair(1, 2).time == 0.0  # no time in the files: the snapshot is at 0
    pairs = [data.snapshot(0).pair(1, 2), data.snapshot(0).pair(2, 3)]
    _drawn_priors_have_their_presets_size(pairs)
    _evaluates(tmp_path / "opv2v-data", tmp_path)


def test_the_dair_pair_imports_with_the_hand_found_links(tmp_path):
    data = _import(tmp_path, "dair-v2x", _source(DAIR))
    assert len(data) == 1
    pair = data[0]
    assert (len(pair.view1.object_ids), len(pair.view2.object_ids)) == (23, 8)
    roadside_to_vehicle = {0: 6, 1: 5, 2: 21, 3: 7, 4: 2, 5: 0, 7: 13}
    assert {(int(i), int(j)) for i, j in pair.gt_pairs} == {
        (v, r) for r, v in roadside_to_vehicle.items()
    }
    assert pair.view2.true_classes[6] == "trafficcone"  # the cone: unlinked
    assert pair.time == 0.0  # no side data_info.json: the snapshot is at 0


def test_the_dair_pair_draws_every_preset_and_evaluates(tmp_path):
    data = _import(tmp_path, "dair-v2x", _source(DAIR))
    _drawn_priors_have_their_presets_size([data[0]])
    _evaluates(tmp_path / "dair-v2x-data", tmp_path)


def test_maximin_pose_finds_what_pose_finds_on_the_dair_pair(tmp_path):
    pair = _import(tmp_path, "dair-v2x", _source(DAIR))[0]
    truth = {tuple(p) for p in pair.gt_pairs.tolist()}
    for preset in ("gnss-open-sky", "gnss-urban"):
        for seed in range(4):
            problem = pair.localise_preset(preset, seed=seed).problem()
            found = {
                name: len({tuple(p) for p in matchers.get(name)(problem, seed=0, threshold=0.5).pairs.tolist()} & truth)
                for name in ("pose", "maximin_pose")
            }  # fmt: skip
            assert found["maximin_pose"] >= min(found["pose"], len(truth) - 1), (preset, seed)
