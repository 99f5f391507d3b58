"""tests/conftest.py's collection: made without the garbage collector, what it left frozen after."""

from __future__ import annotations

import gc


def test_what_collecting_left_is_frozen_and_the_collector_is_back_on() -> None:
    assert gc.isenabled()
    # the modules, functions and items of even one collected module: tens of thousands of objects
    assert gc.get_freeze_count() > 10_000
