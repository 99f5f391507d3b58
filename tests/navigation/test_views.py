"""View goals: the surface a map lacks, where the robot can stand, what it sees from there, square on."""

from __future__ import annotations

import math

import numpy as np
import pytest
from benchmarks.mapping_scenes import cast_scan
from scipy import ndimage

from omnibot.mapping import MapSnapshot, OccupancyGrid, RangeNoise, inflate
from omnibot.motion import Pose2D
from omnibot.navigation.frontiers import choose_view, frontiers, wall_goals
from omnibot.navigation.views import (
    INCIDENCE,
    Surface,
    View,
    line_of_sight,
    stands,
    unseen_surface,
    views,
)
from omnibot.sim import parse_world


def room_without_its_east_wall() -> OccupancyGrid:
    """A 4 m x 3 m room seen whole and walled round but its east side: its wall (x 3.95-4.0) never
    marked, the cells there unknown (seen only from afar, or edge-on)."""
    data = np.zeros((60, 80), dtype=np.int8)
    data[0, :] = data[-1, :] = data[:, 0] = 100
    data[1:-1, -1] = -1
    return OccupancyGrid(data, 0.05, Pose2D(0.0, 0.0, 0.0))


def test_the_unseen_surface_is_the_free_spaces_edge_the_map_does_not_mark() -> None:
    grid = room_without_its_east_wall()
    surface = unseen_surface(grid)
    # the east column but its two ends, beside the marked north and south walls
    assert len(surface) == 56
    assert np.allclose(surface.points[:, 0], 3.975)
    assert surface.points[:, 1].min() == pytest.approx(0.125) and surface.points[:, 1].max() == pytest.approx(
        2.875
    )
    assert (surface.normals[:, 0] <= -0.98).all()  # facing the room: west (bent a little by the corners)
    assert np.allclose(surface.normals[5:-5], [-1.0, 0.0], atol=1e-6)
    marked = grid.data.copy()
    marked[1:-1, -1] = 100
    assert len(unseen_surface(OccupancyGrid(marked, 0.05))) == 0  # walled round: nothing lacks


def test_a_surface_less_the_cells_already_looked_at() -> None:
    surface = unseen_surface(room_without_its_east_wall())
    south = surface.without(np.array([[3.975, 0.5], [3.975, 1.0]]), 0.3)
    assert len(south) == 56 - 22  # y 0.225-1.275 m: within 0.3 m of either
    assert ((south.points[:, 1] < 0.2) | (south.points[:, 1] > 1.3)).all()
    assert surface.without(np.zeros((0, 2)), 0.3) is surface


def test_stands_are_where_the_robot_fits_and_can_get_to() -> None:
    data = np.zeros((40, 80), dtype=np.int8)  # 4 m x 2 m, two rooms, a closed wall between
    data[0, :] = data[-1, :] = data[:, 0] = data[:, -1] = data[:, 40] = 100
    grid = OccupancyGrid(data, 0.05)
    cmap = inflate(grid, robot_radius=0.15, margin=0.05)
    west = stands(grid, cmap, (1.0, 1.0))
    assert len(west) > 0 and west[:, 0].max() < 2.0  # only the room it stands in
    assert west[:, 0].min() >= 0.05 + 0.2 and west[:, 1].max() <= 1.95 - 0.2  # clear by radius + margin
    east = stands(grid, cmap, (3.0, 1.0))
    assert east[:, 0].min() > 2.0
    spacing = np.diff(np.unique(west[:, 0]))
    assert np.allclose(spacing, 0.1)  # a 10 cm lattice


def test_the_best_view_sees_the_unmarked_wall_square_on_within_the_hit_range() -> None:
    grid = room_without_its_east_wall()
    cmap = inflate(grid, robot_radius=0.15, margin=0.05)
    places = stands(grid, cmap, (1.0, 1.5))
    found = views(grid, unseen_surface(grid), places, view_range=1.8)
    assert found and found[0].size >= 40
    (x, y), seen = found[0].stand, found[0].seen
    assert 3.975 - x <= 1.8
    assert abs(y - seen[:, 1].mean()) < 0.3  # in front of what it sees
    surface = unseen_surface(grid)
    normals = surface.normals[[int(np.argmin(np.hypot(*(surface.points - p).T))) for p in seen]]
    way = (np.array([x, y]) - seen) / np.hypot(*(np.array([x, y]) - seen).T)[:, None]
    assert (np.einsum("ij,ij->i", way, normals) >= math.cos(INCIDENCE) - 1e-9).all()  # the incidence
    assert all(3.975 - v.stand[0] <= 1.8 for v in found)  # none from beyond the range
    # a stand beside the wall sees it edge-on: nothing within the incidence
    beside = np.array([[3.675, 0.275]])
    near = views(grid, unseen_surface(grid), beside, view_range=1.8, min_cells=1)
    assert near and near[0].seen[:, 1].max() <= 0.275 + (3.975 - 3.675) * math.tan(INCIDENCE) + 1e-9


