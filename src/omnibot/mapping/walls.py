"""Wall-heading factors: a corridor's straight walls hold the map's heading over its whole length.

A degenerate keyframe (its match leaves a corridor's axis free, :mod:`omnibot.mapping.anchor`) is
matched against the last few keyframes, whose headings came the same way: each match's heading
noise (one scan's walls are turned by about 0.05 degree, 1 sigma) adds up along the corridor, and
a heading 0.1 degree off turns a side wall 30 m on by 5 cm (the map's precision at 5 cm). But the
side walls are the same straight lines over many metres: a keyframe's heading is the wall's
direction in the map minus its direction in the keyframe's own returns. So each degenerate keyframe
whose returns hold a long straight wall along the axis (:func:`wall_direction`, a line fitted to
them) gets a heading factor from the *oldest* keyframe that saw a wall of the same direction (the
start's, its standstill's scans joined: the sharpest): the difference of the two fitted directions,
its variance theirs summed, its x and y left free. Its noise is two fits', whatever the distance
between: the heading no longer random-walks. ``wall_heading=False`` turns it off.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from omnibot.mapping.degeneracy import UNCONSTRAINED_VARIANCE
from omnibot.mapping.icp import MatchResult
from omnibot.mapping.keyframes import KeyframeStore
from omnibot.mapping.se2 import between
from omnibot.motion import Pose2D

FloatArray = NDArray[np.float64]

WALL_BAND = 0.15
"""Half-width (m) of the band around a side's median offset whose returns make its wall."""
MIN_RETURNS = 30
"""The fewest returns a wall's line is fitted to."""
MIN_SPAN = 2.0
"""The shortest stretch (m) along the axis a wall's returns must cover."""
SAME_WALL = math.radians(1.0)
"""Largest difference of two walls' map-frame directions that is the same direction."""


def _fit_side(along: FloatArray, across: FloatArray) -> tuple[float, float] | None:
    """Slope of ``across`` on ``along`` (a wall's returns in the axis frame) and its variance; outliers
    beyond 3 sigma (a door's jamb, a corner's other wall) dropped twice. None: too few or too short."""
    if len(along) < MIN_RETURNS:
        return None
    keep = np.abs(across - np.median(across)) <= WALL_BAND
    for _ in range(3):
        u, v = along[keep], across[keep]
        if len(u) < MIN_RETURNS or np.ptp(u) < MIN_SPAN:
            return None
        spread = u - u.mean()
        slope = float(spread @ (v - v.mean()) / (spread @ spread))
        residual = v - v.mean() - slope * spread
        sigma = max(float(np.sqrt(residual @ residual / (len(u) - 2))), 1e-4)
        keep &= np.abs(across - v.mean() - slope * (along - u.mean())) <= max(3.0 * sigma, 0.01)
    return slope, sigma * sigma / float(spread @ spread)


def wall_direction(points: FloatArray, axis: float) -> tuple[float, float] | None:
    """Direction (rad, within 0.1 rad of ``axis``) of the straight walls along ``axis`` in ``points``
    (a keyframe's returns, base frame) and its variance: a line fitted to each side's, the two
    weighed by their variance. None: no side holds a long enough wall."""
    c, s = math.cos(axis), math.sin(axis)
    along = points[:, 0] * c + points[:, 1] * s
    across = -points[:, 0] * s + points[:, 1] * c
    fits = [
        fit for side in (across > 0, across < 0) if (fit := _fit_side(along[side], across[side])) is not None
    ]
    if not fits:
        return None
    weights = np.array([1.0 / var for _, var in fits])
    slope = float(weights @ np.array([slope for slope, _ in fits]) / weights.sum())
    if abs(slope) > 0.1:
        return None
    return axis + math.atan(slope), 1.0 / float(weights.sum())


class WallHeading(KeyframeStore):
    """The SLAM's wall-heading factors (see the module docstring) on its keyframes and graph."""

    wall_heading: bool
    walled: int
    """Keyframes given a wall-heading factor."""
    _walls: dict[int, tuple[float, float] | None]
    """Keyframe -> its wall's direction (base frame) and variance, None if it saw no wall; oldest first."""

    def _wall_factor(self, new: int, result: MatchResult) -> None:
        """Keyframe ``new`` (its degenerate match ``result``) tied in heading to the oldest keyframe
        that saw a wall along the same direction. The first keyframe (the map frame's heading, its
        standstill's scans joined) and the previous one are measured first: the first, where it sees
        the corridor's walls, is the reference of every factor after."""
        free = result.free[:2, 0]
        if not self.wall_heading or np.hypot(free[0], free[1]) < 1e-6:
            return
        axis = math.atan2(free[1], free[0])  # map frame
        for k in sorted({0, new - 1, new}):
            if k not in self._walls:
                pose = result.pose if k == new else self._estimates[k]
                self._walls[k] = wall_direction(self._frames[k].points, axis - pose.theta)
        mine = self._walls[new]
        if mine is None:
            return
        direction = result.pose.theta + mine[0]
        for k, wall in self._walls.items():
            if wall is None or k == new:
                continue
            turn = math.remainder(direction - self._estimates[k].theta - wall[0], math.pi)
            if abs(turn) <= SAME_WALL:
                self._tie_heading(k, new, wall[0] - mine[0], wall[1] + mine[1], result.pose)
                return

    def _tie_heading(self, older: int, new: int, turn: float, variance: float, pose: Pose2D) -> None:
        """A factor from ``older`` to ``new`` (at ``pose``): their headings ``turn`` apart (within a
        half turn of the estimates'), ``variance``; x and y free."""
        relative = between(self._estimates[older], pose)
        theta = relative.theta + math.remainder(turn - relative.theta, math.pi)
        cov = np.diag([UNCONSTRAINED_VARIANCE, UNCONSTRAINED_VARIANCE, variance])
        self._graph.add_match(older, new, Pose2D(relative.x, relative.y, theta), cov)
        self.walled += 1
