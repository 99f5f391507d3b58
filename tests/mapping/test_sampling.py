"""OMPL's sampling planners through plan_path: clear paths, the first path waited for, no run in vain."""

from __future__ import annotations

import importlib.util
import time

import numpy as np
import pytest

from omnibot.errors import NoPathError
from omnibot.mapping.costmap import inflate
from omnibot.mapping.planner import plan_path
from omnibot.mapping.sampling import FIRST_PATH_WAIT
from omnibot.motion import Pose2D
from tests.mapping.rooms import box_room, grid_of, samples


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
