"""MappingSink: scans matched to the odometry of their time, in the runtime's thread or a worker."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from omnibot.mapping.session import MappingSink
from omnibot.motion import Estimate, Pose2D
from omnibot.scan import Scan
from omnibot.sim import load_world


class Scans:
    """A scan source handing out prepared scans at the cycles given."""

    def __init__(self, by_cycle: dict[int, list[Scan]]) -> None:
        self.by_cycle = by_cycle
        self.cycle = 0
        self.closed = False

    def poll(self) -> list[Scan]:
        return self.by_cycle.get(self.cycle, [])

    def close(self) -> None:
        self.closed = True


def room_scan(pose: Pose2D, stamp: float) -> Scan:
    world = load_world("room")
    angles = np.linspace(0.0, 2 * math.pi, 360, endpoint=False)
    ranges = world.raycast(np.tile([pose.x, pose.y], (360, 1)), angles + pose.theta, 12.0)
    return Scan(stamp, 0.0, 2 * math.pi / 360, np.asarray(ranges, dtype=float), 0.15, 12.0)


def drive(sink: MappingSink, source: Scans, cycles: int = 60) -> None:
    """The robot moves 1 cm per 10 ms cycle along x from (1, 1); a scan every 10 cycles, handed over
    two cycles late (a scan arrives after it ends)."""
    for i in range(cycles):
        source.cycle = i
        t = i * 0.01
        est = Estimate(t, 1.0 + t, 1.0, 0.0, 1.0, 0.0, 0.0)
        sink(SimpleNamespace(t=t, estimate=est))  # type: ignore[arg-type]


@pytest.mark.parametrize("threaded", [False, True])
def test_scans_meet_the_odometry_of_their_time(threaded: bool) -> None:
    scans = {i + 2: [room_scan(Pose2D(1.0 + i * 0.01, 1.0, 0.0), i * 0.01)] for i in range(0, 50, 10)}
    scans[59] = [room_scan(Pose2D(1.6, 1.0, 0.0), 0.65)]  # newer than any odometry: waits, then never placed
    source = Scans(scans)
    sink = MappingSink(source, threaded=threaded)
    drive(sink, source)
    sink.close()
    assert source.closed and sink.failure is None
    assert sink.received == 6 and sink.dropped == 0
    track = sink.trajectory()
    assert track.stamps == pytest.approx([0.0, 0.1, 0.2, 0.3, 0.4])
    for stamp, pose in zip(track.stamps, track.poses, strict=True):
        assert pose.x == pytest.approx(1.0 + stamp, abs=0.01) and pose.y == pytest.approx(1.0, abs=0.01)
    assert len(sink.odometry) == 60


def test_a_scan_before_the_odometry_is_dropped() -> None:
    source = Scans({5: [room_scan(Pose2D(1.0, 1.0, 0.0), -1.0)]})
    sink = MappingSink(source)
    drive(sink, source, 10)
    assert sink.dropped == 1 and not sink.slam.keyframes()
