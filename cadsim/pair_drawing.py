"""Two views side by side with detection boxes and lines between matched detections.

Used by ``cadsim show`` (ground-truth correspondences) and by the evaluation's qualitative
figure (paper Fig. 3 style: green correct, red wrong, yellow missed). Pixel coordinates: (u, v),
u right, v down, as the detection boxes (u0, v0, u1, v1).

Generated records also get a bird's-eye panel (:func:`draw_birdseye`): the true world positions
of every object, both observers with their view frusta, and the same match lines drawn between
the matched objects' true positions — the picture that shows why a matcher failed (two
look-alike cars side by side, an object only one observer sees). World frame: x east, y north,
metres, seen from above.

Records without images (imported data) are drawn from above instead (:func:`topdown_figure`):
each view's detections in its own camera frame's ground plane (x right, z forward, metres), lines
between corresponding detections, and, when the record has a localisation prior, both views'
detections in the shared world frame, where the lines show the prior's error.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

CORRECT, WRONG, MISSED = "#22c55e", "#ef4444", "#facc15"


def side_by_side(color1: np.ndarray, color2: np.ndarray, gap: int = 16) -> tuple[np.ndarray, int]:
    """One (H, W1 + gap + W2, 3) uint8 image (white gap), and view 2's horizontal offset."""
    h = max(color1.shape[0], color2.shape[0])
    offset = color1.shape[1] + gap
    canvas = np.full((h, offset + color2.shape[1], 3), 255, np.uint8)
    canvas[: color1.shape[0], : color1.shape[1]] = color1
    canvas[: color2.shape[0], offset:] = color2
    return canvas, offset


def _boxes(boxes: np.ndarray, name: str) -> np.ndarray:
    arr = np.asarray(boxes, float)
    if arr.size == 0:
        return arr.reshape(0, 4)
    if arr.ndim != 2 or arr.shape[1] != 4:
        raise ValueError(f"{name}: expected (k, 4) boxes (u0, v0, u1, v1), got {arr.shape}")
    return arr


def draw_pair(
    ax,
    color1: np.ndarray,
    color2: np.ndarray,
    boxes1: np.ndarray,
    boxes2: np.ndarray,
    pairs: np.ndarray,
    line_colors: str | Sequence[str] = CORRECT,
    box_color: str = "#38bdf8",
    labels1: Sequence[str] | None = None,
    labels2: Sequence[str] | None = None,
    gap: int = 16,
    linewidth: float = 1.5,
    label_size: float = 6,
) -> None:
    """Draw on matplotlib ``ax``: both views, every box, and for each row (i, j) of ``pairs`` a
    line from box i of view 1 to box j of view 2 (one colour, or one per row); ``labels1/2``
    written above the boxes in ``label_size`` points."""
    from matplotlib.collections import LineCollection, PatchCollection
    from matplotlib.patches import Rectangle

    b1, b2 = _boxes(boxes1, "boxes1"), _boxes(boxes2, "boxes2")
    pairs = np.asarray(pairs, dtype=int).reshape(-1, 2)
    if len(pairs) and (pairs[:, 0].max() >= len(b1) or pairs[:, 1].max() >= len(b2)):
        raise ValueError(f"pairs: index out of range for {len(b1)} and {len(b2)} boxes")
    canvas, offset = side_by_side(color1, color2, gap)
    ax.imshow(canvas, interpolation="nearest")
    b2 = b2 + [offset, 0, offset, 0]
    rects = [Rectangle((u0, v0), u1 - u0, v1 - v0) for u0, v0, u1, v1 in np.vstack([b1, b2])]
    ax.add_collection(
        PatchCollection(rects, facecolor="none", edgecolor=box_color, linewidth=linewidth)
    )
    centres1 = (b1[:, :2] + b1[:, 2:]) / 2
    centres2 = (b2[:, :2] + b2[:, 2:]) / 2
    if len(pairs):
        segments = np.stack([centres1[pairs[:, 0]], centres2[pairs[:, 1]]], axis=1)
        colors = [line_colors] * len(pairs) if isinstance(line_colors, str) else list(line_colors)
        if len(colors) != len(pairs):
            raise ValueError(f"line_colors: {len(colors)} colours for {len(pairs)} pairs")
        ax.add_collection(LineCollection(segments, colors=colors, linewidths=linewidth))
        ax.scatter(*segments.reshape(-1, 2).T, s=8, c=np.repeat(colors, 2), zorder=3)
    for labels, boxes in ((labels1, b1), (labels2, b2)):
        for text, (u0, v0, _, _) in zip(labels or (), boxes, strict=False):
            ax.text(u0, v0 - 2, text, color=box_color, fontsize=label_size, va="bottom")
    ax.set_xlim(0, canvas.shape[1])
    ax.set_ylim(canvas.shape[0], 0)
    ax.set_axis_off()


