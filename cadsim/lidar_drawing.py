"""``cadsim show`` for records with LiDAR points: each view's sweep from above in its own LiDAR
frame (x forward up the page, y left to the left, metres), points shaded by height above the
sensor, and the LiDAR detector's boxes as oriented rectangles — green when the other view has
the same object (ground truth), grey otherwise, labelled with the reported class.

Boxes come from the record's box-only detections (``sensor = "lidar"``: positions in the
camera-frame convention, headings, ``view{k}_sizes``) or from ``lidar.npz``'s ``box_*`` arrays
(``sensor = "both"``). Imports matplotlib only when drawing.
"""

from __future__ import annotations

import numpy as np

from cadsim.pair_drawing import CORRECT

OTHER = "#9ca3af"
MAX_DRAWN_POINTS = 60_000  # per panel; every k-th point beyond (a figure, not a measurement)


def _boxes_in_lidar_frame(pair, k: int, view) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[str], list[str]]:  # fmt: skip
    """(centres (b, 2) x, y; sizes (b, 2) length, width; yaws (b,); classes; ids) of view k's
    LiDAR boxes, LiDAR frame."""
    stored = pair.lidar[k].boxes
    if stored is not None:
        c, s = stored["centres"], stored["sizes"]
        return c[:, :2], s[:, :2], stored["yaws"], list(stored["classes"]), list(stored["ids"])
    from cadsim.dataset.box_record import read_box_sizes

    det = view
    sizes = read_box_sizes(pair.path, pair.view_numbers[k])
    sizes = np.zeros((len(det), 3)) if sizes is None else sizes
    # camera convention (x right, z forward) → LiDAR (x forward, y left); heading h → yaw −h
    centres = np.column_stack([det.positions[:, 2], -det.positions[:, 0]])
    yaws = -det.headings if det.headings is not None else np.zeros(len(det))
    return centres, sizes[:, :2], yaws, list(det.reported_classes or det.true_classes), list(det.object_ids)  # fmt: skip


def lidar_figure(pair, labels: bool = True):
    """A ``Figure`` of a record's two LiDAR views from above (module docstring)."""
    from matplotlib.figure import Figure
    from matplotlib.patches import Polygon

    fig = Figure(figsize=(13.0, 6.6), dpi=100)
    axes = fig.subplots(1, 2)
    other_ids = (set(pair.view2.object_ids), set(pair.view1.object_ids))
    for k, (ax, view) in enumerate(zip(axes, (pair.view1, pair.view2), strict=True)):
        sweep = pair.lidar[k]
        pts = sweep.points
        step = max(1, len(pts) // MAX_DRAWN_POINTS)
        shown = pts[::step]
        ax.scatter(-shown[:, 1], shown[:, 0], s=0.2, c=shown[:, 2], cmap="viridis", vmin=-2.0, vmax=2.0, linewidths=0)  # fmt: skip
        centres, sizes, yaws, classes, ids = _boxes_in_lidar_frame(pair, k, view)
        for (cx, cy), (length, width), yaw, cls, oid in zip(centres, sizes, yaws, classes, ids, strict=True):  # fmt: skip
            c, s = np.cos(yaw), np.sin(yaw)
            corners = np.array([[cx, cy]]) + np.array(
                [
                    [c * a * length / 2 - s * b * width / 2, s * a * length / 2 + c * b * width / 2]
                    for a, b in ((1, 1), (1, -1), (-1, -1), (-1, 1))
                ]  # fmt: skip
            )
            color = CORRECT if oid in other_ids[k] else OTHER
            ax.add_patch(Polygon(np.column_stack([-corners[:, 1], corners[:, 0]]), closed=True, fill=False, edgecolor=color, linewidth=1.2))  # fmt: skip
            if labels:
                ax.text(-cy, cx, cls, fontsize=6, color=color, ha="center", va="center")
        ax.plot([0], [0], marker="^", color="#2563eb", markersize=8)
        reach = 60.0
        ax.set_xlim(-reach, reach)
        ax.set_ylim(-reach, reach)
        ax.set_aspect("equal")
        ax.set_xlabel("left ← y (m) → right")
        ax.set_ylabel("x forward (m)")
        ax.set_title(f"view {k + 1}: {len(pts)} points, {len(view)} boxes ({sweep.pattern.channels} channels)", fontsize=9)  # fmt: skip
    fig.suptitle(f"{pair.name} (pair {pair.index}): {len(pair.gt_pairs)} covisible boxes (green)", fontsize=10)  # fmt: skip
    return fig
