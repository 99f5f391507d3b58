"""A path's ends: a start the robot may leave, a goal it may stand at."""

from __future__ import annotations

import pytest

from omnibot.errors import BlockedError, NoPathError, OffMapError
from omnibot.mapping.costmap import inflate
from omnibot.mapping.ends import check_start
from omnibot.motion import Pose2D
from tests.mapping.rooms import box_room, grid_of


def test_check_start_refuses_only_a_start_no_path_can_leave() -> None:
    cmap = inflate(grid_of(box_room()), robot_radius=0.2, margin=0.05)
    check_start(cmap, Pose2D(0.28, 1.5, 0.0))  # inside the margin: the path climbs out
    with pytest.raises(BlockedError, match=r"start \(0.15, 1.50\) overlaps a wall"):
        check_start(cmap, Pose2D(0.15, 1.5, 0.0))
    with pytest.raises(OffMapError):
        check_start(cmap, Pose2D(5.0, 1.5, 0.0))
    data = box_room()
    data[:, 10] = 100  # a slot 0.45 m wide along the west wall: clearance 0.2 m at most, below 0.25 m
    with pytest.raises(NoPathError, match="hemmed in"):
        check_start(inflate(grid_of(data), robot_radius=0.15, margin=0.1), Pose2D(0.25, 1.5, 0.0))
