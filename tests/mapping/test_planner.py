"""The planner: unknown cells, paths clear of inflated cells and kept off the walls, errors."""

from __future__ import annotations

import math

import numpy as np
import pytest
from benchmarks.planner import free_poses, inside_walls, rasterise

from omnibot.errors import BlockedError, ConfigError, NoPathError, OffMapError, PlanningError
from omnibot.mapping.costmap import MARGIN, inflate
from omnibot.mapping.grid import OccupancyGrid
from omnibot.mapping.planner import plan_path
from omnibot.motion import Pose2D
from omnibot.robot import load_robot
from omnibot.sim import load_world
from tests.mapping.rooms import box_room, grid_of, samples


def test_unknown_cells_are_walls_unless_allowed() -> None:
    data = box_room()
    data[20:40, 30:50] = -1
    strict = inflate(grid_of(data), robot_radius=0.2)
    loose = inflate(grid_of(data), robot_radius=0.2, allow_unknown=True)
    assert strict.blocked[30, 40] and not loose.blocked[30, 40]
    goal = Pose2D(2.0, 1.5, 0.0)  # inside the unknown patch
    with pytest.raises(BlockedError, match=r"goal \(2.00, 1.50\) is in unmapped space"):
        plan_path(grid_of(data), Pose2D(0.5, 0.5, 0.0), goal, robot_radius=0.2)
    path = plan_path(grid_of(data), Pose2D(0.5, 0.5, 0.0), goal, robot_radius=0.2, allow_unknown=True)
    assert np.allclose(path.waypoints[-1], (2.0, 1.5))


def test_a_wall_across_the_room_is_gone_round_and_no_inflated_cell_is_crossed() -> None:
    data = box_room()
    data[:45, 40] = 100  # a wall from the south, leaving a 0.7 m gap in the north
    grid = grid_of(data)
    start, goal = Pose2D(0.5, 0.5, 0.0), Pose2D(3.5, 0.5, math.pi / 2)
    path = plan_path(grid, start, goal, robot_radius=0.2, margin=0.05)
    cmap = inflate(grid, robot_radius=0.2, margin=0.05)
    pts = samples(path.waypoints)
    cells = grid.world_to_cell(pts)
    assert not cmap.blocked[cells[:, 0], cells[:, 1]].any()
    assert pts[:, 1].max() > 2.25  # through the gap
    assert np.allclose(path.waypoints[0], (0.5, 0.5)) and np.allclose(path.waypoints[-1], (3.5, 0.5))
    assert path.theta == goal.theta
    assert path.clearance >= 0.25
    # shortcuts: a handful of straight runs, close to the shortest way round the wall's end
    assert len(path.waypoints) <= 6
    # the shortest way passes the wall's end (2.025, 2.25) at the inflated 0.25 m; the cost keeps
    # the path nearer the gap's middle (y 2.6)
    shortest = math.hypot(2.025 - 0.5, 2.5 - 0.5) + math.hypot(3.5 - 2.025, 2.5 - 0.5)
    assert shortest < path.length < 1.12 * shortest


def test_the_path_keeps_away_from_a_wall_where_there_is_room() -> None:
    grid = grid_of(box_room(6.0, 2.0))
    path = plan_path(grid, Pose2D(0.5, 1.0, 0.0), Pose2D(5.5, 1.0, 0.0), robot_radius=0.2)
    assert len(path.waypoints) == 2  # straight down the middle
    hugging = plan_path(grid, Pose2D(0.5, 0.4, 0.0), Pose2D(5.5, 0.4, 0.0), robot_radius=0.2, weight=3.0)
    # starting and ending 0.35 m from the south wall, it swings out to where the cost is lower
    assert hugging.waypoints[:, 1].max() > 0.5


def test_errors_say_where_and_why() -> None:
    data = box_room()
    data[28:33, 38:43] = 100  # a pillar at about (2.0, 1.5)
    grid = grid_of(data)
    start = Pose2D(0.5, 0.5, 0.0)
    with pytest.raises(OffMapError, match=r"goal \(5.00, 1.00\) is off the map"):
        plan_path(grid, start, Pose2D(5.0, 1.0, 0.0), robot_radius=0.2)
    with pytest.raises(OffMapError, match=r"start \(-1.00, 1.00\) is off the map"):
        plan_path(grid, Pose2D(-1.0, 1.0, 0.0), Pose2D(1.0, 1.0, 0.0), robot_radius=0.2)
    with pytest.raises(BlockedError, match=r"goal \(2.02, 1.52\) is inside a wall or obstacle"):
        plan_path(grid, start, Pose2D(2.02, 1.52, 0.0), robot_radius=0.2)
    with pytest.raises(BlockedError, match=r"goal \(2.00, 1.80\) is too close to a wall: \d+ cm from it"):
        plan_path(grid, start, Pose2D(2.0, 1.8, 0.0), robot_radius=0.2)
    with pytest.raises(ConfigError, match="robot's radius"):
        plan_path(grid, start, Pose2D(1.0, 1.0, 0.0))
    with pytest.raises(ConfigError, match="unknown planner 'astar'"):
        plan_path(grid, start, Pose2D(1.0, 1.0, 0.0), robot_radius=0.2, planner="astar")  # type: ignore[arg-type]
    closed = box_room()
    closed[:, 40] = 100  # the room cut in two
    with pytest.raises(NoPathError, match=r"no path from \(0.50, 0.50\) to \(3.50, 0.50\)"):
        plan_path(grid_of(closed), start, Pose2D(3.5, 0.5, 0.0), robot_radius=0.2)
    assert issubclass(NoPathError, PlanningError)


