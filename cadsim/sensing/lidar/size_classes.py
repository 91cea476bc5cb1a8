"""A class from a box's size, and the box completed to that class's size.

Rules on the fitted (visible) box — height h above the road, footprint length L ≥ width W,
metres — in this order: h < 0.5 m, h > 4.6 m or L > 20 m is no object (curbs, walls,
buildings); L ≤ 1.2 and W ≤ 1.2: a ``pole`` (signs, traffic lights) when h ≥ 2.3, a ``person``
when h ≥ 1.0, else nothing; L ≤ 2.3, W ≤ 0.9 and h ≥ 1.6: a ``bicycle`` (with its rider);
otherwise a vehicle by height: ``bus`` (h ≥ 2.6, L > 9), ``truck`` (h ≥ 2.6), ``van``
(h ≥ 1.95), ``car``. A rear view of a car is a 1.8 m × 0.2 m sliver, so L and W alone would not
tell a car from a cyclist; the height does most of the work.

Completion: a LiDAR sees an object's near faces only, so a fitted box is short on the far side
and its centre is biased towards the sensor. Each footprint side shorter than the class's
:data:`TYPICAL_SIZE` is grown to it *away from the sensor* (the visible faces stay where they
are); sides longer than typical are kept. Heights are kept as measured. When the visible box
is shorter than the class's length on both sides (an object seen end-on: its rear and part of
its roof), which side is the length is re-decided first: the side across the line of sight is
the completely seen one, and it is the width when its extent is nearer (in ratio) the class's
width than its length — unless the side along the line of sight is already wider than the
class's width.
"""

from __future__ import annotations

import math

from cadsim.sensing.lidar.box_fit import FittedBox, fold_yaw

TYPICAL_SIZE: dict[str, tuple[float, float]] = {
    "car": (4.5, 1.8),
    "van": (5.0, 2.0),
    "truck": (8.0, 2.5),
    "bus": (12.0, 2.5),
    "bicycle": (1.8, 0.6),
    "person": (0.5, 0.5),
    "pole": (0.3, 0.3),
}
"""(length, width) metres a completed box of each reported class has at least."""


def class_from_size(size: tuple[float, float, float]) -> str | None:
    """The class of a fitted box's (length, width, height) metres (module docstring), or None."""
    length, width, height = size
    if height < 0.5 or height > 4.6 or length > 20.0:
        return None
    if length <= 1.2 and width <= 1.2:
        if height >= 2.3:
            return "pole"
        return "person" if height >= 1.0 else None
    if length <= 2.3 and width <= 0.9 and height >= 1.6:
        return "bicycle"
    if height >= 2.6:
        return "bus" if length > 9.0 else "truck"
    return "van" if height >= 1.95 else "car"


def complete_box(box: FittedBox, cls: str) -> FittedBox:
    """``box`` with each footprint side grown to ``cls``'s typical size away from the sensor at
    the origin (module docstring)."""
    typical_l, typical_w = TYPICAL_SIZE[cls]
    length, width, height = box.size
    cx, cy, cz = box.centre
    yaw = box.yaw
    c, s = math.cos(yaw), math.sin(yaw)
    sight = math.hypot(cx, cy)
    if length < typical_l - 0.5 and sight > 0:
        # extents along the box's axes: which one lies across the line of sight?
        along_length = abs(c * cx + s * cy) / sight
        cross, along = (length, width) if along_length < math.sqrt(0.5) else (width, length)
        cross_is_length = along_length < math.sqrt(0.5)
        cross_is_width = along <= typical_w + 0.3 and abs(math.log(cross / typical_w)) < abs(
            math.log(cross / typical_l)
        )
        if cross_is_length == cross_is_width:  # swap the axes: the length is the other side
            yaw = fold_yaw(yaw + math.pi / 2)
            length, width = width, length
            c, s = math.cos(yaw), math.sin(yaw)
    for axis, have, want in (((c, s), length, typical_l), ((-s, c), width, typical_w)):
        grow = want - have
        if grow <= 0:
            continue
        away = 1.0 if axis[0] * cx + axis[1] * cy >= 0 else -1.0
        cx += away * axis[0] * grow / 2.0
        cy += away * axis[1] * grow / 2.0
    return FittedBox((cx, cy, cz), (max(length, typical_l), max(width, typical_w), height), yaw)
