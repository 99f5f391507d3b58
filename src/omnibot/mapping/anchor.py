"""The anchor submap: a keyframe's degenerate match completed where the returns seen up close can.

Where a keyframe's match on the sliding submap leaves a direction unconstrained (a corridor's
axis, whose far end wall the submap holds only as a blur of its own distant, noisy views), the
keyframe is matched again (``anchor_reach=None`` turns this off), each return weighed by its own
range noise (``weighted``, :class:`~omnibot.mapping.matcher.ScanMatcher`), against an *anchor*
submap: the returns every keyframe within ``anchor_reach`` of the prediction (12 m by default: an
A1's reach) saw within ``anchor_range`` (sharp: 2 cm at 2 m for an A1). So the end wall seen up
close fixes the axis, as well as its returns from 10 m can (a few centimetres). If that match
converged, fits as well as ``min_fitness`` asks and constrains directions the first left free, it
adds a factor from the anchor submap's oldest keyframe (what was seen first) whose covariance keeps
only those directions: the others stay the first match's, from the previous keyframe, since an old
keyframe's heading would swing them by the lever of the metres between. What stays unconstrained
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

from omnibot.mapping.degeneracy import UNCONSTRAINED_VARIANCE
from omnibot.mapping.icp import MatchResult
from omnibot.mapping.keyframes import Keyframe, KeyframeStore
from omnibot.mapping.se2 import distance, transform
from omnibot.motion import Pose2D

FloatArray = NDArray[np.float64]


class AnchorMatching(KeyframeStore):
    """The SLAM's anchor matches (see the module docstring) on its keyframes and options."""

    search_theta: float
    min_fitness: float
    anchored: int
    """Keyframes whose degenerate match the anchor submap's completed (a factor along what it left free)."""

    def _anchor_match(
        self, frame: Keyframe, predicted: Pose2D, result: MatchResult
    ) -> tuple[int, Pose2D, FloatArray] | None:
        """A degenerate match redone, weighted, on the anchor submap: where it constrains what ``result``
        left free, the keyframe its factor is from (the anchor submap's oldest, which holds what was
        seen first), its pose and a covariance that keeps only those directions (the others are
        ``result``'s, from the previous keyframe: an old keyframe's heading would swing them by the
        lever of the metres between)."""
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
        self.anchored += 1
        return near[0], again.pose, 0.5 * (cov + cov.T)