def pair_figure(color1: np.ndarray, color2: np.ndarray, *args, title: str | None = None, **kwargs):
    """A matplotlib ``Figure`` holding one ``draw_pair`` (same arguments), sized to the images."""
    from matplotlib.figure import Figure

    canvas, _ = side_by_side(color1, color2, kwargs.get("gap", 16))
    dpi = 100
    fig = Figure(
        figsize=(canvas.shape[1] / dpi, canvas.shape[0] / dpi + (0.3 if title else 0)), dpi=dpi
    )
    ax = fig.add_axes((0, 0, 1, canvas.shape[0] / (canvas.shape[0] + (30 if title else 0))))
    draw_pair(ax, color1, color2, *args, **kwargs)
    if title:
        fig.suptitle(title, fontsize=9, y=0.99)
    return fig


def save_figure(fig, path: str | Path) -> Path:
    """Write ``fig`` (format from the suffix: .png, .pdf, .svg); creates the folder. Rendered in
    memory and written atomically (``cadsim.dataset.atomic_writer``: a new temporary file renamed
    into place, never through a link)."""
    import io

    from cadsim.dataset.atomic_writer import write_file_atomic

    path = Path(path)
    buffer = io.BytesIO()
    fig.savefig(buffer, format=path.suffix.lstrip(".") or "png", dpi=fig.dpi)
    write_file_atomic(path, buffer.getvalue())
    return path


def topdown_figure(
    positions1: np.ndarray,
    positions2: np.ndarray,
    pairs: np.ndarray,
    world: tuple[np.ndarray, np.ndarray] | None = None,
    line_colors: str | Sequence[str] = CORRECT,
    labels1: Sequence[str] | None = None,
    labels2: Sequence[str] | None = None,
    title: str | None = None,
):
    """A ``Figure`` seen from above: view 1's and view 2's (k, 3) camera-frame positions
    (x right, y down, z forward, metres; drawn as x across, z up the page, the camera at the
    origin) in two panels, a line per row (i, j) of ``pairs`` between them, and, if ``world``
    = (world1, world2) is given, a third panel with both views in the world frame (x, y)."""
    from matplotlib.figure import Figure
    from matplotlib.patches import ConnectionPatch

    p1 = np.asarray(positions1, float).reshape(-1, 3)
    p2 = np.asarray(positions2, float).reshape(-1, 3)
    pairs = np.asarray(pairs, dtype=int).reshape(-1, 2)
    if len(pairs) and (pairs[:, 0].max() >= len(p1) or pairs[:, 1].max() >= len(p2)):
        raise ValueError(f"pairs: index out of range for {len(p1)} and {len(p2)} positions")
    colors = [line_colors] * len(pairs) if isinstance(line_colors, str) else list(line_colors)
    if len(colors) != len(pairs):
        raise ValueError(f"line_colors: {len(colors)} colours for {len(pairs)} pairs")
    panels = 3 if world is not None else 2
    fig = Figure(figsize=(4.2 * panels, 4.6), dpi=100)
    axes = fig.subplots(1, panels)
    for ax, pts, labels, name, marker in (
        (axes[0], p1, labels1, "view 1", "o"),
        (axes[1], p2, labels2, "view 2", "s"),
    ):
        ax.scatter(pts[:, 0], pts[:, 2], s=18, marker=marker, color="#38bdf8", zorder=3)
        ax.scatter([0], [0], marker="^", s=60, color="black", zorder=3)
        for k, text in enumerate(labels or ()):
            ax.annotate(text, (pts[k, 0], pts[k, 2]), fontsize=6, xytext=(3, 3),
                        textcoords="offset points")  # fmt: skip
        ax.set_title(f"{name}: camera frame from above", fontsize=8)
        ax.set_xlabel("x (m, right)", fontsize=7)
        ax.set_ylabel("z (m, forward)", fontsize=7)
        ax.set_aspect("equal", adjustable="datalim")
        ax.tick_params(labelsize=6)
    for (i, j), color in zip(pairs, colors, strict=True):
        fig.add_artist(
            ConnectionPatch(
                (p1[i, 0], p1[i, 2]), (p2[j, 0], p2[j, 2]), "data", "data",
                axesA=axes[0], axesB=axes[1], color=color, linewidth=1.0,
            )
        )  # fmt: skip
    if world is not None:
        w1 = np.asarray(world[0], float).reshape(-1, 3)
        w2 = np.asarray(world[1], float).reshape(-1, 3)
        ax = axes[2]
        ax.scatter(w1[:, 0], w1[:, 1], s=18, marker="o", color="#2563eb", label="view 1", zorder=3)
        ax.scatter(w2[:, 0], w2[:, 1], s=18, marker="s", color="#f97316", label="view 2", zorder=3)
        for (i, j), color in zip(pairs, colors, strict=True):
            ax.plot([w1[i, 0], w2[j, 0]], [w1[i, 1], w2[j, 1]], color=color, linewidth=1.0)
        ax.set_title("localisation prior: world frame from above", fontsize=8)
        ax.set_xlabel("x (m)", fontsize=7)
        ax.set_ylabel("y (m)", fontsize=7)
        ax.set_aspect("equal", adjustable="datalim")
        ax.tick_params(labelsize=6)
        ax.legend(fontsize=6)
    if title:
        fig.suptitle(title, fontsize=9)
    return fig


