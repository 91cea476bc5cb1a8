"""Stable ids for objects that carry none (highway-env vehicles)."""

import gc

import pytest

from cadsim.sources.highway.tracker import VehicleTracker


class Thing:
    pass


def test_ids_follow_objects_and_are_never_reused():
    t = VehicleTracker(prefix="veh")
    a, b, c = Thing(), Thing(), Thing()
    u = t.update([a, b])
    assert u.ids == ["veh0", "veh1"] and u.new == ["veh0", "veh1"] and u.gone == []
    u = t.update([b, a])  # order does not matter, identity does
    assert u.ids == ["veh1", "veh0"] and u.new == [] and u.gone == []
    u = t.update([c, b])
    assert u.ids == ["veh2", "veh1"] and u.new == ["veh2"] and u.gone == ["veh0"]
    u = t.update([a, c])  # a came back after leaving: a new vehicle as far as ids go
    assert u.ids == ["veh3", "veh2"] and u.new == ["veh3"] and u.gone == ["veh1"]
    assert len(t) == 2


def test_recycled_address_gets_a_fresh_id():
    t = VehicleTracker()
    old = Thing()
    old_address = id(old)
    first = t.update([old]).ids[0]
    t.update([])
    del old
    gc.collect()
    # CPython usually hands the freed block to the next object of the same size.
    fresh = [Thing() for _ in range(1000)]
    reused = [x for x in fresh if id(x) == old_address]
    newcomer = reused[0] if reused else fresh[0]
    assert t.update([newcomer]).ids[0] != first


def test_duplicate_object_rejected():
    t = VehicleTracker()
    a = Thing()
    with pytest.raises(ValueError, match="twice"):
        t.update([a, a])
