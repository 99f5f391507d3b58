"""Online 2D SLAM: scan-to-submap matching on keyframes, a gtsam pose graph with verified loop closures.

Front end: each scan is deskewed (:mod:`omnibot.mapping.deskew`) with the base's twist over the
scan: the caller's (the odometry's motion across the scan's own revolution, what
:class:`~omnibot.mapping.session.MappingSink` gives), else the odometry's motion since the
previous scan (a revolution late: a turn that starts or stops during the scan is left in it; the
first scan of a spinning scanner, with no motion known yet, is skipped). Its odometry delta since
the last keyframe predicts the robot's pose. When the
robot has moved ``keyframe_distance`` or turned ``keyframe_angle`` since then, the scan becomes a
keyframe: it is matched (:class:`~omnibot.mapping.matcher.ScanMatcher`, correlative search then
ICP) against a local submap (the last ``submap_keyframes`` keyframes' points at their current
estimates), starting from the prediction.

Degeneracy: where that match leaves a direction unconstrained (a corridor's axis, whose far end
wall the submap holds only as a blur of its own distant, noisy views), the keyframe is matched
again (``anchor_reach=None`` turns this off), each return weighed by its own range
noise (``weighted``, :class:`ScanMatcher`), against an *anchor* submap: the returns every keyframe
within ``anchor_reach`` of the prediction (12 m by default: an A1's reach) saw within
``anchor_range`` (sharp: 2 cm at 2 m for an A1). So the end wall seen up close fixes the axis, as well as its returns from 10 m can (a few
centimetres). If that match converged, fits as well as ``min_fitness`` asks and constrains
directions the first left free, it adds a factor from the anchor submap's oldest keyframe (what was
seen first) whose covariance keeps only those directions: the others stay the first match's, from
the previous keyframe, since an old keyframe's heading would swing them by the lever of the metres
between. What stays unconstrained is the odometry's alone: the match keeps the prediction there and
its covariance leaves it free (Zhang et al.'s solution remapping, the information matrix as the
factor's weight). A direction no return constrains at all (mid-corridor, no end wall in range)
cannot be recovered by any scan matching: there the SLAM is the odometry. The anchor match takes
the axis from the returns aligned with it alone (the end wall's; :class:`ScanMatcher`'s weighted
match): with the side walls' pull in it, it had biased omni3's corridor by centimetres
(docs/mapping.md).

Back end: a pose graph of the keyframes (gtsam ``Pose2`` nodes). Between consecutive keyframes, an
odometry factor (noise growing with the distance and angle driven, ``odometry_noise``) and the
match factor (the match's own covariance, so a direction the scans leave unconstrained, such as a
corridor's axis, is carried by odometry alone). Loop closures: a keyframe at least
``loop_min_separation`` keyframes back and within ``loop_search_radius`` of the new one is matched
with a wide search (``loop_search_window``); the match is kept only if it converged with a fitness
of at least ``loop_min_fitness``, and enters the graph through a Cauchy robust kernel with its
covariance floored at ``loop_sigma_floor`` (so one false closure that passed the checks is
down-weighted, not obeyed). ``optimizer="isam2"`` updates the graph incrementally on every keyframe
(with extra iterations after a closure); ``"lm"`` runs a batch Levenberg-Marquardt after each
closure and otherwise takes the matched pose as it is. ``scan_to_submap=False`` leaves the front
end out (odometry and loop closures only), ``deskew=False`` the motion-distortion correction: to
measure what each part brings.

Poses between keyframes are their keyframe's estimate composed with the odometry since it, so
:meth:`Slam.trajectory` follows every correction of the graph. The map frame starts at the first
odometry pose (``map_to_odom`` is the identity until the first correction). Deterministic: no
randomness anywhere.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import gtsam
import numpy as np
from numpy.typing import ArrayLike, NDArray

from omnibot.errors import ConfigError
from omnibot.mapping.degeneracy import UNCONSTRAINED_VARIANCE
from omnibot.mapping.deskew import scan_points
from omnibot.mapping.icp import MatchResult
from omnibot.mapping.matcher import ScanMatcher
from omnibot.mapping.se2 import between, compose, distance, inverse, rotate_covariance, transform
from omnibot.mapping.target import Target, voxel_downsample
from omnibot.motion import Pose2D, Twist
from omnibot.scan import Scan

FloatArray = NDArray[np.float64]

OPTIMIZERS = ("isam2", "lm")
PRIOR_SIGMA = 1e-4


@dataclass(frozen=True)
class Keyframe:
    """A keyframe as the SLAM keeps it: its scan, odometry pose and base-frame points (deskewed)."""

    stamp: float
    odom: Pose2D
    scan: Scan
    points: FloatArray
    anchor: FloatArray
    """Its points measured within the SLAM's ``anchor_range`` (sharp), thinned to half a cell, base frame."""


