"""The cost map: walls inflated by the robot's radius and margin, a cost beyond, straight runs checked."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnibot.mapping.costmap import inflate
from omnibot.motion import Pose2D
from tests.mapping.rooms import RES, box_room, grid_of


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


def test_straight_runs_are_checked_exactly_against_the_cells_they_cross() -> None:
    data = np.zeros((20, 20), dtype=np.int8)
    data[10, 10] = 100  # the cell spanning x and y 0.50-0.55
    cmap = inflate(grid_of(data), robot_radius=1e-6, margin=0.0)
    assert cmap.segment_free((0.545, 0.565), (0.565, 0.545))  # passes 0.7 cm outside the corner (0.55, 0.55)
    assert not cmap.segment_free((0.535, 0.56), (0.56, 0.535))  # clips 0.6 cm of the cell's corner
    assert not cmap.segment_free((0.2, 0.2), (0.9, 0.9))  # through the corner (0.5, 0.5) and the cell
    assert cmap.segment_free((0.2, 0.5), (0.49, 0.9))


def test_clearances_of_many_points_are_their_cells_and_zero_off_the_map() -> None:
    # a turned, shifted map: the points' cells come through its origin
    cmap = inflate(grid_of(box_room(), origin=Pose2D(-1.0, 0.5, 0.4)), robot_radius=0.2)
    pts = np.random.default_rng(3).uniform(-3.0, 5.0, (400, 2))
    cells = [cmap.cell_of(float(x), float(y)) for x, y in pts]
    assert 50 < sum(c is not None for c in cells) < 350  # on the map and off it
    expect = [0.0 if c is None else float(cmap.clearance[c]) for c in cells]
    assert cmap.clearances(pts).tolist() == expect
    assert [cmap.clearance_at(float(x), float(y)) for x, y in pts] == expect
