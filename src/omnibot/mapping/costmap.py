"""A grid made ready for planning a disc robot: its walls inflated, a cost that keeps it off them.

::

    OccupancyGrid --inflate()--> CostMap: clearance (m, exact distance transform), blocked cells
        (clearance < robot radius + margin; unknown cells count as walls unless allowed), and a
        cost that decays away from the walls (nav2's inflation layer: exp(-decay (d - r)))

The robot is a disc (its footprint's bounding radius), so any heading fits wherever its centre
may go. The clearance is measured from a cell's centre to the nearest wall cell's edge; a centre
anywhere in the cell may be up to ``resolution / sqrt(2)`` closer, which the margin covers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from omnibot.errors import ConfigError
from omnibot.mapping.cellwalk import line_max
from omnibot.mapping.distance import distance_squared
from omnibot.mapping.grid import OccupancyGrid

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

MARGIN = 0.05
"""m kept free beyond the robot's radius (tracking error, odometry drift, the grid's cells)."""
COST_DECAY = 6.0
"""1/m: how fast the wall cost falls beyond the inflated radius (nav2's cost_scaling_factor)."""
COST_RANGE = 0.6
"""m beyond the inflated radius where the cost ends (nav2's inflation_radius less the robot's)."""
OCCUPIED = 65
"""Occupancy at or above which a cell is a wall (map_server's occupied_thresh 0.65)."""


@dataclass(frozen=True)
class CostMap:
    """A grid made ready for planning a robot of ``robot_radius`` with ``margin`` (see the module)."""

    grid: OccupancyGrid
    robot_radius: float
    margin: float
    allow_unknown: bool
    clearance: FloatArray
    """m from each cell's centre to the nearest wall cell's edge (unknown cells are walls unless
    allowed; 0 on a wall)."""
    blocked: BoolArray
    """Cells the robot's centre may not be in: clearance < radius + margin."""
    cost: FloatArray
    """0..1: 1 at the inflated radius, decaying to 0 ``COST_RANGE`` beyond it (0 on blocked cells)."""

    @property
    def inflated(self) -> float:
        """The radius the walls are inflated by, m (robot radius + margin)."""
        return self.robot_radius + self.margin

    def cell_of(self, x: float, y: float) -> tuple[int, int] | None:
        """(row, col) of the cell holding map point (x, y); None off the map."""
        rc = self.grid.world_to_cell([(x, y)])
        if not bool(self.grid.inside(rc)[0]):
            return None
        return int(rc[0, 0]), int(rc[0, 1])

    def clearance_at(self, x: float, y: float) -> float:
        """The clearance of the cell holding (x, y), m (0 off the map)."""
        return float(self.clearances([(x, y)])[0])

    def clearances(self, points: ArrayLike) -> FloatArray:
        """The clearance of the cells holding (n, 2) map points, m (0 off the map)."""
        rc = self.grid.world_to_cell(points)
        inside = self.grid.inside(rc)
        out = np.zeros(len(rc))
        out[inside] = self.clearance[rc[inside, 0], rc[inside, 1]]
        return out

    def segment_free(self, a: tuple[float, float], b: tuple[float, float]) -> bool:
        """True when the straight run from ``a`` to ``b`` (map frame) crosses no blocked cell."""
        fa, fb = self.local(a), self.local(b)
        return line_max(np.where(self.blocked, np.inf, 0.0), fa[0], fa[1], fb[0], fb[1]) < 0.5

    def local(self, p: tuple[float, float]) -> tuple[float, float]:
        """(row, col) as floats (cell units, cell centres at +0.5) of a map point."""
        o = self.grid.origin
        dx, dy = p[0] - o.x, p[1] - o.y
        c, s = math.cos(o.theta), math.sin(o.theta)
        res = self.grid.resolution
        return ((-s * dx + c * dy) / res, (c * dx + s * dy) / res)


def inflate(
    grid: OccupancyGrid,
    *,
    robot_radius: float,
    margin: float = MARGIN,
    allow_unknown: bool = False,
    occupied: int = OCCUPIED,
    decay: float = COST_DECAY,
    cost_range: float = COST_RANGE,
) -> CostMap:
    """The grid's walls inflated by ``robot_radius + margin`` with a cost beyond (see the module)."""
    if not (math.isfinite(robot_radius) and robot_radius > 0):
        raise ConfigError(f"the robot radius must be a positive length, not {robot_radius}")
    if not (math.isfinite(margin) and margin >= 0):
        raise ConfigError(f"the safety margin must be a length >= 0, not {margin}")
    walls = grid.data >= occupied
    if not allow_unknown:
        walls = walls | (grid.data < 0)
    res = grid.resolution
    if walls.any():
        dist = np.sqrt(distance_squared(walls)) * res
        clearance = np.maximum(dist - 0.5 * res, 0.0)
        clearance[walls] = 0.0
    else:
        clearance = np.full(grid.shape, math.inf)
    inflated = robot_radius + margin
    blocked = clearance < inflated
    beyond = clearance - inflated
    cost = np.where(blocked | (beyond > cost_range), 0.0, np.exp(-decay * np.clip(beyond, 0.0, None)))
    return CostMap(grid, robot_radius, margin, allow_unknown, clearance, blocked, cost)
