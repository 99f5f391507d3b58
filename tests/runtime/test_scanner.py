"""The runtime's scanner: polled once a cycle, its scans on ``Cycle.scans`` for every sink; one that
fails is dropped with an error notice, and the loop goes on."""

from __future__ import annotations

import math

import numpy as np

from omnibot.client import robot_session
from omnibot.runtime.cycle import Cycle
from omnibot.runtime.runtime import Runtime
from omnibot.scan import Scan


class Scripted:
    """A scanner giving one scan per poll, then failing at the third."""

    def __init__(self) -> None:
        self.polls = 0

    def poll(self) -> list[Scan]:
        self.polls += 1
        if self.polls == 3:
            raise OSError("unplugged")
        ranges = np.full(8, 1.0)
        ranges[0] = math.inf
        return [Scan(float(self.polls), 0.0, -math.pi / 4, ranges, 0.1, 5.0)]


def test_scans_reach_every_sink_and_a_failing_scanner_is_dropped() -> None:
    with robot_session("sim://omni4?seed=1", "omni4", timeout=0.5) as session:
        runtime = Runtime(session.client, period=0.01)
        scanner = Scripted()
        runtime.scanner = scanner
        first: list[Cycle] = []
        second: list[Cycle] = []
        runtime.add_sink(first.append)
        runtime.add_sink(second.append)
        try:
            for _ in range(5):
                runtime.step()
                runtime.pacer.wait()
        finally:
            runtime.close()
    assert [[s.stamp for s in c.scans] for c in first] == [[1.0], [2.0], [], [], []]
    assert [c.scans for c in second] == [c.scans for c in first]  # one scanner, every sink
    assert runtime.scanner is None and scanner.polls == 3  # dropped, never polled again
    notices = [n.text for n in first[2].notices if n.level == "error"]
    assert notices == ["the scanner failed and is no longer read: unplugged"]
