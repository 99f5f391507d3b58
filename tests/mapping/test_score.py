"""Map scores against the world: a perfect map, a map with false and missing walls, observability."""

from __future__ import annotations

import numpy as np
import pytest
from benchmarks.mapping_scenes import cast_scan, path_poses

from omnibot.mapping.grid import OccupancyGrid
from omnibot.mapping.mapper import build_map
from omnibot.mapping.score import rasterise, score_map
from omnibot.motion import Pose2D
from omnibot.sim import load_world, parse_world

BOX = parse_world(
    {"name": "box", "walls": [{"shape": "rectangle", "min": [0.0, 0.0], "max": [1.0, 1.0]}]}, "box"
)


def box_grid(fill: int) -> OccupancyGrid:
    """A 0.1 m grid over [-0.5, 1.5]^2 with every cell ``fill``."""
    return OccupancyGrid(np.full((20, 20), fill, np.int8), 0.1, Pose2D(-0.5, -0.5, 0.0))


def test_rasterise_marks_the_cells_edges_pass_through() -> None:
    g = box_grid(-1)
    truth = rasterise(BOX, g)
    # the wall x = 0 lies on the boundary between columns 4 and 5; sampled points at x = 0 fall in 5
    assert truth[5:16, 5].all() and truth[5, 5:16].all()
    assert truth[5:16, 15].all() and truth[15, 5:16].all()
    assert truth.sum() == 4 * 11 - 4  # 11 cells a side, corners shared
    assert not truth[8, 8]


def test_a_map_of_exactly_the_truth_scores_one_and_one() -> None:
    g = box_grid(0)
    truth = rasterise(BOX, g)
    data = np.where(truth, 100, 0).astype(np.int8)
    s = score_map(OccupancyGrid(data, 0.1, g.origin), BOX, tolerance=0.1)
    assert (s.precision, s.recall, s.occupied, s.observable, s.true_cells) == (1.0, 1.0, 40, 40, 40)
    assert s.f1 == 1.0


def test_false_walls_lower_precision_and_missing_walls_lower_recall() -> None:
    g = box_grid(0)
    truth = rasterise(BOX, g)
    data = np.where(truth, 100, 0).astype(np.int8)
    data[10, 10] = 100  # a phantom obstacle in the middle: 1 of 36 occupied cells is wrong
    data[5, 7:12] = 0  # 5 cells of the bottom wall missing
    s = score_map(OccupancyGrid(data, 0.1, g.origin), BOX, tolerance=0.1)
    assert s.occupied == 36
    assert s.precision == pytest.approx(35 / 36)
    # with a one-cell tolerance the cells at each end of the gap still have an occupied neighbour
    assert s.recall == pytest.approx((40 - 3) / 40)


def test_walls_the_robot_never_saw_do_not_count_against_recall() -> None:
    g = box_grid(-1)
    truth = rasterise(BOX, g)
    data = np.full(g.shape, -1, np.int8)
    data[6:9, 7:14] = 0  # free space seen next to the bottom wall only (its cells 7..13)
    data[5, 5:16] = 100  # the bottom wall, mapped
    s = score_map(OccupancyGrid(data, 0.1, g.origin), BOX, tolerance=0.1, seen=0.1)
    assert (s.observable, s.true_cells, s.recall, s.precision) == (7, truth.sum(), 1.0, 1.0)
    s_far = score_map(OccupancyGrid(data, 0.1, g.origin), BOX, tolerance=0.1, seen=0.5)
    assert s_far.observable > s.observable and s_far.recall < 1.0


def test_a_mapped_room_scores_high_and_a_shifted_one_low() -> None:
    world = load_world("room")
    rng = np.random.default_rng(4)
    poses = path_poses()[::3]
    scans = [cast_scan(world, p, rng=rng) for p in poses]
    good = score_map(build_map(list(zip(scans, poses, strict=True))), world)
    assert good.precision > 0.95 and good.recall > 0.95
    shifted = [Pose2D(p.x + 0.12, p.y, p.theta) for p in poses]
    bad = score_map(build_map(list(zip(scans, shifted, strict=True))), world)
    assert bad.precision < 0.8


def test_negative_tolerance_is_refused() -> None:
    with pytest.raises(ValueError, match="tolerance"):
        score_map(box_grid(0), BOX, tolerance=-0.1)