@dataclass(frozen=True)
class LoopClosure:
    """A loop closure the SLAM tried: between keyframes ``older`` and ``newer``, kept or not and why."""

    older: int
    newer: int
    accepted: bool
    reason: str
    match: MatchResult | None


def _pose2(p: Pose2D) -> gtsam.Pose2:
    return gtsam.Pose2(p.x, p.y, p.theta)


def _pose(p: gtsam.Pose2) -> Pose2D:
    return Pose2D(float(p.x()), float(p.y()), float(p.theta()))


class Slam:
    """Online 2D SLAM (see the module docstring): feed :meth:`update` odometry poses and scans."""

    def __init__(
        self,
        *,
        resolution: float = 0.05,
        keyframe_distance: float = 0.25,
        keyframe_angle: float = math.radians(15.0),
        submap_keyframes: int = 10,
        search_xy: float = 0.15,
        search_theta: float = math.radians(6.0),
        odometry_noise: tuple[float, float] = (0.05, 0.05),
        min_fitness: float = 0.5,
        loop_search_radius: float = 1.0,
        loop_search_window: tuple[float, float] = (0.4, math.radians(12.0)),
        loop_min_separation: int = 20,
        loop_every: int = 5,
        loop_min_fitness: float = 0.75,
        loop_sigma_floor: tuple[float, float] = (0.01, math.radians(0.5)),
        loop_kernel_width: float = 3.0,
        anchor_range: float = 2.0,
        anchor_reach: float | None = 12.0,
        optimizer: str = "isam2",
        scan_to_submap: bool = True,
        deskew: bool = True,
        matcher: ScanMatcher | None = None,
    ) -> None:
        self.keyframe_distance = keyframe_distance
        self.keyframe_angle = keyframe_angle
        self.submap_keyframes = submap_keyframes
        self.search_xy = search_xy
        self.search_theta = search_theta
        self.odometry_noise = odometry_noise
        self.min_fitness = min_fitness
        self.loop_search_radius = loop_search_radius
        self.loop_search_window = loop_search_window
        self.loop_min_separation = loop_min_separation
        self.loop_every = loop_every
        self.loop_min_fitness = loop_min_fitness
        self.loop_sigma_floor = loop_sigma_floor
        self.loop_kernel_width = loop_kernel_width
        self.anchor_range = anchor_range
        self.anchor_reach = anchor_reach
        self.optimizer = optimizer
        self.scan_to_submap = scan_to_submap
        self.deskew = deskew
        self._check_options(resolution)
        self.matcher = matcher or ScanMatcher(resolution=resolution)

        self._init_state()

    def _check_options(self, resolution: float) -> None:
        """A :class:`ConfigError` naming the first option out of its range (checked in this order:
        the positive numbers, the pairs of them, the fractions in [0, 1], the counts, the optimizer)."""
        positive = {
            "resolution": resolution,
            "keyframe_distance": self.keyframe_distance,
            "keyframe_angle": self.keyframe_angle,
            "loop_search_radius": self.loop_search_radius,
            "loop_kernel_width": self.loop_kernel_width,
            "anchor_range": self.anchor_range,
        }
        if self.anchor_reach is not None:
            positive["anchor_reach"] = self.anchor_reach
        for key, value in positive.items():
            if not (math.isfinite(value) and value > 0):
                raise ConfigError(f"must be a positive number, not {value}", key)
        for key, pair in (
            ("odometry_noise", self.odometry_noise),
            ("loop_search_window", self.loop_search_window),
            ("loop_sigma_floor", self.loop_sigma_floor),
        ):
            if len(pair) != 2 or not all(math.isfinite(v) and v > 0 for v in pair):
                raise ConfigError(f"must be two positive numbers, not {pair}", key)
        for key, fraction in (("min_fitness", self.min_fitness), ("loop_min_fitness", self.loop_min_fitness)):
            if not 0.0 <= fraction <= 1.0:
                raise ConfigError(f"must be a fraction in [0, 1], not {fraction}", key)
        for key, count in (
            ("submap_keyframes", self.submap_keyframes),
            ("loop_min_separation", self.loop_min_separation),
            ("loop_every", self.loop_every),
        ):
            if count < 1:
                raise ConfigError(f"must be at least 1, not {count}", key)
        if self.optimizer not in OPTIMIZERS:
            raise ConfigError(
                f"unknown optimizer {self.optimizer!r}; choose one of {', '.join(OPTIMIZERS)}", "optimizer"
            )

    def _init_state(self) -> None:
        """An empty map: no keyframes, track or loop closures, an empty factor graph and iSAM2."""
        self._frames: list[Keyframe] = []
        self._estimates: list[Pose2D] = []
        self._track: list[tuple[float, int, Pose2D]] = []  # stamp, keyframe, odometry since it
        self._last_odom: Pose2D | None = None
        self._last_stamp = -math.inf
        self._pose = Pose2D(0.0, 0.0, 0.0)
        self._twist = Twist()
        self._waiting: tuple[float, Pose2D] | None = None
        self._since_loop = 0
        self.loops: list[LoopClosure] = []
        """Every loop closure tried, in order."""
        self.matches: list[MatchResult] = []
        """The front end's match of every keyframe but the first."""
        self.anchored = 0
        """Keyframes whose degenerate match the anchor submap's completed (a factor along what it left free)."""

        self._graph = gtsam.NonlinearFactorGraph()  # every factor (batch optimiser)
        self._values = gtsam.Values()
        self._new_factors = gtsam.NonlinearFactorGraph()  # not yet given to iSAM2
        self._new_values = gtsam.Values()
        params = gtsam.ISAM2Params()
        params.setRelinearizeThreshold(0.01)
        params.relinearizeSkip = 1
        self._isam = gtsam.ISAM2(params)

    # ------------------------------------------------------------------ queries

    @property
    def pose(self) -> Pose2D:
        """The robot's latest pose in the map frame."""
        return self._pose

    @property
    def map_to_odom(self) -> Pose2D:
        """The odometry frame's pose in the map frame (the ``map -> odom`` transform)."""
        if self._last_odom is None:
            return Pose2D(0.0, 0.0, 0.0)
        return compose(self._pose, inverse(self._last_odom))

    @property
    def closures(self) -> int:
        """Number of loop closures accepted."""
        return sum(1 for loop in self.loops if loop.accepted)

    def trajectory(self) -> list[tuple[float, Pose2D]]:
        """(stamp, map-frame pose) of every scan given to :meth:`update`, with the latest corrections."""
        return [(stamp, compose(self._estimates[k], delta)) for stamp, k, delta in self._track]

    def keyframes(self) -> list[tuple[Pose2D, Scan]]:
        """(corrected map-frame pose, scan) of every keyframe: what a mapper rebuilds the map from."""
        return [(pose, frame.scan) for pose, frame in zip(self._estimates, self._frames, strict=True)]

    # ------------------------------------------------------------------ the front end

    def update(self, odom_pose: Pose2D, scan: Scan, stamp: float, twist: Twist | None = None) -> Pose2D:
        """Take one scan and the odometry pose at its first ray; return the robot's map-frame pose.

        ``stamp`` (s, never decreasing) is the time of ``odom_pose`` and the scan's first ray on the
        caller's clock. ``twist`` is the base's body twist over the scan (the odometry's motion from
        its first ray to its last); it removes the scan's motion distortion
        (:mod:`omnibot.mapping.deskew`). None: the odometry's motion since the previous call, a
        revolution late (a turn starting or stopping during the scan leaves it distorted by the
        change of rate).
        """
        if not isinstance(scan, Scan):
            raise ConfigError(f"must be a Scan, not {type(scan).__name__}", "scan")
        if not all(math.isfinite(v) for v in (odom_pose.x, odom_pose.y, odom_pose.theta)):
            raise ConfigError(f"must be finite, not {odom_pose}", "odom_pose")
        if not math.isfinite(stamp) or stamp < self._last_stamp:
            raise ConfigError(
                f"must be finite and not before the previous one ({self._last_stamp}), not {stamp}", "stamp"
            )
        if twist is not None and not all(math.isfinite(v) for v in (twist.vx, twist.vy, twist.w)):
            raise ConfigError(f"must be finite, not {twist}", "twist")
        first_call = self._last_odom is None
        if not self.deskew:
            twist = Twist()
        elif twist is None:
            twist = Twist()
            if self._last_odom is not None and stamp > self._last_stamp:
                step = between(self._last_odom, odom_pose)
                dt = stamp - self._last_stamp
                twist = Twist(step.x / dt, step.y / dt, step.theta / dt)
        else:
            first_call = False  # the scan's own motion is known: it can start the map
        self._twist = twist
        self._last_stamp = stamp
        self._last_odom = odom_pose
        if not self._frames:
            if first_call and self.deskew and scan.time_increment != 0.0:
                # a distorted scan with no motion known yet to undo it with: the next one starts the map
                self._waiting = (stamp, odom_pose)
                self._pose = odom_pose
                return odom_pose
            self._add_first(odom_pose, scan, stamp)
            if self._waiting is not None:
                self._track.insert(0, (self._waiting[0], 0, between(odom_pose, self._waiting[1])))
        else:
            last = len(self._frames) - 1
            delta = between(self._frames[last].odom, odom_pose)
            if (
                math.hypot(delta.x, delta.y) >= self.keyframe_distance
                or abs(delta.theta) >= self.keyframe_angle
            ):
                self._add_keyframe(odom_pose, scan, stamp, delta)
            else:
                self._track.append((stamp, last, delta))
        _, k, delta = self._track[-1]
        self._pose = compose(self._estimates[k], delta)
        return self._pose

    def _keyframe(self, odom_pose: Pose2D, scan: Scan, stamp: float) -> Keyframe:
        points = scan_points(scan, self._twist)
        near = np.hypot(points[:, 0] - scan.mount.x, points[:, 1] - scan.mount.y) <= self.anchor_range
        if self.anchor_reach is None:
            near[:] = False  # no anchor submap: nothing to keep
        anchor = voxel_downsample(points[near], self.matcher.resolution / 2.0)  # as a target thins them
        return Keyframe(stamp, odom_pose, scan, points, anchor)

    def _add_first(self, odom_pose: Pose2D, scan: Scan, stamp: float) -> None:
        self._frames.append(self._keyframe(odom_pose, scan, stamp))
        self._estimates.append(odom_pose)
        noise = gtsam.noiseModel.Isotropic.Sigma(3, PRIOR_SIGMA)
        self._add_factor(gtsam.PriorFactorPose2(0, _pose2(odom_pose), noise))
        self._add_value(0, odom_pose)
        self._optimise(closed=False)
        self._track.append((stamp, 0, Pose2D(0.0, 0.0, 0.0)))

    def _add_keyframe(self, odom_pose: Pose2D, scan: Scan, stamp: float, delta: Pose2D) -> None:
        last = len(self._frames) - 1
        new = last + 1
        frame = self._keyframe(odom_pose, scan, stamp)
        predicted = compose(self._estimates[last], delta)
        result = None
        if self.scan_to_submap:
            result = self.matcher.match(
                frame.points,
                self._submap(last),
                predicted,
                search_xy=self.search_xy,
                search_theta=self.search_theta,
            )
            self.matches.append(result)
        self._frames.append(frame)
        self._add_factor(gtsam.BetweenFactorPose2(last, new, _pose2(delta), self._odometry_noise(delta)))
        seen: list[tuple[int, Pose2D, FloatArray]] = []  # (from keyframe, map-frame pose, covariance)
        if result is not None and result.converged and result.fitness >= self.min_fitness:
            seen.append((last, result.pose, result.covariance))
            anchored = result.unconstrained and self.anchor_reach is not None
            anchor = self._anchor_match(frame, predicted, result) if anchored else None
            if anchor is not None:
                seen.append(anchor)
        for reference, pose, covariance in seen:
            relative = between(self._estimates[reference], pose)
            cov = rotate_covariance(covariance, -pose.theta)
            self._add_factor(
                gtsam.BetweenFactorPose2(
                    reference, new, _pose2(relative), gtsam.noiseModel.Gaussian.Covariance(cov)
                )
            )
        estimate = self._fuse(predicted, delta, [(pose, cov) for _, pose, cov in seen])
        self._estimates.append(estimate)
        self._add_value(new, estimate)
        self._track.append((stamp, new, Pose2D(0.0, 0.0, 0.0)))
        self._since_loop += 1
        closed = False
        if self._since_loop >= self.loop_every:
            closed = self._close_loop(new)
        self._optimise(closed)

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

    def _fuse(self, predicted: Pose2D, delta: Pose2D, seen: list[tuple[Pose2D, FloatArray]]) -> Pose2D:
        """The matches where they constrain, the prediction where they do not (the new node's first guess)."""
        odo = rotate_covariance(self._odometry_cov(delta), predicted.theta)
        info = np.linalg.inv(odo)
        pull = np.zeros(3)
        for pose, covariance in seen:
            info_m = np.linalg.inv(covariance)
            diff = np.array([pose.x - predicted.x, pose.y - predicted.y, pose.theta - predicted.theta])
            diff[2] = math.remainder(diff[2], 2 * math.pi)
            info, pull = info + info_m, pull + info_m @ diff
        step = np.linalg.solve(info, pull)
        return Pose2D(
            predicted.x + step[0],
            predicted.y + step[1],
            math.remainder(predicted.theta + step[2], 2 * math.pi),
        )

    def _odometry_cov(self, delta: Pose2D) -> FloatArray:
        d = math.hypot(delta.x, delta.y)
        sxy = self.odometry_noise[0] * d + 0.005
        sth = self.odometry_noise[1] * d + 0.05 * abs(delta.theta) + 0.002
        return np.diag([sxy * sxy, sxy * sxy, sth * sth])

    def _odometry_noise(self, delta: Pose2D) -> gtsam.noiseModel.Base:
        return gtsam.noiseModel.Diagonal.Sigmas(np.sqrt(np.diag(self._odometry_cov(delta))))

    def _submap(self, last: int, before: int | None = None, after: int = 0) -> Target:
        """The points of keyframes ``last - before .. last + after`` at their estimates, as a match target."""
        count = self.submap_keyframes if before is None else before
        first = max(0, last - count + 1)
        end = min(len(self._frames), last + after + 1)
        pts = np.vstack([transform(self._estimates[k], self._frames[k].points) for k in range(first, end)])
        return self.matcher.target(pts, margin=max(self.search_xy, self.loop_search_window[0]) + 1.0)

    # ------------------------------------------------------------------ loop closures

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
        kernel = gtsam.noiseModel.mEstimator.Cauchy.Create(self.loop_kernel_width)
        noise = gtsam.noiseModel.Robust.Create(kernel, gtsam.noiseModel.Gaussian.Covariance(cov))
        self._add_factor(gtsam.BetweenFactorPose2(older, newer, _pose2(relative), noise))

    # ------------------------------------------------------------------ the back end

    def _add_factor(self, factor: gtsam.NonlinearFactor) -> None:
        self._graph.add(factor)
        self._new_factors.add(factor)

    def _add_value(self, key: int, pose: Pose2D) -> None:
        self._values.insert(key, _pose2(pose))
        self._new_values.insert(key, _pose2(pose))

    def _optimise(self, closed: bool) -> None:
        if self.optimizer == "isam2":
            self._isam.update(self._new_factors, self._new_values)
            for _ in range(3 if closed else 0):
                self._isam.update()
            result = self._isam.calculateEstimate()
        elif closed:
            params = gtsam.LevenbergMarquardtParams()
            result = gtsam.LevenbergMarquardtOptimizer(self._graph, self._values, params).optimize()
        else:
            result = None
        self._new_factors = gtsam.NonlinearFactorGraph()
        self._new_values = gtsam.Values()
        if result is not None:
            self._estimates = [_pose(result.atPose2(k)) for k in range(len(self._frames))]
            self._values = result
