"""The map of a mapping run: its scans' returns at the SLAM's poses of one instant, and the scanner's noise.

A :class:`MapSnapshot` is cheap to take (in the runtime's thread) and mapped later in another (the
ROS 2 ``map`` publisher's): a return marks its cell only within the scanner's
:attr:`RangeNoise.hit_range`; farther ones clear the cells before them, short of their 3-sigma
uncertainty, and mark nothing. Rays without a return clear nothing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from omnibot.mapping.se2 import transform
from omnibot.motion import Pose2D

if TYPE_CHECKING:
    from omnibot.mapping.grid import OccupancyGrid

P_HIT = 0.6
"""What one hit within the hit range says of its cell (two hits make it occupied at map_server's 0.65)."""
REFLECT = 0.1
"""A cell hit by at least this share of the scans that reached it (and by two) is occupied, whatever
the rays grazing past it say (the mapper's ``reflect``): a thin wall on a cell boundary, which a
doorway's rays run along, stays marked (house, omni4, a 59 m route: recall 65 -> 77 %, precision
98.8 -> 99.1 %; 0.03-0.3 measured, BENCHMARKS.md)."""


@dataclass(frozen=True)
class MapSnapshot:
    """The scans' returns (stamp, points in the base frame, mount x/y) and the SLAM's pose of each
    stamp at one instant; called, it makes the map (see
    :meth:`~omnibot.mapping.session.MappingSink.grid`)."""

    clouds: list[tuple[float, NDArray[np.float32], tuple[float, float]]]
    poses: dict[float, Pose2D]

    def __call__(self, resolution: float = 0.05, noise: RangeNoise | None = None) -> OccupancyGrid:
        """The map of the snapshot's scans (``resolution`` m cells; ``noise`` as in
        :meth:`~omnibot.mapping.session.MappingSink.grid`)."""
        from omnibot.mapping.mapper import OccupancyMapper

        noise = noise or RangeNoise()
        mapper = OccupancyMapper(resolution, max_clear=0.0, p_occ=P_HIT, reflect=REFLECT)
        for stamp, points, mount in self.clouds:
            pose = self.poses.get(stamp)
            if pose is None:
                continue
            rays = points - np.asarray(mount, dtype=np.float32)
            r = np.hypot(rays[:, 0], rays[:, 1])
            near = r <= noise.hit_range
            far_r = r[~near]
            shorter = np.maximum(far_r - 3.0 * noise.sigma(far_r), 0.0) / np.maximum(far_r, 1e-9)
            cleared = np.asarray(mount) + rays[~near] * shorter[:, None]
            origin = transform(pose, [mount])[0]
            short = np.maximum(resolution, 3.0 * noise.sigma(r[near]))
            mapper.add_points(
                (float(origin[0]), float(origin[1])),
                transform(pose, points[near]),
                transform(pose, cleared),
                short=short,
            )
        return mapper.to_grid()

    def returns(self, grid: OccupancyGrid) -> NDArray[np.int32]:
        """How many of the snapshot's returns (at every range, those beyond the hit range too) fall
        in each cell of ``grid`` (a map of the same snapshot): where the scanner saw something, even
        where the map does not mark it (a wall seen only from afar, or edge-on)."""
        placed = [transform(self.poses[t], points) for t, points, _ in self.clouds if t in self.poses]
        rows, cols = grid.shape
        if not placed:
            return np.zeros((rows, cols), dtype=np.int32)
        cells = grid.world_to_cell(np.concatenate(placed))
        cells = cells[grid.inside(cells)]
        flat = np.bincount(cells[:, 0] * cols + cells[:, 1], minlength=rows * cols)
        return flat.reshape(rows, cols).astype(np.int32)


@dataclass(frozen=True)
class RangeNoise:
    """A scanner's range noise, 1 sigma = ``std + fraction * range`` (the robot description's
    ``scanner.noise_std`` and ``noise_fraction``), and the range within which a return marks its cell:
    where sigma is at most ``hit_sigma`` (2 cm: 2.5 sigma inside a 5 cm tolerance), or ``range`` if given."""

    std: float = 0.0
    fraction: float = 0.01
    hit_sigma: float = 0.02
    range: float | None = None

    @classmethod
    def of(cls, robot: Any, range: float | None = None) -> RangeNoise:
        """The noise of ``robot``'s scanner section (the defaults without one)."""
        spec = getattr(robot, "scanner", None)
        if spec is None:
            return cls(range=range)
        return cls(float(spec.noise_std), float(spec.noise_fraction), range=range)

    def sigma(self, r: NDArray[np.floating[Any]]) -> NDArray[np.float64]:
        """Range noise at ranges ``r``, 1 sigma, m."""
        return np.asarray(self.std + self.fraction * np.asarray(r, dtype=np.float64), dtype=np.float64)

    @property
    def hit_range(self) -> float:
        """Returns up to this range mark their cells, m."""
        if self.range is not None:
            return self.range
        if self.fraction <= 0:
            return math.inf if self.std <= self.hit_sigma else 0.0
        return max(0.0, (self.hit_sigma - self.std) / self.fraction)
