"""The reader and the garbage collector (issue 26, item 3): the model is built with the collector paused and then
moved to its oldest generation without a pass; the caller's settings are as they were, and a process that froze
objects of its own (``sim serve`` before forking) keeps them frozen."""

from __future__ import annotations

import gc

from ecattool.esi.reader import without_gc


def _build() -> list[object]:
    return [[i] for i in range(5000)]


def test_the_model_goes_to_the_oldest_generation_and_the_collector_is_back_on() -> None:
    assert gc.isenabled()
    built = without_gc(_build)
    assert gc.isenabled() and gc.get_freeze_count() == 0
    assert gc.get_count()[0] < 100  # no pass owed for the thousands of objects just made
    assert all(gc.is_tracked(x) for x in built[:10])
    # still collectable: a cycle made in the build is found by a full pass
    cycle: list[list[object]] = without_gc(lambda: [[]])
    cycle[0].append(cycle)
    del cycle
    assert gc.collect() >= 1


def test_a_disabled_collector_stays_disabled_and_frozen_objects_stay_frozen() -> None:
    gc.disable()
    try:
        without_gc(_build)
        assert not gc.isenabled()
    finally:
        gc.enable()
    gc.freeze()
    try:
        frozen = gc.get_freeze_count()
        without_gc(_build)
        assert gc.get_freeze_count() == frozen and gc.isenabled()
    finally:
        gc.unfreeze()
