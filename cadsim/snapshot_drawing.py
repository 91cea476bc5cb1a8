"""All N views of a snapshot record in a grid, each detection boxed and labelled with a number
shared by every view (the object's index in the record's object list), so the same object
carries the same number wherever it is seen (``cadsim show`` on an N-view dataset). Box colours
follow the number too. Pixel coordinates (u, v), u right, v down."""

from __future__ import annotations

import math

import numpy as np

COLUMNS = 3


def snapshot_figure(snapshot, labels: bool = True):
    """A matplotlib ``Figure`` of ``snapshot`` (:class:`cadsim.dataset.multi_view.SnapshotViews`):
    view k in row-major grid cell k, titled with its number, kind and detection count."""
    from matplotlib import colormaps
    from matplotlib.figure import Figure
    from matplotlib.patches import Rectangle

    from cadsim.dataset import layout
    from cadsim.dataset.encoding import decode_png

    n = snapshot.n_views
    cols = min(COLUMNS, n)
    rows = math.ceil(n / cols)
    number = {o["id"]: k for k, o in enumerate(snapshot.record["objects"])}
    palette = colormaps["tab20"]
    fig = Figure(figsize=(4.0 * cols, 3.3 * rows), dpi=100)
    for k in range(1, n + 1):
        ax = fig.add_subplot(rows, cols, k)
        path = snapshot.path / layout.view_png(k)
        ax.imshow(decode_png(path.read_bytes(), str(path)), interpolation="nearest")
        view = snapshot.view(k)
        for (u0, v0, u1, v1), oid in zip(view.boxes, view.object_ids, strict=True):
            ident = number.get(oid, -1)
            colour = palette(ident % 20) if ident >= 0 else "white"
            ax.add_patch(Rectangle((u0, v0), u1 - u0, v1 - v0, fill=False, ec=colour, lw=1.2))
            if labels:
                ax.text(u0, v0 - 2, str(ident), color=colour, fontsize=6, va="bottom")
        kind = snapshot.kinds[k - 1]
        ax.set_title(f"view {k} ({kind}), {len(view)} detections", fontsize=8)
        ax.set_axis_off()
    fig.suptitle(
        f"{snapshot.name}: {n} views; numbers are object ids shared across views", fontsize=9
    )
    fig.tight_layout()
    return fig


def shared_objects(snapshot) -> np.ndarray:
    """(N, N) int: how many objects views i+1 and j+1 both detect (diagonal: each view's count)."""
    ids = [set(snapshot.view(k).object_ids) for k in range(1, snapshot.n_views + 1)]
    return np.array([[len(a & b) for b in ids] for a in ids], dtype=int)
