"""Ground truth for LiDAR boxes: which object each detected box is, from the object tags of its
points — after detection, for metrics only (the detector never sees the tags).

A box is the object most of its points hit (ties: the lower object index). A box whose points
mostly hit the ground or a non-target object (a wall, a parked prop) is a false positive; so is
every box but the largest of an object split in two. A false positive gets an id of its own,
``clutter:lidar:<view tag>:<k>#<source>``, that no other view can share, and its reported class
as true class (as the camera detector's clutter does). Its *source* says what it is: ``split``
(a piece of a target object whose larger piece is the true box), ``ground`` (mostly road
points), or the class of the non-target object most of its points hit (``building`` — a wall
sliver —, ``tree``, ``pole``, ``bin``, ``trailer``, ...); :func:`false_positive_source` reads
it back.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cadsim.sensing.lidar.box_detector import LidarBoxes

LIDAR_CLUTTER_PREFIX = "clutter:lidar:"


def box_ground_truth(
    boxes: LidarBoxes,
    object_index: np.ndarray,
    object_ids: Sequence[str],
    object_classes: Sequence[str],
    is_target: Sequence[bool],
    view_tag: str,
) -> tuple[list[str], list[str]]:
    """``(ids, true_classes)`` of the k boxes; ``object_index`` (n,) the scan's tag of each point
    the detector got (−1: ground), indexing ``object_ids`` / ``object_classes`` / ``is_target``."""
    k = len(boxes)
    tags = np.asarray(object_index, dtype=np.int64).reshape(-1)
    inside = boxes.point_box >= 0
    box_of, tag_of = boxes.point_box[inside], tags[inside] + 1  # 0 = ground
    n_tags = len(object_ids) + 1
    votes = np.bincount(box_of * n_tags + tag_of, minlength=k * n_tags).reshape(k, n_tags)
    winner = np.argmax(votes, axis=1) - 1 if k else np.zeros(0, np.int64)  # first max: lower index
    support = votes[np.arange(k), winner + 1] if k else np.zeros(0, np.int64)
    target = np.asarray(list(is_target) + [False], dtype=bool)[winner]  # −1 → the appended False
    ids, classes = [], []
    best: dict[int, int] = {}
    for b in range(k):  # per box
        w = int(winner[b])
        if target[b] and (w not in best or support[b] > support[best[w]]):
            best[w] = b
    keeper = {b: w for w, b in best.items()}
    for b in range(k):
        w = int(winner[b])
        if b in keeper:
            ids.append(str(object_ids[keeper[b]]))
            classes.append(str(object_classes[keeper[b]]))
            continue
        source = "ground" if w < 0 else "split" if target[b] else str(object_classes[w])
        ids.append(f"{LIDAR_CLUTTER_PREFIX}{view_tag}:{b}#{source}")
        classes.append(boxes.classes[b])
    return ids, classes


def false_positive_source(object_id: str) -> str | None:
    """What a LiDAR false positive's box mostly hit (module docstring), from its id; None for an
    id that is no LiDAR false positive or names no source (data made before sources were
    recorded)."""
    if not object_id.startswith(LIDAR_CLUTTER_PREFIX) or "#" not in object_id:
        return None
    return object_id.rsplit("#", 1)[1]
