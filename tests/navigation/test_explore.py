"""Frontiers of a map being made, and exploring the room until none is left (lockstep)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from omnibot.cli import main
from omnibot.mapping.grid import OccupancyGrid
from omnibot.mapping.planner import inflate
from omnibot.motion import Pose2D
from omnibot.navigation.explore import frontier_goals


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


def test_explore_maps_the_room_by_itself(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out"
    assert (
        main(["map", "--explore", "--world", "room", "--seed", "1", "--duration", "120", "--out", str(out)])
        == 0
    )
    said = capsys.readouterr().out
    assert "explored: no frontier left" in said, said
    report = json.loads((out / "report.json").read_text())
    assert report["map"]["precision"] >= 0.95 and report["map"]["recall"] >= 0.95
    assert report["trajectory"]["estimate"]["ape_rmse_m"] <= 0.03
