"""The occupancy grid: the map type of the SLAM bench, with ROS nav_msgs/OccupancyGrid's conventions.

``data[row, col]`` is the occupancy of the cell whose lower-left corner is at
``origin + (col, row) * resolution`` in the map frame (row 0 is the bottom row, y grows with the
row, as in the ROS message and map_server's files once flipped): -1 unknown, 0 free ... 100
occupied. ``origin`` is the pose of cell (0, 0)'s lower-left corner in the map frame; a rotated
origin (theta != 0) is allowed, as map_server allows it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from omnibot.motion import Pose2D

UNKNOWN = -1
FREE = 0
OCCUPIED = 100


@dataclass(frozen=True)
class OccupancyGrid:
    """A 2D occupancy grid: ``data`` (rows x cols, int8), cell size ``resolution`` (m), ``origin``."""

    data: NDArray[np.int8]
    resolution: float
    origin: Pose2D = field(default_factory=lambda: Pose2D(0.0, 0.0, 0.0))
    frame: str = "map"

    def __post_init__(self) -> None:
        data = np.asarray(self.data)
        if data.ndim != 2 or 0 in data.shape:
            raise ValueError(f"an occupancy grid needs a non-empty 2D array, not shape {data.shape}")
        if not (math.isfinite(self.resolution) and self.resolution > 0):
            raise ValueError(
                f"an occupancy grid's resolution must be a positive length, not {self.resolution}"
            )
        values = data.astype(np.int16)
        if ((values < UNKNOWN) | (values > OCCUPIED)).any():
            raise ValueError("occupancy values must be -1 (unknown) or 0..100")
        object.__setattr__(self, "data", values.astype(np.int8))

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols)."""
        return (int(self.data.shape[0]), int(self.data.shape[1]))

    @property
    def width(self) -> float:
        """Extent along the map's x axis, m."""
        return float(self.data.shape[1] * self.resolution)

    @property
    def height(self) -> float:
        """Extent along the map's y axis, m."""
        return float(self.data.shape[0] * self.resolution)

    def world_to_cell(self, points: ArrayLike) -> NDArray[np.int64]:
        """(n, 2) map-frame points -> (n, 2) integer (row, col) of the cells holding them (may lie outside)."""
        p = np.atleast_2d(np.asarray(points, dtype=np.float64)) - (self.origin.x, self.origin.y)
        c, s = math.cos(self.origin.theta), math.sin(self.origin.theta)
        local = p @ np.array([[c, -s], [s, c]])
        cells: NDArray[np.int64] = np.floor(local / self.resolution).astype(np.int64)[:, ::-1].copy()
        return cells

    def cell_to_world(self, cells: ArrayLike) -> NDArray[np.float64]:
        """(n, 2) (row, col) -> (n, 2) map-frame points at the cells' centres."""
        rc = np.atleast_2d(np.asarray(cells, dtype=np.float64))
        local = (rc[:, ::-1] + 0.5) * self.resolution
        c, s = math.cos(self.origin.theta), math.sin(self.origin.theta)
        world: NDArray[np.float64] = local @ np.array([[c, s], [-s, c]]) + (self.origin.x, self.origin.y)
        return world

    def inside(self, cells: ArrayLike) -> NDArray[np.bool_]:
        """Which (row, col) cells lie on the grid."""
        rc = np.atleast_2d(np.asarray(cells))
        rows, cols = self.shape
        return (rc[:, 0] >= 0) & (rc[:, 0] < rows) & (rc[:, 1] >= 0) & (rc[:, 1] < cols)

    def occupied(self, threshold: int = 65) -> NDArray[np.bool_]:
        """Cells at or above ``threshold`` (map_server's default occupied_thresh is 0.65)."""
        return self.data >= threshold

    def free(self, threshold: int = 25) -> NDArray[np.bool_]:
        """Known cells at or below ``threshold`` (map_server's default free_thresh is 0.25)."""
        return (self.data >= 0) & (self.data <= threshold)
