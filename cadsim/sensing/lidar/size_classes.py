"""A class from a box's size, and the box completed to that class's size.

Rules on the fitted (visible) box — height h above the road, footprint length L ≥ width W,
metres — in this order: h < :data:`MIN_HEIGHT_M`, h > :data:`MAX_HEIGHT_M` or L >
:data:`MAX_LENGTH_M` is no object (curbs, walls, buildings, tall trees); L and W ≤
:data:`NARROW_M`: a ``pole`` (signs, traffic lights) when h ≥ :data:`POLE_HEIGHT_M`, a ``person``
when h ≥ :data:`PERSON_HEIGHT_M`, else nothing; L ≤ :data:`BICYCLE_LENGTH_M`, W ≤
:data:`BICYCLE_WIDTH_M` and h ≥ :data:`BICYCLE_HEIGHT_M`: a ``bicycle`` (with its rider);
otherwise a vehicle by height: ``bus`` (h ≥ :data:`HEAVY_HEIGHT_M`, L > :data:`BUS_LENGTH_M`),
``truck`` (h ≥ :data:`HEAVY_HEIGHT_M`), ``van`` (h ≥ :data:`VAN_HEIGHT_M`), ``car``. A rear view
of a car is a 1.8 m × 0.2 m sliver, so L and W alone would not tell a car from a cyclist; the
height does most of the work.

The thresholds are derived from the object-size spreads (``cadsim.object_sizes``,
docs/lidar.md "Class thresholds"): between two classes told apart by one dimension, the point
where their normal densities cross (equal priors); against "no object", the class's plausible
bound (mean ∓ 2.5 sd) widened by 0.1 m of fitting slack. ``tests/test_lidar_size_classes.py``
recomputes them from the spreads.

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

from cadsim.object_sizes import SIZE_SPREADS
from cadsim.sensing.lidar.box_fit import FittedBox, fold_yaw

MIN_HEIGHT_M = 0.5  # below every class's lowest object, above kerbs and low walls
MAX_HEIGHT_M = 4.48  # the tallest signal pole (4.38 m; trucks 3.95 m) + 0.1 m
MAX_LENGTH_M = 14.1  # the longest bus (14.0 m) + 0.1 m
NARROW_M = 1.15  # the widest sign plate (1.05 m) + 0.1 m
POLE_HEIGHT_M = 1.98  # person (1.71 ± 0.095) / sign (2.6 ± 0.25) densities cross
PERSON_HEIGHT_M = 1.37  # the shortest adult (1.47 m) - 0.1 m
BICYCLE_LENGTH_M = 2.05  # the longest bicycle (1.95 m) + 0.1 m
BICYCLE_WIDTH_M = 0.83  # the widest handlebar (0.725 m) + 0.1 m
BICYCLE_HEIGHT_M = 1.4  # the lowest rider (1.5 m) - 0.1 m
VAN_HEIGHT_M = 1.77  # car (1.52 ± 0.10) / van (2.3 ± 0.25) densities cross
HEAVY_HEIGHT_M = 2.85  # van / truck (2.88) and van / bus (2.81) crossings, averaged
BUS_LENGTH_M = 10.67  # truck (9.0 ± 1.2) / bus (12.0 ± 0.8) length densities cross

TYPICAL_SIZE: dict[str, tuple[float, float]] = {
    **{c: SIZE_SPREADS[c].mean[:2] for c in ("car", "van", "truck", "bus", "bicycle")},
    "person": tuple(sorted(SIZE_SPREADS["person"].mean[:2], reverse=True)),
    "pole": (0.3, 0.3),
}
"""(length, width) metres a completed box of each reported class has at least: the class's mean
footprint (``cadsim.object_sizes``; a person's as (breadth, depth), the longer side first); a
pole's is a typical post's (signs and signal poles mixed), not derived."""


def class_from_size(size: tuple[float, float, float]) -> str | None:
    """The class of a fitted box's (length, width, height) metres (module docstring), or None."""
    length, width, height = size
    if height < MIN_HEIGHT_M or height > MAX_HEIGHT_M or length > MAX_LENGTH_M:
        return None
    if length <= NARROW_M and width <= NARROW_M:
        if height >= POLE_HEIGHT_M:
            return "pole"
        return "person" if height >= PERSON_HEIGHT_M else None
    if length <= BICYCLE_LENGTH_M and width <= BICYCLE_WIDTH_M and height >= BICYCLE_HEIGHT_M:
        return "bicycle"
    if height >= HEAVY_HEIGHT_M:
        return "bus" if length > BUS_LENGTH_M else "truck"
    return "van" if height >= VAN_HEIGHT_M else "car"


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
