"""The scan feed's odometry: poses interpolated between the cycles around a scan."""

from __future__ import annotations

import math

import pytest

from omnibot.mapping.feed import interpolate
from omnibot.motion import Pose2D


def test_interpolate_between_samples_the_short_way_round() -> None:
    stamps = [0.0, 1.0]
    poses = [Pose2D(0.0, 0.0, math.radians(170)), Pose2D(2.0, 0.0, math.radians(-170))]
    mid = interpolate(stamps, poses, 0.5)
    assert mid is not None
    assert (mid.x, mid.y) == pytest.approx((1.0, 0.0))
    assert abs(abs(mid.theta) - math.pi) < 1e-9  # through 180, not through 0
    assert interpolate(stamps, poses, 1.5) is None and interpolate(stamps, poses, -0.1) is None
