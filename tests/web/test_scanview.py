"""The scans the page draws (web/scanview.py): world points, decimated, at most every SCAN_PERIOD."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnibot.scan import Scan
from omnibot.web.scanview import SCAN_PERIOD, ScanView, scan_points


def _scan(stamp: float, rays: int = 8, distance: float = 2.0) -> Scan:
    return Scan(
        stamp=stamp,
        angle_min=0.0,
        angle_increment=2 * math.pi / rays,
        ranges=np.full(rays, distance),
        range_min=0.1,
        range_max=10.0,
    )


def test_the_points_are_in_the_world_frame_from_the_pose_and_at_most_most() -> None:
    scan = _scan(1.23456, rays=8)
    points = scan_points(scan, (1.0, 2.0, math.pi / 2), most=4)
    assert points["t"] == 1.235
    assert len(points["points"]) == 4  # every other ray
    first = points["points"][0]  # the ray ahead of the robot, which faces +y
    assert first == pytest.approx([1.0, 4.0], abs=1e-3)


def test_the_newest_scan_goes_once_and_at_most_every_period() -> None:
    view = ScanView()
    pose = (0.0, 0.0, 0.0)
    assert view.frame([], 0.0, pose) is None  # nothing seen yet
    sent = view.frame([_scan(0.0), _scan(0.05)], 0.1, pose)
    assert sent is not None and sent["t"] == 0.05  # the newest of the cycle's
    assert view.frame([], 0.15, pose) is None  # nothing new
    assert view.frame([_scan(0.2)], 0.1 + SCAN_PERIOD / 2, pose) is None  # too soon: held
    assert view.frame([], 0.1 + SCAN_PERIOD / 2, None) is None  # no pose to show it from
    held = view.frame([], 0.1 + SCAN_PERIOD, pose)
    assert held is not None and held["t"] == 0.2
