"""Small rooms on a 5 cm grid for the planner's tests, and paths sampled densely."""

from __future__ import annotations

import itertools
import math

import numpy as np

from omnibot.mapping.grid import OccupancyGrid
from omnibot.motion import Pose2D

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
