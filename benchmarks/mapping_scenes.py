"""Synthetic scenes for the mapping benchmarks and tests: scans cast in a world, a path, drifting odometry.

Scans come from :meth:`omnibot.sim.world.World.raycast` (exact ranges plus seeded Gaussian noise),
not from the simulated scanner, so the mapping modules are measured on their own.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from omnibot.motion import Pose2D
from omnibot.scan import Scan
from omnibot.sim import World

ROOM_LOOP = ((1.0, 1.0), (2.6, 0.6), (4.4, 0.5), (4.4, 2.0), (3.0, 2.3), (2.2, 3.4), (0.6, 2.0))
"""Waypoints of a loop through the bundled ``room`` clear of its cabinet and bin (m)."""


def cast_scan(
    world: World,
    pose: Pose2D,
    *,
    rays: int = 360,
    range_max: float = 8.0,
    noise: float = 0.01,
    rng: np.random.Generator | None = None,
    stamp: float = 0.0,
) -> Scan:
    """A full-turn scan from a scanner at the robot's centre (``noise``: range sigma, m)."""
    inc = 2.0 * math.pi / rays
    angles = pose.theta + inc * np.arange(rays)
    ranges = world.raycast((pose.x, pose.y), angles, range_max)
    if noise > 0.0 and rng is not None:
        ranges = ranges + rng.normal(0.0, noise, rays)
    return Scan(stamp, 0.0, inc, ranges, 0.05, range_max)


def path_poses(
    waypoints: tuple[tuple[float, float], ...] = ROOM_LOOP, step: float = 0.05, *, closed: bool = True
) -> list[Pose2D]:
    """Poses every ``step`` m along straight legs between ``waypoints``, the heading turning with the path
    plus a slow swing (a holonomic base need not face where it goes)."""
    pts = list(waypoints) + ([waypoints[0]] if closed else [])
    out: list[Pose2D] = []
    s = 0.0
    for (x0, y0), (x1, y1) in itertools.pairwise(pts):
        n = max(1, round(math.hypot(x1 - x0, y1 - y0) / step))
        heading = math.atan2(y1 - y0, x1 - x0)
        for i in range(n):
            t = i / n
            out.append(Pose2D(x0 + t * (x1 - x0), y0 + t * (y1 - y0), heading + 0.5 * math.sin(s)))
            s += step
    return out


def drifting_odometry(truth: list[Pose2D], scale: float = 1.1, heading_drift: float = 0.0) -> list[Pose2D]:
    """Odometry that integrates the true body-frame steps times ``scale`` and adds ``heading_drift``
    rad per metre to each step's turn (10 % drift: ``scale=1.1``)."""
    out = [truth[0]]
    for a, b in itertools.pairwise(truth):
        c, s = math.cos(a.theta), math.sin(a.theta)
        dx, dy = b.x - a.x, b.y - a.y
        bx, by = c * dx + s * dy, -s * dx + c * dy
        dth = b.theta - a.theta + heading_drift * math.hypot(dx, dy)
        o = out[-1]
        co, so = math.cos(o.theta), math.sin(o.theta)
        out.append(
            Pose2D(o.x + scale * (co * bx - so * by), o.y + scale * (so * bx + co * by), o.theta + dth)
        )
    return out