def test_a_surface_hidden_behind_a_wall_has_no_view() -> None:
    grid = room_without_its_east_wall()
    data = grid.data.copy()
    data[:, 60] = 100  # a wall at x = 3.0 between the robot and the unmarked one
    hidden = OccupancyGrid(data, 0.05)
    cmap = inflate(hidden, robot_radius=0.15, margin=0.05)
    assert views(hidden, unseen_surface(hidden), stands(hidden, cmap, (1.0, 1.5))) == []


def test_a_view_is_chosen_by_what_it_sees_against_the_way_to_it() -> None:
    grid = room_without_its_east_wall()
    cmap = inflate(grid, robot_radius=0.15, margin=0.05)
    here = Pose2D(0.5, 1.5, 0.0)
    near, far = View((1.0, 1.5), np.zeros((10, 2))), View((3.0, 1.5), np.zeros((12, 2)))
    assert choose_view(cmap, here, [far, near]) == (near, False)  # 12 cells 2.5 m away < 10 cells 0.5 m away
    rich = View((3.0, 1.5), np.zeros((40, 2)))
    assert choose_view(cmap, here, [rich, near]) == (rich, False)
    walled = View((3.0, 2.975), np.zeros((40, 2)))  # in the north wall: no way to it
    assert choose_view(cmap, here, [walled]) is None
    assert choose_view(cmap, here, []) is None


def gap_between_two_rooms() -> OccupancyGrid:
    """Two 2 m x 2 m rooms side by side, the wall between them (x 1.95-2.0) open for 0.4 m (y 0.8
    to 1.2): a robot of 15 cm radius passes only without the 5 cm margin."""
    data = np.zeros((40, 80), dtype=np.int8)
    data[0, :] = data[-1, :] = data[:, 0] = data[:, -1] = data[:, 39] = 100
    data[16:24, 39] = 0
    return OccupancyGrid(data, 0.05)


def test_a_view_beyond_a_gap_narrower_than_the_margin_is_gone_to_by_a_tight_way() -> None:
    grid = gap_between_two_rooms()
    cmap = inflate(grid, robot_radius=0.15, margin=0.05)
    tight = inflate(grid, robot_radius=0.15, margin=0.0)
    here = Pose2D(3.0, 1.0, 0.0)  # in the east room: a way planned before the map filled in led here
    assert stands(grid, cmap, (here.x, here.y))[:, 0].min() > 2.0  # by the margin, the east room only
    both = stands(grid, cmap, (here.x, here.y), way=tight)
    assert both[:, 0].min() < 2.0 and both[:, 0].max() > 2.0  # by the radius alone, both rooms
    cells = grid.world_to_cell(both)
    assert not cmap.blocked[cells[:, 0], cells[:, 1]].any()  # the stands themselves keep the margin
    west = View((1.0, 1.0), np.zeros((10, 2)))
    assert choose_view(cmap, here, [west]) is None
    assert choose_view(cmap, here, [west], tight=tight) == (west, True)
    east = View((3.5, 1.0), np.zeros((10, 2)))
    assert choose_view(cmap, here, [west, east], tight=tight) == (east, False)


def test_line_of_sight_stops_at_walls_and_short_of_its_end() -> None:
    grid = room_without_its_east_wall()
    data = grid.data.copy()
    data[:30, 40] = 100  # a wall at x = 2.0 across the south half
    clear = OccupancyGrid(data, 0.05).free(49)
    starts = np.array([[1.0, 2.5], [1.0, 0.5]])
    ends = np.array([[3.975, 2.5], [3.975, 0.5]])  # unknown east cells, past the wall's end; behind it
    assert line_of_sight(grid, clear, starts, ends, stop=0.075).tolist() == [True, False]
    assert line_of_sight(grid, clear, starts, ends, stop=0.0).tolist() == [False, False]
    assert line_of_sight(grid, clear, np.zeros((0, 2)), ends[0], stop=0.0).tolist() == []


