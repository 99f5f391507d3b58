"""The firmware's per-command timing: a stall in one round's baseline cannot make a case negative."""

from __future__ import annotations

import itertools

import pytest

from benchmarks import firmware_timing
from omnibot.firmware.config import build_config
from omnibot.robot import load_robot


def test_a_stalled_baseline_round_is_not_subtracted(monkeypatch: pytest.MonkeyPatch) -> None:
    """Each reading of the clock advances it by 1 us, except one that stalls 10 ms (a garbage
    collection while an empty poll was timed): every case still comes out at 0 or more."""
    ticks = itertools.count()
    calls = itertools.count()

    def fake_ticks() -> int:
        t = next(ticks)
        if next(calls) == 9:  # the third (last) empty poll's end: its round's baseline is 10 ms
            for _ in range(10_000):
                t = next(ticks)
        return t

    monkeypatch.setattr(firmware_timing, "_ticks", fake_ticks)
    monkeypatch.setattr(firmware_timing, "_diff", lambda a, b: a - b)
    results = firmware_timing.measure(build_config(load_robot("omni4")), rounds=3)
    assert [label for label, _ in results] == [case[0] for case in firmware_timing.CASES]
    assert all(us >= 0 for _, us in results)


def test_real_clock_gives_positive_times() -> None:
    results = dict(firmware_timing.measure(build_config(load_robot("omni4")), rounds=3))
    assert results["VEL (powers)"] > 0 and results["MOVE from idle (starts, powers)"] > 0