OBSERVER_COLORS = ("#2563eb", "#f97316")  # view 1, view 2 (markers and frusta)


def detection_world_positions(pair) -> tuple[np.ndarray, np.ndarray]:
    """Per view, (k, 2) true world (x, y) of each detection: its object's bounding-box centre,
    or — for a detection with no object in the record — its camera-frame position through the
    true camera pose."""
    centres = {o.id: o.center[:2] for o in pair.objects}
    out = []
    for view, to_world in zip((pair.view1, pair.view2), pair.camera_to_world, strict=True):
        xyz = np.asarray(view.positions, float).reshape(-1, 3)
        fallback = xyz @ to_world[:3, :3].T + to_world[:3, 3]
        out.append(
            np.array(
                [centres.get(oid, fallback[k, :2]) for k, oid in enumerate(view.object_ids)],
                dtype=float,
            ).reshape(-1, 2)
        )
    return out[0], out[1]


def draw_birdseye(
    ax,
    pair,
    lines: Sequence[tuple[np.ndarray, str, str]] = (),
    frustum_m: float | None = None,
    numbers: Sequence[tuple[int, int, int]] = (),
) -> None:
    """Draw generated ``pair`` from above on matplotlib ``ax`` (world x east, y north, metres):
    every target object (grey), view 1's detections (blue circles) and view 2's (orange
    squares) at their true positions, each observer's camera and view frustum (its horizontal
    field of view out to ``frustum_m``, default the farthest detection + 5 m), and per entry
    (pairs (k, 2), colour, linestyle) of ``lines`` a line between the matched detections — or,
    where both are one object (a correct or a missed match), a disc ("-") or ring (other
    styles) around it. ``numbers``: (i, j, number) rows — the number is written beside view 1's
    detection i and view 2's detection j (one label where both are one object), the same
    number :func:`draw_pair_from_record` writes on the two images."""
    from matplotlib.patches import Wedge

    cams = pair.cameras
    if cams is None:
        raise ValueError(
            f"{pair.name}: no cameras in the record (imported data): no bird's-eye view"
        )
    w1, w2 = detection_world_positions(pair)
    targets = np.array([o.center[:2] for o in pair.objects if o.target], float).reshape(-1, 2)
    depth = max(
        [float(np.max(v.positions[:, 2])) for v in (pair.view1, pair.view2) if len(v.positions)],
        default=30.0,
    )
    reach = frustum_m if frustum_m is not None else depth + 5.0
    for cam, color, name in zip(cams, OBSERVER_COLORS, ("observer 1", "observer 2"), strict=True):
        centre = np.degrees(cam.yaw)
        ax.add_patch(
            Wedge(cam.position[:2], reach, centre - cam.hfov_deg / 2, centre + cam.hfov_deg / 2,
                  facecolor=color, alpha=0.08, edgecolor=color, linewidth=0.8)
        )  # fmt: skip
        ax.scatter(*cam.position[:2], marker="^", s=60, color=color, zorder=4, label=name)
    ax.scatter(*targets.T, s=6, color="#9ca3af", zorder=2, label="objects")
    for pairs, color, style in lines:
        pairs = np.asarray(pairs, int).reshape(-1, 2)
        a, b = w1[pairs[:, 0]], w2[pairs[:, 1]]
        same = np.hypot(*(a - b).T) < 0.5  # one object seen twice: a line of no length
        for (x0, y0), (x1, y1) in zip(a[~same], b[~same], strict=True):
            ax.plot([x0, x1], [y0, y1], color=color, linestyle=style, linewidth=1.4, zorder=3)
        ax.scatter(*a[same].T, s=90, marker="o", zorder=3, linewidths=1.6,
                   facecolor="none" if style != "-" else color, edgecolor=color,
                   linestyle=style)  # fmt: skip
    ax.scatter(*w1.T, s=30, facecolor="none", edgecolor=OBSERVER_COLORS[0], marker="o", zorder=5,
               label="seen by 1")  # fmt: skip
    ax.scatter(*w2.T, s=44, facecolor="none", edgecolor=OBSERVER_COLORS[1], marker="s", zorder=5,
               label="seen by 2")  # fmt: skip
    for i, j, number in numbers:
        spots = [w1[i]] if np.hypot(*(w1[i] - w2[j])) < 0.5 else [w1[i], w2[j]]
        for x, y in spots:
            ax.annotate(str(number), (x, y), xytext=(6, 4), textcoords="offset points",
                        fontsize=8, fontweight="bold", color="#15803d", zorder=6)  # fmt: skip
    shown = np.vstack([w1, w2, [c.position[:2] for c in cams]])
    low, high = shown.min(axis=0) - 8.0, shown.max(axis=0) + 8.0
    ax.set_xlim(low[0], high[0])
    ax.set_ylim(low[1], high[1])
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("x (m, east)", fontsize=7)
    ax.set_ylabel("y (m, north)", fontsize=7)
    ax.tick_params(labelsize=6)
    ax.legend(fontsize=6, loc="upper right", framealpha=0.8, ncol=2)


