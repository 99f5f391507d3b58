"""A path's ends: a start the robot may leave, a goal it may stand at."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnibot.errors import BlockedError, NoPathError, OffMapError
from omnibot.mapping.costmap import inflate
from omnibot.mapping.ends import check_start
from omnibot.mapping.planner import plan_path
from omnibot.motion import Pose2D
from tests.mapping.rooms import RES, box_room, grid_of, samples


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


def test_a_start_on_a_ridge_of_the_margin_leaves_through_the_cells_the_robot_fits_in() -> None:
    # a slot 0.55 m wide along the south wall, open to the east: the robot (0.4 m across) fits in
    # it but every cell of it is within its margin, and along the slot's middle the clearance does
    # not climb (a ridge): the start is not hemmed in, the way out runs along the slot
    data = box_room()
    data[12, :40] = 100  # a wall at y = 0.6 m from the west wall to x = 2 m
    cmap = inflate(grid_of(data), robot_radius=0.2, margin=0.1)
    start = Pose2D(1.0, 0.32, 0.0)
    check_start(cmap, start)
    plan = plan_path(cmap, start, Pose2D(3.0, 2.0, 0.0))
    along = samples(plan.waypoints)
    # never overlapping a wall, and out of the slot at its open end, not through its wall
    assert float(cmap.clearances(along).min()) >= cmap.robot_radius - 0.5 * RES * math.sqrt(2)
    crossing = along[np.argmax(along[:, 1] > 0.6)]
    assert crossing[0] > 2.0
