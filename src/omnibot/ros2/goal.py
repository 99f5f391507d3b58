"""Nav2's ``goal_pose`` on a saved map (``omnibot ros2 --map MAP.yaml``): localise, publish the map
and ``map -> odom``, go to each goal.

* :class:`Localisation` is a runtime sink: a :class:`~omnibot.mapping.session.LocalisingSink` (the
  particle filter and scan-to-map matching of ``omnibot goto``) fed by the runtime's scans and
  odometry, started at the robot's pose in the map; it publishes the map once on ``map``
  (nav_msgs/OccupancyGrid, transient local: a node that joins late gets it) and the localiser's
  ``map -> odom`` on ``/tf`` at 20 Hz once the first scan is placed, through the bridge's
  :class:`~omnibot.ros2.bridge.Ros2Sink`.
* :class:`GoalPoseSource` reads ``goal_pose`` (geometry_msgs/PoseStamped, what rviz2's "2D Goal
  Pose" tool and Nav2's users publish) and goes there with a
  :class:`~omnibot.navigation.goto_source.GotoSource` (plan on the map inflated by the robot's
  radius, the tracker, the scan watching for what the map lacks, re-plans), at priority 20: ``cmd_vel``
  (90) and every person take the robot over, and goto plans again from where they left it. A goal
  must be in the map frame (``<prefix>map``); any other frame, a goal off the map, inside a wall or
  too near one, or not a finite pose is refused with one warning and changes nothing. A new goal
  pre-empts the one being gone to. The outcome (arrived, or why not: no path, blocked, timed out,
  stalled, stopped, missed, off path, cancelled) is a status line and the ``omnibot: goal`` diagnostic status.
* ``initialpose`` (geometry_msgs/PoseWithCovarianceStamped, rviz2's "2D Pose Estimate", Nav2's
  initial pose) in the map frame re-places the localiser there (:meth:`GoalPoseSource.initial_pose`,
  read by the bridge's :class:`~omnibot.ros2.odometry.OdometryReset`): its particles are drawn
  with the message's x/y and yaw standard deviations (:func:`spread_of`), the goal being gone to
  is cancelled. A pose in another frame, off the map, overlapping a wall or not finite is refused
  with one warning and changes nothing, as AMCL ignores a pose outside its global frame.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

from omnibot.errors import ConfigError, OffMapError, PlanningError
from omnibot.logs import MAP, TF, map_to_odom, occupancy_grid
from omnibot.mapping import LocalisingSink, OccupancyGrid, compose, inverse
from omnibot.motion import Pose2D
from omnibot.navigation import GotoOptions, GotoResult, GotoSource
from omnibot.robot import RobotDescription
from omnibot.ros2.backend import LATCHED, RosNode
from omnibot.ros2.bridge import Ros2Sink
from omnibot.ros2.diagnostics import Diagnosed
from omnibot.ros2.mapping import MAP_TYPE, TF_PERIOD
from omnibot.ros2.odometry import pose_of
from omnibot.ros2.types import from_dds
from omnibot.runtime import Cycle, Level, Proposal

if TYPE_CHECKING:
    from omnibot.lidar import ScanSource
    from omnibot.mapping import Localiser
    from omnibot.scan import Scan

GOAL_POSE = "goal_pose"
GOAL_TYPE = "geometry_msgs/msg/PoseStamped"
SPREAD_MIN = (0.01, 0.01)
"""The least spread (m, rad) the particles are drawn with when re-placed (a zero covariance)."""

Spread = tuple[float, float]
RefusalKind = Literal["frame", "pose", "off map", "blocked"]


@dataclass(frozen=True)
class Refusal:
    """Why a goal was refused: the warning's ``text``, and what was wrong with it (``frame``: not the map
    frame; ``pose``: not finite; ``off map``; ``blocked``: in or too near a wall)."""

    text: str
    kind: RefusalKind


Placer = Callable[[Pose2D, Spread], object]


def spread_of(covariance: Any) -> Spread | None:
    """(xy, theta) standard deviations of a PoseWithCovariance's 6x6 row-major covariance: the larger of
    x's and y's, and yaw's, each at least :data:`SPREAD_MIN`; None when a variance is negative or not
    finite."""
    variances = [float(covariance[i]) for i in (0, 7, 35)]
    if not all(math.isfinite(v) and v >= 0.0 for v in variances):
        return None
    vx, vy, vt = variances
    return max(math.sqrt(max(vx, vy)), SPREAD_MIN[0]), max(math.sqrt(vt), SPREAD_MIN[1])


class PlaceableSink(LocalisingSink):
    """A LocalisingSink that can be re-placed from the runtime's thread while its worker localises:
    :meth:`place` takes effect at once on :meth:`pose_now` and on the localiser before its next scan
    (the localiser is reset in the thread that updates it)."""

    def __init__(self, scans: ScanSource | None, localiser: Localiser, *, threaded: bool = False) -> None:
        self._placing: tuple[Pose2D, Spread] | None = None
        super().__init__(scans, localiser, threaded=threaded)

    def place(self, pose: Pose2D, spread: Spread) -> None:
        """The robot stands at ``pose`` in the map (particles drawn ``spread`` around it)."""
        odom = self.last_odometry
        with self._lock:
            self._placing = (pose, spread)
            self._points = None
            if odom is not None:
                self._map_to_odom = compose(pose, inverse(odom))

    def _update(self, scan: Scan, odom: Pose2D) -> None:
        with self._lock:
            placing, self._placing = self._placing, None
        if placing is not None:
            self.localiser.reset(*placing)
        super()._update(scan, odom)


class Localisation:
    """A sink: ``sink`` (a LocalisingSink) fed every cycle; the map and ``map -> odom`` published
    through ``bridge`` (see the module docstring). :meth:`close` when the run ends."""

    def __init__(self, bridge: Ros2Sink, grid: OccupancyGrid, sink: PlaceableSink) -> None:
        self.bridge = bridge
        self.grid = grid
        self.sink = sink
        bridge.add_topic(MAP, MAP_TYPE, LATCHED)
        self._map_sent = False
        self._last_tf = -math.inf

    def pose(self) -> Pose2D | None:
        """The robot's map-frame pose now (None until the first scan placed it)."""
        return self.sink.pose_now() if self.sink.updates else None

    def __call__(self, cycle: Cycle) -> None:
        """Feed the localiser; the map once, ``map -> odom`` every TF_PERIOD s once localised."""
        self.sink(cycle)
        ns = self.bridge.recorder.ns(cycle.t)
        if not self._map_sent:
            self._map_sent = True
            self.bridge.write(MAP, occupancy_grid(self.grid, ns))
        if self.sink.updates and cycle.now - self._last_tf >= TF_PERIOD:
            self._last_tf = cycle.now
            self.bridge.write(TF, map_to_odom(self.sink.map_to_odom_now(), ns))

    def place(self, pose: Pose2D, spread: Spread) -> None:
        """Re-place the localiser at ``pose`` (:meth:`PlaceableSink.place`)."""
        self.sink.place(pose, spread)

    def close(self) -> None:
        """Finish the localiser's work and close it."""
        self.sink.close()