def _labels(view) -> list[str]:
    """A view's labels as its detector reported them (the true class where the record has none)."""
    return view.true_classes if view.reported_classes is None else view.reported_classes


def _numbered(classes: Sequence[str], numbers: dict[int, int], labels: bool) -> list[str]:
    """Each detection's label: "number class" for one of a true pair (its number), the class
    alone for the others; with ``labels`` False only the numbers."""
    return [
        " ".join(([str(numbers[k])] if k in numbers else []) + ([c] if labels else []))
        for k, c in enumerate(classes)
    ]


def draw_pair_from_record(pair, labels: bool = True):
    """Figure of a dataset ``FramePair``: its boxes and its ground-truth pairs, with a bird's-eye
    panel below (:func:`draw_birdseye`); from above only, with the localisation prior, when the
    record has no images."""
    if not pair.has_images:
        prior = pair.prior()
        return topdown_figure(
            pair.view1.positions,
            pair.view2.positions,
            pair.gt_pairs,
            world=None if prior is None else prior[:2],
            labels1=_labels(pair.view1) if labels else None,
            labels2=_labels(pair.view2) if labels else None,
            title=f"{pair.name} (pair {pair.index}): {len(pair.view1)} | {len(pair.view2)} "
            f"detections, {len(pair.gt_pairs)} covisible (ground truth)",
        )
    title = (
        f"{pair.name} (pair {pair.index}, t = {pair.time:.1f} s): {len(pair.view1)} | "
        f"{len(pair.view2)} detections, {len(pair.gt_pairs)} covisible"
    )
    from matplotlib.figure import Figure

    canvas, _ = side_by_side(pair.color1, pair.color2)
    dpi, below = 100, 5.0  # inches of bird's-eye panel
    width, images = canvas.shape[1] / dpi, canvas.shape[0] / dpi
    height = images + below + 0.35
    fig = Figure(figsize=(width, height), dpi=dpi)
    gt = np.asarray(pair.gt_pairs, int).reshape(-1, 2)
    numbered = [(int(i), int(j), k + 1) for k, (i, j) in enumerate(gt)]
    draw_pair(
        fig.add_axes((0, (below + 0.05) / height, 1, images / height)),
        pair.color1,
        pair.color2,
        pair.view1.boxes,
        pair.view2.boxes,
        gt,
        labels1=_numbered(_labels(pair.view1), {i: k for i, _, k in numbered}, labels),
        labels2=_numbered(_labels(pair.view2), {j: k for _, j, k in numbered}, labels),
        label_size=8,
    )
    draw_birdseye(
        fig.add_axes((0.08, 0.45 / height, 0.84, (below - 0.5) / height)),
        pair,
        [(gt, CORRECT, "-")],
        numbers=numbered,
    )
    fig.suptitle(
        title + " — ground truth: a true pair carries one number in both views and from above "
        "(green discs: objects both observers detect)",
        fontsize=9,
        y=0.995,
    )
    return fig


