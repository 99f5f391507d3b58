"""The wall-clock token bucket, on a fake clock (and one short real-time check)."""

from __future__ import annotations

import time

import pytest

from omnibot.transport.pacing import Pacer


class FakeTime:
    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        return self.t

    def sleep(self, seconds: float) -> None:
        self.t += seconds


def test_burst_then_line_rate() -> None:
    clock = FakeTime()
    pacer = Pacer(115200, burst=16, clock=clock)
    assert pacer.take(100) == 16
    assert pacer.take(1) == 0
    clock.t += 0.001  # 11.52 bytes' worth
    assert pacer.take(100) == 11
    assert pacer.delay(1) == pytest.approx((1 - 0.52) * 10 / 115200)


def test_tokens_cap_at_burst() -> None:
    clock = FakeTime()
    pacer = Pacer(9600, burst=4, clock=clock)
    clock.t += 100.0
    assert pacer.available() == 4


def test_wait_holds_the_rate() -> None:
    clock = FakeTime()
    pacer = Pacer(115200, burst=16, clock=clock)
    pacer.wait(11520 + 16, sleep=clock.sleep)
    assert clock.t == pytest.approx(1.0, rel=1e-3)


def test_unpaced() -> None:
    pacer = Pacer(0)
    assert pacer.take(10**9) == 10**9
    assert pacer.delay(10**9) == 0.0


def test_bad_arguments() -> None:
    with pytest.raises(ValueError, match="burst"):
        Pacer(9600, burst=0)
    with pytest.raises(ValueError, match="baud"):
        Pacer(-1)


def test_real_time() -> None:
    pacer = Pacer(115200, burst=16)
    t0 = time.monotonic()
    pacer.wait(16 + 1152)  # 0.1 s after the burst
    assert time.monotonic() - t0 >= 0.095
