"""Per-object sizes: drawn from each class's published spread, per object id and seed, within
the plausible bounds — and the LiDAR's class thresholds derived from those spreads."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cadsim.object_sizes import CLIP_SD, SIZE_SPREADS, draw_size
from cadsim.sensing.lidar import size_classes as sc


def test_an_object_keeps_its_size_whatever_else_is_drawn():
    a = draw_size(11, "veh:veh3", "car")
    for other in ("veh:veh1", "veh:veh2", "person:ped7"):
        draw_size(11, other, "car")
    assert draw_size(11, "veh:veh3", "car") == a
    assert draw_size(12, "veh:veh3", "car") != a  # another episode's seed: another car
    assert draw_size(11, "veh:veh4", "car") != a


@pytest.mark.parametrize("cls", sorted(SIZE_SPREADS))
def test_every_class_spreads_within_its_bounds_around_its_mean(cls):
    spread = SIZE_SPREADS[cls]
    sizes = np.array([draw_size(3, f"o{k}", cls) for k in range(400)])
    lo, hi = spread.bounds()
    assert (sizes >= lo - 0.006).all() and (sizes <= hi + 0.006).all()  # centimetres
    assert len({tuple(s) for s in sizes}) > 300  # a spread, not one size per class
    np.testing.assert_allclose(sizes.mean(axis=0), spread.mean, atol=3 * max(spread.sd) / 20 + 0.01)
    np.testing.assert_allclose(sizes.std(axis=0), spread.sd, rtol=0.25, atol=0.006)


def test_a_source_mean_moves_the_spread_and_unknown_classes_keep_their_size():
    bus = np.array([draw_size(5, f"b{k}", "bus", (10.0, 2.5, 3.0)) for k in range(200)])
    assert abs(bus[:, 0].mean() - 10.0) < 0.2 and bus[:, 0].max() <= 10.0 + CLIP_SD * 0.8 + 1e-9
    assert draw_size(5, "x", "building", (18.0, 14.0, 9.0)) == (18.0, 14.0, 9.0)
    with pytest.raises(ValueError, match="no spread for class 'building'"):
        draw_size(5, "x", "building")


def _crossing(m1: float, s1: float, m2: float, s2: float) -> float:
    """Where N(m1, s1) and N(m2, s2) densities cross between the means."""
    a = 1 / (2 * s1**2) - 1 / (2 * s2**2)
    b = m2 / s2**2 - m1 / s1**2
    c = m1**2 / (2 * s1**2) - m2**2 / (2 * s2**2) - math.log(s2 / s1)
    roots = [(-b + sign * math.sqrt(b * b - 4 * a * c)) / (2 * a) for sign in (1, -1)]
    return next(x for x in roots if min(m1, m2) <= x <= max(m1, m2))


def test_lidar_thresholds_are_the_ones_the_spreads_give():
    s = SIZE_SPREADS
    h = {c: (s[c].mean[2], s[c].sd[2]) for c in s}
    hi = {c: s[c].bounds()[1] for c in s}
    lo = {c: s[c].bounds()[0] for c in s}
    assert sc.VAN_HEIGHT_M == pytest.approx(_crossing(*h["car"], *h["van"]), abs=0.01)
    heavy = (_crossing(*h["van"], *h["truck"]) + _crossing(*h["van"], *h["bus"])) / 2
    assert sc.HEAVY_HEIGHT_M == pytest.approx(heavy, abs=0.01)
    length = _crossing(s["truck"].mean[0], s["truck"].sd[0], s["bus"].mean[0], s["bus"].sd[0])
    assert sc.BUS_LENGTH_M == pytest.approx(length, abs=0.01)
    assert sc.POLE_HEIGHT_M == pytest.approx(_crossing(*h["person"], *h["sign"]), abs=0.01)
    assert sc.PERSON_HEIGHT_M == pytest.approx(lo["person"][2] - 0.1, abs=0.01)
    assert sc.MAX_HEIGHT_M == pytest.approx(
        max(hi["traffic_light"][2], hi["truck"][2]) + 0.1, abs=0.01
    )
    assert sc.MAX_LENGTH_M == pytest.approx(hi["bus"][0] + 0.1, abs=0.01)
    assert sc.NARROW_M == pytest.approx(hi["sign"][1] + 0.1, abs=0.01)
    assert sc.BICYCLE_LENGTH_M == pytest.approx(hi["bicycle"][0] + 0.1, abs=0.01)
    assert sc.BICYCLE_WIDTH_M == pytest.approx(hi["bicycle"][1] + 0.1, abs=0.01)
    assert sc.BICYCLE_HEIGHT_M == pytest.approx(lo["bicycle"][2] - 0.1, abs=0.01)
    for cls in ("car", "van", "truck", "bus", "bicycle"):
        assert sc.TYPICAL_SIZE[cls] == s[cls].mean[:2]
    # the mean object of each class is given its class
    for cls in ("car", "van", "truck", "bus", "bicycle"):
        length, width, height = s[cls].mean
        assert sc.class_from_size((length, width, height)) == cls
    assert (
        sc.class_from_size(tuple(sorted(s["person"].mean[:2], reverse=True)) + (1.71,)) == "person"
    )
