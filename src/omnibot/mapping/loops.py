"""The SLAM's loop closures: tried every few keyframes, verified, added through a robust kernel.

Every ``loop_every`` keyframes, the keyframe at least ``loop_min_separation`` keyframes back
nearest the new one, within ``loop_search_radius``, is matched with a wide search
(``loop_search_window``) on the submap around it; the match is kept only if it converged with a
fitness of at least ``loop_min_fitness``, and enters the graph through a Cauchy robust kernel with
its covariance floored at ``loop_sigma_floor`` (so one false closure that passed the checks is
down-weighted, not obeyed). A closure of one's own (a place recogniser's) is added with
:meth:`LoopClosing.add_loop_closure`, or matched and verified with
:meth:`LoopClosing.try_loop_closure`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from omnibot.errors import ConfigError
from omnibot.mapping.icp import MatchResult
from omnibot.mapping.keyframes import KeyframeStore
from omnibot.mapping.se2 import between, distance, rotate_covariance
from omnibot.motion import Pose2D


@dataclass(frozen=True)
class LoopClosure:
    """A loop closure the SLAM tried: between keyframes ``older`` and ``newer``, kept or not and why."""

    older: int
    newer: int
    accepted: bool
    reason: str
    match: MatchResult | None


class LoopClosing(KeyframeStore):
    """The SLAM's loop closures (see the module docstring) on its keyframes and options."""

    loop_search_radius: float
    loop_min_separation: int
    loop_every: int
    loop_min_fitness: float
    loop_sigma_floor: tuple[float, float]
    loop_kernel_width: float
    loops: list[LoopClosure]
    """Every loop closure tried, in order."""
    _since_loop: int

    @property
    def closures(self) -> int:
        """Number of loop closures accepted."""
        return sum(1 for loop in self.loops if loop.accepted)

    def _loop_after(self, new: int) -> bool:
        """A loop closure of keyframe ``new`` tried if ``loop_every`` keyframes have come since the
        last try; True if one was added."""
        self._since_loop += 1
        if self._since_loop >= self.loop_every:
            return self._close_loop(new)
        return False

    def _close_loop(self, new: int) -> bool:
        """Try the nearest old keyframe as a loop closure of ``new``; True if one was added."""
        here = self._estimates[new]
        old = range(new - self.loop_min_separation + 1)
        near = [(distance(self._estimates[k], here), k) for k in old]
        near = [(d, k) for d, k in near if d <= self.loop_search_radius]
        if not near:
            return False
        self._since_loop = 0
        _, older = min(near)
        return self._verify_and_add(older, new, self._loop_match(older, new, here))

    def _loop_match(self, older: int, newer: int, start: Pose2D) -> MatchResult:
        """Keyframe ``newer`` matched from ``start`` on the submap around ``older``, with the wide window."""
        half = max(1, self.submap_keyframes // 2)
        return self.matcher.match(
            self._frames[newer].points,
            self._submap(older, before=half + 1, after=half),
            start,
            search_xy=self.loop_search_window[0],
            search_theta=self.loop_search_window[1],
        )

    def try_loop_closure(self, older: int, newer: int, guess: Pose2D | None = None) -> LoopClosure:
        """Match keyframe ``newer`` against the submap around ``older`` from ``guess`` (default: its estimate).

        The closure is verified as an automatic one is and, if accepted, added and optimised.
        """
        for key, k in (("older", older), ("newer", newer)):
            if not 0 <= k < len(self._frames):
                raise ConfigError(f"no keyframe {k} (there are {len(self._frames)})", key)
        start = self._estimates[newer] if guess is None else guess
        accepted = self._verify_and_add(older, newer, self._loop_match(older, newer, start))
        if accepted:
            self._optimise(closed=True)
        return self.loops[-1]

    def _verify_and_add(self, older: int, newer: int, result: MatchResult) -> bool:
        """``result`` added as a closure if it converged and fits well enough; the try recorded."""
        if not result.converged:
            self.loops.append(LoopClosure(older, newer, False, "match did not converge", result))
            return False
        if result.fitness < self.loop_min_fitness:
            reason = f"fitness {result.fitness:.2f} below {self.loop_min_fitness:.2f}"
            self.loops.append(LoopClosure(older, newer, False, reason, result))
            return False
        relative = between(self._estimates[older], result.pose)
        cov = rotate_covariance(result.covariance, -result.pose.theta)
        self.add_loop_closure(older, newer, relative, cov)
        self.loops.append(LoopClosure(older, newer, True, "accepted", result))
        return True

    def add_loop_closure(self, older: int, newer: int, relative: Pose2D, covariance: ArrayLike) -> None:
        """Add a closure factor: keyframe ``newer``'s pose seen from ``older`` (robust, floored covariance).

        For a place recogniser of one's own; the graph is optimised with the next keyframe.
        """
        cov = np.array(covariance, dtype=np.float64)
        if cov.shape != (3, 3) or not np.isfinite(cov).all():
            raise ConfigError(f"must be a finite 3x3 matrix, not shape {cov.shape}", "covariance")
        floor = np.array([self.loop_sigma_floor[0] ** 2] * 2 + [self.loop_sigma_floor[1] ** 2])
        cov = cov + np.diag(floor)
        self._graph.add_robust(older, newer, relative, cov, self.loop_kernel_width)