def match_classes(declared, gt) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(correct, wrong, missed) (k, 2) pair arrays: the declared pairs that are true, those that
    are not, and the true pairs not declared."""
    declared = np.asarray(declared, int).reshape(-1, 2)
    gt = np.asarray(gt, int).reshape(-1, 2)
    true = (declared[:, None, :] == gt[None, :, :]).all(axis=2).any(axis=1)
    found = (gt[:, None, :] == declared[None, :, :]).all(axis=2).any(axis=1)
    return declared[true], declared[~true], gt[~found]


def draw_matches_from_record(pair, declared, matcher: str, labels: bool = True):
    """Figure of a dataset ``FramePair`` with the pairs a matcher declared (``declared``, (k, 2)):
    correct ones green, wrong ones red, true pairs it missed yellow (dashed); the bird's-eye
    panel below shows the same lines between the true positions. From above only when the
    record has no images."""
    correct, wrong, missed = match_classes(declared, pair.gt_pairs)
    shown = np.vstack([correct, wrong, missed])
    colors = [CORRECT] * len(correct) + [WRONG] * len(wrong) + [MISSED] * len(missed)
    summary = (
        f"{pair.name} (pair {pair.index}) — {matcher}: {len(correct)} correct (green), "
        f"{len(wrong)} wrong (red), {len(missed)} missed (yellow) of {len(pair.gt_pairs)} true"
    )
    if not pair.has_images:
        prior = pair.prior()
        return topdown_figure(
            pair.view1.positions,
            pair.view2.positions,
            shown,
            world=None if prior is None else prior[:2],
            line_colors=colors,
            labels1=_labels(pair.view1) if labels else None,
            labels2=_labels(pair.view2) if labels else None,
            title=summary,
        )
    from matplotlib.figure import Figure

    canvas, _ = side_by_side(pair.color1, pair.color2)
    dpi, below = 100, 5.0  # inches of bird's-eye panel
    width, images = canvas.shape[1] / dpi, canvas.shape[0] / dpi
    height = images + below + 0.35
    fig = Figure(figsize=(width, height), dpi=dpi)
    draw_pair(
        fig.add_axes((0, (below + 0.05) / height, 1, images / height)),
        pair.color1,
        pair.color2,
        pair.view1.boxes,
        pair.view2.boxes,
        shown,
        colors,
        labels1=_labels(pair.view1) if labels else None,
        labels2=_labels(pair.view2) if labels else None,
        label_size=8,
    )
    if pair.cameras is not None:
        draw_birdseye(
            fig.add_axes((0.08, 0.45 / height, 0.84, (below - 0.5) / height)),
            pair,
            [(correct, CORRECT, "-"), (wrong, WRONG, "-"), (missed, MISSED, "--")],
        )
    fig.suptitle(summary, fontsize=9, y=0.995)
    return fig
