"""The demo's ground truth on its own: the controller's clock placed on the link's."""

from __future__ import annotations

import pytest

from omnibot.demos import truth


def test_the_controllers_clock_is_placed_by_the_tels_either_side() -> None:
    """An emulator that falls behind the wall clock (a loaded, cold one: its first second took three)
    moves the offset between its clock and the link's; each instant is placed by the TELs sent either
    side of it (the demo's truth in CI was put 1.3 s early by one offset, the soonest TEL's, for all)."""
    import numpy as np

    from omnibot.client import Telemetry

    clock = truth.ControllerClock()
    assert clock.link_time(0.0) is None and clock.place([(0.0, 1.0, 1.0, 0.0)]) == []
    rng = np.random.default_rng(1)

    def link(c: float) -> float:  # 3 s of link time for the first controller second, then in step
        return 3.0 * c if c < 1.0 else 2.0 + c

    for k in range(200):  # TEL every 20 ms, each 2-12 ms on the line
        c = 0.02 * k
        clock(Telemetry(time=link(c) + 0.002 + 0.01 * rng.random(), controller_time=c))
    for c in (0.1, 0.5, 0.9, 1.5, 3.0, 3.98, 5.0):
        assert abs(clock.link_time(c) - link(c)) < 0.05, c  # type: ignore[operator]
    clock(Telemetry(time=10.0, controller_time=0.0))  # a restart: its clock from 0 again
    assert clock.link_time(0.0) == pytest.approx(10.0)
