"""The walls of a grid as local lines: a band's middle, below a cell; corners and posts as points."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnibot.mapping.grid import OccupancyGrid
from omnibot.mapping.surface import SurfaceField, faces, window_moments
from omnibot.motion import Pose2D

RES = 0.1


def grid_with(rows: slice | int, cols: slice | int, origin: Pose2D | None = None) -> OccupancyGrid:
    data = np.zeros((30, 30), np.int8)
    data[rows, cols] = 100
    return OccupancyGrid(data, RES, origin or Pose2D(0.0, 0.0, 0.0))


def at(field: SurfaceField, x: float, y: float) -> tuple[float, float, float, bool]:
    r, gx, gy, ok = field.residuals(np.array([x]), np.array([y]))
    return float(r[0]), float(gx[0]), float(gy[0]), bool(ok[0])


@pytest.mark.parametrize("offset", [-0.03, 0.0, 0.04, 0.3])
def test_a_band_two_cells_thick_is_matched_to_its_middle_not_to_its_cells(offset: float) -> None:
    field = SurfaceField(grid_with(slice(10, 12), slice(None)))  # rows 10, 11: y from 1.0 to 1.2
    r, gx, gy, ok = at(field, 1.53, 1.1 + offset)  # 1.1: the band's middle, between the cells' centres
    assert ok and gx == pytest.approx(0.0, abs=1e-12) and abs(gy) == pytest.approx(1.0)
    assert r * gy == pytest.approx(offset, abs=1e-12)  # signed along the normal, its gradient


def test_a_band_one_cell_thick_is_the_line_through_its_centres() -> None:
    field = SurfaceField(grid_with(slice(None), 7))  # column 7: x from 0.7 to 0.8
    for y in (0.52, 1.5, 2.03):
        r, gx, _, ok = at(field, 0.75 + 0.02, y)
        assert ok and r * gx == pytest.approx(0.02, abs=1e-12)


def test_a_rotated_origin_turns_the_lines_with_it() -> None:
    turn = math.radians(30)
    field = SurfaceField(grid_with(slice(10, 12), slice(None), Pose2D(1.0, -2.0, turn)))
    # the band's middle is 1.1 m along the grid's y from its origin; 0.05 m beyond it, 1.7 m along
    along, across = 1.7, 1.15
    x = 1.0 + along * math.cos(turn) - across * math.sin(turn)
    y = -2.0 + along * math.sin(turn) + across * math.cos(turn)
    r, gx, gy, ok = at(field, x, y)
    assert ok and r * np.array([gx, gy]) == pytest.approx(0.05 * np.array([-math.sin(turn), math.cos(turn)]))


def test_a_corner_and_a_post_are_points() -> None:
    data = np.zeros((30, 30), np.int8)
    data[5, 5:15] = 100
    data[5:15, 5] = 100  # an L with its corner at cell (5, 5)
    data[20, 20] = 100  # a post
    field = SurfaceField(OccupancyGrid(data, RES))
    assert not field.line[5, 5] and not field.line[20, 20] and field.line[5, 10] and field.line[10, 5]
    r, gx, gy, ok = at(field, 2.05 + 0.03, 2.05 + 0.04)  # from the post's centre
    assert ok and r == pytest.approx(0.05) and (gx, gy) == pytest.approx((0.6, 0.8))


def test_nothing_within_reach_or_off_the_map_has_no_residual() -> None:
    field = SurfaceField(grid_with(0, slice(None)), max_dist=1.0)
    _, _, _, ok = field.residuals(np.array([1.0, 1.0, -0.5, 1.0]), np.array([0.5, 1.5, 0.05, 3.5]))
    assert ok.tolist() == [True, False, False, False]
    with pytest.raises(ValueError, match="no occupied cell"):
        SurfaceField(OccupancyGrid(np.zeros((3, 3), np.int8), RES))


def test_faces_are_the_occupied_cells_beside_one_that_is_not() -> None:
    block = np.zeros((9, 9), bool)
    block[2:7, 2:7] = True
    ring = faces(block)
    assert ring.sum() == 16 and not ring[3:6, 3:6].any() and ring[2, 2:7].all()


def test_window_moments_are_the_cells_count_mean_and_spread_around_each() -> None:
    cells = np.zeros((7, 7), bool)
    cells[3, 1:6] = True  # five in a row
    count, mean, cov = window_moments(cells, 2)
    assert count[3, 3] == 5 and mean[3, 3] == pytest.approx((0.0, 0.0))
    assert cov[3, 3] == pytest.approx(np.array([[2.0, 0.0], [0.0, 0.0]]))  # offsets -2..2 along x
    assert count[3, 1] == 3 and mean[3, 1] == pytest.approx((1.0, 0.0))