class GoalPoseSource:
    """Goes to the newest ``goal_pose`` (see the module docstring): a runtime source."""

    def __init__(
        self,
        node: RosNode,
        robot: RobotDescription,
        grid: OccupancyGrid,
        period: float,
        pose: Callable[[], Pose2D | None],
        *,
        map_frame: str,
        notify: Callable[[Level, str], object],
        scan: Callable[[], Any] | None = None,
        options: GotoOptions | None = None,
        diagnosed: Diagnosed | None = None,
        place: Placer | None = None,
    ) -> None:
        self.map_frame = map_frame
        self.place = place
        """Re-places the localiser (None: ``initialpose`` is refused)."""
        self.notify = notify
        self.diagnosed = diagnosed or Diagnosed.of(robot.name)
        self.reader = node.reader(GOAL_POSE, GOAL_TYPE)
        self.goto = GotoSource(
            robot, grid, period, pose, options=options, scan=scan, on_result=self._result, name="goal_pose"
        )
        self.name = self.goto.name
        self.priority = self.goto.priority
        self.timeout = self.goto.timeout
        self.wait_reply = False
        self.received = 0
        self.refused = ""
        """Why the last goal was refused ("" once one is taken)."""
        self.detail = "no goal received"
        self.via = GOAL_POSE
        """What the goal being gone to (or the last) came by."""
        self.listeners: list[Callable[[GotoResult], object]] = []
        """Called with each goal's result after it is told (the navigate_to_pose action's)."""

    @property
    def watchdog(self) -> float:
        """The goto's VEL timeout."""
        return self.goto.watchdog

    @property
    def accel(self) -> float:
        """The goto's planned acceleration."""
        return self.goto.accel

    @property
    def body_accel(self) -> tuple[float, float, float] | None:
        """The goto's planned body acceleration."""
        return self.goto.body_accel

    def propose(self, cycle: Cycle) -> Proposal | None:
        """Take the newest goal, if one came; the goto's twist."""
        samples = [s for s in self.reader.take(N=16) if hasattr(s, "__idl_typename__")]
        self.received += len(samples)
        if samples:
            self.receive(from_dds(samples[-1], GOAL_TYPE))
        return self.goto.propose(cycle)

    def cancel(self, why: str) -> None:
        """End the goal being gone to (if any), ``why`` in its result."""
        self.goto.cancel(why)

    def receive(self, msg: Any, via: str = GOAL_POSE) -> GotoResult | Refusal:
        """Go to a geometry_msgs/PoseStamped that came by ``via`` (``goal_pose``, or Nav2's action
        ``navigate_to_pose``): the goal's result (filled in as it is gone to), or why it was refused
        (one warning; nothing changes)."""
        frame = msg.header.frame_id.lstrip("/")
        if frame != self.map_frame:
            return self._refuse(
                f"{via} in frame {frame!r} refused: goals are taken in the map frame {self.map_frame!r}",
                "frame",
            )
        goal = pose_of(msg.pose)
        if goal is None:
            return self._refuse(f"{via} refused: not a finite position and rotation", "pose")
        try:
            replaced = self.goto.go(goal)
        except ConfigError as exc:  # OffMapError, BlockedError: the robot cannot stand there
            return self._refuse(
                f"{via} refused: {exc}", "off map" if isinstance(exc, OffMapError) else "blocked"
            )
        self.via = via
        self.refused = ""
        self.detail = f"going to ({goal.x:.2f}, {goal.y:.2f}, {math.degrees(goal.theta):.0f} deg)"
        self.notify("info", f"{via} {'replaced' if replaced else 'received'}: {self.detail}")
        result = self.goto.result
        assert result is not None
        return result

    def initial_pose(self, msg: Any) -> tuple[bool, str]:
        """Re-place the localiser at a geometry_msgs/PoseWithCovarianceStamped in the map frame, or say
        why not (nothing changes): (done, what happened)."""
        frame = msg.header.frame_id.lstrip("/")
        if frame != self.map_frame or self.place is None:
            return False, (
                f"initialpose in frame {frame!r} refused: the localiser is placed in the map frame "
                f"{self.map_frame!r}"
            )
        pose = pose_of(msg.pose.pose)
        spread = spread_of(msg.pose.covariance)
        if pose is None or spread is None:
            return False, "initialpose refused: not a finite position, rotation and covariance"
        try:
            self.goto.check_pose(pose)
        except (ConfigError, PlanningError) as exc:
            return False, f"initialpose refused: {exc}"
        self.goto.cancel("the robot was re-placed by initialpose")
        self.place(pose, spread)
        return True, (
            f"localiser re-placed by initialpose at ({pose.x:.2f}, {pose.y:.2f}, "
            f"{math.degrees(pose.theta):.0f} deg), spread {100 * spread[0]:.0f} cm, "
            f"{math.degrees(spread[1]):.0f} deg"
        )

    def _refuse(self, text: str, kind: RefusalKind) -> Refusal:
        self.refused = text
        self.notify("warn", text)
        return Refusal(text, kind)

    def _result(self, result: GotoResult) -> None:
        self.detail = result.summary()
        level: Level = "info" if result.arrived else "warn"
        self.notify(level, f"{self.via}: {self.detail}")
        for listener in self.listeners:
            listener(result)

    def status(self) -> Any:
        """The ``omnibot: goal`` diagnostic status."""
        goto = self.goto
        result = goto.result
        state = goto.state if goto.active else ("idle" if result is None else result.outcome)
        values: dict[str, object] = {
            "state": state,
            "received": self.received,
            "refused": self.refused or "none",
        }
        if result is not None:
            g = result.goal
            values["goal"] = f"{g.x:.3f},{g.y:.3f},{math.degrees(g.theta):.1f}"
            values["outcome"] = "going" if goto.active else result.outcome
            values["reason"] = result.reason or "none"
            values["error_m"] = f"{result.error:.3f}"
            values["heading_error_deg"] = f"{math.degrees(result.heading_error):.1f}"
            values["plans"] = len(result.plans)
            values["replans"] = result.replans
        failed = result is not None and not goto.active and not result.arrived
        text = self.detail + (f" ({self.refused})" if self.refused else "")
        return self.diagnosed.status(1 if failed or self.refused else 0, "goal", text, values)
