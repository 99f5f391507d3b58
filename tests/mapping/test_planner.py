"""The planner: inflation, unknown cells, paths clear of inflated cells, errors, OMPL's planners."""

from __future__ import annotations

import importlib.util
import itertools
import math
import time

import numpy as np
import pytest
from benchmarks.planner import free_poses, inside_walls, rasterise

from omnibot.errors import BlockedError, ConfigError, NoPathError, OffMapError, PlanningError
from omnibot.mapping.grid import OccupancyGrid
from omnibot.mapping.planner import FIRST_PATH_WAIT, MARGIN, check_start, distance_squared, inflate, plan_path
from omnibot.motion import Pose2D
from omnibot.robot import load_robot
from omnibot.sim import load_world

RES = 0.05


def box_room(width: float = 4.0, height: float = 3.0, res: float = RES) -> np.ndarray:
    """A closed room: a one-cell wall all round."""
    rows, cols = round(height / res), round(width / res)
    data = np.zeros((rows, cols), dtype=np.int8)
    data[0, :] = data[-1, :] = data[:, 0] = data[:, -1] = 100
    return data


def grid_of(data: np.ndarray, res: float = RES, origin: Pose2D | None = None) -> OccupancyGrid:
    return OccupancyGrid(data, res, origin or Pose2D(0.0, 0.0, 0.0))


def samples(points: np.ndarray, step: float = 0.01) -> np.ndarray:
    """Points every ``step`` m along the polyline."""
    out = [points[:1]]
    for a, b in itertools.pairwise(points):
        n = max(1, math.ceil(float(np.hypot(*(b - a))) / step))
        out.append(a + (b - a) * (np.arange(1, n + 1)[:, None] / n))
    return np.vstack(out)


def test_distance_transform_is_exact() -> None:
    walls = np.zeros((30, 40), dtype=bool)
    walls[[3, 17, 25], [5, 30, 12]] = True
    got = distance_squared(walls)
    r, c = np.mgrid[0:30, 0:40]
    want = np.min([(r - a) ** 2 + (c - b) ** 2 for a, b in zip(*np.nonzero(walls), strict=True)], axis=0)
    assert np.array_equal(got, want)


def test_inflation_blocks_radius_plus_margin_from_a_wall() -> None:
    cmap = inflate(grid_of(box_room()), robot_radius=0.2, margin=0.05)
    # row 30 (y = 1.525) along x: the west wall's cell 0 ends at x = 0.05
    row = 30
    x = (np.arange(cmap.grid.shape[1]) + 0.5) * RES
    clearance = x - 0.05
    expect = clearance < 0.25
    interior = slice(1, 28)  # nearer the west wall than any other
    assert np.array_equal(cmap.blocked[row, interior], expect[interior])
    assert np.allclose(cmap.clearance[row, interior], clearance[interior])
    # the cost is highest at the inflated edge and falls away from it
    free = cmap.cost[row, interior][~expect[interior]]
    assert free[0] == pytest.approx(math.exp(-6.0 * (clearance[interior][~expect[interior]][0] - 0.25)))
    assert np.all(np.diff(free[free > 0]) < 0)


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


@pytest.mark.skipif(importlib.util.find_spec("ompl") is None, reason="OMPL's Python bindings not installed")
@pytest.mark.parametrize("planner", ["rrtstar", "prmstar", "bitstar"])
def test_ompl_planners_give_clear_paths(planner: str) -> None:
    data = box_room()
    data[:30, 40] = 100  # a wall half across: sampling planners find wide gaps within their time
    grid = grid_of(data)
    cmap = inflate(grid, robot_radius=0.2)
    path = plan_path(cmap, Pose2D(0.5, 0.5, 0.0), Pose2D(3.5, 0.5, 0.0), planner=planner, time_limit=0.2)  # type: ignore[arg-type]
    cells = grid.world_to_cell(samples(path.waypoints))
    assert not cmap.blocked[cells[:, 0], cells[:, 1]].any()
    assert path.planner == planner
    assert np.allclose(path.waypoints[-1], (3.5, 0.5))


@pytest.mark.skipif(importlib.util.find_spec("ompl") is None, reason="OMPL's Python bindings not installed")
@pytest.mark.parametrize("planner", ["rrtstar", "prmstar", "bitstar"])
def test_an_ompl_planner_short_of_time_still_gives_the_path_there_is(planner: str) -> None:
    """The time limit is for improving a path: one too short to find the first (here 0.1 ms, as a
    loaded machine makes 0.2 s) waits for it rather than refuse a plan that exists."""
    data = box_room()
    data[:30, 40] = 100
    cmap = inflate(grid_of(data), robot_radius=0.2)
    path = plan_path(cmap, Pose2D(0.5, 0.5, 0.0), Pose2D(3.5, 0.5, 0.0), planner=planner, time_limit=1e-4)  # type: ignore[arg-type]
    cells = cmap.grid.world_to_cell(samples(path.waypoints))
    assert not cmap.blocked[cells[:, 0], cells[:, 1]].any()
    assert np.allclose(path.waypoints[-1], (3.5, 0.5))


@pytest.mark.skipif(importlib.util.find_spec("ompl") is None, reason="OMPL's Python bindings not installed")
def test_an_ompl_planner_is_not_run_where_no_path_exists() -> None:
    """The grid planner says first whether the goal can be reached: a room cut in two is refused at
    once with its reason, not after the sampling planner's whole wait."""
    closed = box_room()
    closed[:, 40] = 100
    start = time.perf_counter()
    with pytest.raises(NoPathError, match=r"no path from \(0.50, 0.50\) to \(3.50, 0.50\): "):
        plan_path(
            grid_of(closed), Pose2D(0.5, 0.5, 0.0), Pose2D(3.5, 0.5, 0.0), robot_radius=0.2, planner="rrtstar"
        )
    assert time.perf_counter() - start < FIRST_PATH_WAIT


def test_straight_runs_are_checked_exactly_against_the_cells_they_cross() -> None:
    data = np.zeros((20, 20), dtype=np.int8)
    data[10, 10] = 100  # the cell spanning x and y 0.50-0.55
    cmap = inflate(grid_of(data), robot_radius=1e-6, margin=0.0)
    assert cmap.segment_free((0.545, 0.565), (0.565, 0.545))  # passes 0.7 cm outside the corner (0.55, 0.55)
    assert not cmap.segment_free((0.535, 0.56), (0.56, 0.535))  # clips 0.6 cm of the cell's corner
    assert not cmap.segment_free((0.2, 0.2), (0.9, 0.9))  # through the corner (0.5, 0.5) and the cell
    assert cmap.segment_free((0.2, 0.5), (0.49, 0.9))
