"""The planar range scan every part of the SLAM bench shares: its checks, and a copy unchecked."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnibot.motion import Pose2D
from omnibot.scan import Scan


def scan(ranges: list[float]) -> Scan:
    return Scan(
        0.5,
        0.0,
        -math.pi / 2,
        np.array(ranges),
        0.15,
        12.0,
        0.025,
        0.1,
        frame="laser",
        mount=Pose2D(0.1, 0, 0),
    )


def test_a_scan_refuses_nan_and_ranges_of_more_dimensions() -> None:
    with pytest.raises(ValueError, match="must not be nan"):
        scan([1.0, math.nan, 2.0, 3.0])
    with pytest.raises(ValueError, match="one-dimensional"):
        Scan(0.0, 0.0, 0.1, np.ones((2, 2)), 0.15, 12.0)


def test_but_keeps_every_field_but_the_stamp_and_ranges_and_leaves_the_original_alone() -> None:
    first = scan([1.0, 2.0, math.inf, 3.0])
    ranges = np.array([4.0, math.inf, 5.0, 6.0])
    second = first.but(0.6, ranges)
    assert second.stamp == 0.6 and second.ranges is ranges
    assert (second.angle_increment, second.time_increment, second.scan_time, second.frame, second.mount) == (
        first.angle_increment, first.time_increment, first.scan_time, first.frame, first.mount,
    )  # fmt: skip
    assert first.stamp == 0.5 and first.ranges[0] == 1.0
    np.testing.assert_allclose(second.points("scanner"), [[4.0, 0.0], [-5.0, 0.0], [0.0, 6.0]], atol=1e-12)
    with pytest.raises(AttributeError):
        second.stamp = 1.0  # type: ignore[misc]
