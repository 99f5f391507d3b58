"""The anchor submap: a keyframe's degenerate match completed where the returns seen up close can.

Where a keyframe's match on the sliding submap leaves a direction unconstrained (a corridor's
axis, whose far end wall the submap holds only as a blur of its own distant, noisy views), the
keyframe is matched again (``anchor_reach=None`` turns this off), each return weighed by its own
range noise (``weighted``, :class:`~omnibot.mapping.matcher.ScanMatcher`), against an *anchor*
submap: the returns every keyframe within ``anchor_reach`` of the prediction (12 m by default: an
A1's reach) saw within ``anchor_range`` (sharp: 2 cm at 2 m for an A1). So the end wall seen up
close fixes the axis, as well as its returns from 10 m can (a few centimetres). If that match
converged, fits as well as ``min_fitness`` asks and constrains directions the first left free, it
adds a factor whose covariance keeps only those directions (the others stay the first match's, from
the previous keyframe, since an old keyframe's heading would swing them by the lever of the metres
between), from the keyframe that holds what fixed them: the oldest that came within
``anchor_range`` of the walls across them (the end wall's first close view). A factor is a relative
pose: from a keyframe whose own returns did not fix the axis (the anchor submap's oldest on the
way back from the far end, a keyframe of the blind stretch 12 m from the wall) it ties that keyframe
to where the wall's keyframes stood at that moment, and every later correction of theirs drags it
and the stretch between along the axis (the bench's mecanum4 seed 2: the far end 2.5 cm further off
after the return than on the way out). :attr:`AnchorMatching.anchors` keeps each factor's two
keyframes. What stays unconstrained
is the odometry's alone: the match keeps the prediction there and its covariance leaves it free
(Zhang et al.'s solution remapping, the information matrix as the factor's weight). A direction no
return constrains at all (mid-corridor, no end wall in range) cannot be recovered by any scan
matching: there the SLAM is the odometry. The anchor match takes the axis from the returns aligned
with it alone (the end wall's; the matcher's weighted match): with the side walls' pull in it, it
had biased omni3's corridor by centimetres (docs/mapping.md).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from omnibot.mapping.degeneracy import ALIGNED, UNCONSTRAINED_VARIANCE
from omnibot.mapping.icp import MatchResult
from omnibot.mapping.keyframes import Keyframe, KeyframeStore
from omnibot.mapping.se2 import distance, transform
from omnibot.mapping.target import Target
from omnibot.motion import Pose2D

FloatArray = NDArray[np.float64]


class AnchorMatching(KeyframeStore):
    """The SLAM's anchor matches (see the module docstring) on its keyframes and options."""

    search_theta: float
    min_fitness: float
    anchored: int
    """Keyframes whose degenerate match the anchor submap's completed (a factor along what it left free)."""
    anchors: list[tuple[int, int]]
    """(from, to) keyframes of every anchor factor, in order."""

    def _anchor_match(
        self, frame: Keyframe, predicted: Pose2D, result: MatchResult
    ) -> tuple[int, Pose2D, FloatArray] | None:
        """A degenerate match redone, weighted, on the anchor submap: where it constrains what ``result``
        left free, the keyframe its factor is from (:meth:`_anchor_reference`), its pose and a
        covariance that keeps only those directions (the others are ``result``'s, from the previous
        keyframe: an old keyframe's heading would swing them by the lever of the metres between)."""
        reach = self.anchor_reach if self.anchor_reach is not None else math.inf
        near = [k for k in range(len(self._estimates)) if distance(self._estimates[k], predicted) <= reach]
        pts = [transform(self._estimates[k], self._frames[k].anchor) for k in near]
        if not pts:
            return None
        target = self.matcher.target(np.vstack(pts), margin=self.search_xy + 1.0)
        again = self.matcher.match(
            frame.points,
            target,
            predicted,
            search_xy=self.search_xy,
            search_theta=self.search_theta,
            weighted=True,
            range_max=frame.scan.range_max,
        )
        if not (
            again.converged
            and again.fitness >= self.min_fitness
            and again.unconstrained < result.unconstrained
        ):
            return None
        free, _ = np.linalg.qr(result.free)
        cov = free @ (free.T @ again.covariance @ free) @ free.T
        cov += UNCONSTRAINED_VARIANCE * (np.eye(3) - free @ free.T)
        reference = self._anchor_reference(near, target, free)
        self.anchored += 1
        self.anchors.append((reference, len(self._estimates)))
        return reference, again.pose, 0.5 * (cov + cov.T)

    def _anchor_reference(self, near: list[int], target: Target, free: FloatArray) -> int:
        """Of the keyframes ``near`` (oldest first) whose anchor points make ``target``, the oldest that
        came within ``anchor_range`` of its lines across the first ``free`` direction (those that fix
        it: an end wall); the oldest of all if none did (a free turn, no such line)."""
        across = free[:2, 0]
        length = float(np.hypot(across[0], across[1]))
        if length < 1e-6:
            return near[0]
        wall = target.lines & (np.abs(target.normals @ (across / length)) >= ALIGNED)
        if not wall.any():
            return near[0]
        where = np.array([(self._estimates[k].x, self._estimates[k].y) for k in near])
        gap, _ = cKDTree(target.points[wall]).query(where)
        close = np.flatnonzero(gap <= self.anchor_range)
        return near[int(close[0])] if len(close) else near[0]
