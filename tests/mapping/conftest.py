"""The mapping tests' shared route: a lap and a half around the room and its drifting odometry."""

from __future__ import annotations

import numpy as np
import pytest
from benchmarks.slam_synthetic import drifting_odometry, room_path

from omnibot.motion import Pose2D


@pytest.fixture(scope="module")
def room_loop() -> tuple[list[Pose2D], list[Pose2D]]:
    """A lap and a half around the room (8 m) and its odometry: 3 % scale error, 2 deg/m heading bias."""
    truth = room_path(8.0)
    return truth, drifting_odometry(truth, np.random.default_rng(11))
