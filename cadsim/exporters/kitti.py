"""``cadsim export kitti``: every view's detections as KITTI object labels (15 columns), one
text file per view and record, in the view's camera coordinates.

Layout: ``DIR/view<k>/label_2/<index>.txt`` (index = the record's position in the dataset,
six digits) and ``DIR/records.txt`` (index and record name per line). Each line: ``type
truncated occluded alpha x1 y1 x2 y2 h w l x y z rotation_y`` —

- ``type``: the class a matcher sees mapped to KITTI's (``Car``, ``Van``, ``Truck``,
  ``Pedestrian``, ``Cyclist``, ``Tram``; anything else ``Misc``);
- ``truncated`` 0, ``occluded`` 3 (unknown);
- ``x1 y1 x2 y2``: the detection's image box in pixels (box-only views have no image: 0 0 0 0);
- ``h w l``: the box's height, width, length (metres);
- ``x y z``: the bottom centre of the box in the view's camera frame (x right, y down, z
  forward, metres: the box centre plus half its height along y) — for a box-only view the
  camera-frame convention at its LiDAR;
- ``rotation_y = heading − π/2`` (KITTI's yaw about the camera's y axis, 0 along x) and ``alpha
  = rotation_y − atan2(x, z)``, both wrapped to [−π, π).

What is lost: object ids (hence the ground truth between views), poses, the class when it is
not one of KITTI's. The output folder must be new or empty.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from cadsim import portable_math as pm
from cadsim.dataset.output_folder import check_output_folder
from cadsim.exporters.opv2v import ExportResult
from cadsim.exporters.view_boxes import ViewBoxes, snapshot_views
from cadsim.world import wrap_angle

KITTI_TYPES = {
    "car": "Car", "van": "Van", "truck": "Truck", "bus": "Tram", "tram": "Tram",
    "person": "Pedestrian", "pedestrian": "Pedestrian", "bicycle": "Cyclist",
    "cyclist": "Cyclist", "bike": "Cyclist", "motorcyclist": "Cyclist",
}  # fmt: skip


def kitti_type(cls: str) -> str:
    """KITTI's type of a cadsim class (``Misc`` when it has none)."""
    return KITTI_TYPES.get(str(cls).lower(), "Misc")


def label_lines(view: ViewBoxes) -> list[str]:
    """The KITTI label lines of one view (module docstring)."""
    positions = view.detections.positions
    bottom = positions + np.column_stack(
        [np.zeros(len(positions)), view.sizes[:, 2] / 2, np.zeros(len(positions))]
    )
    ry = wrap_angle(view.headings - np.pi / 2)
    alpha = wrap_angle(ry - pm.arctan2(positions[:, 0], positions[:, 2]).reshape(-1))
    boxes = view.pixel_boxes if view.pixel_boxes is not None else np.zeros((len(positions), 4))
    lines = []
    for k, cls in enumerate(view.classes):
        length, width, height = view.sizes[k]
        numbers = [alpha[k], *boxes[k], height, width, length, *bottom[k], ry[k]]
        lines.append(f"{kitti_type(cls)} 0.00 3 " + " ".join(f"{v:.6f}" for v in numbers))
    return lines


def export_kitti(dataset: str | Path, out: str | Path) -> ExportResult:
    """Write every view of the dataset at ``dataset`` (verified first) as KITTI labels at
    ``out`` (a new or empty folder).

    >>> export_kitti("data/cad-v2x", "export/cad-v2x-kitti")  # doctest: +SKIP
    ExportResult(out=PosixPath('export/cad-v2x-kitti'), scenarios=25, files=50)
    """
    from cadsim.dataset import Dataset

    out = check_output_folder(out, resumable=False)
    ds = Dataset(dataset, verify=True)
    files, index = 0, []
    for k in range(len(ds)):
        for view in snapshot_views(ds, k):
            folder = out / f"view{view.view}" / "label_2"
            folder.mkdir(parents=True, exist_ok=True)
            text = "".join(f"{line}\n" for line in label_lines(view))
            (folder / f"{k:06d}.txt").write_text(text, encoding="utf-8")
            files += 1
        index.append(f"{k:06d} {ds[k].name}\n")
    (out / "records.txt").write_text("".join(index), encoding="utf-8")
    return ExportResult(out, len(ds), files)


__all__ = ["KITTI_TYPES", "export_kitti", "kitti_type", "label_lines"]
