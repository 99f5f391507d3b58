"""The frontiers of a map being made, the walls it does not mark, the goals to them and the choice
among them."""

from __future__ import annotations

import numpy as np
import pytest

from omnibot.mapping import OccupancyGrid, inflate
from omnibot.motion import Pose2D
from omnibot.navigation.frontiers import (
    choose_frontier,
    frontier_goals,
    frontiers,
    unmarked_walls,
    wall_goals,
)


def half_known_room() -> OccupancyGrid:
    """A 4 m x 3 m room walled round, its west half seen (free), its east half unknown."""
    data = np.full((60, 80), -1, dtype=np.int8)
    data[:, :40] = 0
    data[0, :40] = data[-1, :40] = data[:, 0] = 100
    return OccupancyGrid(data, 0.05, Pose2D(0.0, 0.0, 0.0))


def test_the_frontier_is_where_the_known_free_space_meets_the_unknown() -> None:
    grid = half_known_room()
    cmap = inflate(grid, robot_radius=0.15, margin=0.05)
    goals = frontier_goals(grid, cmap)
    assert len(goals) == 1
    x, y, size = goals[0]
    assert size >= 50  # the whole north-south seam
    assert 1.5 <= x < 2.0 and 1.2 <= y <= 1.8  # near the seam's middle, where the robot can stand
    known = grid.data.copy()
    known[known < 0] = 0
    assert frontier_goals(OccupancyGrid(known, 0.05), cmap) == []  # all known: nothing to explore


def test_tiny_frontiers_are_noise() -> None:
    data = np.zeros((40, 40), dtype=np.int8)
    data[20, 20] = -1  # one unknown cell in the open
    grid = OccupancyGrid(data, 0.05)
    assert frontier_goals(grid, inflate(grid, robot_radius=0.1)) == []


def half_seen_doorway() -> OccupancyGrid:
    """A 3 m x 2 m room (south) seen whole, a wall at y = 2 with a 0.8 m doorway (x 1.1-1.9), and
    beyond it the north room unknown but for a strip 0.25 m wide seen through the doorway (x 1.4 to
    1.65, y 2.0 to 3.5): the robot cannot stand in the strip clear of the unknown."""
    data = np.full((80, 60), -1, dtype=np.int8)  # 3 m x 4 m
    data[:40, :] = 0  # the south room
    data[0, :] = data[:40, 0] = data[:40, -1] = 100
    data[40, :] = 100
    data[40, 22:38] = 0  # the doorway
    data[41:70, 28:33] = 0  # the strip seen through it
    return OccupancyGrid(data, 0.05, Pose2D(0.0, 0.0, 0.0))


def test_a_room_half_seen_through_a_doorway_is_gone_to_through_the_unknown() -> None:
    grid = half_seen_doorway()
    cmap = inflate(grid, robot_radius=0.15, margin=0.05)
    optimistic = inflate(grid, robot_radius=0.15, margin=0.05, allow_unknown=True)
    # clear of the unknown, nowhere within reach of the strip: its frontier had no goal
    assert frontier_goals(grid, cmap) == []
    found = frontiers(grid, cmap, optimistic)
    assert len(found) == 1 and found[0].goal is not None and not found[0].in_known
    gx, gy = found[0].goal
    assert 1.3 <= gx <= 1.75 and 2.3 <= gy <= 3.5  # in the strip, beyond the doorway
    choice, unreachable = choose_frontier(cmap, optimistic, Pose2D(0.5, 0.5, 0.0), [found[0].goal])
    assert unreachable == []
    assert choice == (found[0].goal, True)  # a way through the unknown


def test_only_a_frontier_with_no_way_even_through_the_unknown_is_unreachable() -> None:
    grid = half_seen_doorway()
    data = grid.data.copy()
    data[:40, 40] = 100  # a closet in the south room's east end, walled off from the rest ...
    data[10:30, 50:59] = -1  # ... and not seen inside
    grid = OccupancyGrid(data, grid.resolution, grid.origin)
    cmap = inflate(grid, robot_radius=0.15, margin=0.05)
    optimistic = inflate(grid, robot_radius=0.15, margin=0.05, allow_unknown=True)
    goals = [f.goal for f in frontiers(grid, cmap, optimistic) if f.goal is not None]
    assert len(goals) == 2
    closet = next(g for g in goals if g[0] > 2.0)
    doorway = next(g for g in goals if g[0] < 2.0)
    choice, unreachable = choose_frontier(cmap, optimistic, Pose2D(1.5, 1.0, 0.0), goals)
    assert choice == (doorway, True)
    assert [(x, y) for x, y, _ in unreachable] == [closet]
    assert "no path" in unreachable[0][2]
    # from inside the closet, the doorway is the one without a way
    choice, unreachable = choose_frontier(cmap, optimistic, Pose2D(2.5, 0.5, 0.0), goals)
    assert choice is not None and choice[0] == closet and [(x, y) for x, y, _ in unreachable] == [doorway]


def room_with_an_unmarked_wall() -> tuple[OccupancyGrid, np.ndarray]:
    """A 4 m x 3 m room seen whole and walled round, but its east wall (x 3.95-4.0) only seen from
    afar: returns fell there (3 each) and the map does not mark it (its cells unknown)."""
    data = np.zeros((60, 80), dtype=np.int8)
    data[0, :] = data[-1, :] = data[:, 0] = 100
    data[1:-1, -1] = -1
    returns = np.zeros(data.shape, dtype=np.int32)
    returns[data == 100] = 5
    returns[10:50, -1] = 3
    return OccupancyGrid(data, 0.05, Pose2D(0.0, 0.0, 0.0)), returns


def test_a_wall_the_scans_saw_but_the_map_does_not_mark_is_gone_to_within_the_hit_range() -> None:
    grid, returns = room_with_an_unmarked_wall()
    cmap = inflate(grid, robot_radius=0.15, margin=0.05)
    unmarked = unmarked_walls(grid, returns)
    assert unmarked[10:50, -1].all() and unmarked.sum() == 40  # the marked walls are not
    goals = wall_goals(grid, cmap, returns)
    assert len(goals) == 1
    (gx, gy), (cx, cy) = goals[0]
    assert cx == pytest.approx(3.975) and cy == pytest.approx(1.5)
    assert 0.4 <= np.hypot(gx - cx, gy - cy) <= 1.2  # within the hit range
    assert abs(gy - cy) < 0.2  # square on to the wall
    # a wall hidden behind another (no line of sight from anywhere within reach): no goal
    hidden = grid.data.copy()
    hidden[:, 70] = 100
    assert (
        wall_goals(
            OccupancyGrid(hidden, 0.05), inflate(OccupancyGrid(hidden, 0.05), robot_radius=0.15), returns
        )
        == []
    )
    # marked, or a stray return or two: nothing to see
    returns[10:50, -1] = 1
    assert wall_goals(grid, cmap, returns) == []
