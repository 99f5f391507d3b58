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

The parts, each in its module: the keyframes and the submaps made of them
(:mod:`~omnibot.mapping.keyframes`); where a match is degenerate (a corridor's axis), the anchor
submap's match completing it (:mod:`~omnibot.mapping.anchor`); the back end, a pose graph of the
keyframes (:mod:`~omnibot.mapping.posegraph`, gtsam ``Pose2`` nodes; ``optimizer`` iSAM2 or batch
Levenberg-Marquardt): between consecutive keyframes an odometry factor (noise growing with the
distance and angle driven, ``odometry_noise``) and the match factor (the match's own covariance, so
a direction the scans leave unconstrained, such as a corridor's axis, is carried by odometry
alone); where a match is degenerate, a heading factor from the first keyframe through the
corridor's straight side walls (:mod:`~omnibot.mapping.walls`: each match's heading noise would
otherwise random-walk along it); loop closures, verified and robust (:mod:`~omnibot.mapping.loops`).
The scans taken while the robot stands still (the odometry where it was at the previous scan, no
twist over the scan: the start's standstill while the gyro's bias is learned, a stop) join the
keyframe they were taken at (:meth:`~omnibot.mapping.keyframes.KeyframeStore._join`): one scan's
noise turns its walls by 0.05-0.2 degree, which every keyframe matched against it takes, so the
first keyframe's would set the map's heading (a corridor's side wall 30 m on 3-10 cm off, a turn
the side walls cannot see); the standstill's scans average it out.
``scan_to_submap=False`` leaves the front end out (odometry and loop closures only),
``deskew=False`` the motion-distortion correction, ``join_still=False`` the standstill's joins,
``wall_heading=False`` the wall-heading factors: to measure what each part brings.

Poses between keyframes are their keyframe's estimate composed with the odometry since it, so
:meth:`Slam.trajectory` follows every correction of the graph. The map frame starts at the first
odometry pose (``map_to_odom`` is the identity until the first correction). Deterministic: no
randomness anywhere.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from omnibot.errors import ConfigError
from omnibot.mapping.anchor import AnchorMatching
from omnibot.mapping.icp import MatchResult
from omnibot.mapping.loops import LoopClosing
from omnibot.mapping.matcher import ScanMatcher
from omnibot.mapping.posegraph import OPTIMIZERS, PoseGraph
from omnibot.mapping.se2 import between, compose, inverse, rotate_covariance
from omnibot.mapping.walls import WallHeading
from omnibot.motion import Pose2D, Twist
from omnibot.scan import Scan

FloatArray = NDArray[np.float64]

STILL = (1e-4, 1e-5)
"""The odometry's largest move between two scans (m, rad) that still counts as standing still."""


class Slam(LoopClosing, AnchorMatching, WallHeading):
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
        join_still: bool = True,
        wall_heading: bool = True,
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
        self.join_still = join_still
        self.wall_heading = wall_heading
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
        self._frames = []
        self._estimates = []
        self._track: list[tuple[float, int, Pose2D]] = []  # stamp, keyframe, odometry since it
        self._last_odom: Pose2D | None = None
        self._last_stamp = -math.inf
        self._pose = Pose2D(0.0, 0.0, 0.0)
        self._twist = Twist()
        self._waiting: tuple[float, Pose2D] | None = None
        self._since_loop = 0
        self.loops = []
        self.matches: list[MatchResult] = []
        """The front end's match of every keyframe but the first."""
        self.anchored = 0
        self.anchors = []
        self._walls = {}
        self.walled = 0
        self._graph = PoseGraph(self.optimizer)

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

    def trajectory(self) -> list[tuple[float, Pose2D]]:
        """(stamp, map-frame pose) of every scan given to :meth:`update`, with the latest corrections."""
        return [(stamp, compose(self._estimates[k], delta)) for stamp, k, delta in self._track]

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
        still = self._still(odom_pose, twist)
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
                if still and self.join_still:
                    self._join(last, scan, delta)
                self._track.append((stamp, last, delta))
        _, k, delta = self._track[-1]
        self._pose = compose(self._estimates[k], delta)
        return self._pose

    def _still(self, odom_pose: Pose2D, twist: Twist | None) -> bool:
        """Whether the robot stood still over the scan: the odometry where it was at the previous scan
        (within :data:`STILL`) and, if given, no twist over the scan."""
        if self._last_odom is None or not (twist is None or twist.is_zero):
            return False
        step = between(self._last_odom, odom_pose)
        return math.hypot(step.x, step.y) <= STILL[0] and abs(step.theta) <= STILL[1]

    def _add_first(self, odom_pose: Pose2D, scan: Scan, stamp: float) -> None:
        self._frames.append(self._keyframe(odom_pose, scan, stamp))
        self._estimates.append(odom_pose)
        self._graph.add_prior(0, odom_pose)
        self._graph.add_node(0, odom_pose)
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
        self._graph.add_odometry(last, new, delta, np.sqrt(np.diag(self._odometry_cov(delta))))
        seen: list[tuple[int, Pose2D, FloatArray]] = []  # (from keyframe, map-frame pose, covariance)
        if result is not None and result.converged and result.fitness >= self.min_fitness:
            seen.append((last, result.pose, result.covariance))
            anchored = result.unconstrained and self.anchor_reach is not None
            anchor = self._anchor_match(frame, predicted, result) if anchored else None
            if anchor is not None:
                seen.append(anchor)
            if result.unconstrained:
                self._wall_factor(new, result)
        for reference, pose, covariance in seen:
            relative = between(self._estimates[reference], pose)
            cov = rotate_covariance(covariance, -pose.theta)
            self._graph.add_match(reference, new, relative, cov)
        estimate = self._fuse(predicted, delta, [(pose, cov) for _, pose, cov in seen])
        self._estimates.append(estimate)
        self._graph.add_node(new, estimate)
        self._track.append((stamp, new, Pose2D(0.0, 0.0, 0.0)))
        self._optimise(self._loop_after(new))

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