def test_an_empty_surface_or_no_stand_has_no_view() -> None:
    grid = room_without_its_east_wall()
    empty = Surface(np.zeros((0, 2)), np.zeros((0, 2)))
    assert views(grid, empty, np.array([[1.0, 1.0]])) == []
    assert views(grid, unseen_surface(grid), np.zeros((0, 2))) == []


def test_returns_the_map_does_not_mark_are_surface_where_they_edge_the_free_space() -> None:
    data = np.zeros((60, 81), dtype=np.int8)  # the room, its east wall's cells (column 79) free ...
    data[0, :80] = data[-1, :80] = data[:, 0] = 100
    data[:, 80] = -1  # ... and unknown beyond
    cleared = OccupancyGrid(data, 0.05)
    returns = np.zeros(cleared.shape, dtype=np.int32)
    returns[10:50, 79] = 3  # a few returns fell on it, edge-on: the rays grazing along it cleared it
    returns[30, 30] = 5  # a stray in the open
    beyond = unseen_surface(cleared)
    assert len(beyond) == 58 and np.allclose(beyond.points[:, 0], 4.025)  # the unknown beyond only
    surface = unseen_surface(cleared, returns)
    assert len(surface) == 58 + 40
    assert np.isclose(surface.points[:, 0], 3.975).sum() == 40  # the returns' cells, not the stray's
    assert (surface.normals[:, 0] < -0.9).all()


GRAZED = parse_world(
    {
        "name": "grazed",
        "walls": [{"shape": "rectangle", "min": [-2.4, 1.0], "max": [1.3, 2.6]}],
        "obstacles": [{"shape": "box", "center": [0.65, 2.3], "size": [1.3, 0.6]}],
    },
    "grazed",
)
"""A 3.7 m x 1.6 m room with a cabinet against its north wall, its south face (y 2.0, x 0-1.3)
in line with the way the robot came: seen only edge-on."""


def test_a_face_seen_only_edge_on_is_marked_once_its_view_goal_is_taken() -> None:
    rng = np.random.default_rng(1)
    clouds: list[tuple[float, np.ndarray, tuple[float, float]]] = []
    poses: dict[float, Pose2D] = {}

    def scan_at(pose: Pose2D, revolutions: int = 1) -> None:
        for _ in range(revolutions):
            stamp = float(len(clouds))
            clouds.append(
                (stamp, cast_scan(GRAZED, pose, rng=rng).points("base").astype(np.float32), (0.0, 0.0))
            )
            poses[stamp] = pose

    def mapped() -> tuple[OccupancyGrid, np.ndarray, int]:
        snapshot = MapSnapshot(list(clouds), dict(poses))
        grid = snapshot(0.05, RangeNoise())
        face = grid.world_to_cell([(x, 2.0) for x in np.arange(0.025, 1.3, 0.05)])  # its cells (26)
        marked = ndimage.binary_dilation(grid.occupied(65), structure=ndimage.generate_binary_structure(2, 1))
        return grid, snapshot.returns(grid), int((~marked[face[:, 0], face[:, 1]]).sum())

    for x in np.arange(-2.0, -0.3, 0.04):  # along the face's line, 15 cm off it
        scan_at(Pose2D(float(x), 1.85, 0.0))
    here = Pose2D(-0.34, 1.85, 0.0)
    grid, returns, unmarked = mapped()
    cmap = inflate(grid, robot_radius=0.15, margin=0.05)
    optimistic = inflate(grid, robot_radius=0.15, margin=0.05, allow_unknown=True)
    # before: no frontier and no unmarked wall left to go to (exploring ended there), the face not whole
    assert [f for f in frontiers(grid, cmap, optimistic) if f.goal is not None] == []
    assert wall_goals(grid, cmap, returns) == []
    assert unmarked >= 5
    found = views(grid, unseen_surface(grid, returns), stands(grid, cmap, (here.x, here.y)))
    chosen = choose_view(cmap, here, found)
    assert chosen is not None and not chosen[1]
    x, y = chosen[0].stand
    assert y < 2.0 - 0.2 and 0.0 - 0.5 < x < 1.3  # before the face, not in line with it
    scan_at(Pose2D(x, y, 0.0), revolutions=10)  # the dwell
    grid, returns, unmarked = mapped()
    assert unmarked == 0  # after: the whole face marked
    cmap = inflate(grid, robot_radius=0.15, margin=0.05)
    assert views(grid, unseen_surface(grid, returns), stands(grid, cmap, (x, y))) == []  # nothing left
