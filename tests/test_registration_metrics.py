"""The V2X-Reg++ registration protocol (:mod:`eval.core.registration_metrics`, ``cadsim evaluate
--pose-metrics v2x-reg``): success@1/2/3 m over all frames with a frame without a pose a
failure, mean errors over the successful frames, their JSON frame list."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from cadsim.cli import main
from cadsim.importers.dair_v2x import import_dair_v2x
from eval.bench.dair_import import write_dair_layout
from eval.core.registration_metrics import read_frame_list, registration_summary

NAN = float("nan")


def test_success_is_strict_in_both_errors_and_counts_frames_without_a_pose():
    rte = [0.5, 0.99, 1.0, 2.5, 0.2, NAN]
    rre = [0.5, 1.5, 0.1, 0.1, 2.9, NAN]
    s = registration_summary(rte, rre, [0.1] * 6)
    assert s["reg_success_1m"] == pytest.approx(1 / 6)  # 0.99 m but 1.5°; 1.0 m is not < 1
    assert s["reg_success_2m"] == pytest.approx(3 / 6)
    assert s["reg_success_3m"] == pytest.approx(5 / 6)
    assert s["reg_mrte_2m"] == pytest.approx((0.5 + 0.99 + 1.0) / 3)  # successful frames only
    assert s["reg_mrre_3m_deg"] == pytest.approx((0.5 + 1.5 + 0.1 + 0.1 + 2.9) / 5)
    assert s["reg_mrte_all_m"] == pytest.approx(np.mean([0.5, 0.99, 1.0, 2.5, 0.2]))
    assert (s["reg_no_pose"], s["reg_frames"]) == (1, 6)
    assert s["reg_s_per_frame"] == pytest.approx(0.1)


def test_no_success_leaves_the_means_undefined():
    s = registration_summary([NAN, 9.0], [NAN, 9.0], [1.0, 1.0])
    assert s["reg_success_3m"] == 0.0 and np.isnan(s["reg_mrte_1m"])


def test_a_frame_list_is_their_cooperative_json(tmp_path):
    path = tmp_path / "list.json"
    path.write_text(json.dumps([{"vehicle_pointcloud_path": "vehicle-side/velodyne/000606.pcd",
                                 "infrastructure_pointcloud_path": "infrastructure-side/velodyne/007100.pcd",
                                 "box_count": 53}]))  # fmt: skip
    assert read_frame_list(path) == {("000606", "007100")}
    path.write_text(json.dumps([{"vehicle_pointcloud_path": 3}]))
    with pytest.raises(ValueError, match=r"list.json: \[0\]: expected an object with"):
        read_frame_list(path)


@pytest.fixture(scope="module")
def dair(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("reg")
    data = import_dair_v2x(write_dair_layout(tmp / "src", frames=6, seed=5), tmp / "data").out
    frames = [{"vehicle_pointcloud_path": f"vehicle-side/velodyne/{k:06d}.pcd",
               "infrastructure_pointcloud_path": f"infrastructure-side/velodyne/{k + 500_000:06d}.pcd"}
              for k in (0, 2, 3, 5)]  # fmt: skip
    (tmp / "list.json").write_text(json.dumps(frames))
    return data, tmp / "list.json"


def test_evaluate_writes_the_registration_table_with_failures_counted(dair, tmp_path):
    data, frames = dair
    out = tmp_path / "out"
    args = ["evaluate", str(data), "--matchers", "none,pose", "--localisation", "gnss-urban"]
    args += ["--no-calibration", "--runs", "1", "--workers", "1", "--no-progress"]
    args += ["--cache", str(tmp_path / "c"), "--out", str(out), "--pose-metrics", "v2x-reg"]
    assert main([*args, "--frames", str(frames)]) == 0
    table = pd.read_csv(out / "registration.csv").set_index("matcher")
    assert (table["reg_frames"] == 4).all()  # the frame list's 4 of 6
    assert table.loc["none", "reg_no_pose"] == 4 and table.loc["none", "reg_success_3m"] == 0
    assert table.loc["pose", "reg_success_3m"] > 0
    assert "Success@1 m" in (out / "registration.md").read_text()


def test_help_names_the_metrics_and_options_need_the_protocol(capsys, tmp_path):
    with pytest.raises(SystemExit):
        main(["evaluate", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for part in ("--pose-metrics", "v2x-reg", "success@1/2/3 m", "mRTE/mRRE", "seconds per frame"):
        assert part in text, part
    assert main(["evaluate", str(tmp_path), "--top-k", "10", "--out", str(tmp_path / "o")]) == 2


def test_the_v2x_tables_carry_the_protocol_columns_and_the_baseline_row():
    from eval.engine.matcher_list import with_prior
    from eval.studies.v2x.table import COLUMNS

    assert {"reg_success_1m", "reg_success_2m", "reg_success_3m"} <= set(COLUMNS)
    assert "v2x_reg" in [m.name for m in with_prior("all")]