def test_a_start_in_the_margin_climbs_out_first() -> None:
    grid = grid_of(box_room())
    start = Pose2D(0.28, 1.5, 0.0)  # 0.23 m from the west wall: clear of it, inside its margin
    path = plan_path(grid, start, Pose2D(3.0, 1.5, 0.0), robot_radius=0.2, margin=0.05)
    assert np.allclose(path.waypoints[0], (0.28, 1.5))
    cmap = inflate(grid, robot_radius=0.2, margin=0.05)
    pts = samples(path.waypoints[1:])
    cells = grid.world_to_cell(pts)
    assert not cmap.blocked[cells[:, 0], cells[:, 1]].any()
    with pytest.raises(BlockedError, match=r"start \(0.15, 1.50\) overlaps a wall"):
        plan_path(grid, Pose2D(0.15, 1.5, 0.0), Pose2D(3.0, 1.5, 0.0), robot_radius=0.2)


def test_a_rotated_and_shifted_map_plans_in_the_map_frame() -> None:
    data = box_room()
    data[:45, 40] = 100
    origin = Pose2D(-1.0, 2.0, math.pi / 2)  # the room stands on its side, south-west corner at (-1, 2)
    grid = grid_of(data, origin=origin)

    def to_map(x: float, y: float) -> tuple[float, float]:
        return (origin.x - y, origin.y + x)

    a, b = to_map(0.5, 0.5), to_map(3.5, 0.5)
    path = plan_path(grid, Pose2D(*a, 0.0), Pose2D(*b, 0.0), robot_radius=0.2)
    cmap = inflate(grid, robot_radius=0.2)
    cells = grid.world_to_cell(samples(path.waypoints))
    assert not cmap.blocked[cells[:, 0], cells[:, 1]].any()
    assert np.allclose(path.waypoints[-1], b)


def test_room_world_random_pairs_are_planned_clear_of_the_inflated_walls() -> None:
    world = load_world("room")
    grid = rasterise(world)
    cmap = inflate(grid, robot_radius=0.15)
    poses = free_poses(cmap, 20, seed=3, region=inside_walls(grid, 1.0, 1.0))
    for a, b in zip(poses[::2], poses[1::2], strict=True):
        path = plan_path(cmap, a, b)
        cells = grid.world_to_cell(samples(path.waypoints))
        assert not cmap.blocked[cells[:, 0], cells[:, 1]].any()
        assert path.clearance >= cmap.inflated


@pytest.fixture(scope="module")
def house() -> OccupancyGrid:
    """The house world's own map, made once for the doors' nine cases (the planner only reads it)."""
    return rasterise(load_world("house"))


@pytest.mark.parametrize("preset", ["omni4", "omni3", "mecanum4"])
@pytest.mark.parametrize(
    ("door", "room"), [((1.5, 2.4), (2.0, 5.5)), ((5.0, 5.9), (5.3, 5.5)), ((7.5, 8.4), (8.0, 5.5))]
)
def test_every_house_door_lets_every_preset_through_on_the_worlds_own_map(
    house: OccupancyGrid, preset: str, door: tuple[float, float], room: tuple[float, float]
) -> None:
    # the house's doors are 0.9 m wide (its description): every preset's disc passes each one with
    # the planner's margin (the bedroom's was 0.70 m while the sideboard stood 20 cm into it)
    grid = house
    radius = load_robot(preset).footprint.bounding_radius
    path = plan_path(grid, Pose2D(sum(door) / 2, 3.6, 0.0), Pose2D(*room, 0.0), robot_radius=radius)
    assert path.clearance >= radius + MARGIN
    points = samples(path.waypoints)
    crossing = points[np.abs(points[:, 1] - 4.5) < 0.01]
    assert len(crossing) and (door[0] < crossing[:, 0]).all() and (crossing[:, 0] < door[1]).all()
